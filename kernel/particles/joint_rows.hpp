// Joint rows: what the particle method adds to its distance constraints for joints that are more
// than two limb ends held together — anchors anywhere on a limb, hinges, universal and fixed
// joints, limits, friction and drives (kernel/verlet/README.md, "Joints beyond the ends").
//
// A limb that needs an orientation of its own (a hinge axis, a twist, a drive, an anchor off
// its axis) carries a *frame*: two particles F⁺, F⁻ at its centre ± δ·v̂ (v̂ ⟂ its axis), held
// by the distance constraints head–F⁺, tail–F⁺ and the linear row F⁺ + F⁻ − head − tail = 0.
// Its orthonormal frame is then u = (head − tail)/|·|, v = (F⁺ − F⁻) made orthogonal to u,
// w = u × v. A limb without one is a stick: only u is defined, and it cannot roll.
//
// Two kinds of rows, both coloured into SIMD batches (layouts/constraints/joint_row_batches.hpp):
// - point rows, linear: C = Σ c_k x_k = 0 (3 rows), x_k particles of both sides, c_k the anchor's
//   affine coefficients on each limb (Σ c = +1 on the inboard side, −1 on the outboard). The
//   weighted projection Δx_k = −c_k w_k C / Σ c_j² w_j keeps linear and angular momentum and
//   is the thesis's eq. 4.7 when the anchors are two particles (c = ±1).
// - angular rows: a scalar C(x) of the two sides' frames with a Jacobian J_B about which side B
//   turns (J_A = −J_B); each side is moved as a rigid cluster about its centre of mass,
//   Δφ = I⁺·J·Δλ, I its inertia tensor from its particles (a stick's pseudo-inverse ignores its
//   axis). Sources: Müller et al. 2020, "Detailed rigid body simulation with extended
//   position based dynamics" (angular constraints, XPBD compliance); Macklin et al. 2016 (XPBD).
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/kernel/model/model.hpp"
#include "limber/layouts/constraints/joint_row_batches.hpp"

