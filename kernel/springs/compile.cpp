// GCC 12 false positive inside Eigen's AVX-512 code (bug 105593); must precede Eigen's headers.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "limber/kernel/springs/compile.hpp"

#include <cmath>

#include "limber/kernel/springs/implicit_step.hpp"

namespace limber {

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
  require_joint_types(model, {JointType::spherical}, /*gears_supported=*/false, "stiff-spring");
  require_joint_controls(model, {.limits = true, .friction = true, .drives = true}, "stiff-spring");
  state.options = options;
  state.joint_controls = joint_controls(model);
  for (std::size_t k = 0; k < model.joints.size(); ++k) {
    if (has_joint_controls(model.joints[k])) state.controlled_joints.push_back(static_cast<std::uint32_t>(k));
  }
  state.time_step = model.settings.time_step;

  // Springs, one per joint, anchors relative to the centres of mass.
  SpringBuffer& springs = state.springs;
  static_cast<JointAnchors&>(springs) = joint_anchors(state, model);
  for (const Joint& joint : model.joints) {
    springs.stiffness.push_back(options.stiffness.value_or(joint.stiffness.value_or(options.defaults.stiffness)));
    springs.damping.push_back(options.damping.value_or(joint.damping.value_or(options.defaults.damping)));
  }

  const std::size_t body_count = state.bodies.size();
  state.scratch.resize(body_count);
  state.scratch_world_inertia.assign(body_count, Eigen::Matrix3d::Zero());
  if (options.integrator == Integrator::backward_euler) prepare_implicit_system(state);
  return state;
}

}  // namespace limber
