#include "limber/kernel/springs/compile.hpp"

#include <algorithm>
#include <cmath>

#include "limber/kernel/model/capabilities.hpp"
#include "limber/kernel/springs/implicit_step.hpp"

namespace limber {
namespace {

// A revolute joint's two springs sit at anchor ± ε·h, ε this fraction of the shorter limb's
// length (compile.hpp says why).
constexpr double kHingeSpacing = 0.25;

// A world direction at the Model's poses in body b's rigid (principal) frame.
Eigen::Vector3d body_direction(const RigidScene& scene, const Model& model, std::size_t b, const Eigen::Vector3d& world) {
  return scene.shapes.principal_frame[b].conjugate() * (model.bodies[b].orientation().conjugate() * world);
}

}  // namespace

SpringState compile_springs(const Model& model, const SpringOptions& options) {
  if (options.stiffness && !(*options.stiffness > 0 && std::isfinite(*options.stiffness))) {
    throw ModelError("stiffness: must be a finite number > 0");
  }
  if (options.damping && !(*options.damping >= 0 && std::isfinite(*options.damping))) {
    throw ModelError("damping: must be a finite number >= 0");
  }
  validate(options.defaults);
  SpringState state;
  static_cast<RigidScene&>(state) = compile_rigid_scene(model);
  require_supported(model, Method::springs);
  require_joint_controls(model, {.limits = true, .friction = true, .drives = true}, "stiff-spring");
  state.options = options;
  state.joint_controls = joint_controls(model);
  for (std::size_t k = 0; k < model.joints.size(); ++k) {
    if (has_joint_controls(model.joints[k])) state.controlled_joints.push_back(static_cast<std::uint32_t>(k));
  }
  state.time_step = model.settings.time_step;

  // Springs: one at a spherical joint's anchors, relative to the centres of mass; a revolute
  // joint's two at anchor ± ε·h.
  SpringBuffer& springs = state.springs;
  static_cast<JointAnchors&>(springs) = joint_anchors(state, model);
  for (const Joint& joint : model.joints) {
    springs.stiffness.push_back(options.stiffness.value_or(joint.stiffness.value_or(options.defaults.stiffness)));
    springs.damping.push_back(options.damping.value_or(joint.damping.value_or(options.defaults.damping)));
    const auto outboard = static_cast<std::size_t>(joint.outboard);
    if (joint.type != JointType::revolute) {
      springs.inboard_offset.emplace_back(Eigen::Vector3d::Zero());
      springs.outboard_offset.emplace_back(Eigen::Vector3d::Zero());
      springs.count.push_back(1);
      continue;
    }
    double shorter = model.bodies[outboard].shape.length;
    if (joint.inboard != kWorld) shorter = std::min(shorter, model.bodies[static_cast<std::size_t>(joint.inboard)].shape.length);
    const Eigen::Vector3d offset = kHingeSpacing * shorter * joint.axis.normalized();
    springs.inboard_offset.push_back(joint.inboard == kWorld ? offset
                                                             : body_direction(state, model, static_cast<std::size_t>(joint.inboard), offset));
    springs.outboard_offset.push_back(body_direction(state, model, outboard, offset));
    springs.count.push_back(2);
  }

  const std::size_t body_count = state.bodies.size();
  state.scratch.resize(body_count);
  state.scratch_world_inertia.assign(body_count, Eigen::Matrix3d::Zero());
  if (options.integrator == Integrator::backward_euler) prepare_implicit_system(state);
  if (!model.actuators.empty()) state.coordinate_axes = CoordinateAxes::of(model);
  return state;
}

}  // namespace limber
