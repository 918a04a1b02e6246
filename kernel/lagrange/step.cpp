#include "limber/kernel/lagrange/step.hpp"

#include <algorithm>
#include <cmath>

#include "limber/kernel/collision/rigid_contacts.hpp"
#include "limber/kernel/lagrange/contacts.hpp"
#include "limber/kernel/lagrange/multipliers.hpp"
#include "limber/kernel/model/guarded_step.hpp"

namespace limber {
namespace {

// Moves positions onto C = 0: solves [M Jᵀ; J 0](Δq, −μ) = (0, −C) and applies Δq (Δx, and the
// rotation Δθ), a Newton step on the joint equations weighted by the mass matrix. Velocities are
// left as they were (v and the world ω; L follows the turned inertia): keeping L instead would
// turn a thin limb's L onto its axis, where the smallest moment makes a fast spin of it.
void project_positions(LagrangeState& state) {
  RigidBodyState& y = state.bodies.state;
  body_velocities(state, y);  // ω before, kept in state.angular_velocity (nothing below writes it)
  for (auto& rhs : state.body_rhs) rhs.setZero();
  for (int iteration = 0; iteration < state.options.projection_iterations; ++iteration) {
    update_geometry(state, y);
    for (std::size_t c = 0; c < state.constraints.size(); ++c) {
      state.constraint_rhs[c] = -constraint_error(state.constraints, state.joints, y, c);
    }
    if (state.controls.empty()) {
      solve_constrained(state, y, state.body_rhs, state.constraint_rhs, state.accelerations);
    } else {  // violated limits pushed back onto their bounds, one-sided
      set_control_problem(state, ControlLevel::position, state.time_step, 0);
      solve_with_controls(state, y, state.body_rhs, state.accelerations);
    }
    for (std::size_t b = 0; b < state.bodies.size(); ++b) {
      y.position[b] += state.accelerations[b].head<3>();
      y.orientation[b] = (rotation_quaternion(state.accelerations[b].tail<3>()) * y.orientation[b]).normalized();
    }
  }
  for (std::size_t b = 0; b < state.bodies.size(); ++b) {
    y.angular_momentum[b] = state.bodies.world_inertia(y, b) * state.angular_velocity[b];
  }
}

// Moves velocities onto J·u = 0 the same way: (Δu, −μ) with J·Δu = −J·u; limits at or past
// their bounds stop approaching them (one-sided).
void project_velocities(LagrangeState& state, double dt) {
  RigidBodyState& y = state.bodies.state;
  body_velocities(state, y);
  update_geometry(state, y);
  for (auto& rhs : state.body_rhs) rhs.setZero();
  for (std::size_t c = 0; c < state.constraints.size(); ++c) {
    state.constraint_rhs[c] = -constraint_rate(state.constraints, state.geometry, state.velocity, state.angular_velocity, c);
  }
  if (state.controls.empty()) {
    solve_constrained(state, y, state.body_rhs, state.constraint_rhs, state.accelerations);
  } else {
    set_control_problem(state, ControlLevel::velocity_stop, dt, 0);
    solve_with_controls(state, y, state.body_rhs, state.accelerations);
  }
  for (std::size_t b = 0; b < state.bodies.size(); ++b) {
    const Eigen::Vector3d velocity = state.velocity[b] + state.accelerations[b].head<3>();
    const Eigen::Vector3d omega = state.angular_velocity[b] + state.accelerations[b].tail<3>();
    y.linear_momentum[b] = state.bodies.mass[b] * velocity;
    y.angular_momentum[b] = state.world_inertia[b] * omega;
  }
}

// Each body's impulse over a step of dt into state.body_rhs, (h·F, h·(τ − ω × Iω)) with the
// applied forces and the gyroscopic torque, plus its momentum (M·v₀, I·ω₀) when asked; fills
// v₀, ω₀ and the constraint geometry of the current state first.
void step_impulses(LagrangeState& state, double dt, bool with_momentum) {
  RigidBodyState& y = state.bodies.state;
  RigidForces& forces = state.scratch.forces;
  forces.clear();
  accumulate_applied_forces(state, y, forces);  // also fills v₀, ω₀
  update_geometry(state, y);
  for (std::size_t b = 0; b < state.bodies.size(); ++b) {
    const Eigen::Matrix3d& inertia = state.world_inertia[b];
    const Eigen::Vector3d& omega = state.angular_velocity[b];
    state.body_rhs[b].head<3>() = dt * forces.force[b];
    state.body_rhs[b].tail<3>() = dt * (forces.torque[b] - omega.cross(inertia * omega));
    if (with_momentum) {
      state.body_rhs[b].head<3>() = state.bodies.mass[b] * state.velocity[b] + state.body_rhs[b].head<3>();
      state.body_rhs[b].tail<3>() = inertia * omega + state.body_rhs[b].tail<3>();
    }
  }
}

// The joints' limits, friction and drives for an acceleration-level step of dt, as impulses
// before it. x₁ is the velocity change of a velocity-level step with the step's forces (h·F) and
// the control rows (speculative limits, friction up to f·dt, compliant drives; J·Δu = 0 on the
// joints' equations); x₂ the change the step's stages will make themselves with the same forces
// (they hold reached limits and the friction that held in x₁, and no drive). Δu = x₁ − x₂ is
// applied now, so that the step ends near x₁: what the velocity-level step would give.
void control_impulses(LagrangeState& state, double dt) {
  RigidBodyState& y = state.bodies.state;
  step_impulses(state, dt, /*with_momentum=*/false);
  for (auto& rhs : state.constraint_rhs) rhs.setZero();
  const double frequency = baumgarte_frequency(state, dt);
  set_control_problem(state, ControlLevel::velocity_change, dt, frequency);
  solve_with_controls(state, y, state.body_rhs, state.accelerations);
  for (ControlledJoint& joint : state.controls.joints) joint.stuck = joint.friction_bound > 0 && !joint.sliding;
  std::vector<Eigen::Matrix<double, 6, 1>>& stage_change = state.stage_change;  // x₂
  for (auto& rhs : state.constraint_rhs) rhs.setZero();
  set_control_problem(state, ControlLevel::stage_change, dt, frequency);
  solve_with_controls(state, y, state.body_rhs, stage_change);
  for (std::size_t b = 0; b < state.bodies.size(); ++b) {
    const Eigen::Matrix<double, 6, 1> change = state.accelerations[b] - stage_change[b];
    y.linear_momentum[b] = state.bodies.mass[b] * (state.velocity[b] + change.head<3>());
    y.angular_momentum[b] = state.world_inertia[b] * (state.angular_velocity[b] + change.tail<3>());
  }
}

// Symplectic Euler with the joints enforced at the velocity level (the form ODE, Bullet and
// Box2D use): the multipliers are impulses h·λ chosen so the new velocities satisfy
//   J·u₁ = −ω_b·C   (Baumgarte's position feedback; 0 under projection),
// by one augmented solve [M Jᵀ; J 0](u₁, −hλ) = (M·u₀ + h·F, −ω_b·C) with F the applied forces
// and the gyroscopic torque. Then L₁ = L₀ + h·(τ + Σ r × λ), x += h·v₁, and q turns by the free
// rotation with L₁. Enforcing the acceleration (C̈ = 0) instead and integrating explicitly
// gains energy and diverges on the heavy-end chain within 4 s (measured); this does not.
// Sets the momenta; move_bodies then moves the bodies (after the contacts, before the move).
void velocity_level_step(LagrangeState& state, double dt) {
  RigidBodyState& y = state.bodies.state;
  step_impulses(state, dt, /*with_momentum=*/true);
  const std::size_t body_count = state.bodies.size();
  const double frequency = baumgarte_frequency(state, dt);
  for (std::size_t c = 0; c < state.constraints.size(); ++c) {
    state.constraint_rhs[c] = -frequency * constraint_error(state.constraints, state.joints, y, c);
  }
  if (state.controls.empty()) {
    solve_constrained(state, y, state.body_rhs, state.constraint_rhs, state.accelerations);
  } else {  // limits, friction and drives as rows of the same solve (joint_controls.hpp)
    set_control_problem(state, ControlLevel::velocity, dt, frequency);
    solve_with_controls(state, y, state.body_rhs, state.accelerations);
  }
  for (std::size_t b = 0; b < body_count; ++b) {
    if (state.islands[state.island_of_body[b]].sleeping) continue;
    const Eigen::Matrix3d& inertia = state.world_inertia[b];
    const Eigen::Vector3d& omega = state.angular_velocity[b];
    const Eigen::Vector3d velocity = state.accelerations[b].head<3>(), new_omega = state.accelerations[b].tail<3>();
    y.linear_momentum[b] = state.bodies.mass[b] * velocity;
    y.angular_momentum[b] = inertia * new_omega + dt * omega.cross(inertia * omega);
  }
  for (auto& lambda : state.multipliers) lambda /= dt;  // the solve gave impulses h·λ
}

// Symplectic Euler's move with the momenta the contacts left: x += h·v, q turned by the free
// rotation with L (velocity_level_step's).
void move_bodies(LagrangeState& state, double dt) {
  RigidBodyState& y = state.bodies.state;
  for (std::size_t b = 0; b < state.bodies.size(); ++b) {
    if (state.islands[state.island_of_body[b]].sleeping) continue;
    y.position[b] += dt * state.bodies.linear_velocity(y, b);
    rotate_free_body(y.orientation[b], y.angular_momentum[b], state.bodies.body_inertia[b].diagonal(), dt);
  }
}

// Whether the step solves its contacts before the move (contacts_with_joints.hpp, "Before the
// move"): semi-implicit Euler on a scene with joints. Free bodies alone are moved first and their
// contacts solved after, by the same projected solve (the springs' sequential impulses, which
// they once took, let a stack of ten boxes fall: 382 mm in 9 s, against 67 mm; solved before
// the move it held to 13 mm, but two balls passing 2 cm apart turned each other; bench/collision.md,
// "Boxes as themselves").
bool constraints_before_move(const LagrangeState& state) {
  return state.options.integrator == Integrator::semi_implicit_euler && state.constraints.size() > 0;
}

// One step after the guard: integrate, contacts, projections, errors, sleep.
void advance(LagrangeState& state, double dt, StepReport& report) {
  StageClock clock(state.options.profile);
  state.time_step = dt;
  const bool before_move = constraints_before_move(state);
  if (before_move) {
    state.speculative_time = dt;  // gaps the step may close are contacts too
    detect_rigid_contacts(state);  // sweeps the balls' paths of the last step
    report.profile.detect = clock.lap();
  }
  remember_step_start(state);
  if (state.options.integrator == Integrator::semi_implicit_euler) {
    velocity_level_step(state, dt);
    if (!before_move) move_bodies(state, dt);
  } else {
    // Limits (speculative), friction and drives (implicit) as one velocity change before the
    // step; within it, limits at their bounds hold at the acceleration level.
    if (!state.controls.empty()) control_impulses(state, dt);
    integrate_rigid_bodies(state.bodies, dt, state.options.integrator, state.scratch,
                           [&state](const RigidBodyState& y, RigidForces& forces) { accumulate_constrained_forces(state, y, forces); });
  }
  // The projections reuse the solver; the step's multipliers are what observers report.
  std::swap(state.multipliers, state.projection_multipliers);
  const bool projection = state.options.stabilization == Stabilization::projection;
  report.profile.integrate = clock.lap();
  if (!before_move) {
    detect_rigid_contacts(state);
    report.profile.detect = clock.lap();
  }
  const bool constrained = state.constraints.size() > 0;
  resolve_contacts_with_joints(state, dt, before_move);
  if (before_move) move_bodies(state, dt);
  if (projection && constrained) project_positions(state);
  if ((projection || !state.contacts.empty()) && constrained) project_velocities(state, dt);
  std::swap(state.multipliers, state.projection_multipliers);
  report.contacts = static_cast<int>(state.contacts.size());
  for (std::size_t c = 0; c < state.constraints.joint_count; ++c) {
    const ConstraintVector error = constraint_error(state.constraints, state.joints, state.bodies.state, c);
    const ConstraintRows& rows = state.constraints.rows[c];
    report.constraint_error = std::max(report.constraint_error, position_error(rows, error));
    report.angular_error = std::max(report.angular_error, angular_error(rows, error));
  }
  state.time += dt;
  report.status = update_sleep(state, dt);
  clear_applied_loads(state);
  if (state.servos.any) {  // the World sets them again before the next step
    for (std::vector<double>* terms : {&state.servos.force, &state.servos.stiffness, &state.servos.damping}) std::fill(terms->begin(), terms->end(), 0.0);
    state.servos.any = false;
  }
  if (state.options.profile) count_rigid_step(state, report);
}

}  // namespace

StepReport step(LagrangeState& state, double dt) {
  return guarded_step(state, dt, [&](StepReport& report) { advance(state, dt, report); });
}

}  // namespace limber
