// Serial joints under the Featherstone method (MuJoCo's several joints in one body): a chain of
// tree bodies, one per axis, each its own coordinate. A serial joint of one hinge is the revolute
// joint with the same range, spring, friction and armature; two skew hinges conserve energy and
// hold their ranges; an axis's spring settles at its rest angle.
#include <cmath>

#include <gtest/gtest.h>

#include "limber/kernel/featherstone/compile.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

// A rod hanging along −x from the origin, turned about +y at 3 rad/s.
Model swinging_rod(JointType type) {
  Model model = testing::rod_held_at_head(type);
  model.bodies[0].angular_velocity = Eigen::Vector3d(0, 3, 0);
  model.bodies[0].linear_velocity = Eigen::Vector3d(0, 3, 0).cross(model.bodies[0].position);
  return model;
}

// Two hinges in a row at the rod's top: about y through the origin, then about z through a point
// 0.1 m down the rod (the axes skew, 0.1 m apart, as MuJoCo's humanoid's ankles are).
Model rod_on_two_skew_hinges() {
  Model model = swinging_rod(JointType::serial);
  Joint& joint = model.joints[0];
  SerialAxis about_y, about_z;
  about_y.name = "about_y", about_y.axis = Eigen::Vector3d::UnitY();
  about_z.name = "about_z", about_z.axis = Eigen::Vector3d::UnitZ(), about_z.point = Eigen::Vector3d(0.1, 0, 0);
  joint.serial_axes = {about_y, about_z};
  joint.outboard_anchor = Eigen::Vector3d(0, 0, 0.4);  // the last axis's point on the rod (its head is at local z 0.5)
  model.bodies[0].angular_velocity = Eigen::Vector3d(0, 3, 2);
  model.bodies[0].linear_velocity = Eigen::Vector3d(0, 3, 0).cross(model.bodies[0].position) +
                                    Eigen::Vector3d(0, 0, 2).cross(model.bodies[0].position - Eigen::Vector3d(0.1, 0, 0));
  return model;
}

TEST(FeatherstoneSerial, OneHingeIsTheRevoluteJoint) {
  Model revolute = swinging_rod(JointType::revolute);
  Joint& hinge = revolute.joints[0];
  hinge.limits.range = Range{-0.5, 0.4};
  hinge.drive = JointDrive{.stiffness = 2, .damping = 0.1, .target = 0.2};
  hinge.friction = 0.05, hinge.armature = 0.01;
  Model serial = swinging_rod(JointType::serial);
  serial.joints[0].serial_axes = {{.name = "hinge",
                                   .axis = hinge.axis,
                                   .point = Eigen::Vector3d::Zero(),
                                   .range = hinge.limits.range,
                                   .drive = hinge.drive,
                                   .friction = hinge.friction,
                                   .armature = hinge.armature}};
  FeatherstoneState a = compile_featherstone(revolute, {}), b = compile_featherstone(serial, {});
  double highest = 0;
  for (int n = 0; n < 1200; ++n) {
    step(a, 1.0 / 240), step(b, 1.0 / 240);
    highest = std::max(highest, a.q[0]);
    ASSERT_LT((a.bodies.state.position[0] - b.bodies.state.position[0]).norm(), 1e-9) << "step " << n;
    ASSERT_LT((a.bodies.state.orientation[0].coeffs() - b.bodies.state.orientation[0].coeffs()).norm(), 1e-9) << "step " << n;
  }
  // The rod fell onto the limit (gravity turns it the positive way) and the limit held it.
  EXPECT_GT(highest, 0.4 - 1e-3);
  EXPECT_LT(highest, 0.4 + 1e-3);
}

TEST(FeatherstoneSerial, TwoSkewHingesConserveEnergy) {
  FeatherstoneOptions options;
  options.integrator = Integrator::rk4;
  FeatherstoneState state = compile_featherstone(rod_on_two_skew_hinges(), options);
  const double start = observe(state).energy();
  double largest_change = 0;
  for (int n = 0; n < 1000; ++n) {
    step(state, 1e-3);
    largest_change = std::max(largest_change, std::abs(observe(state).energy() - start));
  }
  EXPECT_LT(largest_change, 1e-6 * std::abs(start) + 1e-9);
  // The second axis's point on the rod turns only with the first axis: it stays 0.1 m from the origin.
  const Eigen::Vector3d point = world_point(state, 0, Eigen::Vector3d(0, 0, 0.4));
  EXPECT_NEAR(point.norm(), 0.1, 1e-9);
}

TEST(FeatherstoneSerial, EachAxisHoldsItsRange) {
  Model model = rod_on_two_skew_hinges();
  model.joints[0].serial_axes[0].range = Range{-0.3, 0.3};
  model.joints[0].serial_axes[1].range = Range{-0.2, 0.25};
  FeatherstoneState state = compile_featherstone(model, {});
  double low[2] = {0, 0}, high[2] = {0, 0};
  for (int n = 0; n < 2400; ++n) {
    step(state, 1.0 / 240);
    for (int a = 0; a < 2; ++a) {
      const double angle = state.q[state.tree.position_offset(state.serial_axes[a].body)];
      low[a] = std::min(low[a], angle), high[a] = std::max(high[a], angle);
    }
  }
  EXPECT_GT(low[0], -0.3 - 2e-3);
  EXPECT_LT(high[0], 0.3 + 2e-3);
  EXPECT_GT(low[1], -0.2 - 2e-3);
  EXPECT_LT(high[1], 0.25 + 2e-3);
  EXPECT_TRUE(high[0] > 0.3 - 2e-3 || low[0] < -0.3 + 2e-3) << "the first axis never reached its range's end";
  // The observers measure the axes' ranges as they measure a joint's own.
  const Observation seen = observe(state);
  EXPECT_EQ(seen.joints.limited_joints, 1);
  EXPECT_LT(seen.joints.limit_violation, 2e-3);
}

TEST(FeatherstoneSerial, AnAxisSpringSettlesAtItsRest) {
  Model model = rod_on_two_skew_hinges();
  model.settings.gravity.setZero();
  model.joints[0].serial_axes[1].drive = JointDrive{.stiffness = 5, .damping = 0.5, .target = 0.3};
  model.joints[0].serial_axes[0].drive = JointDrive{.damping = 0.5};
  FeatherstoneState state = compile_featherstone(model, {});
  for (int n = 0; n < 240 * 20; ++n) step(state, 1.0 / 240);
  EXPECT_NEAR(state.q[state.tree.position_offset(state.serial_axes[1].body)], 0.3, 1e-3);
  EXPECT_NEAR(state.v.norm(), 0, 1e-3);
}

}  // namespace
}  // namespace limber
