// The mutable state of the Featherstone method (reduced coordinates): the Model's bodies as one
// kinematic tree (kernel/featherstone/articulated_tree.hpp) whose joints cannot open, stepped by
// the articulated-body algorithm. Built by compile_featherstone() (compile.hpp); stepped by
// step() (step.hpp).
//
// Beside the joint state (q, v) it keeps the maximal-coordinate rigid bodies of the shared rigid
// scene (kernel/rigid/rigid_scene.hpp), refreshed from (q, v) after every step: positions,
// orientations and momenta. Contact detection, sleeping, the observers and the command line's
// summary then run on the same code as for the other rigid-body methods.
//
// Frames. Tree body i is rigid-scene body `scene_body[i]` (a Model body, or the ball). Its frame
// has the axes of the Model's body frame (z: the limb's axis; the ball: the world's at the start)
// and its origin at
// - the anchor of the joint to its parent, on this body (the joint frame coincides with it at
//   q = 0, and the Model's initial poses are every joint's zero), or
// - the centre of mass, for a floating root (a 6-DOF joint to the world).
// The rigid body's frame is on the principal axes at the centre of mass; `centre_of_mass[i]` and
// `principal_frame[i]` give that frame in tree body i's frame.
//
// Serial joints. A Model joint of k axes (JointType::serial) is k consecutive tree bodies, each a
// 1-DOF revolute or prismatic joint at its axis's point: k − 1 massless joint frames (scene_body
// −1, axes those of the chain's child) and then the child, whose frame's origin is the last axis's
// point. Their k velocities are contiguous in v, each the axis's coordinate rate (MuJoCo's qvel of
// those joints), so a limit, spring or friction on an axis is a row on one velocity.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/kernel/collision/contact_memory.hpp"
#include "limber/kernel/featherstone/articulated_tree.hpp"
#include "limber/kernel/featherstone/dynamics.hpp"
#include "limber/kernel/featherstone/integration.hpp"
#include "limber/kernel/featherstone/joint_space_factor.hpp"
#include "limber/kernel/featherstone/spatial.hpp"
#include "limber/kernel/model/joint_coordinates.hpp"
#include "limber/kernel/model/options.hpp"
#include "limber/kernel/numerics/active_set.hpp"
#include "limber/kernel/rigid/rigid_scene.hpp"
#include "limber/kernel/threading/block_runner.hpp"

namespace limber {


/// Islands joined by the step's contacts, with their contacts and limit rows: solved as one task,
/// apart from every other group (joint_space_contacts.hpp, "Groups"). Its islands are
/// JointSpaceContactScratch::group_island[first_island … last_island) (ascending); its blocks
/// first_block … last_block − 1, its contacts' first and its limit rows' from first_row_block
/// (island by island); its islands with limit rows limit_islands[first_limit … last_limit).
struct ConstraintGroup {
  int first_island = 0, last_island = 0;
  int first_block = 0, first_row_block = 0, last_block = 0;
  int first_limit = 0, last_limit = 0;
  bool pushed = false;  ///< its push-out moved it (before the move: its displacement waits for advance_positions)
};

/// An island's limit rows, solved together (joint_space_limits.cpp, "Holding rows"): blocks
/// first_block … first_block + rows − 1, their Delassus matrix (rows × rows, column-major) at
/// JointSpaceContactScratch::limit_matrix[matrix].
struct LimitIsland {
  std::int32_t island = 0;
  int first_block = 0, rows = 0;
  std::size_t matrix = 0;
};

/// What one island's group uses alone while it is solved (the group's first island's; its own
/// limit rows' solve its own): reserved at compile, grown past that by the rows a step needs.
struct IslandSolveScratch {
  std::vector<int> path;  ///< one block's coordinates
  // The island's limit rows solved together: values, targets, accumulated impulses, changes, held
  // flags.
  Eigen::VectorXd limit_value, limit_target, limit_accumulated, limit_change;
  std::vector<char> limit_active;
  ActiveSet active_set;

