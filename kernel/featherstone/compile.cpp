#include "limber/kernel/featherstone/compile.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/model/capabilities.hpp"
#include "limber/kernel/numerics/tree_elimination.hpp"

namespace limber {
namespace {

ArticulatedJoint articulated_joint(JointType type) {
  switch (type) {
    case JointType::revolute: return ArticulatedJoint::revolute;
    case JointType::prismatic: return ArticulatedJoint::prismatic;
    case JointType::fixed: return ArticulatedJoint::fixed;
    case JointType::spherical:
    case JointType::universal:  // refused before
    case JointType::serial: break;  // a chain of tree bodies (push_joint)
  }
  return ArticulatedJoint::spherical;
}

// Refuses a joint that closes a loop (order_tree's loop constraints: between bodies already
// joined, or a second joint to the world in one island), naming the first in joint order.
void refuse_kinematic_loops(const Model& model) {
  std::vector<std::int32_t> inboard, outboard;
  inboard.reserve(model.joints.size()), outboard.reserve(model.joints.size());
  for (const Joint& joint : model.joints) inboard.push_back(joint.inboard), outboard.push_back(joint.outboard);
  const std::vector<std::uint32_t> loops = order_tree(model.bodies.size(), inboard, outboard).loop_constraints;
  if (loops.empty()) return;
  const std::uint32_t j = *std::min_element(loops.begin(), loops.end());
  throw ModelError("joints[" + std::to_string(j) + "] '" + model.joints[j].name +
                   "': closes a kinematic loop, which reduced coordinates cannot express; use --method lagrange");
}

// A tree body before it is built: its rigid-scene body (−1: a serial joint's massless frame), its
// parent (tree index, −1: the world), the Model joint to it (−1: a floating root) and, for a
// serial joint, which of its axes (featherstone_state.hpp, "Serial joints").
struct TreeNode {
  std::int32_t body = 0, parent = -1, joint = -1, axis = -1;
};

// Joint j's tree bodies below tree body `parent` (−1: the world) down to Model body `child`: one,
// or a serial joint's chain, a massless frame per axis but the last, which is the child's.
void push_joint(std::vector<TreeNode>& nodes, const Model& model, std::int32_t child, std::int32_t parent, std::int32_t j) {
  const Joint& joint = model.joints[static_cast<std::size_t>(j)];
  if (joint.type != JointType::serial) {
    nodes.push_back({child, parent, j});
    return;
  }
  if (joint.outboard != child) {
    throw ModelError("joints[" + std::to_string(j) + "] '" + joint.name +
                     "': a serial joint's axes run from its inboard body, but the tree reaches it from its outboard body; "
                     "list the island's root side as inboard");
  }
  const auto count = static_cast<std::int32_t>(joint.serial_axes.size());
  for (std::int32_t a = 0; a < count; ++a) {
    nodes.push_back({a + 1 == count ? child : -1, parent, j, a});
    parent = static_cast<std::int32_t>(nodes.size()) - 1;
  }
}

// The tree order: island by island, breadth first from each island's root.
std::vector<TreeNode> tree_order(const FeatherstoneState& state, const Model& model, std::vector<std::int32_t>& island_begin) {
  const std::size_t limb_count = model.bodies.size();
  std::vector<std::vector<std::int32_t>> incident(limb_count);  // joints between two bodies, per body, in joint order
  std::vector<std::int32_t> world_joint(limb_count, -1);
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    if (joint.inboard == kWorld) {
      world_joint[joint.outboard] = static_cast<std::int32_t>(j);  // at most one per island (no loops)
    } else {
      incident[joint.inboard].push_back(static_cast<std::int32_t>(j));
      incident[joint.outboard].push_back(static_cast<std::int32_t>(j));
    }
  }
  std::vector<TreeNode> nodes;
  nodes.reserve(state.bodies.size());
  for (const RigidIsland& island : state.islands) {
    island_begin.push_back(static_cast<std::int32_t>(nodes.size()));
    TreeNode root{static_cast<std::int32_t>(island.bodies.front()), -1, -1};
    for (std::uint32_t b : island.bodies) {
      if (b < limb_count && world_joint[b] >= 0) root = {static_cast<std::int32_t>(b), -1, world_joint[b]};
    }
    const std::size_t first = nodes.size();
    if (root.joint < 0) {
      nodes.push_back(root);
    } else {
      push_joint(nodes, model, root.body, -1, root.joint);
    }
    for (std::size_t next = first; next < nodes.size(); ++next) {
      const TreeNode node = nodes[next];
      if (node.body < 0 || static_cast<std::size_t>(node.body) >= limb_count) continue;  // a joint frame, a ball
      for (std::int32_t j : incident[node.body]) {
        if (j == node.joint) continue;
        const Joint& joint = model.joints[j];
        const std::int32_t child = joint.inboard == node.body ? joint.outboard : joint.inboard;
        push_joint(nodes, model, child, static_cast<std::int32_t>(next), j);
      }
    }
  }
  island_begin.push_back(static_cast<std::int32_t>(nodes.size()));
  return nodes;
}

// The Model body frame's world pose at the start (rotation, origin), per rigid-scene body (the
// limbs, then the balls), and per tree body its frame's (featherstone_state.hpp, "Frames").
struct StartFrames {
  std::vector<Eigen::Matrix3d> model_rotation;
  std::vector<Eigen::Vector3d> model_origin;
  std::vector<Eigen::Matrix3d> rotation;  // tree body frame → world, at the start
  std::vector<Eigen::Vector3d> origin;    // tree body frame's origin in world, at the start, m
};

StartFrames model_frames(const FeatherstoneState& state, const Model& model) {
  const std::size_t limb_count = model.bodies.size(), body_count = state.bodies.size();
  StartFrames frames;
  frames.model_rotation.resize(body_count), frames.model_origin.resize(body_count);
  for (std::size_t b = 0; b < body_count; ++b) {
    if (b < limb_count) {
      frames.model_rotation[b] = model.bodies[b].orientation().toRotationMatrix();
      frames.model_origin[b] = model.bodies[b].position;
    } else {
      frames.model_rotation[b].setIdentity();
      frames.model_origin[b] = model.balls[b - limb_count].position;
    }
  }
  return frames;
}

// Tree bodies: frames, inertias, joints, X_tree (featherstone_state.hpp, "Frames").
void build_tree(FeatherstoneState& state, const Model& model, const std::vector<TreeNode>& nodes, StartFrames& frames) {
  const std::size_t limb_count = model.bodies.size();
  const std::size_t tree_size = nodes.size();
  const std::vector<Eigen::Matrix3d>& model_rotation = frames.model_rotation;
  const std::vector<Eigen::Vector3d>& model_origin = frames.model_origin;
  std::vector<Eigen::Matrix3d>& rotation = frames.rotation;
  std::vector<Eigen::Vector3d>& origin = frames.origin;
  rotation.resize(tree_size), origin.resize(tree_size);
  state.scene_body.resize(tree_size), state.model_joint.resize(tree_size);
  state.centre_of_mass.resize(tree_size), state.principal_frame.resize(tree_size), state.centre_inertia.resize(tree_size);
  state.tree_body.assign(state.bodies.size(), -1);
  for (std::size_t i = 0; i < tree_size; ++i) {
    const TreeNode& node = nodes[i];
    ArticulatedBody body;
    body.parent = node.parent;
    state.scene_body[i] = node.body, state.model_joint[i] = node.joint;
    const SerialAxis* serial = node.axis >= 0 ? &model.joints[node.joint].serial_axes[static_cast<std::size_t>(node.axis)] : nullptr;
    if (node.body < 0) {
      // A serial joint's frame: at its axis's point, with the axes of the chain's child (the last node).
      const auto child = static_cast<std::size_t>(nodes[i + model.joints[node.joint].serial_axes.size() - 1 - node.axis].body);
      rotation[i] = model_rotation[child], origin[i] = serial->point;
      state.centre_of_mass[i].setZero(), state.principal_frame[i].setIdentity(), state.centre_inertia[i].setZero();
      body.name = serial->name;
      body.joint_frame = true;
      body.inertia = SpatialInertia::from_mass_properties(0, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero());
    } else {
      const std::int32_t b = node.body;
      state.tree_body[b] = static_cast<std::int32_t>(i);
      // The frame's origin in the Model body frame: the child's anchor of its joint (the Model's
      // outboard anchor unless the tree turned the joint round; a serial joint's last axis's
      // point), or the centre of mass. The joint sits there: where a non-prismatic joint's two
      // anchors do not coincide at the initial poses, the child's anchor is taken as the joint's
      // location and the gap is kept as it started (the other methods close it; the joint-gap
      // observer reports it).
      Eigen::Vector3d anchor = state.shapes.centre_offset[b];
      if (serial) {
        anchor = model_rotation[b].transpose() * (serial->point - model_origin[b]);
      } else if (node.joint >= 0) {
        const Joint& joint = model.joints[node.joint];
        anchor = joint.outboard == b ? joint.outboard_anchor : joint.inboard_anchor;
      }
      rotation[i] = model_rotation[b];
      origin[i] = model_origin[b] + model_rotation[b] * anchor;
      state.centre_of_mass[i] = state.shapes.centre_offset[b] - anchor;
      state.principal_frame[i] = state.shapes.principal_frame[b];
      body.name = static_cast<std::size_t>(b) < limb_count ? model.bodies[b].name : ball_name(model, static_cast<std::size_t>(b) - limb_count);
      // The rigid body's inertia (principal moments, floored as the rigid scene floors them) in the
      // tree body's axes, about the centre of mass.
      const Eigen::Matrix3d principal = state.principal_frame[i].toRotationMatrix();
      Eigen::Matrix3d inertia = principal * state.bodies.body_inertia[b] * principal.transpose();
      inertia = 0.5 * (inertia + inertia.transpose()).eval();
      state.centre_inertia[i] = inertia;
      body.inertia = SpatialInertia::from_mass_properties(state.bodies.mass[b], state.centre_of_mass[i], inertia);
    }
    if (node.joint < 0) {
      body.joint = ArticulatedJoint::floating;  // X_tree = 1: q holds the world pose
      state.floating_roots.push_back(static_cast<std::int32_t>(i));
    } else {
      const Joint& joint = model.joints[node.joint];
      body.joint = serial ? (serial->slide ? ArticulatedJoint::prismatic : ArticulatedJoint::revolute) : articulated_joint(joint.type);
      body.armature = serial ? serial->armature : joint.armature;
      // Child frame = joint frame at q = 0.
      body.joint_axis = (rotation[i].transpose() * (serial ? serial->axis : joint.axis)).normalized();
      // X_tree: the child's frame at its initial pose, seen from the parent's frame (or the world).
      if (node.parent < 0) {
        body.tree_transform = PluckerTransform::from_pose(rotation[i], origin[i]);
      } else {
        const Eigen::Matrix3d& parent_rotation = rotation[node.parent];
        body.tree_transform = PluckerTransform::from_pose(parent_rotation.transpose() * rotation[i],
                                                          parent_rotation.transpose() * (origin[i] - origin[node.parent]));
      }
    }
    state.tree.add_body(std::move(body));
  }

}

// q: the joints' zero, the floating roots at their world poses.
void set_positions(FeatherstoneState& state, const StartFrames& frames) {
  const ArticulatedTree& tree = state.tree;
  state.q = tree.neutral_positions();
  for (std::int32_t i : state.floating_roots) {
    const int p = tree.position_offset(i);
    const Eigen::Quaterniond orientation(frames.rotation[i]);
    state.q.segment<3>(p) = frames.origin[i];
    state.q.segment<4>(p + 3) << orientation.w(), orientation.x(), orientation.y(), orientation.z();
  }
}

// A serial joint's rates at its initial poses, where its axes lie as the Model gives them: the
// least-squares q̇ of Σ ξ_a q̇_a = (ω, v at `point`), ξ_a the axis's twist (a, a × (point − p_a)) for
// a hinge, (0, a) for a slide. Exact when the Model's velocities are ones the joint allows.
void set_serial_rates(FeatherstoneState& state, const Joint& joint, std::size_t first, const Eigen::Vector3d& angular,
                      const Eigen::Vector3d& linear, const Eigen::Vector3d& point) {
  const auto count = static_cast<Eigen::Index>(joint.serial_axes.size());
  Eigen::Matrix<double, 6, Eigen::Dynamic> twists(6, count);
  for (Eigen::Index a = 0; a < count; ++a) {
    const SerialAxis& axis = joint.serial_axes[static_cast<std::size_t>(a)];
    if (axis.slide) {
      twists.col(a) << Eigen::Vector3d::Zero(), axis.axis;
    } else {
      twists.col(a) << axis.axis, axis.axis.cross(point - axis.point);
    }
  }
  Eigen::Matrix<double, 6, 1> relative;
  relative << angular, linear;
  const Eigen::VectorXd rates = twists.colPivHouseholderQr().solve(relative);
  state.v.segment(state.tree.velocity_offset(static_cast<int>(first)), count) = rates;
}

// v: each body's spatial velocity relative to its parent, at its frame's origin, in its frame,
// projected on the joint's motion subspace S: q̇ = Sᵀ v_rel (S's columns are orthonormal).
void set_velocities(FeatherstoneState& state, const Model& model, const std::vector<TreeNode>& nodes, const StartFrames& frames) {
  const ArticulatedTree& tree = state.tree;
  const RigidBodyState& y = state.bodies.state;
  const std::vector<Eigen::Matrix3d>& rotation = frames.rotation;
  const std::vector<Eigen::Vector3d>& origin = frames.origin;
  const std::size_t tree_size = nodes.size();
  state.v.setZero(tree.velocity_count());
  auto velocity_at = [&](std::int32_t b, const Eigen::Vector3d& point) -> Eigen::Vector3d {
    return state.bodies.linear_velocity(y, b) + state.bodies.angular_velocity(y, b).cross(point - y.position[b]);
  };
  for (std::size_t i = 0; i < tree_size; ++i) {
    const std::int32_t b = state.scene_body[i];
    if (b < 0) continue;  // a serial joint's frame: its rate is set with the chain's child
    const std::size_t first = nodes[i].axis >= 0 ? i - static_cast<std::size_t>(nodes[i].axis) : i;  // the chain's first node
    Eigen::Vector3d angular = state.bodies.angular_velocity(y, b), linear = velocity_at(b, origin[i]);
    if (nodes[first].parent >= 0) {
      const std::int32_t parent = state.scene_body[nodes[first].parent];
      angular -= state.bodies.angular_velocity(y, parent);
      linear -= velocity_at(parent, origin[i]);
    }
    if (nodes[i].axis >= 0) {
      set_serial_rates(state, model.joints[nodes[i].joint], first, angular, linear, origin[i]);
      continue;
    }
    const Eigen::Vector3d angular_in_child = rotation[i].transpose() * angular, linear_in_child = rotation[i].transpose() * linear;
    const ArticulatedBody& body = tree.body(static_cast<int>(i));
    const int offset = tree.velocity_offset(static_cast<int>(i));
    switch (body.joint) {
      case ArticulatedJoint::revolute: state.v[offset] = body.joint_axis.dot(angular_in_child); break;
      case ArticulatedJoint::prismatic: state.v[offset] = body.joint_axis.dot(linear_in_child); break;
      case ArticulatedJoint::spherical: state.v.segment<3>(offset) = angular_in_child; break;
      case ArticulatedJoint::floating: state.v.segment<3>(offset) = angular_in_child, state.v.segment<3>(offset + 3) = linear_in_child; break;
      case ArticulatedJoint::fixed: break;
    }
  }
  zero_sleeping_velocities(state);
}

// The joint-gap observer's anchors and slide axes.
void set_joint_anchors(FeatherstoneState& state, const Model& model, const StartFrames& frames) {
  state.joints = joint_anchors(state, model);
  state.slide_axis.assign(model.joints.size(), Eigen::Vector3d::Zero());
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    if (joint.type != JointType::prismatic) continue;
    state.slide_axis[j] =
        state.shapes.principal_frame[joint.outboard].conjugate() * (frames.model_rotation[joint.outboard].transpose() * joint.axis);
  }
}

