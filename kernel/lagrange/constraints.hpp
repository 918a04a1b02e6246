// The constraint equations of the Lagrange method: every joint type and the gear as rows
// C(x, q) = 0 (or, for the gear, J·u = 0) on the rigid bodies' states, with their Jacobian
// blocks J_b (rows × 6, acting on a body's (v, ω), world frame; thesis 3.1.4, figure 3.5) and
// the velocity product J̇u that the acceleration-level solve needs.
//
// Row kinds, each written in the bodies' (principal) frames at compile and turned into world
// vectors from the state (p: anchor, x: centre of mass, r = p − x the lever, d = p_i − p_o the
// separation; i inboard, o outboard; the world as inboard has x = 0, q = identity, ω = 0):
// - point:   C = d (3 rows, world axes).           J_i = [E, −[r_i]×],  J_o = −[E, −[r_o]×]
// - slide:   C = b·d, b fixed in the inboard body. J_i = [bᵀ, ((p_o − x_i)×b)ᵀ],  J_o = [−bᵀ, −(r_o×b)ᵀ]
// - angular: C = u·v, u fixed in the inboard body, v in the outboard, perpendicular at rest.
//                                                   J_i = [0, (u×v)ᵀ],  J_o = [0, −(u×v)ᵀ]
// - gear:    Ċ = n_o·ω_o − ratio·(n_i·ω_i) = 0, a velocity constraint with no position form.
//                                                   J_i = [0, −ratio·n_iᵀ],  J_o = [0, n_oᵀ]
// Joint types as rows: spherical 3 point; revolute 3 point + 2 angular (u = b₁, b₂ ⟂ axis,
// v = axis); universal 3 point + 1 angular (u = axis, v = second axis); fixed 3 point + 3 angular
// (u, v = the pairs (x, y), (y, z), (z, x) of the world axes at rest); prismatic 2 slide (b₁, b₂ ⟂
// axis) + 3 angular. Point rows come first, then slide, then angular, then the joint's control
// rows (limits, friction, drive: kernel/lagrange/joint_controls.hpp), which are not equations:
// constraint_error and velocity_product give them 0, and each solve sets them itself.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/lagrange/joint_controls.hpp"
#include "limber/kernel/model/joint_coordinates.hpp"
#include "limber/kernel/model/model.hpp"
#include "limber/kernel/rigid/rigid_scene.hpp"

