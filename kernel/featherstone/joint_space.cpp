#include "limber/kernel/featherstone/joint_space.hpp"

#include <algorithm>
#include <cmath>

#include "limber/kernel/featherstone/dynamics.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/rigid/bodies.hpp"

namespace limber {
namespace {

// Adds a position, a velocity, or both (a 1-DOF coordinate: an angle or a slide and its rate),
// named `name`.
void add(JointSpaceLayout& layout, int position, int velocity, double sign, const std::string& name) {
  if (position >= 0) layout.position.push_back(position), layout.position_sign.push_back(sign), layout.position_names.push_back(name);
  if (velocity < 0) return;
  layout.velocity.push_back(velocity), layout.velocity_sign.push_back(sign), layout.names.push_back(name);
  layout.angle_or_slide.push_back(position >= 0 ? static_cast<int>(layout.position.size()) - 1 : -1);
}

// A floating tree body's 7 positions and 6 velocities, as the tree holds them.
void add_floating(JointSpaceLayout& layout, const ArticulatedTree& tree, int i, const std::string& name) {
  const int p = tree.position_offset(i), v = tree.velocity_offset(i);
  static constexpr const char* kPositions[] = {".x", ".y", ".z", ".qw", ".qx", ".qy", ".qz"};
  for (int k = 0; k < 7; ++k) add(layout, p + k, -1, 1, name + kPositions[k]);
  static constexpr const char* kVelocities[] = {".wx", ".wy", ".wz", ".vx", ".vy", ".vz"};
  for (int k = 0; k < 6; ++k) add(layout, -1, v + k, 1, name + kVelocities[k]);
}

// Joint j's coordinates, as the tree holds them.
void add_joint(JointSpaceLayout& layout, const FeatherstoneState& state, const Joint& joint, std::size_t j) {
  const TreeJoint& held = state.tree_joint[j];
  const ArticulatedTree& tree = state.tree;
  layout.joint_velocity[j] = held.dofs > 0 ? static_cast<int>(layout.velocity.size()) : -1;
  switch (joint.type) {
    case JointType::fixed: return;
    case JointType::revolute:
    case JointType::prismatic: add(layout, tree.position_offset(held.body), held.offset, held.sign, joint.name); return;
    case JointType::spherical: {
      if (held.sign < 0) {
        throw ModelError("joints[" + std::to_string(j) + "] '" + joint.name +
                         "': the tree holds this spherical joint the other way round, so its coordinates are not the Model's; "
                         "joint space is not available (list the island's root side as inboard)");
      }
      const int p = tree.position_offset(held.body);
      static constexpr const char* kQuaternion[] = {".qw", ".qx", ".qy", ".qz"};
      for (int k = 0; k < 4; ++k) add(layout, p + k, -1, 1, joint.name + kQuaternion[k]);
      for (int k = 0; k < 3; ++k) add(layout, -1, held.offset + k, 1, joint.name + (k == 0 ? ".wx" : k == 1 ? ".wy" : ".wz"));
      return;
    }
    case JointType::serial: {
      const auto count = static_cast<int>(joint.serial_axes.size());
      for (int a = 0; a < count; ++a) {
        add(layout, tree.position_offset(held.axis_body(a)), held.offset + a, 1, joint.serial_axes[static_cast<std::size_t>(a)].name);
      }
      return;
    }
    case JointType::universal: break;  // refused by the compile
  }
}

Eigen::VectorXd to_tree(const JointSpaceLayout& layout, const Eigen::VectorXd& in, int size) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(size);
  for (std::size_t r = 0; r < layout.velocity.size(); ++r) out[layout.velocity[r]] = layout.velocity_sign[r] * in[static_cast<Eigen::Index>(r)];
  return out;
}

Eigen::VectorXd from_tree(const JointSpaceLayout& layout, const Eigen::VectorXd& in) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(layout.velocity.size()));
  for (std::size_t r = 0; r < layout.velocity.size(); ++r) out[static_cast<Eigen::Index>(r)] = layout.velocity_sign[r] * in[layout.velocity[r]];
  return out;
}