// The joints' limits, friction and drives, and where the tree holds each joint.
void place_tree_joints(FeatherstoneState& state, const Model& model) {
  const ArticulatedTree& tree = state.tree;
  state.joint_controls = joint_controls(model);
  state.tree_joint.assign(model.joints.size(), TreeJoint{});
  state.serial_axes.clear();
  for (std::size_t i = 0; i < state.model_joint.size(); ++i) {
    const std::int32_t j = state.model_joint[i];
    if (j < 0 || state.scene_body[i] < 0) continue;  // a floating root; a serial joint's frame (its child holds the joint)
    const Joint& joint = model.joints[static_cast<std::size_t>(j)];
    const auto count = static_cast<int>(joint.serial_axes.size());
    TreeJoint& held = state.tree_joint[static_cast<std::size_t>(j)];
    held.body = static_cast<std::int32_t>(i);
    held.offset = tree.velocity_offset(static_cast<int>(i) - (count > 0 ? count - 1 : 0));
    held.dofs = count > 0 ? count : joint_velocity_count(tree.body(static_cast<int>(i)).joint);
    held.sign = joint.outboard == state.scene_body[i] ? 1 : -1;
    for (int a = 0; a < count; ++a) {
      const std::int32_t node = static_cast<std::int32_t>(i) - (count - 1 - a);
      state.serial_axes.push_back({j, a, node, tree.velocity_offset(node)});
    }
  }
}