  /// Room for m limit rows in one solve (grows, never shrinks).
  void reserve_limit_rows(int m) {
    if (limit_value.size() >= m) return;
    limit_value.setZero(m), limit_target.setZero(m), limit_accumulated.setZero(m), limit_change.setZero(m);
    limit_active.assign(static_cast<std::size_t>(m), 0);
    active_set.reserve(m);
  }
};

/// Scratch of the contact response (kernel/featherstone/joint_space_contacts.hpp), sized at
/// compile so a step allocates nothing. The vectors over bodies or coordinates are shared by the
/// groups, each writing only its islands' entries.
///
/// Blocks. The step's constraints in joint space are blocks of rows (joint_space_contacts.hpp,
/// "Responses"), group after group: a contact's block has three rows (its points' relative
/// velocity along its normal and two tangents), a limit row's block one (its first column; the
/// other two are zero).
struct JointSpaceContactScratch {
  /// Articulated-body inertias (ABA's U_i, D_i⁻¹) of the drives' pass (with their armature).
  DynamicsWorkspace articulated;
  Eigen::VectorXd joint_change;                ///< nv: the joints' change, H⁻¹ Jᵀ j
  Eigen::VectorXd displacement;                ///< nv: the push-out, a tangent vector laid out like v
  /// nv: before the move, v before the constraints and after them (resolve_joint_space_contacts)
  Eigen::VectorXd free_velocity, constrained_velocity;
  std::vector<SpatialVector> body_momentum;      ///< per tree body: the push-out's re-projection, I_i v_i before it less after, body coordinates
  Eigen::VectorXd generalized_momentum;          ///< nv: Σ J_iᵀ of those momenta
  Eigen::VectorXd joint_impulse;                 ///< nv: generalized impulses on the joints for the response (consumed)
  // The blocks' responses through the factor (joint_space_contacts.hpp, "Responses").
  // The factors hold O(Σ depth) entries: compile sizes them for a small tree, a large tree's
  // first step that needs them does (compile.cpp, size_constraint_scratch).
  JointSpaceFactor factor;                       ///< H's LᵀDL at the constraints' configuration (before the move H + h·G; or the friction's H + h·G)
  /// Per island, before the move: a contact touches it this step, so its velocity update goes
  /// through the factor (factored_forward_dynamics) instead of the articulated-body algorithm.
  std::vector<char> touched;
  /// Per island: `factor` holds its H + h·G at the constraints' poses, from its velocity update
  /// this step (the constraints take it as it is).
  std::vector<char> factored;
  JointSpaceFactor inertia;                      ///< with joint friction: H + h·G, not factored
  JointSpaceFactor held;                         ///< with joint friction: H + h·G with the held joints' penalties, factored per island
  DynamicsWorkspace composite;                   ///< the composite-rigid-body algorithm's scratch
  Eigen::VectorXd response;                      ///< nv: a solve's scratch
  std::vector<int> path_length;                  ///< per tree body: the coordinates on its path to the root

  /// Per block: the contact (an index into state.contacts) or limit row (into
  /// JointControlScratch::rows) it holds.
  std::vector<std::int32_t> block_source;
  /// Per block: where its entries start in row_coordinate and row_value (blocks + 1).
  std::vector<int> row_begin;
  /// The blocks' rows J_g on the coordinates of their paths to the root: each entry a coordinate
  /// and the three rows' values there (a contact's b path entered negated; a limit row's
  /// ancestors with zeros, so that its entries hold its whole path).
  std::vector<int> row_coordinate;
  std::vector<Eigen::Vector3d> row_value;
  /// The blocks' half rows Y_g = L⁻ᵀ J_gᵀ: from row_begin[g] to half_end[g] (each coordinate of
  /// the block's paths once, in descending order, and Y_g's three columns there):
  /// A_hg = Y_hᵀ D⁻¹ Y_g.
  std::vector<int> half_end;
  std::vector<int> half_coordinate;
  std::vector<Eigen::Vector3d> half_value;
  /// Per block (a contact's): K = Y_cᵀ D⁻¹ Y_c, impulse at p → relative velocity at p, both in the
  /// contact's frame (normal, t₁, t₂: contact_frame).
  std::vector<Eigen::Matrix3d> contact_matrix;
  std::vector<Eigen::Vector3d> free_motion;      ///< per block (a contact's): J_c v before the impulses, m/s, its frame (v holds still until they settle)
  std::vector<double> push;                      ///< per block (a contact's): accumulated push-out "impulse", kg·m
  /// Per block (a contact's): its accumulated impulse λ (N·s, its frame; λ_n ≥ 0, in Coulomb's
  /// cone), from its warm start (joint_space_contacts.hpp, "Impulses", "Warm start").
  std::vector<Eigen::Vector3d> impulse;
  /// The last step's contact impulses, where this step's contacts find their warm start.
  ContactMemory memory;
  /// The last step's limit rows' impulses (key, N·s or N·m·s), by key, and this step's being
  /// recorded (scaled to a step as memory scales the contacts').
  std::vector<std::pair<std::int32_t, double>> remembered_rows, recording_rows;
  /// nv: y = D⁻¹ Σ_g Y_g λ_g of the impulses not yet in x (v, or the push-out's displacement),
  /// which moves x by L⁻¹ y (settle); J_g of it is Y_gᵀ y.
  Eigen::VectorXd lagging;
  Eigen::Matrix<double, Eigen::Dynamic, 3> scatter;  ///< nv × 3 scratch, zero between uses

