// step(FeatherstoneState, dt): one time step of the Featherstone method (reduced coordinates).
#pragma once

#include "limber/kernel/featherstone/featherstone_state.hpp"

namespace limber {

/// Advances `state` by dt seconds:
///  1. integrate  each awake island's (q, v) with the articulated-body algorithm (Featherstone
///                2008, Table 7.1) by options.integrator (integration.hpp): RK4 or semi-implicit
///                Euler, gravity Settings::gravity, Settings::drag as joint forces held over the
///                step (Jᵀ of each body's drag at the step's start). In substeps when a body or
///                joint of the island turns fast: as many as keep its turn below 0.5 rad a
///                substep (at most 32; friction at a thin limb's rim spins it about its axis at
///                v/r, which the explicit integrators follow only while hΩ is small); the other
///                islands take one step. Sleeping islands are skipped: they keep their q and
///                v = 0. Joint drives (stable PD) and joint friction are found at each substep's
///                start and held over it as joint forces (joint_control_forces,
///                joint_space_contacts.hpp);
///  2. damp       v ← v·exp(−damping·dt) (Settings::damping: speed decays as exp(−damping·t),
///                whatever Δt, as in the other methods);
///  3. refresh    the island's rigid bodies from (q, v) (forward kinematics). Steps 1–3 are a
///                task per island on options.threads (unless a joint has friction, whose factors
///                the islands share: then on the calling thread);
///  4. collide    contacts with the planes and the ball found on the rigid bodies
///                (kernel/collision/rigid_contacts.hpp; a ball it moves back to where its path
///                first hit something goes into its floating joint's q, take_moved_balls),
///                answered by impulses through the joint-space inertia and a position push-out
///                (joint_space_contacts.hpp), with the joint limits' rows: each group of islands
///                the contacts join a task, on options.threads;
///  5. sleep      still islands fall asleep (their v is zeroed); divergence is detected.
/// That is RK4's order, the thesis's loop (move, then collide). Under semi-implicit Euler the
/// constraints come before the move (joint_space_contacts.hpp, "Before the move"): 4 collide
/// (speculative contacts, at the step's start pose) first; then 1–2, the last substep's velocity
/// update alone (for an island a contact touches, through H's factor, which the constraints then
/// take: factored_forward_dynamics); the contacts and limits on that velocity; then each awake island moves,
/// q ← q ⊕ h·v plus the push-out (advance_positions), and 3 refreshes its rigid bodies (a task
/// per island); then 5.
/// The joints cannot open: every body's pose is computed from q. Never throws; a bad Δt or a
/// divergence is reported in the result (also state.last_report). Allocates nothing.
StepReport step(FeatherstoneState& state, double dt);

/// step() with the scene's own time step.
inline StepReport step(FeatherstoneState& state) { return step(state, state.settings.time_step); }

/// The step's stages 1–3 for every awake island (listed in state.awake_islands), each a task on
/// the state's threads when it has them (not with joint friction, whose factors the islands
/// share); sleeping ones keep q and v = 0. Before the move (constraints_before_move,
/// joint_space_contacts.hpp) its last substep is the velocity update alone, and the positions wait
/// for advance_positions.
void integrate_awake_islands(FeatherstoneState& state, double dt);

/// Recomputes the rigid bodies (positions, orientations, momenta) and state.kinematics (poses
/// and spatial velocities of the tree bodies) from (q, v) by forward kinematics.
void refresh_rigid_bodies(FeatherstoneState& state);
/// The same from state.kinematics as it stands (its poses and velocities already those of (q, v)).
void mirror_rigid_bodies(FeatherstoneState& state);
/// The same for the tree bodies of `range` alone.
void mirror_rigid_bodies(FeatherstoneState& state, BodyRange range);

/// Islands put to sleep had their rigid momenta zeroed: so are their joint velocities and their
/// bodies' spatial velocities in state.kinematics, which no step refreshes while they sleep.
void rest_sleeping_islands(FeatherstoneState& state);

/// After detect_rigid_contacts moved a ball (continuous collision): every ball's floating joint
/// takes its rigid body's position (its origin is the centre of mass), then refresh_rigid_bodies.
void take_moved_balls(FeatherstoneState& state);

}  // namespace limber
