// The shared measure of joint coordinates: swing-twist, hinge angle, slide, limit violations and
// drive errors on poses built from known rotations.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "limber/kernel/model/joint_coordinates.hpp"

namespace limber {
namespace {

Model two_limbs(JointType type) {
  Model model;
  Body upper;
  upper.name = "upper", upper.shape = {ShapeType::capsule, 0.4, 0.05}, upper.mass = 1, upper.position = Vector3(0, 0, 1);
  Body lower = upper;
  lower.name = "lower", lower.position = Vector3(0, 0, 0.6);
  model.bodies = {upper, lower};
  Joint joint = spherical_joint("joint", 0, 1, Vector3(0, 0, -0.2), Vector3(0, 0, 0.2));
  joint.type = type, joint.axis = Vector3::UnitY();
  model.joints.push_back(joint);
  return model;
}

// The outboard's pose after turning it by `turn` (world) about the joint's anchor.
FramePose turned(const Model& model, const Eigen::Quaterniond& turn) {
  const Body& lower = model.bodies[1];
  const Vector3 anchor = lower.to_world(Vector3(0, 0, 0.2));
  return {turn * lower.orientation(), anchor + turn * (lower.position - anchor)};
}

FramePose rest(const Body& body) { return {body.orientation(), body.position}; }

TEST(JointCoordinates, AHingeTurnIsItsAngleAndItsSwing) {
  const Model model = two_limbs(JointType::revolute);
  const JointFrame frame = joint_frame(model, 0);
  const JointCoordinates q =
      joint_coordinates(model.joints[0], frame, rest(model.bodies[0]), turned(model, Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Vector3::UnitY()))));
  EXPECT_NEAR(q.angle, 0.7, 1e-12);
  EXPECT_NEAR(q.swing, 0.7, 1e-12);  // the cone's axis defaults to the outboard's axis at rest
  EXPECT_NEAR(q.twist, 0, 1e-12);
  EXPECT_NEAR(q.rotation.norm(), 0.7, 1e-12);
}

TEST(JointCoordinates, SwingAndTwistSeparate) {
  const Model model = two_limbs(JointType::spherical);
  const JointFrame frame = joint_frame(model, 0);
  // Twist about the outboard's own axis, then swing it sideways: swing-twist reads both back.
  const Eigen::Quaterniond twist(Eigen::AngleAxisd(0.3, Vector3::UnitZ()));
  const Eigen::Quaterniond swing(Eigen::AngleAxisd(0.5, Vector3(1, 1, 0).normalized()));
  const JointCoordinates q = joint_coordinates(model.joints[0], frame, rest(model.bodies[0]), turned(model, swing * twist));
  EXPECT_NEAR(q.swing, 0.5, 1e-12);
  EXPECT_NEAR(q.twist, 0.3, 1e-12);
  // Turning the inboard with the outboard changes nothing.
  const Eigen::Quaterniond both(Eigen::AngleAxisd(1.1, Vector3(0.2, -1, 0.4).normalized()));
  FramePose inboard = rest(model.bodies[0]), outboard = turned(model, swing * twist);
  inboard.orientation = both * inboard.orientation, outboard.orientation = both * outboard.orientation;
  const JointCoordinates moved = joint_coordinates(model.joints[0], frame, inboard, outboard);
  EXPECT_NEAR(moved.swing, 0.5, 1e-12);
  EXPECT_NEAR(moved.twist, 0.3, 1e-12);
}

