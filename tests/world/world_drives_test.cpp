// Joint drives through the World, as an engine blends animation and simulation: a drive holds a
// pose, follows new targets, goes limp when told to or when the ball hits (thesis 5.2).
#include <cmath>

#include <gtest/gtest.h>

#include "limber/kernel/model/joint_coordinates.hpp"
#include "limber/kernel/world/world.hpp"
#include "limber/kernel/world/world_internals.hpp"

namespace limber {
namespace {

// A limb on a hinge about y at its head, horizontal at rest (the hinge's zero), under gravity.
Model held_limb() {
  Model model;
  Body arm;
  arm.name = "arm", arm.shape = {ShapeType::capsule, 0.5, 0.03}, arm.mass = 2;
  arm.axis = Vector3(-1, 0, 0), arm.position = Vector3(0.25, 0, 1);
  model.bodies.push_back(arm);
  Joint hinge;
  hinge.name = "shoulder", hinge.type = JointType::revolute, hinge.inboard = kWorld, hinge.outboard = 0;
  hinge.inboard_anchor = Vector3(0, 0, 1), hinge.outboard_anchor = Vector3(0, 0, 0.25), hinge.axis = Vector3::UnitY();
  JointDrive drive;
  drive.stiffness = 400, drive.damping = 20;
  hinge.drive = drive;
  model.joints.push_back(hinge);
  model.settings.time_step = 1.0 / 240;
  model.settings.sleep.enabled = false;
  return model;
}

// The arm's lowest point so far: its centre's height.
double centre_height(const World& world) { return world.pose(world.body("arm")).position.z(); }

double hinge_angle(const World& world) {
  const Model& model = world.model();
  const Pose pose = world.pose(world.body("arm"));
  return joint_coordinates(model.joints[0], joint_frame(model, 0), FramePose{}, FramePose{pose.orientation, pose.position}).angle;
}

class WorldDrives : public ::testing::TestWithParam<Method> {};

TEST_P(WorldDrives, ADriveFollowsItsTargetsAndGoesLimpWhenTold) {
  World world(held_limb(), WorldOptions{.method = GetParam()});
  const JointId shoulder = world.joint("shoulder");
  // Key frames: the target moves from 0 to −0.6 rad (raising the arm) over a second.
  JointDrive drive = *world.model().joints[0].drive;
  double lag = 0;
  for (int s = 1; s <= 480; ++s) {
    drive.target = -0.6 * std::min(1.0, s / 240.0);
    world.set_joint_drive(shoulder, drive);
    ASSERT_EQ(world.step(), StepStatus::ok);
    if (s > 360) lag = std::max(lag, std::abs(hinge_angle(world) - drive.target));
  }
  // Gravity's torque m·g·L/2 ≈ 4.9 N·m sags a 400 N·m/rad drive by ≈ 0.012 rad.
  EXPECT_LT(lag, 0.03) << "rad from the key frame after it stopped moving";
  drive.stiffness = drive.damping = 0;
  world.set_joint_drive(shoulder, drive);
  double lowest = centre_height(world);
  for (int s = 0; s < 240; ++s) {
    ASSERT_EQ(world.step(), StepStatus::ok);
    lowest = std::min(lowest, centre_height(world));
  }
  EXPECT_LT(lowest, 1 - 0.2) << "limp, the arm swings down below its hinge";
}

// The held limb with drives released on impact, and a bouncy ball dropped on it.
Model limb_under_a_ball() {
  Model model = held_limb();
  model.settings.release_drives_on_impact = true;
  Ball ball;
  ball.radius = 0.05, ball.mass = 1, ball.restitution = 0.5;
  ball.position = Vector3(0.4, 0, 1.5), ball.velocity = Vector3(0, 0, -6);
  model.balls = {ball};
  return model;
}

TEST(WorldDrives, DrivesGoLimpWhenTheBallBouncesOffASpeculativeContact) {
  // The methods that solve their contacts before the move find the ball's contact across a gap
  // and bounce it from there: that is its hit, though it never overlaps the limb.
  for (const Method method : {Method::lagrange, Method::featherstone}) {
    WorldOptions options{.method = method};
    options.featherstone.integrator = Integrator::semi_implicit_euler;
    World world(limb_under_a_ball(), options);
    for (int s = 0; s < 240 && !world.drives_released(); ++s) ASSERT_EQ(world.step(), StepStatus::ok);
    EXPECT_TRUE(world.drives_released()) << method_name(method);
  }
}

TEST_P(WorldDrives, DrivesGoLimpWhenTheBallHits) {
  const Model model = limb_under_a_ball();
  const Ball& ball = model.balls.front();
  World world(model, WorldOptions{.method = GetParam()});
  double lowest = centre_height(world);
  for (int s = 0; s < 480; ++s) {
    ASSERT_EQ(world.step(), StepStatus::ok);
    lowest = std::min(lowest, centre_height(world));
  }
  const std::optional<JointDrive> now = world.joint_drive(world.joint("shoulder"));
  ASSERT_TRUE(now.has_value());
  EXPECT_EQ(now->stiffness, 0) << "the ball hit and the drive let go";
  EXPECT_TRUE(world.drives_released());
  EXPECT_GT(world.model().joints[0].drive->stiffness, 0) << "the Model stays the description it was given";
  // A recompile (an added ball) keeps the drive limp: the World's drives, not the Model's.
  Ball second = ball;
  second.position = Vector3(3, 0, 3), second.velocity = Vector3::Zero();
  world.add_ball(second);
  EXPECT_EQ(world.joint_drive(world.joint("shoulder"))->stiffness, 0);
  std::visit([](const auto& state) { EXPECT_EQ(state.joint_controls.joints[0].drive->stiffness, 0) << "the recompiled state's drive"; },
             world.internals().state);
  EXPECT_LT(lowest, 1 - 0.2) << "the arm fell";
}

TEST(WorldDrives, ABadDriveIsRefusedByName) {
  World world(held_limb(), WorldOptions{.method = Method::particles});
  JointDrive drive;
  drive.stiffness = -1;
  EXPECT_THROW(world.set_joint_drive(world.joint("shoulder"), drive), WorldError);
  drive.stiffness = std::nan("");
  EXPECT_THROW(world.set_joint_drive(world.joint("shoulder"), drive), WorldError);
}

TEST(WorldDrives, AStickThatBecomesHingedGetsItsFrameWhereItIs) {
  // A spherical pendulum swinging as a stick (no frame); the engine swaps its joint for a hinge
  // mid-swing. The limb gains frame particles, placed where the limb is now: no jump, no gap.
  Model model = held_limb();
  model.joints[0].type = JointType::spherical, model.joints[0].drive.reset();
  World world(model, WorldOptions{.method = Method::particles});
  for (int s = 0; s < 60; ++s) ASSERT_EQ(world.step(), StepStatus::ok);
  const Pose before = world.pose(world.body("arm"));
  Joint hinge = world.model().joints[0];
  hinge.name = "hinge", hinge.type = JointType::revolute, hinge.axis = Vector3::UnitY();
  world.remove_joint(world.joint("shoulder"));
  world.add_joint(hinge);
  EXPECT_LT((world.pose(world.body("arm")).position - before.position).norm(), 1e-12);
  for (int s = 0; s < 240; ++s) {
    ASSERT_EQ(world.step(), StepStatus::ok);
    ASSERT_LT(world.observe().max_joint_gap, 0.01);
  }
}

INSTANTIATE_TEST_SUITE_P(EveryMethodWithHinges, WorldDrives, ::testing::Values(Method::particles, Method::lagrange, Method::featherstone),
                         [](const auto& info) { return std::string(method_name(info.param)); });

}  // namespace
}  // namespace limber
