// Actuators through the World (Model::actuators, World::set_controls): a motor's joint force is
// gear × control, clamped to its control range, on its coordinate alone, for every method that
// runs the joint; position and velocity actuators servo the coordinate (MuJoCo's); bad controls
// are refused and change nothing; removing a motor's joint drops it.
#include <cmath>
#include <string>
#include <tuple>
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

// MuJoCo's PD servo: a position actuator (kp) and a velocity actuator (kv) on one hinge, each of
// gear 2, the hinge's coordinate 0.1 rad at the initial pose (MuJoCo's ref). The position
// actuator pulls the length 2·(q + 0.1) to its control, so at rest q = control/2 − 0.1; the pair
// is a spring of 4·kp and a damper of 4·kv on q (ζ ≈ 0.77 below). The velocity actuator alone
// drives the hinge to q̇ = control/2.
Model servo_rod(bool with_position) {
  Model model = motorized_rod();
  model.actuators.clear();
  if (with_position) model.actuators.push_back({.name = "hold", .joint = 0, .kind = ActuatorKind::position, .gear = 2, .gain = 5, .reference = 0.1, .control_range = {}});
  model.actuators.push_back({.name = "damp", .joint = 0, .kind = ActuatorKind::velocity, .gear = 2, .gain = 1, .control_range = {}});
  return model;
}

// The rod's turn about z from its initial pose, rad.
double turn(const World& world, const Eigen::Vector3d& initial_axis) {
  const Eigen::Vector3d now = world.pose(world.body("rod")).orientation * Eigen::Vector3d::UnitZ();
  return std::atan2(initial_axis.cross(now).z(), initial_axis.dot(now));
}

class WorldServos : public ::testing::TestWithParam<Method> {};

TEST_P(WorldServos, APositionAndAVelocityActuatorHoldTheCommandedAngle) {
  World world(servo_rod(true), WorldOptions{.method = GetParam()});
  const Eigen::Vector3d initial = world.pose(world.body("rod")).orientation * Eigen::Vector3d::UnitZ();
  const double controls[] = {0.8, 0};
  world.set_controls(controls);
  for (int n = 0; n < 1200; ++n) ASSERT_EQ(world.step(1.0 / 400), StepStatus::ok);
  EXPECT_NEAR(turn(world, initial), 0.8 / 2 - 0.1, 1e-3) << "rad";
  EXPECT_NEAR(world.motion(world.body("rod")).angular.z(), 0, 1e-3) << "at rest";
  // Joint space agrees where the method has it: the servo's force at rest is 0.
  if (GetParam() == Method::featherstone) {
    EXPECT_NEAR(world.joint_passive_forces()[0], 0, 1e-3);
  }
}

TEST_P(WorldServos, AVelocityActuatorSpinsItsHingeAtControlOverGear) {
  World world(servo_rod(false), WorldOptions{.method = GetParam()});
  const double controls[] = {1};
  world.set_controls(controls);
  for (int n = 0; n < 400; ++n) ASSERT_EQ(world.step(1.0 / 400), StepStatus::ok);  // 12 time constants of I/(gear²·kv)
  EXPECT_NEAR(world.motion(world.body("rod")).angular.z(), 1.0 / 2, 1e-3) << "rad/s";
}

// Not the springs: on this 1 mm rod, even a motor's torque alone makes them diverge within 5
// steps (the rod's spin about its own axis, m r²/2, against the stiff hinge springs).
INSTANTIATE_TEST_SUITE_P(Methods, WorldServos, ::testing::Values(Method::particles, Method::lagrange, Method::featherstone),
                         [](const auto& info) { return std::string(method_name(info.param)); });

// A stiff servo at MuJoCo's default step, 0.005 s: on the rod (I ≈ 1/3 kg·m²), gear 2, kp = 10⁵
// and kv = 100 make gear²·kp·h²/I = 30 and gear²·kv·h/I = 6, past where an explicit servo is
// stable under either integrator (ω·h < 2 for semi-implicit Euler, < 2.8 for RK4; explicit, the
// first step's force spins the rod at 1800 rad/s and the step reports a divergence). Featherstone and
// Lagrange take it implicitly, as a drive: it makes no energy — the rod's kinetic energy plus the
// servo's spring ½·gear²·kp·(q − q*)² never rises past what the control gave it — and settles at
// q* = control/gear − reference. Under semi-implicit Euler the step is backward Euler's on the
// servo, whose energy falls every step; RK4 moves by the mean of the step's two velocities, and
// its energy may rise in one step, but not past its start.
class StiffServo : public ::testing::TestWithParam<std::tuple<Method, Integrator>> {};

