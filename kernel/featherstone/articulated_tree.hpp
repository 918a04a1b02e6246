// A kinematic tree in reduced (joint) coordinates, the input of Featherstone's algorithms
// (Featherstone, "Rigid Body Dynamics Algorithms", 2008, chapter 4: the kinematic-tree model
// with the joints of Table 4.1). Independent of limber's Model: a compile step can build one
// from a Model, tests and benchmarks build them directly.
//
// Bodies are numbered 0..N−1 with every parent before its children; parent −1 is the fixed world
// base. Body i hangs from its parent by one joint: the tree transform X_tree takes the parent's
// body frame to the joint frame, the joint transform X_J(q) takes the joint frame to body i's
// frame (at q = 0 the two coincide), so ⁱX_λ = X_J(q_i) X_tree.
//
// Generalized coordinates: q (size position_count, "nq") and v (size velocity_count, "nv"),
// each joint owning a contiguous slice at its offsets. The joint-space acceleration is v̇ (size
// nv), and joint forces τ (size nv) are dual to v (τ·v is power, W).
//   joint      q (nq)                                   v (nv)                          motion subspace S
//   revolute   1: angle about the axis, rad              1: rad/s                        (a, 0)
//   prismatic  1: displacement along the axis, m         1: m/s                          (0, a)
//   spherical  4: unit quaternion (w, x, y, z), the      3: ω, the child's angular       [1₃ ; 0]
//                 child frame's orientation in the          velocity relative to its
//                 joint frame (p_joint = R p_child)         parent, child coordinates
//   fixed      0                                         0                               (none)
//   floating   7: p (3), the child origin in the joint   6: (ω, v) the child's spatial    1₆
//                 frame, m; then a unit quaternion          velocity relative to its
//                 (w, x, y, z) as for spherical             parent, child coordinates: ω
//                                                           rad/s, v the velocity of the
//                                                           child origin, m/s
// Position derivatives: revolute/prismatic q̇ = v; spherical q̇ = ½ q ⊗ (0, ω); floating
// ṗ = R(q) v and the quaternion as spherical. Every S is constant in the child frame, so the
// joint's bias acceleration c_J = Ṡ q̇ is zero (chapter 4).
#pragma once

#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build
#include "limber/kernel/featherstone/spatial.hpp"

namespace limber {

/// The joints of Table 4.1 that limber uses; see the table above for their coordinates.
enum class ArticulatedJoint : std::uint8_t { revolute, prismatic, spherical, fixed, floating };

/// Position and velocity coordinates of a joint type: (1, 1), (1, 1), (4, 3), (0, 0), (7, 6).
int joint_position_count(ArticulatedJoint type);
inline int joint_velocity_count(ArticulatedJoint type) {  // inline: every tree pass asks, per body
  switch (type) {
    case ArticulatedJoint::revolute:
    case ArticulatedJoint::prismatic: return 1;
    case ArticulatedJoint::spherical: return 3;
    case ArticulatedJoint::fixed: return 0;
    case ArticulatedJoint::floating: return 6;
  }
  return 0;
}
const char* articulated_joint_name(ArticulatedJoint type);

/// One body and the joint that connects it to its parent.
struct ArticulatedBody {
  std::string name;                                     ///< optional, used in error messages
  int parent = -1;                                      ///< index of the parent body; −1: the world
  ArticulatedJoint joint = ArticulatedJoint::revolute;
  Eigen::Vector3d joint_axis = Eigen::Vector3d::UnitZ();  ///< unit, joint-frame coordinates (revolute, prismatic)
  PluckerTransform tree_transform;                      ///< X_tree: parent body frame → joint frame
  SpatialInertia inertia;                               ///< in the body's own frame (eq. 2.63)
  /// Revolute and prismatic: added to the joint's diagonal of H (kg·m² or kg, ≥ 0): a rotor's
  /// reflected inertia, MuJoCo's armature. Every algorithm below includes it.
  double armature = 0;
  /// A massless frame between two axes of a serial joint (MuJoCo's several joints in one body):
  /// its inertia must be zero. ABA stays defined as long as the bodies beyond it have mass, or the
  /// joint armature.
  bool joint_frame = false;
};

/// Tree bodies first … last − 1 holding whole subtrees (an island's): each body's parent is in
/// the range or is −1 (the world). The algorithms that take one read and write only its bodies'
/// and coordinates' entries, so that disjoint ranges may run on different threads.
struct BodyRange {
  int first = 0, last = 0;
};

/// A validated tree with the offsets of each joint's coordinates. Adding bodies keeps it valid;
/// nothing else changes it.
class ArticulatedTree {
 public:
  ArticulatedTree() = default;
  /// Validates (validate_articulated_bodies) and indexes `bodies`. Throws ModelError.
  explicit ArticulatedTree(std::vector<ArticulatedBody> bodies);