  // The groups (ConstraintGroup), their islands and their islands with limit rows.
  std::vector<ConstraintGroup> groups;
  std::vector<std::int32_t> group_island;
  std::vector<LimitIsland> limit_islands;
  std::vector<double> limit_matrix;  ///< the islands' limit rows' Delassus matrices
  // Forming the groups, per island: union–find links, its group, its limit rows' count, and where
  // the next of them goes among the blocks.
  std::vector<std::int32_t> island_link, island_group, island_rows, island_cursor;
  std::vector<IslandSolveScratch> island_scratch;  ///< per island
};

/// A Model joint as the tree holds it (every Model joint is one tree body's joint to its parent).
struct TreeJoint {
  std::int32_t body = 0;  ///< the tree body it joins to its parent
  int offset = 0;         ///< where its coordinates start in v
  int dofs = 0;           ///< 1 (revolute, prismatic), 3 (spherical), 0 (fixed)
  /// +1 when the tree's child is the Model's outboard body, −1 when the tree turned the joint
  /// round: the Model's coordinate rates are sign·(rates of v) (rotated into the child's frame
  /// for a spherical joint).
  double sign = 1;

  /// The tree body of a revolute or prismatic joint's coordinate (axis 0), or of a serial
  /// joint's axis `axis`: its axes are consecutive tree bodies, the last the child.
  int axis_body(int axis) const { return body - (dofs - 1 - axis); }
};

/// One axis of a serial joint as the tree holds it.
struct TreeSerialAxis {
  std::int32_t joint = 0;  ///< the Model joint
  int axis = 0;            ///< which of its serial_axes
  std::int32_t body = 0;   ///< its tree body (a joint frame, or the child for the last axis)
  int offset = 0;          ///< its velocity in v
};

/// One row of a joint limit (joint_space_contacts.hpp, "Joint limits"): the coordinate's rate
/// `direction`·v (over the joint's `dofs` velocities from `offset`) must keep the gap C ≥ 0.
struct JointLimitRow {
  std::int32_t island = 0, body = 0;  ///< the joint's island and tree body
  int offset = 0, dofs = 1;
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();  ///< first `dofs` entries: ∂C/∂v
  double gap = 0;             ///< C: how far inside the limit (< 0: violated), rad or m
  double inverse_mass = 0;    ///< direction·H⁻¹·direction
  double impulse = 0, push = 0;  ///< accumulated, ≥ 0
  /// Which limit of which joint it is, the same every step (find_limit_rows numbers them in
  /// order: the rows' keys ascend): where the next step's row finds its warm start.
  std::int32_t key = 0;
};

/// A joint's friction over a step (joint_space_contacts.hpp, "Drives and friction").
struct JointFrictionBlock {
  std::int32_t body = 0;
  int offset = 0, dofs = 1;
  double bound = 0;                                   ///< friction·h, N·m·s or N·s
  Eigen::Matrix3d mass = Eigen::Matrix3d::Zero();     ///< its block of (H + h·G)⁻¹, inverted (top-left dofs × dofs)
  Eigen::Vector3d rate = Eigen::Vector3d::Zero();     ///< the predicted velocity before friction
  Eigen::Vector3d impulse = Eigen::Vector3d::Zero();  ///< j, |j| ≤ bound
  bool stuck = true;                                  ///< to be held at rest (else sliding with `impulse`)
  bool held = true;                                   ///< held in the last factorization
};

/// The servos (MuJoCo's position and velocity actuators) set for the next step, per velocity
/// coordinate (apply_actuator, kernel/featherstone/bodies.hpp). Each is taken implicitly, as a
/// drive is (joint_space_drives.cpp): its force at the end of each substep of h,
/// force − stiffness·(q + h·q̇⁺) − damping·q̇⁺, q in the tree's sign. Zeroed after each step.
struct ServoTerms {
  Eigen::VectorXd force;      ///< nv: Σ gear·kp·(u − gear·ref) + gear·kv·u, N·m or N, tree sign
  Eigen::VectorXd stiffness;  ///< nv: Σ gear²·kp, N·m/rad or N/m
  Eigen::VectorXd damping;    ///< nv: Σ gear²·kv, N·m·s/rad or N·s/m
  std::vector<std::int32_t> position;  ///< nv: the coordinate's index in q (set where a servo acts)
  std::vector<char> island;            ///< per island: a servo acts on it this step
};

/// Scratch of the joint limits, friction and drives, sized at compile so a step allocates nothing.
struct JointControlScratch {
  Eigen::VectorXd drive_force;    ///< nv: a drive's k·(target − x) + c·target_velocity, mapped onto v
  Eigen::VectorXd drive_gain;     ///< nv: k·h + c on the driven velocities, 0 elsewhere
  Eigen::VectorXd armature;       ///< nv: h·drive_gain
  Eigen::VectorXd explicit_force; ///< nv: the loads plus the drive terms known at the step's start
  Eigen::VectorXd acceleration;   ///< nv
  Eigen::VectorXd predicted;      ///< nv: v + h·v̇, the velocity the step would end with
  Eigen::VectorXd forces;         ///< nv: the loads plus the drives' and friction's forces, held over the step
  std::vector<JointFrictionBlock> friction;  ///< the island's whose friction is being solved; capacity: one per joint
  std::vector<JointLimitRow> rows;           ///< capacity: three per joint
  /// Per tree body: the penalty added to its joint's block of H + h·G (top-left dofs × dofs) to
  /// hold its friction (JointSpaceContactScratch::held).
  std::vector<Eigen::Matrix3d> penalty;
};

struct FeatherstoneState : RigidScene {
  ArticulatedTree tree;
  Eigen::VectorXd q;  ///< nq: joint positions (articulated_tree.hpp's layout)
  Eigen::VectorXd v;  ///< nv: joint velocities
  FeatherstoneOptions options;
  /// The threads of the islands' integration and of the contact groups (FeatherstoneOptions::threads; one: none).
  RunnerHandle runner;
  bool joint_friction = false;              ///< some joint or serial axis has friction (its islands integrate on the calling thread)
  std::vector<std::int32_t> awake_islands;  ///< the islands a step integrates (scratch; capacity: every island)
  std::vector<double> last_substep;         ///< per island: its last substep this step, s (the move after the constraints takes it)