// Each island's joints and serial axes, in order (counted, then placed): what an island's drives
// and friction read (joint_control_forces).
void index_island_joints(FeatherstoneState& state, const Model& model) {
  const std::size_t islands = state.islands.size();
  const auto island_of_joint = [&](std::size_t j) { return island_of(state, state.tree_joint[j]); };
  const auto controlled = [&](std::size_t j) {
    const Joint& joint = model.joints[j];
    return state.tree_joint[j].dofs > 0 && (joint.limits.any() || joint.friction > 0 || joint.drive.has_value());
  };
  const auto axis_of = [&](const TreeSerialAxis& node) -> const SerialAxis& {
    return model.joints[static_cast<std::size_t>(node.joint)].serial_axes[static_cast<std::size_t>(node.axis)];
  };
  const auto axis_controlled = [&](const TreeSerialAxis& node) {
    const SerialAxis& axis = axis_of(node);
    return axis.range || axis.friction > 0 || axis.drive.has_value();
  };
  state.limited_joints.clear(), state.limited_axes.clear();
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    if (state.tree_joint[j].dofs > 0 && model.joints[j].limits.any()) state.limited_joints.push_back(static_cast<std::int32_t>(j));
  }
  for (std::size_t a = 0; a < state.serial_axes.size(); ++a) {
    if (axis_of(state.serial_axes[a]).range) state.limited_axes.push_back(static_cast<std::int32_t>(a));
  }
  state.island_joint_begin.assign(islands + 1, 0), state.island_axis_begin.assign(islands + 1, 0);
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    if (controlled(j)) ++state.island_joint_begin[island_of_joint(j) + 1];
  }
  for (const TreeSerialAxis& axis : state.serial_axes) {
    if (axis_controlled(axis)) ++state.island_axis_begin[island_of_joint(static_cast<std::size_t>(axis.joint)) + 1];
  }
  for (std::size_t k = 0; k < islands; ++k) {
    state.island_joint_begin[k + 1] += state.island_joint_begin[k], state.island_axis_begin[k + 1] += state.island_axis_begin[k];
  }
  state.island_joint.resize(static_cast<std::size_t>(state.island_joint_begin[islands]));
  state.island_axis.resize(static_cast<std::size_t>(state.island_axis_begin[islands]));
  std::vector<std::int32_t> next_joint(state.island_joint_begin.begin(), state.island_joint_begin.end() - 1);
  std::vector<std::int32_t> next_axis(state.island_axis_begin.begin(), state.island_axis_begin.end() - 1);
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    if (controlled(j)) state.island_joint[static_cast<std::size_t>(next_joint[island_of_joint(j)]++)] = static_cast<std::int32_t>(j);
  }
  for (std::size_t a = 0; a < state.serial_axes.size(); ++a) {
    if (!axis_controlled(state.serial_axes[a])) continue;
    state.island_axis[static_cast<std::size_t>(next_axis[island_of_joint(static_cast<std::size_t>(state.serial_axes[a].joint))]++)] = static_cast<std::int32_t>(a);
  }
}

