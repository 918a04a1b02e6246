// A joint's coordinates from its bodies' poses: the swing and twist of a spherical joint, the
// angle of a revolute one, the slide of a prismatic one, and how far a pose is past the joint's
// limits or off its drive's target. One implementation that every method (and the observers)
// measures with, so "the knee is 0.02 rad past its range" means the same thing under each.
//
// Conventions (model.hpp's Joint): a joint's zero is the bodies' poses in the Model. With q_i
// and q_o the inboard and outboard body frames' orientations (body → world; the world's is the
// identity), the relative rotation R = q_i⁻¹·q_o takes outboard-frame vectors to inboard-frame
// ones, and its deviation from rest, D = R·R₀⁻¹, is a rotation in the inboard frame. Then
// - swing: the angle between the cone axis c (fixed in the inboard) and the outboard's axis
//   a = R·ẑ (its local +z);
// - twist: about the cone axis c, by the swing-twist decomposition of the rotation that takes c
//   to the outboard's axis: D·Q = S·T, Q the shortest turn from c to the outboard's axis at rest
//   a₀ = R₀·ẑ, T a rotation about c by ψ = 2·atan2((D·Q).vec·c, (D·Q).w) (Bullet's cone-twist
//   constraint, PhysX's D6 joint). ψ is 0 at rest (Q turns about c × a₀ ⟂ c) and undefined only
//   where a points opposite c, outside every cone. Without a swing axis c = a₀ and Q = 1: the
//   twist about the outboard's rest axis (Jolt's SwingTwistConstraint). Measured about a₀
//   instead, the twist would be undefined at a = −a₀, which a cone off the rest axis can reach
//   (a shoulder's arm overhead), and a small swing there would turn it by up to a radian;
// - angle (revolute): the same twist formula about the hinge axis h (inboard frame), which is D's
//   whole rotation when the hinge holds;
// - slide (prismatic): (p_o − p_i)·(q_i·h) minus its value at rest, p the anchors (world).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/kernel/model/model.hpp"

