#include "limber/kernel/model/joint_coordinates.hpp"

#include <cmath>
#include <numbers>

namespace limber {
namespace {

// The rotation `rotation_vector` (axis × angle, rad) as a quaternion.
Eigen::Quaterniond from_rotation_vector(const Eigen::Vector3d& rotation_vector) {
  const double angle = rotation_vector.norm();
  if (!(angle > 0)) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, rotation_vector / angle));
}

// The quaternion of the shorter way round (w ≥ 0): angles in [0, π].
Eigen::Quaterniond shorter(Eigen::Quaterniond q) {
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  return q;
}

double wrapped(double angle) {
  constexpr double pi = std::numbers::pi;
  angle = std::fmod(angle + pi, 2 * pi);
  if (angle < 0) angle += 2 * pi;
  return angle - pi;
}

}  // namespace

JointFrame joint_frame(const Model& model, std::size_t k) {
  const Joint& joint = model.joints[k];
  const Body& outboard = model.bodies[static_cast<std::size_t>(joint.outboard)];
  const Body* inboard = joint.inboard == kWorld ? nullptr : &model.bodies[static_cast<std::size_t>(joint.inboard)];
  JointFrame frame;
  frame.inboard_rest = inboard ? inboard->orientation() : Eigen::Quaterniond::Identity();
  const Eigen::Quaterniond to_inboard = frame.inboard_rest.conjugate();
  frame.rest_relative = shorter(to_inboard * outboard.orientation());
  frame.rest_axis = (to_inboard * outboard.axis).normalized();
  frame.cone_axis = (to_inboard * joint.limits.swing_axis.value_or(outboard.axis)).normalized();
  frame.twist_rest = Eigen::Quaterniond::FromTwoVectors(frame.rest_axis, frame.cone_axis) * frame.rest_relative;
  frame.axis = (to_inboard * joint.axis).normalized();
  const Eigen::Vector3d inboard_anchor = inboard ? inboard->to_world(joint.inboard_anchor) : joint.inboard_anchor;
  frame.rest_slide = (outboard.to_world(joint.outboard_anchor) - inboard_anchor).dot(joint.axis);
  return frame;
}

std::vector<JointFrame> joint_frames(const Model& model) {
  std::vector<JointFrame> frames;
  frames.reserve(model.joints.size());
  for (std::size_t k = 0; k < model.joints.size(); ++k) frames.push_back(joint_frame(model, k));
  return frames;
}

JointControls joint_controls(const Model& model) {
  return {model.joints, joint_frames(model)};
}

double twist_angle(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& axis) {
  const Eigen::Quaterniond q = shorter(rotation);
  return wrapped(2 * std::atan2(q.vec().dot(axis), q.w()));
}

Eigen::Vector3d twist_gradient(const Eigen::Vector3d& a, const Eigen::Vector3d& c) {
  const double denominator = 1 + a.dot(c);
  return denominator > 1e-9 ? Eigen::Vector3d((a + c) / denominator) : a;
}

JointCoordinates joint_coordinates(const Joint& joint, const JointFrame& frame, const FramePose& inboard,
                                   const FramePose& outboard) {
  const Eigen::Quaterniond relative = inboard.orientation.conjugate() * outboard.orientation;
  const Eigen::Quaterniond deviation = shorter(relative * frame.rest_relative.conjugate());
  JointCoordinates q;
  const Eigen::Vector3d outboard_axis = (relative * Eigen::Vector3d::UnitZ()).normalized();
  q.swing = std::acos(std::clamp(frame.cone_axis.dot(outboard_axis), -1.0, 1.0));
  q.twist = twist_angle(relative * frame.twist_rest.conjugate(), frame.cone_axis);
  q.angle = twist_angle(deviation, frame.axis);
  const Eigen::AngleAxisd turn(deviation);
  q.rotation = turn.angle() * turn.axis();
  const Eigen::Vector3d inboard_anchor = inboard.position + inboard.orientation * joint.inboard_anchor;
  const Eigen::Vector3d outboard_anchor = outboard.position + outboard.orientation * joint.outboard_anchor;
  q.slide = (outboard_anchor - inboard_anchor).dot(inboard.orientation * frame.axis) - frame.rest_slide;
  return q;
}

double limit_violation(const Joint& joint, const JointCoordinates& q) {
  const JointLimits& limits = joint.limits;
  double excess = 0;
  const auto outside = [&](double value, const Range& range) {
    excess = std::max({excess, value - range.max, range.min - value});
  };
  if (limits.swing) excess = std::max(excess, q.swing - *limits.swing);
  if (limits.twist) outside(q.twist, *limits.twist);
  if (limits.range) outside(joint.type == JointType::prismatic ? q.slide : q.angle, *limits.range);
  return excess;
}

Eigen::Quaterniond drive_target_rotation(const JointDrive& drive, const JointFrame& frame) {
  return from_rotation_vector(frame.inboard_rest.conjugate() * drive.target_rotation);
}

double drive_error(const Joint& joint, const JointFrame& frame, const JointCoordinates& q) {
  if (!joint.drive) return 0;
  const JointDrive& drive = *joint.drive;
  switch (joint.type) {
    case JointType::revolute: return std::abs(wrapped(q.angle - drive.target));
    case JointType::prismatic: return std::abs(q.slide - drive.target);
    default: break;
  }
  // Spherical: the angle of D·D_target⁻¹, both rotations in the inboard frame.
  const Eigen::Quaterniond error = shorter(from_rotation_vector(q.rotation) * drive_target_rotation(drive, frame).conjugate());
  return 2 * std::atan2(error.vec().norm(), error.w());
}

}  // namespace limber
