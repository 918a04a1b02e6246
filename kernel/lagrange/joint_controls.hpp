// Joint limits, friction, drives and armature in the Lagrange method (kernel/lagrange/README.md,
// "Joint controls"): rows appended to a joint's own rows, after its equality rows, so each joint stays
// one constraint node of Baraff's tree (≤ 6 rows: revolute and prismatic 5 + 1, spherical 3 + 3,
// universal 4 + 2) and nothing closes a loop.
//
// A joint's control rows span the motions its type leaves free, with Jacobian blocks J_i, J_o
// (rate w = J_i·u_i + J_o·u_o, world):
// - revolute: one row along t = (a + a₀)/(1 + a·a₀), a₀ and a the hinge axis fixed in the inboard
//   and in the outboard body: w is exactly the rate of the hinge angle (the swing-twist
//   decomposition's twist rate, joint_coordinates.hpp); J_o = [0, tᵀ], J_i = −J_o;
// - prismatic: one row along the slide axis h (fixed in the inboard body): w is exactly the rate
//   of the slide; J_o = [hᵀ, (r_o×h)ᵀ], J_i = [−hᵀ, −((p_o − x_i)×h)ᵀ];
// - spherical: an orthonormal frame e₁ = c×a/|c×a| (the swing direction: c the cone axis, a the
//   outboard's axis), e₃ the twist direction (a + c)/(1 + a·c), e₂ = e₃×e₁; three rows (drive or
//   friction) or only those carrying a limit (e₁ the swing, e₃ the twist). e₁ and e₃ are the
//   swing's and the twist's exact gradients (both about c, so (a + c) ⟂ c×a and the limits do
//   not couple: joint_coordinates.hpp);
// - universal: friction only, two rows along its two axes.
//
// Each row is, at each solve, in one mode (ControlMode), chosen by an active-set loop
// (solve_with_controls, multipliers.hpp): a limit row is a one-sided rigid row, a drive a
// compliant row, friction a rigid "stick" row whose multiplier is bounded (|λ| ≤ friction, a
// disc over a joint's rows), sliding at the bound otherwise.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/model/joint_coordinates.hpp"
#include "limber/kernel/rigid/rigid_scene.hpp"

namespace limber {

/// What a control row does in one solve.
enum class ControlMode : std::uint8_t {
  off,    ///< no row: zero Jacobian, unit compliance, multiplier 0
  limit,  ///< rigid, at its bound: s·w = bound, s·λ_limit ≥ 0
  stick,  ///< friction holding: rigid, w = stick_rate
  soft,   ///< the drive: w + A·λ = drive_rhs + A·slip (slip: the friction multiplier while sliding)
  slide,  ///< friction sliding with no drive: no row, the multiplier `slip` applied as a known force
};

/// One control row: its geometry and measures at the state last measured, the problem of the
/// solve under way, and the result.
struct ControlRow {
  Eigen::Matrix<double, 1, 6> inboard_jacobian = Eigen::Matrix<double, 1, 6>::Zero();
  Eigen::Matrix<double, 1, 6> outboard_jacobian = Eigen::Matrix<double, 1, 6>::Zero();
  std::uint8_t direction = 0;  ///< spherical, universal: which vector of the joint's frame (0…2)
  // Measured (measure_joint_controls):
  std::int8_t side = 0;          ///< the nearer limit on this row: +1 a lower, −1 an upper, 0 none
  double gap = 0;                ///< distance inside that limit, in the row's rate units (< 0: violated)
  double drive_error = 0;        ///< target − coordinate along the row (rad or m)
  double coordinate = 0;         ///< revolute, prismatic: the joint's angle or slide (rad or m), for its servos
  double target_rate = 0;        ///< the drive's target rate along the row
  double velocity_product = 0;   ///< J̇u (approximate for angular rows: the row turning with the inboard body)
  double rate = 0;               ///< w₀ = J·u at the state measured (measure_control_rates)
  // The problem (set by the solve's caller):
  std::int8_t limit = 0;     ///< s: +1 or −1 when the limit may engage (s·J·x ≥ bound), 0 not
  double bound = 0;
  double compliance = 0;     ///< A > 0: the row carries the drive (w + A·λ = drive_rhs); 0: no drive
  double drive_rhs = 0;
  double stick_rate = 0;     ///< J·x while sticking
  double slip = 0;           ///< the friction multiplier while sliding
  ControlMode mode = ControlMode::off, previous = ControlMode::off;
  // The result:
  double multiplier = 0, solved_rate = 0;
};

/// A joint with control rows.
struct ControlledJoint {
  std::uint32_t joint = 0;       ///< Model joint index (= its constraint index)
  std::uint32_t first_row = 0;   ///< its first row in JointControlSet::rows
  std::uint8_t row_offset = 0;   ///< where its control rows start among the constraint's rows
  std::uint8_t count = 0;        ///< control rows
  std::int8_t swing_row = -1, twist_row = -1;  ///< spherical: its rows carrying those limits (local), −1 none
  JointType type = JointType::spherical;
  /// Rigid-body (principal) frames, or world for the world: revolute/prismatic/universal: the
  /// axis fixed in the inboard body and (revolute, universal) the one fixed in the outboard body;
  /// spherical: the outboard's axis (local +z) and, in the inboard, the cone axis c (the swing's
  /// and the twist's axis).
  Eigen::Vector3d inboard_axis = Eigen::Vector3d::UnitZ(), outboard_axis = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d cone_axis = Eigen::Vector3d::UnitZ();
  // The solve under way:
  double friction_bound = 0;  ///< |λ| bound over the rows (0: no friction in this solve)
  bool sliding = false;
  /// Friction held the joint still in the impulse pass before an acceleration-level step: the
  /// step's stages hold it (|λ| ≤ friction at the acceleration level).
  bool stuck = false;
};

/// Every controlled joint's rows.
struct JointControlSet {
  std::vector<ControlledJoint> joints;
  std::vector<ControlRow> rows;
  bool empty() const { return joints.empty(); }
};

/// The servos (position and velocity actuators) set for the next step, per joint (of the Model
/// the method runs: a serial joint's axes are joints of their own), in the joint's coordinate.
/// Each is taken implicitly on its joint's row, as a drive is (set_control_problem): its force
/// force − stiffness·(q + h·q̇) − damping·q̇ at the rate q̇ the step ends with. Zeroed after each step.
struct JointServos {
  std::vector<double> force;      ///< Σ gear·kp·(u − gear·ref) + gear·kv·u, N·m or N
  std::vector<double> stiffness;  ///< Σ gear²·kp, N·m/rad or N/m
  std::vector<double> damping;    ///< Σ gear²·kv, N·m·s/rad or N·s/m
  bool any = false;               ///< a servo acts this step
};

/// How many control rows joint `joint` gets (0 without limits, friction, drive, armature or a
/// servo; `servo`: an actuator that is not a motor acts on it, a revolute or prismatic joint).
int control_row_count(const Joint& joint, bool servo = false);

/// A body's Model frame (the shape's centre, Model axes) from its rigid state.
FramePose model_frame_pose(const RigidScene& scene, const RigidBodyState& y, std::int32_t body);

}  // namespace limber