namespace limber {

/// What measuring joint `k` needs, from the Model's rest poses (body frames as Body::orientation()).
struct JointFrame {
  Eigen::Quaterniond rest_relative = Eigen::Quaterniond::Identity();  ///< R₀ = q_i⁻¹·q_o at rest
  Eigen::Quaterniond inboard_rest = Eigen::Quaterniond::Identity();   ///< q_i at rest: world-at-rest axes → inboard frame
  /// Q⁻¹·R₀: the rest relative rotation with the outboard's axis turned onto the cone axis, so the
  /// twist is that of R·(Q⁻¹·R₀)⁻¹ = D·Q about c (spherical).
  Eigen::Quaterniond twist_rest = Eigen::Quaterniond::Identity();
  Eigen::Vector3d cone_axis = Eigen::Vector3d::UnitZ();      ///< c, unit, inboard frame (spherical): the swing's and the twist's axis
  Eigen::Vector3d rest_axis = Eigen::Vector3d::UnitZ();      ///< a₀ = R₀·ẑ, unit, inboard frame: the outboard's axis at rest
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();           ///< h = Joint::axis, unit, inboard frame
  double rest_slide = 0;                                     ///< prismatic: (p_o − p_i)·h at rest, m
};

JointFrame joint_frame(const Model& model, std::size_t joint);

/// A body's pose for measuring joints: its Model body frame's orientation (body → world) and
/// position (the frame's origin, the shape's centre), world. The world is the identity at 0.
struct FramePose {
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

struct JointCoordinates {
  double swing = 0;  ///< rad, [0, π]
  double twist = 0;  ///< rad, (−π, π]
  double angle = 0;  ///< rad, (−π, π]: revolute
  double slide = 0;  ///< m: prismatic
  /// The deviation D from rest as a rotation vector (axis × angle), rad, inboard frame.
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();
};

/// Joint `joint`'s coordinates with its inboard body at `inboard` and outboard at `outboard`
/// (pass FramePose{} for the world).
JointCoordinates joint_coordinates(const Joint& joint, const JointFrame& frame, const FramePose& inboard,
                                   const FramePose& outboard);

/// The angle of rotation D about unit axis `axis` by the swing-twist decomposition, rad, (−π, π].
double twist_angle(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& axis);

/// `angle` (rad) the shorter way round: its IEEE remainder by 2π, in [−π, π]; `angle` itself when
/// already there, which is what the remainder gives too (the same bits, without its division).
inline double shorter_way_round(double angle) {
  return std::abs(angle) <= std::numbers::pi ? angle : std::remainder(angle, 2 * std::numbers::pi);
}

/// The gradient of the twist about unit `c` (fixed in the inboard body) of the rotation that took
/// c to unit `a` (fixed in the outboard), with respect to the relative angular velocity ω_o − ω_i
/// (world, rad/s → rad/s): (a + c)/(1 + a·c); a where a = −c, the decomposition's singularity.
/// c is a spherical joint's cone axis or a revolute joint's hinge axis (then a is the hinge axis
/// as the outboard carries it): the twist's and the hinge angle's rate is its dot with ω_o − ω_i.
Eigen::Vector3d twist_gradient(const Eigen::Vector3d& a, const Eigen::Vector3d& c);

/// How far `coordinates` are past the joint's limits: the largest excess over its swing, twist
/// or range, ≥ 0 (rad; m for a prismatic range); 0 without limits.
double limit_violation(const Joint& joint, const JointCoordinates& coordinates);

/// A spherical drive's target deviation D_target (inboard frame) from its rotation vector in
/// world axes at rest (JointDrive::target_rotation).
Eigen::Quaterniond drive_target_rotation(const JointDrive& drive, const JointFrame& frame);

/// How far `coordinates` are from the joint's drive target: |q − target| (rad or m; a spherical
/// joint's the angle of D·D_target⁻¹); 0 without a drive.
double drive_error(const Joint& joint, const JointFrame& frame, const JointCoordinates& coordinates);

/// What a method's state keeps to apply and measure its joints' limits, friction and drives:
/// the Model's joints (read every step, so World::set_joint_drive can change a drive between
/// steps) and their frames.
struct JointControls {
  std::vector<Joint> joints;
  std::vector<JointFrame> frames;
  bool any() const {
    for (const Joint& joint : joints) {
      if (has_joint_controls(joint)) return true;
    }
    return false;
  }
};
JointControls joint_controls(const Model& model);

/// The largest limit violation and drive error over the joints, given every body's pose
/// (pose_of(body index) -> FramePose).
struct JointMeasures {
  double limit_violation = 0;  ///< rad (or m for prismatic ranges), the largest
  double drive_error = 0;      ///< rad (or m), the largest
  int limited_joints = 0, driven_joints = 0;
};
template <typename PoseOf>
JointMeasures measure_joints(const JointControls& controls, PoseOf&& pose_of) {
  JointMeasures measures;
  for (std::size_t k = 0; k < controls.joints.size(); ++k) {
    const Joint& joint = controls.joints[k];
    if (!joint.limits.any() && !joint.drive) continue;
    const FramePose inboard = joint.inboard == kWorld ? FramePose{} : pose_of(static_cast<std::size_t>(joint.inboard));
    const JointCoordinates q = joint_coordinates(joint, controls.frames[k], inboard, pose_of(static_cast<std::size_t>(joint.outboard)));
    if (joint.limits.any()) ++measures.limited_joints, measures.limit_violation = std::max(measures.limit_violation, limit_violation(joint, q));
    if (joint.drive) ++measures.driven_joints, measures.drive_error = std::max(measures.drive_error, drive_error(joint, controls.frames[k], q));
  }
  return measures;
}

/// Every joint's frame, in Model order.
std::vector<JointFrame> joint_frames(const Model& model);

}  // namespace limber