namespace limber {

/// A constraint's Jacobian block on one body: rows × (v, ω), at most 6 rows; fixed-capacity
/// storage, so no heap allocation.
using ConstraintBlock = Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor, 6, 6>;
/// A constraint's rows (error, rate, multipliers): at most 6, fixed-capacity storage.
using ConstraintVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1>;

/// One joint's or gear's rows. Vectors are in the body frames of the rigid bodies (principal
/// axes), the world's when the inboard side is the world.
struct ConstraintRows {
  std::uint8_t point_rows = 0;    ///< 3 (anchors coincide) or 0
  std::uint8_t slide_rows = 0;    ///< 2 (prismatic) or 0
  std::uint8_t angular_rows = 0;  ///< 0…3
  std::uint8_t control_rows = 0;  ///< 0…3: limits, friction, drive (joint_controls.hpp), after the rest
  bool gear = false;              ///< one gear row instead of all the above
  std::array<Eigen::Vector3d, 2> slide_normal{};        ///< b, inboard frame
  std::array<Eigen::Vector3d, 3> inboard_direction{};   ///< u (angular rows) or n_i (gear), inboard frame
  std::array<Eigen::Vector3d, 3> outboard_direction{};  ///< v (angular rows) or n_o (gear), outboard frame
  double ratio = 0;                                     ///< gear only
  int rows() const { return gear ? 1 : point_rows + slide_rows + angular_rows + control_rows; }
  int equality_rows() const { return gear ? 1 : point_rows + slide_rows + angular_rows; }
};

/// The Model's joints, then its gears, as constraints between pairs of bodies. A gear's
/// `inboard` is its first body and `outboard` its second; joints keep their anchors in
/// JointAnchors (the first joints.size() constraints).
struct ConstraintSet {
  std::vector<std::int32_t> inboard, outboard;  ///< body index, −1: the world
  std::vector<ConstraintRows> rows;
  std::vector<std::int32_t> row_offset;  ///< size() + 1 entries: constraint c owns rows [row_offset[c], row_offset[c + 1])
  std::size_t joint_count = 0;           ///< constraints [0, joint_count) are the Model's joints
  std::size_t size() const { return inboard.size(); }
  std::size_t total_rows() const { return row_offset.empty() ? 0 : static_cast<std::size_t>(row_offset.back()); }
};

/// The rows of `model`'s joints and gears, from the bodies' poses in `scene` (the joints' zero).
ConstraintSet compile_constraints(const RigidScene& scene, const Model& model, const std::vector<char>& servo_joints = {});

/// The control rows of `model`'s joints (those of `constraints` with control_rows > 0), their axes
/// carried into the bodies' frames from the poses in `scene`.
JointControlSet compile_joint_controls(const RigidScene& scene, const Model& model, const ConstraintSet& constraints);

/// Measures every controlled joint at state y with velocities (v, ω per body, world; only the
/// rates and J̇u read them): each row's Jacobian, nearer limit and gap, drive error and target
/// rate (from `controls`, read afresh: limits, friction and drives may change between steps),
/// rate and J̇u.
void measure_joint_controls(const RigidScene& scene, const JointAnchors& anchors, const JointControls& controls,
                            const RigidBodyState& y, const std::vector<Eigen::Vector3d>& velocity,
                            const std::vector<Eigen::Vector3d>& angular_velocity, JointControlSet& set);

/// Everything about the constraints at one state that the solves read, computed once per state.
struct ConstraintGeometry {
  std::vector<Eigen::Vector3d> inboard_lever, outboard_lever;  ///< per joint: r_i, r_o (world, m; r_i = 0 for the world)
  std::vector<ConstraintBlock> inboard_jacobian, outboard_jacobian;  ///< per constraint: J_i, J_o
  void resize(const ConstraintSet& constraints);
};

/// Fills `geometry` for state y.
void update_constraint_geometry(const ConstraintSet& constraints, const JointAnchors& anchors, const RigidBodyState& y,
                                ConstraintGeometry& geometry);

/// C of constraint c at state y (metres for point and slide rows, the cosine u·v for angular
/// rows; 0 for a gear, which has no position form).
ConstraintVector constraint_error(const ConstraintSet& constraints, const JointAnchors& anchors, const RigidBodyState& y,
                                  std::size_t c);

/// The joint gap that `error` (constraint_error of a joint with `rows`) leaves: the norm of its
/// point and slide rows, m.
double position_error(const ConstraintRows& rows, const ConstraintVector& error);
/// The largest |u·v| of its angular rows (≈ the misalignment in rad), 0 without angular rows.
double angular_error(const ConstraintRows& rows, const ConstraintVector& error);

/// Ċ = J_i·u_i + J_o·u_o of constraint c, from the velocities (v, ω per body, world) and the
/// geometry of the same state.
ConstraintVector constraint_rate(const ConstraintSet& constraints, const ConstraintGeometry& geometry,
                                 const std::vector<Eigen::Vector3d>& velocity, const std::vector<Eigen::Vector3d>& angular_velocity,
                                 std::size_t c);

/// J̇u of constraint c: the part of C̈ that does not depend on the accelerations, so that
/// C̈ = J·u̇ + J̇u (the acceleration-level solve's right-hand side is −J̇u).
ConstraintVector velocity_product(const ConstraintSet& constraints, const JointAnchors& anchors, const ConstraintGeometry& geometry,
                                  const RigidBodyState& y, const std::vector<Eigen::Vector3d>& velocity,
                                  const std::vector<Eigen::Vector3d>& angular_velocity, std::size_t c);

}  // namespace limber
