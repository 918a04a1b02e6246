#include "limber/kernel/featherstone/step.hpp"

#include <algorithm>
#include <cmath>

#include "limber/kernel/collision/rigid_contacts.hpp"
#include "limber/kernel/featherstone/joint_space_contacts.hpp"
#include "limber/kernel/model/guarded_step.hpp"

namespace limber {
namespace {

// Settings::drag (thesis 2.1.5, 2.1.6; in the limb's own frame, z its axis) at the step's start,
// and the applied loads (RigidScene::applied_force, applied_torque), as joint forces
// τ = Σ J_iᵀ f_i (held over the step, so RK4 is first order in the drag), on the bodies of `bodies`.
void body_load_joint_forces(FeatherstoneState& state, bool drag_on, BodyRange bodies) {
  const DragSettings& drag = state.settings.drag;
  const RigidBodyState& y = state.bodies.state;
  for (int i = bodies.first; i < bodies.last; ++i) {
    const auto index = static_cast<std::size_t>(i);
    const std::int32_t b = state.scene_body[index];
    if (b < 0) {  // a serial joint's massless frame: no load
      state.drag_force[index].setZero();
      continue;
    }
    Eigen::Vector3d force = state.applied_force[b], torque = state.applied_torque[b];
    if (drag_on) {
      const Eigen::Matrix3d rotation = (y.orientation[b] * state.shapes.principal_frame[b].conjugate()).toRotationMatrix();
      force -= rotation * drag.linear.cwiseProduct(rotation.transpose() * state.bodies.linear_velocity(y, b));
      torque -= rotation * drag.angular.cwiseProduct(rotation.transpose() * state.bodies.angular_velocity(y, b));
    }
    // (τ + (x − r) × F, F) about the body's origin r, in its coordinates.
    const PluckerTransform& world_to_body = state.kinematics.world_to_body[index];
    state.drag_force[index].head<3>() = world_to_body.rotation * (torque + (y.position[b] - world_to_body.translation).cross(force));
    state.drag_force[index].tail<3>() = world_to_body.rotation * force;
  }
  joint_forces_of_body_forces(state, state.drag_force, state.joint_forces, bodies);
}

// How many substeps keep every body's turn under kLargestTurn a substep: the explicit
// integrators follow a body-frame vector turning at Ω only while hΩ is small (RK4: stable below
// 2.8, dissipating (hΩ)⁶/144 of it per step), and friction at a thin limb's rim can spin it about
// its axis at v/r — hundreds of rad/s. Ω is the island's fastest body's or joint's angular speed
// at the step's start; at most kMostSubsteps.
constexpr double kLargestTurn = 0.5;  // rad
constexpr int kMostSubsteps = 32;
int turn_substeps(const FeatherstoneState& state, double dt, BodyRange bodies) {
  double fastest = 0;
  for (int i = bodies.first; i < bodies.last; ++i) {
    fastest = std::max(fastest, state.kinematics.velocity[static_cast<std::size_t>(i)].head<3>().norm());
    const ArticulatedJoint joint = state.tree.body(i).joint;
    if (joint == ArticulatedJoint::spherical || joint == ArticulatedJoint::floating) {
      fastest = std::max(fastest, state.v.segment<3>(state.tree.velocity_offset(i)).norm());
    }
  }
  if (!(fastest * dt > kLargestTurn)) return 1;  // also when not finite: update_sleep reports it
  return static_cast<int>(std::min(std::ceil(fastest * dt / kLargestTurn), double(kMostSubsteps)));
}

// Integrates awake island k (step.hpp, 1–3): its loads, substeps, drives and friction, integrator,
// damping, and its rigid bodies refreshed. When the step solves its constraints before the move
// (constraints_before_move), its last substep is the velocity update alone, and the positions and
// the rigid bodies wait for the constraints (advance_positions). Touches only its bodies' and
// coordinates' entries.
void integrate_island(FeatherstoneState& state, std::size_t k, double dt, bool loads) {
  const bool before_move = constraints_before_move(state);
  const BodyRange bodies = island_bodies(state, k);
  const auto [first, last] = island_velocities(state, k);
  const auto on_island = [first = first, count = last - first](Eigen::VectorXd& x) { return x.segment(first, count); };
  const bool drag = !state.settings.drag.linear.isZero(0) || !state.settings.drag.angular.isZero(0);
  if (drag || loads) body_load_joint_forces(state, drag, bodies);
  if (!on_island(state.actuation).isZero(0)) on_island(state.joint_forces) += on_island(state.actuation);  // zeroed at the last step's end
  // An island a contact touches has its velocity update through H's factor, which the constraints
  // then take (factored_forward_dynamics); joint friction keeps its own factors.
  const bool through_factor = before_move && state.contact.touched[k] && !state.joint_friction;
  const int substeps = turn_substeps(state, dt, bodies);
  const double h = dt / substeps;
  state.last_substep[k] = h;
  for (int s = 0; s < substeps; ++s) {
    const bool velocity_only = before_move && s == substeps - 1;
    // Drives and joint friction, as forces held over the substep (joint_space_contacts.hpp), and
    // the integrator's first pass, at the poses and velocities of (q, v): state.kinematics' at the
    // step's start, found again after a substep (the bias forces through the factor read them).
    if (s > 0) forward_kinematics(state.tree, state.q, state.v, state.kinematics, bodies);
    const bool controlled = joint_control_forces(state, state.joint_forces, h, k, velocity_only && through_factor);
    if (controlled && state.options.integrator == Integrator::semi_implicit_euler && state.controls.friction.empty()) {
      // The stable PD's dynamics already are this step's: (H + h·G) v̇ = τ − C + F − G·v gives
      // v⁺ = v + h·v̇ with H v̇ = τ − C + F − G·v⁺, the velocity semi-implicit Euler ends with
      // under the forces held: the integrator's own ABA would find the same v̇ again. (Friction's
      // held joints are within its penalty's 1/kPenalty in the predicted velocity; the integrator
      // takes them exactly.)
      on_island(state.v) = on_island(state.controls.predicted);
      if (!velocity_only) semi_implicit_move(state.tree, state.q, state.v, h, state.integration.stage_displacement, bodies);
      continue;
    }
    const Eigen::VectorXd& forces = controlled ? state.controls.forces : state.joint_forces;
    if (velocity_only && through_factor) {
      factored_forward_dynamics(state, k, forces, nullptr, state.integration.accelerations);
      semi_implicit_velocity(state.tree, state.v, state.integration.accelerations, h, bodies);
    } else if (velocity_only) {
      accelerate(state.tree, state.q, state.v, forces, state.settings.gravity, h, state.integration, &state.kinematics, bodies);
    } else {
      integrate(state.tree, state.q, state.v, forces, state.settings.gravity, h, state.options.integrator, state.integration,
                &state.kinematics, bodies);
    }
  }
  if (state.settings.damping > 0) on_island(state.v) *= std::exp(-state.settings.damping * dt);
  if (before_move) return;  // state.kinematics keeps the poses of q, which the constraints' rows are taken at
  forward_kinematics(state.tree, state.q, state.v, state.kinematics, bodies);
  mirror_rigid_bodies(state, bodies);
}

// The constraints before the move: detection at the step's start, the velocity update, the
// constraints on it, then the positions (step.hpp).
void step_constraints_before_move(FeatherstoneState& state, double dt, StepReport& report, StageClock& clock) {
  state.speculative_time = dt;  // gaps the step may close are contacts too
  if (detect_rigid_contacts(state, state.runner.get())) take_moved_balls(state);  // sweeps the balls' paths of the last step
  remember_step_start(state);
  report.profile.detect = clock.lap();
  integrate_awake_islands(state, dt);
  report.profile.integrate = clock.lap();
  resolve_joint_space_contacts(state, dt);
  run_stage(state.runner.get(), state.awake_islands.size(),
            [&](std::size_t n) { advance_positions(state, static_cast<std::size_t>(state.awake_islands[n])); });
}

// The thesis's loop (figure 2.5): move, then collide — with speculative contacts for the next move.
void step_constraints_after_move(FeatherstoneState& state, double dt, StepReport& report, StageClock& clock) {
  remember_step_start(state);
  integrate_awake_islands(state, dt);
  report.profile.integrate = clock.lap();
  // Speculative contacts (Catto's) for the next move: the gaps it may close are contacts too, so
  // a limb falling onto another is held before it sinks a step's travel into it (the ragdoll's
  // side landing: 9.8–12.3 mm of overlap without them, 0.6–4.2 mm with).
  state.speculative_time = dt;
  if (detect_rigid_contacts(state, state.runner.get())) take_moved_balls(state);
  report.profile.detect = clock.lap();
  resolve_joint_space_contacts(state, dt);
}

// The servos act for one step: the World sets them again before the next (apply_actuator).
void clear_servos(ServoTerms& servos) {
  if (std::find(servos.island.begin(), servos.island.end(), 1) == servos.island.end()) return;
  servos.force.setZero(), servos.stiffness.setZero(), servos.damping.setZero();
  std::fill(servos.island.begin(), servos.island.end(), 0);
}

}  // namespace

void integrate_awake_islands(FeatherstoneState& state, double dt) {
  state.awake_islands.clear();
  for (std::size_t k = 0; k < state.islands.size(); ++k) {
    if (!state.islands[k].sleeping) state.awake_islands.push_back(static_cast<std::int32_t>(k));
  }
  JointSpaceContactScratch& s = state.contact;
  std::fill(s.touched.begin(), s.touched.end(), 0), std::fill(s.factored.begin(), s.factored.end(), 0);
  if (constraints_before_move(state)) {
    state.controls.armature.setZero();  // h·G, which the constraints add to H: the drives' islands set theirs
    for (const RigidContact& contact : state.contacts) {
      s.touched[state.island_of_body[contact.a]] = 1;
      if (contact.b >= 0) s.touched[state.island_of_body[contact.b]] = 1;
    }
    // A large tree's first step with a contact sizes the factor here, not in the islands' tasks.
    if (!state.contacts.empty() && s.factor.size() != state.tree.velocity_count()) s.factor.assign(state.tree);
  }
  bool loads = false;
  for (std::size_t b = 0; b < state.applied_force.size(); ++b) loads = loads || !state.applied_force[b].isZero(0) || !state.applied_torque[b].isZero(0);
  run_stage(state.joint_friction ? nullptr : state.runner.get(), state.awake_islands.size(),
            [&](std::size_t n) { integrate_island(state, static_cast<std::size_t>(state.awake_islands[n]), dt, loads); });
}

void rest_sleeping_islands(FeatherstoneState& state) {
  zero_sleeping_velocities(state);
  for (std::size_t k = 0; k < state.islands.size(); ++k) {
    if (!state.islands[k].sleeping) continue;
    for (int i = state.island_begin[k]; i < state.island_begin[k + 1]; ++i) {
      state.kinematics.velocity[static_cast<std::size_t>(i)].setZero();
      state.kinematics.bias_acceleration[static_cast<std::size_t>(i)].setZero();  // v_i × S_i q̇_i
    }
  }
}

void refresh_rigid_bodies(FeatherstoneState& state) {
  forward_kinematics(state.tree, state.q, state.v, state.kinematics);
  mirror_rigid_bodies(state);
}

void mirror_rigid_bodies(FeatherstoneState& state) { mirror_rigid_bodies(state, state.tree.all_bodies()); }

void mirror_rigid_bodies(FeatherstoneState& state, BodyRange range) {
  RigidBodyState& y = state.bodies.state;
  for (int i = range.first; i < range.last; ++i) {
    const auto index = static_cast<std::size_t>(i);
    const std::int32_t b = state.scene_body[index];
    if (b < 0) continue;  // a serial joint's frame
    const PluckerTransform& world_to_body = state.kinematics.world_to_body[index];
    const Eigen::Matrix3d rotation = world_to_body.rotation.transpose();  // body → world
    const Eigen::Vector3d& centre = state.centre_of_mass[index];
    // Unit to round-off without normalizing: the rotation is composed afresh from q every step
    // (forward kinematics), so no error accumulates (the normalization was half the read-out).
    y.orientation[b] = Eigen::Quaterniond(rotation) * state.principal_frame[index];
    y.position[b] = world_to_body.translation + rotation * centre;
    // v_i = (ω, v_O) in the body's frame: the centre of mass moves at v_O + ω × c. The world
    // velocities are kept for the sleep and speed guard (update_sleep_from_velocities).
    const SpatialVector& velocity = state.kinematics.velocity[index];
    state.velocity[b] = rotation * (velocity.tail<3>() + velocity.head<3>().cross(centre));
    state.angular_velocity[b] = rotation * velocity.head<3>();
    y.linear_momentum[b] = state.bodies.mass[b] * state.velocity[b];
    y.angular_momentum[b] = rotation * (state.centre_inertia[index] * velocity.head<3>());  // R I Rᵀ ω in the tree body's axes
  }
}

void take_moved_balls(FeatherstoneState& state) {
  const RigidBodyState& y = state.bodies.state;
  for (std::size_t b = 0; b < state.bodies.size(); ++b) {
    if (!state.shapes.is_ball[b]) continue;
    const std::int32_t i = state.tree_body[b];
    const Eigen::Matrix3d rotation = state.kinematics.world_to_body[static_cast<std::size_t>(i)].rotation.transpose();
    state.q.segment<3>(state.tree.position_offset(i)) = y.position[b] - rotation * state.centre_of_mass[static_cast<std::size_t>(i)];
  }
  refresh_rigid_bodies(state);
}

StepReport step(FeatherstoneState& state, double dt) {
  return guarded_step(state, dt, [&](StepReport& report) {
    StageClock clock(state.options.profile);
    const AwakeHelpers awake(state.runner.get());
    if (constraints_before_move(state)) {
      step_constraints_before_move(state, dt, report, clock);
    } else {
      step_constraints_after_move(state, dt, report, clock);
    }
    report.contacts = static_cast<int>(state.contacts.size());
    state.time += dt;
    report.status = update_sleep_from_velocities(state, dt);  // the mirror's velocities
    if (state.joint_forces.size() > 0 && !state.joint_forces.isZero(0)) state.joint_forces.setZero();  // loads held this step only
    clear_applied_loads(state);
    state.actuation.setZero();
    clear_servos(state.servos);
    rest_sleeping_islands(state);
    if (state.options.profile) count_rigid_step(state, report);
  });
}

}  // namespace limber
