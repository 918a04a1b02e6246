// Contact passes of the Verlet step: detection, position projection, restitution.
//
// Contacts are position constraints solved inside relaxation, like the joints (thesis 3.2.3:
// the stick in a box loops its length and box constraints together):
// - plane contacts (ground, bound walls) push a particle out along the plane normal — the
//   box clamp of eq. 3.8 — and apply Coulomb friction to the step's tangential displacement
//   (static when it is within μ times the normal push, else reduced by that much;
//   Macklin et al. 2014, "Unified particle physics", eq. 24);
// - ball–limb contacts are a weighted projection (eq. 4.7 generalized to a point on a segment):
//   the ball and the limb's two particles move in inverse proportion to their masses, with the
//   limb's share split by where on its axis the contact lies (C = separation,
//   gradients +n, −(1−a)·n, −a·n; λ = −C / (w_ball + (1−a)² w_head + a² w_tail)).
// Penetration made by the step's own motion is removed in full; penetration the step began with
// (an initial overlap) is removed at most at Settings::contact_recovery_speed, because pushing a
// particle out also drags its neighbours through the joints, as real velocity.
// Restitution is then a velocity pass (Müller et al. 2020, "Detailed rigid body simulation with
// extended position based dynamics", 3.6): a contact still touching after relaxation leaves with
// normal speed exactly e·v, v its approach speed before the step (thesis eq. 2.33, the impulse
// spread by inverse mass) — which also removes any push-out velocity; approach speeds below
// 2|g|Δt bounce with e = 0 so resting contacts stay at rest. Under the rattle rule the pass runs
// after each sweep of the velocity stage, each contact an inequality row (contact_impulse), and
// the stage sweeps on while contacts act and the sweeps still change velocities
// (kernel/verlet/README.md, "Contacts under the rattle rule").
// Limbs with a centre particle (LimbMasses::inertia): contacts act on the head and tail only
// (the ends' features reach the whole surface); in relaxation the centre follows through its
// constraints, sweep by sweep. The velocity pass has no sweeps after it, so there the impulse
// moves the limb as the rigid body of its three particles — its effective mass at the contact
// point is 1/(1/m + s²/I), as for the rigid limb — and the pass is repeated (8 times) because
// such a limb couples its two ends' contacts.
#pragma once

#include <algorithm>

#include "limber/kernel/particles/verlet_state.hpp"

namespace limber {

/// A contact whose surfaces are this close after relaxation still touches, m: its normal
/// velocity is set by the restitution pass (balls and limbs alike).
inline constexpr double kTouchingSlop = 1e-4;

/// A particle's velocity as the contact passes see it, m/s: (x − x_previous)/dt under pbd, the
/// state's v under rattle (during relaxation x − x_previous = v·dt there too).
template <typename Scalar>
Eigen::Vector3d contact_velocity(const VerletState<Scalar>& state, std::uint32_t p, double dt) {
  const auto& particles = state.particles;
  if (uses_rattle(state)) return particles.velocity(p).template cast<double>();
  return (particles.position(p) - particles.previous(p)).template cast<double>() / dt;
}

/// A velocity change of `delta_v` (m/s): of the previous position under pbd (v = (x − x_previous)/dt),
/// of v under rattle.
template <typename Scalar>
void change_velocity(VerletState<Scalar>& state, std::uint32_t p, const Eigen::Vector3d& delta_v, double dt) {
  auto& particles = state.particles;
  if (uses_rattle(state)) {
    particles.set_velocity(p, particles.velocity(p) + delta_v.cast<Scalar>());
    return;
  }
  particles.set_previous(p, particles.previous(p) - (delta_v * dt).cast<Scalar>());
}

/// Approaches slower than this do not bounce, m/s: what gravity adds in two steps of dt (a body
/// resting on a contact approaches it at g·dt each step).
template <typename Scalar>
double resting_speed(const VerletState<Scalar>& state, double dt) {
  return 2 * state.gravity.template cast<double>().norm() * dt;
}

/// The normal speed a contact must leave with, m/s: e·(approach speed, < 0), or 0 for
/// approaches slower than `resting_speed` (resting contacts do not bounce).
inline double bounce_speed(double approach_speed, double restitution, double resting_speed) {
  return approach_speed < -resting_speed ? -restitution * approach_speed : 0.0;
}

/// The impulse a contact takes in one restitution pass, N·s, given `wanted`, the one that brings
/// its normal speed to its target (bounce_speed). Under pbd (one pass after relaxation) `wanted`
/// itself. Under the rattle rule the passes are the contacts' rows of the velocity stage's
/// Gauss-Seidel sweeps, and a contact is an inequality there: `velocity_impulse` accumulates what
/// it has taken this substep, held at or above −position_impulse/dt (position_impulse: relaxation's
/// pushes, kg·m) — its whole impulse over the substep never pulls, yet the velocity stage may take
/// back the speed a push gave it (push-out speed is not kept). Sequential impulses' accumulated
/// clamp (Catto 2005), with the position stage's push counted in.
template <typename Scalar>
double contact_impulse(const VerletState<Scalar>& state, double wanted, double position_impulse, double dt,
                       double& velocity_impulse) {
  if (!uses_rattle(state)) return wanted;
  const double total = std::max(velocity_impulse + wanted, -position_impulse / dt);
  const double taken = total - velocity_impulse;
  velocity_impulse = total;
  return taken;
}

/// Finds the awake balls' contacts with the limbs (asleep or not) and wakes the islands they
/// touch: each ball tests its candidates from the broadphase (BallCandidates,
/// kernel/geometry/broadphase.hpp), in increasing order. dt converts displacements to velocities.
template <typename Scalar>
void detect_ball_contacts(VerletState<Scalar>& state, double dt);

/// Finds the plane contacts of the awake islands' features.
template <typename Scalar>
void detect_plane_contacts(VerletState<Scalar>& state, double dt);

/// One projection of every plane contact (dt: the step's, for the recovery limit). Returns the
/// largest particle displacement, m.
template <typename Scalar>
double project_plane_contacts(VerletState<Scalar>& state, double dt);

/// One projection of every ball contact. Returns the largest particle displacement, m.
template <typename Scalar>
double project_ball_contacts(VerletState<Scalar>& state, double dt);

/// The restitution pass over all contacts of the step: velocities (pbd: previous positions only),
/// contact_impulse's rule. Returns the largest change of a contact's normal speed, m/s.
template <typename Scalar>
double apply_restitution(VerletState<Scalar>& state, double dt);

}  // namespace limber