void require_size(const Eigen::VectorXd& v, std::size_t size, const char* what) {
  if (static_cast<std::size_t>(v.size()) != size) {
    throw std::invalid_argument(std::string(what) + ": expected " + std::to_string(size) + " values, got " + std::to_string(v.size()));
  }
}

}  // namespace

JointSpaceLayout joint_space_layout(const FeatherstoneState& state, const Model& model) {
  JointSpaceLayout layout;
  layout.joint_velocity.assign(model.joints.size(), -1);
  std::vector<std::vector<std::size_t>> joints_of(state.bodies.size());
  for (std::size_t j = 0; j < model.joints.size(); ++j) joints_of[static_cast<std::size_t>(model.joints[j].outboard)].push_back(j);
  for (std::size_t b = 0; b < state.bodies.size(); ++b) {
    const int i = state.tree_body[b];
    const std::string name = b < model.bodies.size() ? model.bodies[b].name : ball_name(model, b - model.bodies.size());
    if (state.tree.body(i).joint == ArticulatedJoint::floating) add_floating(layout, state.tree, i, name);
    for (std::size_t j : joints_of[b]) add_joint(layout, state, model.joints[j], j);
  }
  return layout;
}

Eigen::VectorXd joint_positions(const FeatherstoneState& state, const JointSpaceLayout& layout) {
  Eigen::VectorXd q(static_cast<Eigen::Index>(layout.position.size()));
  for (std::size_t r = 0; r < layout.position.size(); ++r) q[static_cast<Eigen::Index>(r)] = layout.position_sign[r] * state.q[layout.position[r]];
  return q;
}

Eigen::VectorXd joint_velocities(const FeatherstoneState& state, const JointSpaceLayout& layout) { return from_tree(layout, state.v); }

void set_joint_state(FeatherstoneState& state, const JointSpaceLayout& layout, const Eigen::VectorXd& q, const Eigen::VectorXd& v) {
  require_size(q, layout.position.size(), "joint positions");
  require_size(v, layout.velocity.size(), "joint velocities");
  for (std::size_t r = 0; r < layout.position.size(); ++r) state.q[layout.position[r]] = layout.position_sign[r] * q[static_cast<Eigen::Index>(r)];
  state.v = to_tree(layout, v, state.tree.velocity_count());
  for (int i = 0; i < state.tree.body_count(); ++i) {  // unit quaternions
    const ArticulatedJoint type = state.tree.body(i).joint;
    if (type != ArticulatedJoint::spherical && type != ArticulatedJoint::floating) continue;
    const int p = state.tree.position_offset(i) + (type == ArticulatedJoint::floating ? 3 : 0);
    state.q.segment<4>(p).normalize();
  }
  refresh_rigid_bodies(state);
}

Eigen::MatrixXd joint_mass_matrix(const FeatherstoneState& state, const JointSpaceLayout& layout) {
  DynamicsWorkspace workspace;
  Eigen::MatrixXd tree_matrix;
  mass_matrix(state.tree, state.q, workspace, tree_matrix);
  const auto n = static_cast<Eigen::Index>(layout.velocity.size());
  Eigen::MatrixXd out(n, n);
  for (Eigen::Index r = 0; r < n; ++r) {
    for (Eigen::Index c = 0; c < n; ++c) {
      out(r, c) = layout.velocity_sign[static_cast<std::size_t>(r)] * layout.velocity_sign[static_cast<std::size_t>(c)] *
                  tree_matrix(layout.velocity[static_cast<std::size_t>(r)], layout.velocity[static_cast<std::size_t>(c)]);
    }
  }
  return out;
}

Eigen::VectorXd joint_bias_forces(const FeatherstoneState& state, const JointSpaceLayout& layout) {
  return inverse_joint_dynamics(state, layout, Eigen::VectorXd::Zero(static_cast<Eigen::Index>(layout.velocity.size())));
}