namespace limber {

/// What a row's kind measures (C_raw) and about which axis side B turns to increase it (J_B),
/// from the two sides' frames. Directions are read from JointRow::direction as coordinates in a
/// side's frame (v, w, u); A's "d" and B's "e":
enum class JointRowKind : std::uint8_t {
  point,          ///< linear, C = Σ c_k x_k: direction[k] is c_k of particle[k]
  align,          ///< θ = ∠(d, e), J = (d × e)/|·|; d [0..2], e [3..5]: a hinge's axis in both (2 DOF)
  perpendicular,  ///< d·e, J = e × d; d [0..2], e [3..5]: a universal joint's two axes
  orientation,    ///< |r|, J = r/|r|, r = ½ Σ t_i × b_i: B's frame b_i against targets t_i fixed in
                  ///< A, [0..8] (B's basis at the target in A coordinates); ω_t [9..11] (A coordinates)
  swing,          ///< θ = ∠(d, u_B), J = (d × u_B)/|·|; d [0..2] the cone's axis
  twist,          ///< ψ about u_B: e [6..8] against A's reference [3..5] carried by the swing from
                  ///< c [0..2] (the cone axis, fixed in A) to u_B (Bullet's cone-twist); J = ∇ψ
                  ///< (u_B only while B has not swung: joint_projection.hpp's twist_angle)
  hinge,          ///< ψ about d [0..2]: e [6..8] against A's reference [3..5]; J = ∇ψ (d while e ⟂ d)
};
inline constexpr int kJointRowKinds = 7;

/// A row side's kind: the world (immovable; its frame the world's), a stick (head and tail
/// only), or a limb with a frame.
enum class JointSide : std::uint8_t { world = 0, stick = 1, framed = 2 };

/// One row, as compile builds it; the relaxation copies the awake ones into the batches.
/// Bounds and targets are in the kind's unit (rad, or the sine for perpendicular):
///   C = (C_raw − τ) − clamp(C_raw − τ, lower, upper),  τ = (1 − β)·target + β·(C_start + ω·h),
/// C_start the kind's value at the substep's start (orientation: r against the start pose). A
/// drive (stiffness k, damping c) has k_eff = k + c/h, α̃ = 1/(k_eff h²), β = (c/h)/k_eff
/// (joint_projection.hpp); friction > 0 clamps the accumulated multiplier to ±friction·h².
struct JointRow {
  JointRowKind kind = JointRowKind::point;
  JointSide side_a = JointSide::world, side_b = JointSide::stick;
  std::uint32_t island = 0;
  std::array<std::uint32_t, kJointRowParticles> particle{};
  std::array<double, kJointRowDirections> direction{};
  double lower = 0, upper = 0, target = 0, target_velocity = 0;
  double blend = 0;      ///< rigid rows: 1 holds the start pose (friction), 0 the target
  double stiffness = 0;  ///< a drive's k, N·m/rad (0 with damping 0: a rigid row)
  double damping = 0;    ///< a drive's c, N·m·s/rad
  double friction = 0;   ///< N·m, 0: none
  std::int32_t joint = -1;   ///< Model joint
  double reference = 0;   ///< point rows of joints: the length a gap is measured against, m
  /// A drive's row (World::set_joint_drive rewrites it): a limp drive (k = c = 0) holds nothing,
  /// its bounds open. An orientation drive keeps B's rest basis in A coordinates (M at a zero
  /// target) and A's rest frame (v, w, u), to turn a new target into M.
  bool drive = false;
  Eigen::Matrix3d rest_basis = Eigen::Matrix3d::Identity(), inboard_frame = Eigen::Matrix3d::Identity();
};

/// Writes `drive`'s gains and target into a drive row (JointRow::drive).
inline void set_drive_row(JointRow& row, const JointDrive& drive) {
  row.stiffness = drive.stiffness, row.damping = drive.damping;
  const bool limp = !(drive.stiffness + drive.damping > 0);
  row.lower = limp ? -std::numeric_limits<double>::infinity() : 0;
  row.upper = limp ? std::numeric_limits<double>::infinity() : 0;
  if (row.kind != JointRowKind::orientation) {
    row.target = drive.target, row.target_velocity = drive.target_velocity;
    return;
  }
  // M = T_A·M_rest, T_A the target rotation in A's coordinates; ω_t likewise.
  const double angle = drive.target_rotation.norm();
  const Eigen::Vector3d axis = angle > 0 ? Eigen::Vector3d(drive.target_rotation / angle) : Eigen::Vector3d::UnitX();
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(angle, row.inboard_frame.transpose() * axis).toRotationMatrix();
  const Eigen::Matrix3d target = turn * row.rest_basis;
  for (int i = 0; i < 9; ++i) row.direction[static_cast<std::size_t>(i)] = target(i % 3, i / 3);
  const Eigen::Vector3d rate = row.inboard_frame.transpose() * drive.target_angular_velocity;
  for (int i = 0; i < 3; ++i) row.direction[static_cast<std::size_t>(9 + i)] = rate[i];
}

/// The particle method's frames and rows (fixed at compile).
struct JointRowSet {
  std::vector<JointRow> rows;
  /// Per Model body: its frame particles (the null particle for a stick) and the rotation from
  /// its particle frame (v, w, u) to its Model body frame.
  std::vector<std::uint32_t> frame_plus, frame_minus;
  std::vector<Eigen::Quaterniond> frame_to_body;
  /// Per Model joint with controls: its rows [first, last) in `rows` (drive targets are written
  /// there by set_joint_drive, kernel/verlet/step.hpp).
  std::vector<std::pair<std::uint32_t, std::uint32_t>> joint_rows;
  /// Rows the colouring placed: colour per row (kNoColour: overflow), and the colour count.
  std::vector<std::uint8_t> colour;
  std::uint32_t colour_count = 0;
  bool empty() const { return rows.empty(); }
};

}  // namespace limber
