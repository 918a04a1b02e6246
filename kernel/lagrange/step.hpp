// step(LagrangeState, dt): one time step of the Lagrange-multiplier method.
#pragma once

#include "limber/kernel/lagrange/lagrange_state.hpp"

namespace limber {

/// Advances `state` by dt seconds:
///  1. integrate  the awake bodies with the constraint forces: symplectic Euler solves them at the
///                velocity level (J·u₁ = −ω_b·C), the other integrators at the acceleration level
///                at every stage (multipliers.hpp), with Baumgarte terms when asked. The joints'
///                limits, friction and drives (joint_controls.hpp) are rows of the velocity-level
///                solve; the other integrators take them as an impulse pass before the step and
///                hold reached limits and held friction in its stages;
///  2. collide    contacts with the planes, balls, limbs and colliders answered by impulses on single bodies
///                (kernel/collision/rigid_contacts.hpp);
///  3. project    (projection stabilization) positions back onto C = 0 (and violated limits
///                onto their bounds); then — whenever there
///                were contacts, and always under projection — velocities onto J·u = 0 through
///                the mass matrix: a contact impulse reaches the rest of the body through the
///                joints as an impulse of the constraint system;
///  4. sleep      still islands fall asleep; divergence is detected.
/// Never throws; a bad Δt or a divergence is reported in the result (also state.last_report).
/// The tree solver allocates nothing; the sparse one (graphs with loops) allocates per solve.
StepReport step(LagrangeState& state, double dt);

/// step() with the scene's own time step.
inline StepReport step(LagrangeState& state) { return step(state, state.settings.time_step); }

}  // namespace limber
