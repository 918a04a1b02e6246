// Relaxation of the distance constraints, as step() runs it (thesis 3.2.2, 4.3): one sweep at a
// time, Gauss-Seidel (coloured or sequential) or Jacobi, over whichever layout, lane width and
// thread count the VerletOptions chose — or, for the direct solver, one Newton step of its
// global projection (direct_projection.hpp). Every combination gives the same bits for any thread
// count; the SIMD and scalar paths, and the three layouts, give the same bits as each other.
//
// Coloured Gauss-Seidel: colour after colour (constraint_colouring.hpp); inside a colour the
// constraints are independent, so they run in SIMD lanes and are split across threads. The
// overflow (constraints at pinned particles, and at hubs the colouring could not place) runs
// scalar, before the colours (SweepDirection::pinned_first) or after them in reverse.
//
// Rattle (ProjectionRule::rattle): the same sweeps project along each constraint's gradient at
// the substep's start (SHAKE), and the velocity stage sweeps the velocities onto the tangent
// space (RATTLE); kernel/relaxation/README.md derives both.
//
// Jacobi: every constraint computes its correction from the positions at the start of the
// sweep; a particle's corrections are summed (colour by colour, so without races or atomics)
// and it moves by ω·(sum)/(its number of constraints) — the averaged Jacobi of Müller et al.,
// "Unified particle physics for real-time applications" (2014), eq. 11 — ω the relaxation
// factor (RelaxationSettings::over_relaxation).
#pragma once

#include "limber/kernel/particles/verlet_state.hpp"

namespace limber {

/// Colours the state's constraints and sets up its threads (called by compile()). Throws
/// std::invalid_argument on options that do not go together (the AoS or AoSoA layout or Jacobi with
/// the sequential order, threads < 0, max_colours outside [1, 64]).
template <typename Scalar>
void prepare_relaxation_plan(VerletState<Scalar>& state);

/// Starts relaxation for a (sub)step of dt seconds: rebuilds the batches if islands slept or
/// woke since the last step (O(awake constraints), no re-colouring, no allocation), copies the
/// awake particles into the interleaved layout if one is used, and starts the helper threads;
/// under the rattle rule, stores each constraint's gradient at the substep's start (the previous
/// positions); for the direct solver, applies its warm start.
template <typename Scalar>
void begin_relaxation(VerletState<Scalar>& state, double dt);

/// One sweep with relaxation factor ω (1: plain projections), or one Newton step of the direct
/// solver (which ignores ω); along the current gradients (pbd) or the start gradients (rattle).
/// Returns the largest particle displacement it made, m.
template <typename Scalar>
double relaxation_sweep(VerletState<Scalar>& state, double over_relaxation);

/// The rattle rule's velocity stage (RATTLE, Andersen 1983), after end_relaxation: stores each
/// awake constraint's gradient at the current positions and wakes the helpers; each
/// velocity_sweep then projects the velocities onto the constraints' tangent space
/// (Gauss-Seidel or Jacobi by colour, or sequential; the direct solver solves the projection
/// exactly, J W Jᵀ μ = −J v, in one call) and returns the largest velocity change, m/s.
template <typename Scalar>
void begin_velocity_projection(VerletState<Scalar>& state);
template <typename Scalar>
double velocity_sweep(VerletState<Scalar>& state);
template <typename Scalar>
void end_velocity_projection(VerletState<Scalar>& state);

/// Ends relaxation for one step: stops the helpers and copies positions back from the
/// interleaved layout.
template <typename Scalar>
void end_relaxation(VerletState<Scalar>& state);

/// Long-range attachments (VerletOptions::long_range_attachments; Kim, Chentanez, Müller,
/// "Long range attachments", 2012): every particle of the awake islands farther from its pin
/// than the rest length of the path between them is moved back onto that sphere (the pin does
/// not move). Returns the largest displacement, m.
template <typename Scalar>
double project_long_range_attachments(VerletState<Scalar>& state);

/// With an interleaved layout, the contact passes work on state.particles: these copy the
/// positions of state.contact_particles out of the layout before them and back after.
template <typename Scalar>
void contact_particles_to_buffer(VerletState<Scalar>& state);
template <typename Scalar>
void contact_particles_from_buffer(VerletState<Scalar>& state);

}  // namespace limber