// Scratch, sized once: step() never allocates.
// The constraint blocks' scratch (joint_space_contacts.hpp, "Constraint space"), for every
// contact the scene reserved and every limit row its limited joints can have. The factor of H
// (and, with joint friction, H + h·G and its held copy) holds O(Σ depth) entries — a chain of n
// one-DOF joints n²/2 — so only a tree within kEagerFactorEntries gets it here; a larger one's
// first step with a contact or limit row sizes it (solve_groups). The rows' entries and
// the limit rows' Delassus matrices are reserved up to kReservedEntries each; a step past them
// allocates.
constexpr std::size_t kEagerFactorEntries = std::size_t{1} << 21;
constexpr std::size_t kReservedEntries = std::size_t{1} << 21;
void size_constraint_scratch(FeatherstoneState& state, const Model& model) {
  const ArticulatedTree& tree = state.tree;
  const int nv = tree.velocity_count();
  JointSpaceContactScratch& contact = state.contact;
  const std::vector<int> parent = dof_parents(tree);
  std::vector<std::size_t> depth(parent.size(), 1);
  std::size_t factor_entries = 0, deepest = 0;
  for (std::size_t i = 0; i < parent.size(); ++i) {
    if (parent[i] >= 0) depth[i] = depth[static_cast<std::size_t>(parent[i])] + 1;
    factor_entries += depth[i] - 1, deepest = std::max(deepest, depth[i]);
  }
  bool friction = false;
  for (const Joint& joint : model.joints) {
    friction = friction || joint.friction > 0;
    for (const SerialAxis& axis : joint.serial_axes) friction = friction || axis.friction > 0;
  }
  state.joint_friction = friction;
  if (factor_entries <= kEagerFactorEntries) {
    contact.factor.assign(tree);
    if (friction) contact.inertia.assign(tree), contact.held.assign(tree);
  }
  contact.composite.resize(tree);
  contact.touched.assign(state.islands.size(), 0), contact.factored.assign(state.islands.size(), 0);
  contact.response.setZero(nv);
  // Limit rows: two for a hinge's or slide's range or a serial axis's, three for a ball's cone
  // and twist; per island.
  std::vector<std::size_t> rows_of_island(state.islands.size(), 0);
  for (std::size_t k = 0; k < model.joints.size(); ++k) {
    const Joint& joint = model.joints[k];
    const TreeJoint& held = state.tree_joint[k];
    std::size_t rows = joint.limits.any() && held.dofs > 0 ? (joint.type == JointType::spherical ? 3 : 2) : 0;
    for (const SerialAxis& axis : joint.serial_axes) rows += axis.range ? 2 : 0;
    if (rows > 0) rows_of_island[island_of(state, held)] += rows;
  }
  std::size_t limit_rows = 0, limit_entries = 0;
  for (const std::size_t rows : rows_of_island) limit_rows += rows, limit_entries += rows * rows;
  // A block's rows hold the coordinates of at most two paths to the root.
  const std::size_t blocks = state.contacts.capacity() + limit_rows;
  const std::size_t entries = std::min(2 * deepest * blocks, kReservedEntries);
  contact.block_source.reserve(blocks);
  contact.row_begin.reserve(blocks + 1), contact.half_end.reserve(blocks);
  contact.row_coordinate.reserve(entries), contact.row_value.reserve(entries);
  contact.half_coordinate.reserve(entries), contact.half_value.reserve(entries);
  contact.contact_matrix.reserve(blocks), contact.free_motion.reserve(blocks), contact.push.reserve(blocks), contact.impulse.reserve(blocks);
  contact.memory.reserve(state.contacts.capacity());
  contact.path_length.assign(static_cast<std::size_t>(tree.body_count()), 0);
  for (int i = 0; i < tree.body_count(); ++i) {
    const int parent = tree.body(i).parent;
    contact.path_length[static_cast<std::size_t>(i)] = joint_velocity_count(tree.body(i).joint) + (parent >= 0 ? contact.path_length[static_cast<std::size_t>(parent)] : 0);
  }
  // The groups: at most one per island.
  const std::size_t islands = state.islands.size();
  contact.groups.reserve(islands), contact.group_island.reserve(islands), contact.limit_islands.reserve(islands);
  contact.limit_matrix.reserve(std::min(limit_entries, kReservedEntries));
  contact.island_link.assign(islands, 0), contact.island_group.assign(islands, 0);
  contact.island_rows.assign(islands, 0), contact.island_cursor.assign(islands, 0);
  contact.island_scratch.resize(islands);
  for (std::size_t k = 0; k < islands; ++k) {
    contact.island_scratch[k].path.reserve(2 * deepest);
    contact.island_scratch[k].reserve_limit_rows(static_cast<int>(std::min<std::size_t>(rows_of_island[k], 256)));
  }
  contact.lagging.setZero(nv);
  contact.scatter.setZero(nv, 3);
}