  // Tree body i ↔ rigid-scene body b.
  std::vector<std::int32_t> scene_body;  ///< per tree body: the rigid-scene body (Model body index; the ball last); −1: a joint frame
  std::vector<std::int32_t> tree_body;   ///< per rigid-scene body: its tree body
  /// Per tree body: the Model joint that connects it to its parent, −1 for a floating root.
  std::vector<std::int32_t> model_joint;
  /// Per tree body: its rigid body's centre of mass in the tree body's frame, m.
  std::vector<Eigen::Vector3d> centre_of_mass;
  /// Per tree body: rotation from the rigid body's (principal) frame to the tree body's frame.
  std::vector<Eigen::Quaterniond> principal_frame;
  /// Per tree body: its rigid body's inertia about its centre of mass in the tree body's axes
  /// (P·I·Pᵀ, P the principal frame), kg·m²: the mirror's angular momentum without the world inertia.
  std::vector<Eigen::Matrix3d> centre_inertia;
  /// Tree bodies of island k are [island_begin[k], island_begin[k + 1]) (islands of the rigid
  /// scene, in its order; each is one subtree).
  std::vector<std::int32_t> island_begin;
  std::vector<std::int32_t> floating_roots;  ///< tree bodies hanging from the world by a 6-DOF joint

  /// The Model's joints as anchor pairs on the rigid bodies, for the joint-gap observer (which
  /// must read ~0: reduced coordinates cannot open a joint).
  JointAnchors joints;
  /// Per Model joint: the slide axis of a prismatic joint in its outboard rigid body's frame
  /// (zero for other types); the gap ignores separation along it.
  std::vector<Eigen::Vector3d> slide_axis;

