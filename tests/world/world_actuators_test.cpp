// Motors through the World (Model::actuators, World::set_controls): a motor's joint force is
// gear × control, clamped to its control range, on its coordinate alone, for every method that
// runs the joint; bad controls are refused and change nothing; removing a motor's joint drops it.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/world/world.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

// A rod on a hinge about z (vertical) through its head at the origin, no gravity, with a motor of
// gear 2 whose control is clamped to [−1, 0.5]. Its moment of inertia about the hinge is
// m L²/3 (a thin rod about its end) plus the radius's small share.
Model motorized_rod() {
  Model model = testing::rod_held_at_head(JointType::revolute, Eigen::Vector3d::UnitZ(), 0.001);
  model.settings.gravity.setZero();
  model.actuators.push_back({.name = "motor", .joint = 0, .axis = 0, .gear = 2, .control_range = Range{-1, 0.5}});
  return model;
}

// The hinge's angular speed after `steps` steps of dt with the control `control` held.
double spin_after(Method method, double control, int steps, double dt) {
  WorldOptions options;
  options.method = method;
  World world(motorized_rod(), options);
  const double controls[] = {control};
  world.set_controls(controls);
  for (int n = 0; n < steps; ++n) world.step(dt);
  return world.motion(world.body("rod")).angular.z();
}

TEST(WorldActuators, AMotorTurnsItsHingeAtGearTimesControlOverInertia) {
  const double inertia = 1.0 / 3.0 + 1.0 * (0.001 * 0.001) / 4;  // m L²/3 + m r²/4, m = 1, L = 1
  const double time = 0.25, dt = 1.0 / 400;
  for (const Method method : {Method::featherstone, Method::lagrange}) {
    // control 0.3: torque 0.6 N·m; control 3 is clamped to 0.5: torque 1 N·m.
    EXPECT_NEAR(spin_after(method, 0.3, 100, dt), 0.6 * time / inertia, 2e-3) << method_name(method);
    EXPECT_NEAR(spin_after(method, 3, 100, dt), 1.0 * time / inertia, 2e-3) << method_name(method);
  }
}

TEST(WorldActuators, ControlsAreCheckedAndKeptUntilSetAgain) {
  World world(motorized_rod(), WorldOptions{});
  EXPECT_EQ(std::vector<double>(world.controls().begin(), world.controls().end()), std::vector<double>{0.0});
  const double two[] = {1, 2};
  EXPECT_THROW(world.set_controls(two), WorldError);
  const double bad[] = {std::nan("")};
  EXPECT_THROW(world.set_controls(bad), WorldError);
  EXPECT_EQ(world.controls()[0], 0.0);  // nothing changed
  const double one[] = {0.25};
  world.set_controls(one);
  world.step(1.0 / 240), world.step(1.0 / 240);
  EXPECT_EQ(world.controls()[0], 0.25);
  EXPECT_GT(world.motion(world.body("rod")).angular.z(), 0);
}

TEST(WorldActuators, RemovingTheJointDropsItsMotor) {
  World world(motorized_rod(), WorldOptions{.method = Method::lagrange});
  world.remove_joint(world.joint("hinge"));
  EXPECT_TRUE(world.controls().empty());
  EXPECT_TRUE(world.model().actuators.empty());
}

TEST(WorldActuators, TheModelRefusesAMotorOnAJointWithoutACoordinate) {
  Model model = motorized_rod();
  model.joints[0].type = JointType::spherical;
  EXPECT_THROW(validate(model), ModelError);
  model = motorized_rod();
  model.actuators[0].axis = 1;
  EXPECT_THROW(validate(model), ModelError);
}

}  // namespace
}  // namespace limber