void size_scratch(FeatherstoneState& state, const Model& model) {
  const ArticulatedTree& tree = state.tree;
  const std::size_t tree_size = state.scene_body.size();
  const int nv = tree.velocity_count();
  state.kinematics.resize(tree);
  state.integration.resize(tree);
  state.joint_forces.setZero(nv);
  state.actuation.setZero(nv);
  state.servos.force.setZero(nv), state.servos.stiffness.setZero(nv), state.servos.damping.setZero(nv);
  state.servos.position.assign(static_cast<std::size_t>(nv), -1), state.servos.island.assign(state.islands.size(), 0);
  state.drag_force.assign(tree_size, SpatialVector::Zero());
  state.awake_islands.reserve(state.islands.size());
  state.last_substep.assign(state.islands.size(), 0.0);
  JointSpaceContactScratch& contact = state.contact;
  contact.articulated.resize(tree);
  contact.body_momentum.assign(tree_size, SpatialVector::Zero());
  contact.generalized_momentum.setZero(nv);
  contact.joint_change.setZero(nv), contact.displacement.setZero(nv);
  contact.free_velocity.setZero(nv), contact.constrained_velocity.setZero(nv);
  contact.joint_impulse.setZero(nv);
  size_constraint_scratch(state, model);

  JointControlScratch& controls = state.controls;
  controls.drive_force.setZero(nv), controls.drive_gain.setZero(nv), controls.armature.setZero(nv);
  controls.explicit_force.setZero(nv), controls.acceleration.setZero(nv), controls.predicted.setZero(nv), controls.forces.setZero(nv);
  controls.friction.reserve(model.joints.size() + state.serial_axes.size());
  controls.rows.reserve(3 * model.joints.size() + 2 * state.serial_axes.size());  // what find_limit_rows may add
  state.contact.remembered_rows.reserve(controls.rows.capacity()), state.contact.recording_rows.reserve(controls.rows.capacity());
  controls.penalty.assign(tree_size, Eigen::Matrix3d::Zero());

}