  /// The Model's joints and their frames (kernel/model/joint_coordinates.hpp): their limits,
  /// friction and drives are read from here every step, so a drive written here between steps
  /// (World::set_joint_drive) acts from the next step on.
  JointControls joint_controls;
  /// Per Model joint: where the tree holds it (a serial joint: its child's tree body, its first
  /// velocity and its axis count).
  std::vector<TreeJoint> tree_joint;
  /// Every serial joint's axes, joint by joint, in order.
  std::vector<TreeSerialAxis> serial_axes;
  /// Island k's Model joints with coordinates (tree_joint's dofs > 0) and a control of their own
  /// (a limit, friction or a drive) are island_joint[island_joint_begin[k] … island_joint_begin[k + 1]),
  /// in joint order; its serial axes with one (indices into serial_axes) island_axis[island_axis_begin[k] …],
  /// likewise. Which joints have controls is fixed at compile (the World recompiles when a drive
  /// appears or goes): a step reads no other joint's.
  std::vector<std::int32_t> island_joint_begin, island_joint, island_axis_begin, island_axis;
  /// The Model joints with coordinates and a limit, and the serial axes with a range (indices
  /// into serial_axes), ascending: the joints find_limit_rows measures.
  std::vector<std::int32_t> limited_joints, limited_axes;
  JointControlScratch controls;

  /// forward_kinematics of the current (q, v): world_to_body and the bodies' spatial velocities.
  DynamicsWorkspace kinematics;
  FeatherstoneIntegratorWorkspace integration;
  JointSpaceContactScratch contact;
  Eigen::VectorXd joint_forces;  ///< nv: Settings::drag, the loads and the actuation as joint forces, held over a step
  Eigen::VectorXd actuation;     ///< nv: generalized forces for the next step (apply_joint_force), zeroed after it
  ServoTerms servos;             ///< the servos for the next step (apply_actuator), zeroed after it
  std::vector<SpatialVector> drag_force;  ///< per tree body (scratch)
  StepReport last_report;
};

/// The island of a Model joint (held: where the tree holds it; its child's island).
inline std::size_t island_of(const FeatherstoneState& state, const TreeJoint& held) {
  return state.island_of_body[state.scene_body[static_cast<std::size_t>(held.body)]];
}

/// Island k's tree bodies.
inline BodyRange island_bodies(const FeatherstoneState& state, std::size_t k) { return {state.island_begin[k], state.island_begin[k + 1]}; }
/// Where island k's tree bodies' coordinates lie: [first, last) in v (velocities) or q (positions).
inline std::pair<int, int> island_velocities(const FeatherstoneState& state, std::size_t k) {
  return state.tree.velocity_span(island_bodies(state, k));
}
inline std::pair<int, int> island_positions(const FeatherstoneState& state, std::size_t k) {
  return state.tree.position_span(island_bodies(state, k));
}

/// Sleeping islands rest: their joint velocities are zero (as their bodies' momenta are).
inline void zero_sleeping_velocities(FeatherstoneState& state) {
  for (std::size_t k = 0; k < state.islands.size(); ++k) {
    if (!state.islands[k].sleeping) continue;
    const auto [first, last] = island_velocities(state, k);
    state.v.segment(first, last - first).setZero();
  }
}

}  // namespace limber
