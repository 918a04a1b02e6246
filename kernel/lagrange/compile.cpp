#include "limber/kernel/lagrange/compile.hpp"

#include <optional>

#include "limber/kernel/lagrange/contacts.hpp"
#include "limber/kernel/lagrange/multipliers.hpp"
#include "limber/kernel/model/capabilities.hpp"
#include "limber/kernel/scene/serial_links.hpp"

namespace limber {

LagrangeState compile_lagrange(const Model& input, const LagrangeOptions& options) {
  // Serial joints run as revolute and prismatic joints through virtual links (serial_links.hpp),
  // each axis's armature on its joint (a compliant row: joint_controls.hpp).
  require_supported(input, Method::lagrange);
  std::optional<SerialExpansion> expansion;
  if (needs_serial_expansion(input, Armature::on_joint)) validate(input), expansion = expand_serial_joints(input, Armature::on_joint);
  const Model& model = expansion ? expansion->model : input;
  LagrangeState state;
  static_cast<RigidScene&>(state) = compile_rigid_scene(model);
  if (expansion) require_supported(model, Method::lagrange);  // compile_rigid_scene validated it
  if (!input.actuators.empty()) state.coordinate_axes = expansion ? CoordinateAxes::of(*expansion) : CoordinateAxes::of(model);
  require_joint_controls(model, {.limits = true, .friction = true, .drives = true, .armature = true}, "lagrange");
  require_integrator(options.integrator, {Integrator::euler, Integrator::semi_implicit_euler, Integrator::rk2, Integrator::rk4}, "lagrange");
  state.options = options;
  state.time_step = model.settings.time_step;
  state.joints = joint_anchors(state, model);
  // A joint a servo acts on gets a control row, which takes the servo as a drive.
  std::vector<char> servo_joints(model.joints.size(), 0);
  for (const Actuator& actuator : input.actuators) {
    if (actuator.kind != ActuatorKind::motor) servo_joints[joint_of_axis(state.coordinate_axes.first_added_joint, static_cast<std::size_t>(actuator.joint), actuator.axis)] = 1;
  }
  for (std::vector<double>* terms : {&state.servos.force, &state.servos.stiffness, &state.servos.damping}) terms->assign(model.joints.size(), 0.0);
  state.constraints = compile_constraints(state, model, servo_joints);
  const ConstraintSet& constraints = state.constraints;
  state.joint_controls = joint_controls(model);
  state.controls = compile_joint_controls(state, model, constraints);
  prepare_multiplier_solver(state, model);
  const std::size_t body_count = state.bodies.size();
  state.scratch.resize(body_count);
  state.body_rhs.assign(body_count, Eigen::Matrix<double, 6, 1>::Zero());
  state.accelerations.assign(body_count, Eigen::Matrix<double, 6, 1>::Zero());
  state.constraint_rhs = state.multipliers;  // zeros, each its constraint's rows
  state.projection_multipliers = state.multipliers;
  state.compliance = state.multipliers;
  state.control_body_rhs = state.body_rhs;
  state.stage_change = state.body_rhs;
  state.geometry.resize(constraints);
  state.world_inertia.assign(body_count, Eigen::Matrix3d::Zero());
  prepare_contacts_with_joints(state);
  return state;
}

}  // namespace limber
