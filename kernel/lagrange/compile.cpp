#include "kernel/lagrange/compile.hpp"

#include "kernel/lagrange/multipliers.hpp"

namespace limber {

LagrangeState compile_lagrange(const Model& model, const LagrangeOptions& options) {
  LagrangeState state;
  static_cast<RigidScene&>(state) = compile_rigid_scene(model);
  state.options = options;
  state.time_step = model.settings.time_step;
  JointBuffer& joints = state.joints;
  for (const Joint& joint : model.joints) {
    joints.inboard.push_back(joint.inboard);
    joints.outboard.push_back(joint.outboard);
    joints.outboard_anchor.push_back(body_anchor(state, joint.outboard, joint.outboard_anchor));
    double reference = model.bodies[joint.outboard].shape.length;
    if (joint.inboard == kWorld) {
      joints.inboard_anchor.push_back(joint.inboard_anchor);
    } else {
      joints.inboard_anchor.push_back(body_anchor(state, joint.inboard, joint.inboard_anchor));
      reference = 0.5 * (reference + model.bodies[joint.inboard].shape.length);
    }
    joints.reference_length.push_back(reference);
  }
  prepare_multiplier_solver(state, model);
  const std::size_t body_count = state.bodies.size();
  state.scratch.resize(body_count);
  state.body_rhs.assign(body_count, Eigen::Matrix<double, 6, 1>::Zero());
  state.accelerations.assign(body_count, Eigen::Matrix<double, 6, 1>::Zero());
  state.joint_rhs.assign(joints.size(), Eigen::Vector3d::Zero());
  state.projection_multipliers.assign(joints.size(), Eigen::Vector3d::Zero());
  state.inboard_lever.assign(joints.size(), Eigen::Vector3d::Zero());
  state.outboard_lever.assign(joints.size(), Eigen::Vector3d::Zero());
  state.world_inertia.assign(body_count, Eigen::Matrix3d::Zero());
  return state;
}

}  // namespace limber