TEST(JointCoordinates, ATwistIsMeasuredAboutTheConesAxis) {
  // A cone 1 rad off the outboard's rest axis (+z). A pose built as: the outboard's axis turned
  // onto the cone's axis by the shortest arc, twisted by ψ about it, then swung by the shortest
  // arc onto d. It reads ψ wherever d is in the cone, even 170° from the rest axis, where a twist
  // about the rest axis is undefined (a small swing there would turn it by radians).
  Model model = two_limbs(JointType::spherical);
  const Vector3 cone = Eigen::AngleAxisd(1.0, Vector3::UnitY()) * Vector3::UnitZ();
  model.joints[0].limits.swing = 2.5, model.joints[0].limits.swing_axis = cone;
  model.joints[0].limits.twist = Range{-1, 1};
  const JointFrame frame = joint_frame(model, 0);
  EXPECT_NEAR(joint_coordinates(model.joints[0], frame, rest(model.bodies[0]), rest(model.bodies[1])).twist, 0, 1e-12);
  const Eigen::Quaterniond onto_cone = Eigen::Quaterniond::FromTwoVectors(Vector3::UnitZ(), cone);
  for (const double psi : {-0.7, 0.0, 0.4}) {
    const Eigen::Quaterniond twist(Eigen::AngleAxisd(psi, cone));
    for (const double away : {0.0, 0.5, 1.5, 2.4}) {
      for (const double around : {0.0, 1.0, 2.5, 4.0}) {
        // d at `away` rad from the cone's axis, `around` rad round it.
        const Vector3 side = Eigen::AngleAxisd(around, cone) * Vector3::UnitY();
        const Vector3 d = Eigen::AngleAxisd(away, side) * cone;
        const Eigen::Quaterniond pose = Eigen::Quaterniond::FromTwoVectors(cone, d) * twist * onto_cone;
        const JointCoordinates q = joint_coordinates(model.joints[0], frame, rest(model.bodies[0]), turned(model, pose));
        EXPECT_NEAR(q.swing, away, 1e-9) << "away " << away << ", around " << around;
        EXPECT_NEAR(q.twist, psi, 1e-9) << "away " << away << ", around " << around << ", rest-axis angle "
                                        << std::acos(std::clamp(d.dot(Vector3::UnitZ()), -1.0, 1.0));
      }
    }
  }
}

TEST(JointCoordinates, LimitViolationIsTheExcessOverTheNearestBound) {
  Model model = two_limbs(JointType::spherical);
  model.joints[0].limits.swing = 0.4;
  model.joints[0].limits.twist = Range{-0.1, 0.2};
  JointCoordinates q;
  q.swing = 0.45, q.twist = -0.3;
  EXPECT_NEAR(limit_violation(model.joints[0], q), 0.2, 1e-15);
  q.twist = 0;
  EXPECT_NEAR(limit_violation(model.joints[0], q), 0.05, 1e-15);
  q.swing = 0.1;
  EXPECT_EQ(limit_violation(model.joints[0], q), 0);
}

TEST(JointCoordinates, ASphericalDriveErrorIsTheAngleToItsTarget) {
  Model model = two_limbs(JointType::spherical);
  JointDrive drive;
  drive.target_rotation = Vector3(0, 0.4, 0);
  model.joints[0].drive = drive;
  const JointFrame frame = joint_frame(model, 0);
  const auto error_after = [&](const Eigen::Quaterniond& turn) {
    return drive_error(model.joints[0], frame, joint_coordinates(model.joints[0], frame, rest(model.bodies[0]), turned(model, turn)));
  };
  EXPECT_NEAR(error_after(Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Vector3::UnitY()))), 0, 1e-12);
  EXPECT_NEAR(error_after(Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Vector3::UnitY()))), 0.3, 1e-12);
}

TEST(JointCoordinates, APrismaticSlideIsMeasuredAlongItsAxisFromRest) {
  Model model = two_limbs(JointType::prismatic);
  model.joints[0].axis = Vector3::UnitZ();
  const JointFrame frame = joint_frame(model, 0);
  FramePose lower = rest(model.bodies[1]);
  lower.position.z() -= 0.15;
  EXPECT_NEAR(joint_coordinates(model.joints[0], frame, rest(model.bodies[0]), lower).slide, -0.15, 1e-12);
}

TEST(JointCoordinates, BadLimitsAndDrivesAreRefusedByField) {
  Model model = two_limbs(JointType::spherical);
  model.joints[0].limits.range = Range{-1, 1};
  EXPECT_THROW(validate(model), ModelError);
  model = two_limbs(JointType::revolute);
  model.joints[0].limits.range = Range{0.1, 1};  // the rest pose must be inside
  EXPECT_THROW(validate(model), ModelError);
  model = two_limbs(JointType::spherical);
  model.joints[0].limits.swing = 0.5;
  model.joints[0].limits.swing_axis = Vector3::UnitX();  // the rest axis is 90° off it
  try {
    validate(model);
    FAIL() << "a cone that misses the rest pose was accepted";
  } catch (const ModelError& error) {
    EXPECT_NE(std::string(error.what()).find("joints[0].limits.swing_axis"), std::string::npos) << error.what();
  }
  model = two_limbs(JointType::fixed);
  model.joints[0].drive = JointDrive{};
  EXPECT_THROW(validate(model), ModelError);
  model = two_limbs(JointType::revolute);
  model.joints[0].friction = -1;
  EXPECT_THROW(validate(model), ModelError);
}

}  // namespace
}  // namespace limber