TEST_P(StiffServo, MakesNoEnergyAndSettlesAtMujocosStep) {
  const auto [method, integrator] = GetParam();
  Model model = servo_rod(true);
  model.actuators[0].gain = 1e5, model.actuators[1].gain = 100;
  WorldOptions options{.method = method};
  options.featherstone.integrator = integrator, options.lagrange.integrator = integrator;
  options.divergence_check = false;  // the servo's spring, which the check does not count, turns into motion: the test counts it
  World world(model, options);
  const Eigen::Vector3d initial = world.pose(world.body("rod")).orientation * Eigen::Vector3d::UnitZ();
  const double controls[] = {0.8, 0};
  world.set_controls(controls);
  const double stiffness = 2 * 2 * 1e5, target = 0.8 / 2 - 0.1;  // gear²·kp, rad
  const auto energy = [&] {
    const double offset = turn(world, initial) - target;
    return world.observe().kinetic_energy + 0.5 * stiffness * offset * offset;
  };
  const double start = energy();  // J: the servo's spring at the control's first step
  double last = start;
  for (int n = 0; n < 400; ++n) {
    ASSERT_EQ(world.step(0.005), StepStatus::ok) << "step " << n;
    const double now = energy();
    ASSERT_LE(now, start) << "step " << n << ": energy made";
    if (integrator == Integrator::semi_implicit_euler) ASSERT_LE(now, last * (1 + 1e-12) + 1e-12) << "step " << n << ": energy made";
    last = now;
  }
  EXPECT_NEAR(turn(world, initial), target, 1e-6) << "rad";
  EXPECT_NEAR(world.motion(world.body("rod")).angular.z(), 0, 1e-6) << "rad/s, at rest";
}

INSTANTIATE_TEST_SUITE_P(Methods, StiffServo,
                         ::testing::Combine(::testing::Values(Method::lagrange, Method::featherstone),
                                            ::testing::Values(Integrator::semi_implicit_euler, Integrator::rk4)),
                         [](const auto& info) {
                           return std::string(method_name(std::get<0>(info.param))) + "_" +
                                  (std::get<1>(info.param) == Integrator::rk4 ? "rk4" : "semi_implicit_euler");
                         });

// Two stiff position servos on the two axes of a serial joint (about z, then about y as the first
// turn carries it: MuJoCo's two hinges in one body), no gravity: the rod comes to rest with each
// axis at its own servo's target, the rotation Rz(α*)·Ry(β*) from its initial pose — so each
// servo acts on its own axis's row (Lagrange: through the serial joint's virtual links).
TEST_P(StiffServo, ServosOnASerialJointsAxesEachHoldTheirOwn) {
  const auto [method, integrator] = GetParam();
  Model model = testing::rod_held_at_head(JointType::serial);
  model.settings.gravity.setZero();
  SerialAxis about_z, about_y;
  about_z.name = "about_z", about_z.axis = Eigen::Vector3d::UnitZ();
  about_y.name = "about_y", about_y.axis = Eigen::Vector3d::UnitY();
  model.joints[0].serial_axes = {about_z, about_y};
  for (int axis = 0; axis < 2; ++axis) {
    model.actuators.push_back({.name = "hold" + std::to_string(axis), .joint = 0, .axis = axis, .kind = ActuatorKind::position, .gear = 1, .gain = 1e4, .control_range = {}});
    model.actuators.push_back({.name = "damp" + std::to_string(axis), .joint = 0, .axis = axis, .kind = ActuatorKind::velocity, .gear = 1, .gain = 50, .control_range = {}});
  }
  WorldOptions options{.method = method};
  options.featherstone.integrator = integrator, options.lagrange.integrator = integrator;
  options.divergence_check = false;  // as above: the servos' springs turn into motion
  World world(model, options);
  const Eigen::Quaterniond initial = world.pose(world.body("rod")).orientation;
  const double alpha = 0.3, beta = -0.2;
  const double controls[] = {alpha, 0, beta, 0};
  world.set_controls(controls);
  for (int n = 0; n < 400; ++n) ASSERT_EQ(world.step(0.005), StepStatus::ok) << "step " << n;
  const Eigen::Quaterniond expected(Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(beta, Eigen::Vector3d::UnitY()));
  const Eigen::Quaterniond turned = world.pose(world.body("rod")).orientation * initial.conjugate();
  EXPECT_LT(turned.angularDistance(expected), 1e-4) << "rad";
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
  model = motorized_rod();
  model.actuators[0].gain = 1;  // a motor has none
  EXPECT_THROW(validate(model), ModelError);
  model = servo_rod(true);
  model.actuators[0].gain = -1;
  EXPECT_THROW(validate(model), ModelError);
}

}  // namespace
}  // namespace limber