  /// Appends `body` after validating it; returns its index. Throws ModelError naming the body.
  int add_body(ArticulatedBody body);

  const std::vector<ArticulatedBody>& bodies() const { return bodies_; }
  const ArticulatedBody& body(int index) const { return bodies_[static_cast<std::size_t>(index)]; }
  int body_count() const { return static_cast<int>(bodies_.size()); }
  int position_count() const { return position_count_; }  ///< nq
  int velocity_count() const { return velocity_count_; }  ///< nv
  /// Where body i's joint coordinates start in q and in v (and τ, v̇).
  int position_offset(int body) const { return position_offset_[static_cast<std::size_t>(body)]; }
  int velocity_offset(int body) const { return velocity_offset_[static_cast<std::size_t>(body)]; }

  /// q for the zero configuration: angles and displacements 0, quaternions (1, 0, 0, 0).
  Eigen::VectorXd neutral_positions() const;

  /// Every body: the whole tree as a BodyRange.
  BodyRange all_bodies() const { return {0, body_count()}; }
  /// Where the bodies of `bodies` have their coordinates in v and in q: [begin, end).
  std::pair<int, int> velocity_span(BodyRange bodies) const {
    return {velocity_offset(bodies.first), bodies.last < body_count() ? velocity_offset(bodies.last) : velocity_count_};
  }
  std::pair<int, int> position_span(BodyRange bodies) const {
    return {position_offset(bodies.first), bodies.last < body_count() ? position_offset(bodies.last) : position_count_};
  }

 private:
  std::vector<ArticulatedBody> bodies_;
  std::vector<int> position_offset_, velocity_offset_;
  int position_count_ = 0, velocity_count_ = 0;
};

/// Checks body `index` as the next body of a tree that already has `index` bodies: the parent
/// comes before it (−1 ≤ parent < index); the joint axis is finite and unit (revolute,
/// prismatic; within 1e-9); X_tree is finite with a proper rotation (‖EᵀE − 1‖ ≤ 1e-9,
/// det E > 0); the armature is finite and ≥ 0 (0 unless revolute or prismatic); the mass is finite
/// and > 0 (exactly 0, with no inertia, for a joint frame); the centre of mass is finite; the inertia about the
/// centre of mass is symmetric and positive definite, with principal moments that satisfy the
/// triangle inequality (a real mass distribution). Throws ModelError (kernel/model/model.hpp), one line:
/// "bodies[3] (\"forearm\").mass: must be > 0, got -1".
void validate_articulated_body(const ArticulatedBody& body, int index);

/// validate_articulated_body for each body in order; throws at the first bad one.
void validate_articulated_bodies(const std::vector<ArticulatedBody>& bodies);

/// Calls visit(std::integral_constant<int, k>{}) with k the joint's degrees of freedom (0, 1, 3
/// or 6), so per-joint arithmetic can use fixed-size blocks.
template <typename Visitor>
void with_degrees_of_freedom(ArticulatedJoint type, Visitor&& visit) {
  switch (type) {
    case ArticulatedJoint::revolute:
    case ArticulatedJoint::prismatic: visit(std::integral_constant<int, 1>{}); return;
    case ArticulatedJoint::spherical: visit(std::integral_constant<int, 3>{}); return;
    case ArticulatedJoint::floating: visit(std::integral_constant<int, 6>{}); return;
    case ArticulatedJoint::fixed: visit(std::integral_constant<int, 0>{}); return;
  }
}

/// The joint's motion subspace S (6 × k, Table 4.1), child coordinates: revolute (a, 0),
/// prismatic (0, a), spherical [1₃; 0], floating 1₆.
template <int k>
Eigen::Matrix<double, 6, k> motion_subspace(const ArticulatedBody& body) {
  Eigen::Matrix<double, 6, k> s = Eigen::Matrix<double, 6, k>::Zero();
  if constexpr (k == 1) {
    if (body.joint == ArticulatedJoint::revolute) {
      s.template head<3>() = body.joint_axis;
    } else {
      s.template tail<3>() = body.joint_axis;
    }
  } else if constexpr (k == 3) {
    s.template topRows<3>().setIdentity();
  } else if constexpr (k == 6) {
    s.setIdentity();
  }
  return s;
}

}  // namespace limber