// The threads of the islands and the contact groups (FeatherstoneOptions::threads): none for one.
void start_threads(FeatherstoneState& state) {
  const FeatherstoneOptions& options = state.options;
  if (options.threads < 0 || options.threads > kMaxThreads) {
    throw std::invalid_argument("options: threads must be 0 (automatic) or in [1, " + std::to_string(kMaxThreads) + "]");
  }
  const bool crowd = state.islands.size() >= kParallelMinimumTreeIslands;
  const int threads = options.threads > 0 ? options.threads : crowd ? static_cast<int>(std::max(1u, std::thread::hardware_concurrency())) : 1;
  if (threads > 1) state.runner.reset(options.threading, threads, options.tasks);
}

}  // namespace

// The passes in order (kernel/PIPELINE.md lists them).
FeatherstoneState compile_featherstone(const Model& model, const FeatherstoneOptions& options) {
  FeatherstoneState state;
  static_cast<RigidScene&>(state) = compile_rigid_scene(model);  // validates
  require_supported(model, Method::featherstone);
  require_joint_controls(model, {.limits = true, .friction = true, .drives = true, .armature = true}, "featherstone");
  refuse_kinematic_loops(model);
  require_integrator(options.integrator, {Integrator::semi_implicit_euler, Integrator::rk4}, "featherstone");
  state.options = options;
  const std::vector<TreeNode> nodes = tree_order(state, model, state.island_begin);
  StartFrames frames = model_frames(state, model);
  build_tree(state, model, nodes, frames);
  set_positions(state, frames);
  set_velocities(state, model, nodes, frames);
  set_joint_anchors(state, model, frames);
  place_tree_joints(state, model);
  index_island_joints(state, model);
  size_scratch(state, model);
  start_threads(state);
  refresh_rigid_bodies(state);
  return state;
}

}  // namespace limber