Eigen::VectorXd forward_joint_dynamics(const FeatherstoneState& state, const JointSpaceLayout& layout, const Eigen::VectorXd& forces) {
  require_size(forces, layout.velocity.size(), "joint forces");
  DynamicsWorkspace workspace;
  Eigen::VectorXd accelerations;
  forward_dynamics(state.tree, state.q, state.v, to_tree(layout, forces, state.tree.velocity_count()), state.settings.gravity, workspace,
                   accelerations);
  return from_tree(layout, accelerations);
}

Eigen::VectorXd inverse_joint_dynamics(const FeatherstoneState& state, const JointSpaceLayout& layout, const Eigen::VectorXd& accelerations) {
  require_size(accelerations, layout.velocity.size(), "joint accelerations");
  DynamicsWorkspace workspace;
  Eigen::VectorXd forces;
  inverse_dynamics(state.tree, state.q, state.v, to_tree(layout, accelerations, state.tree.velocity_count()), state.settings.gravity,
                   workspace, forces);
  return from_tree(layout, forces);
}

std::vector<JointReaction> joint_reactions(const FeatherstoneState& state, const Model& model, const JointSpaceLayout& layout,
                                           const Eigen::VectorXd& accelerations) {
  require_size(accelerations, layout.velocity.size(), "joint accelerations");
  DynamicsWorkspace workspace;
  Eigen::VectorXd forces;
  body_poses(state.tree, state.q, workspace);  // ⁱX_0, which the inverse dynamics leaves as it is
  inverse_dynamics(state.tree, state.q, state.v, to_tree(layout, accelerations, state.tree.velocity_count()), state.settings.gravity,
                   workspace, forces);
  std::vector<JointReaction> reactions(model.joints.size());
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const TreeJoint& held = state.tree_joint[j];
    const auto node = static_cast<std::size_t>(held.body);  // a serial joint's last axis: the outboard's own body
    // f_i on the tree's child from its parent, about the world origin; the Model's outboard
    // takes −f_i where the tree turned the joint round (its child is the Model's inboard).
    const SpatialVector world = held.sign * workspace.world_to_body[node].transpose_apply_force(workspace.bias_force[node]);
    const Joint& joint = model.joints[j];
    const Eigen::Vector3d anchor = body_point(state, static_cast<std::size_t>(joint.outboard), joint.outboard_anchor);
    reactions[j].force = world.tail<3>();
    reactions[j].torque = world.head<3>() - anchor.cross(reactions[j].force);
  }
  return reactions;
}

Eigen::VectorXd joint_passive_forces(const FeatherstoneState& state, const Model& model, const JointSpaceLayout& layout,
                                     const std::vector<double>& controls) {
  const Eigen::VectorXd q = joint_positions(state, layout), v = joint_velocities(state, layout);
  Eigen::VectorXd out = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(layout.velocity.size()));
  // A 1-DOF coordinate's spring and damper (velocity r, position angle_or_slide[r]).
  const auto spring = [&](const std::optional<JointDrive>& drive, int r, bool angle) {
    if (!drive || r < 0) return;
    double error = drive->target - q[layout.angle_or_slide[static_cast<std::size_t>(r)]];
    if (angle) error = shorter_way_round(error);  // as the step
    out[r] += drive->stiffness * error + drive->damping * (drive->target_velocity - v[r]);
  };
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    const int r = layout.joint_velocity[j];
    if (joint.type == JointType::revolute || joint.type == JointType::prismatic) spring(joint.drive, r, joint.type == JointType::revolute);
    for (std::size_t a = 0; a < joint.serial_axes.size(); ++a) {
      spring(joint.serial_axes[a].drive, r + static_cast<int>(a), !joint.serial_axes[a].slide);
    }
  }
  for (std::size_t a = 0; a < model.actuators.size() && a < controls.size(); ++a) {
    const Actuator& actuator = model.actuators[a];
    const int r = layout.joint_velocity[static_cast<std::size_t>(actuator.joint)] + actuator.axis;
    out[r] += actuator_force(actuator, controls[a], q[layout.angle_or_slide[static_cast<std::size_t>(r)]], v[r]);
  }
  return out;
}

}  // namespace limber
