// step(SpringState, dt): one time step of the stiff-spring method.
#pragma once

#include "limber/kernel/springs/spring_state.hpp"

namespace limber {

/// Advances `state` by dt seconds (thesis 4.4.1, figure 2.5):
///  1. integrate  the awake bodies under gravity, drag and the joints' springs — explicitly
///                (forward or symplectic Euler, RK2, RK4: kernel/rigid/rigid_integration.hpp)
///                or implicitly (linearized backward Euler: implicit_step.hpp);
///  2. collide    contacts with the planes, balls, limbs and colliders, impulses (collision/rigid_contacts.hpp);
///  3. sleep      still islands fall asleep; divergence is detected.
/// Never throws; a bad Δt or a divergence is reported in the result (also state.last_report).
/// The explicit integrators allocate nothing; the implicit step allocates inside Eigen's sparse
/// factorization (a few temporaries per step).
StepReport step(SpringState& state, double dt);

/// step() with the scene's own time step.
inline StepReport step(SpringState& state) { return step(state, state.settings.time_step); }

}  // namespace limber
