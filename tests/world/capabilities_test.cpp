// The capability table (kernel/model/capabilities.hpp) says what each method compiles, and
// the README's status table says the same: each joint type compiles under a method exactly
// when the table says so, a serial joint's axis takes an actuator exactly where it says so, and
// the README's row for the method names exactly those joint types and, for precision, float
// exactly when the table allows it.
#include <array>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/model/capabilities.hpp"
#include "limber/kernel/methods/method.hpp"
#include "limber/kernel/world/world.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

constexpr std::array<JointType, 6> kJointTypes{JointType::spherical, JointType::revolute, JointType::prismatic, JointType::universal,
                                               JointType::fixed,     JointType::serial};

// Two rods end to end along +x, the first's head held at the origin (a spherical joint to the
// world), the second's head at the first's tail by a joint of `type` (axis y, second axis z; a
// serial joint: a hinge about y then one about z, there).
Model two_rods(JointType type) {
  Model model = testing::rod_held_at_head(JointType::spherical);
  Body second = model.bodies[0];
  second.name = "second";
  second.position = Eigen::Vector3d(1.5, 0, 0);
  model.bodies.push_back(second);
  Joint joint = spherical_joint("joint", 0, 1, Eigen::Vector3d(0, 0, -0.5), Eigen::Vector3d(0, 0, 0.5));
  joint.type = type;
  joint.axis = Eigen::Vector3d::UnitY();
  joint.second_axis = Eigen::Vector3d::UnitZ();
  if (type == JointType::serial) {
    const Eigen::Vector3d point(1, 0, 0);
    SerialAxis about_y, about_z;
    about_y.name = "about_y", about_y.axis = Eigen::Vector3d::UnitY(), about_y.point = point;
    about_z.name = "about_z", about_z.axis = Eigen::Vector3d::UnitZ(), about_z.point = point;
    joint.serial_axes = {about_y, about_z};
  }
  model.joints.push_back(joint);
  return model;
}

bool compiles(Method method, JointType type, bool single_precision = false) {
  WorldOptions options;
  options.method = method;
  options.single_precision = single_precision;
  try {
    compile_method(two_rods(type), options);
    return true;
  } catch (const ModelError&) {
    return false;
  } catch (const std::invalid_argument&) {
    return false;
  }
}

// The README's status table row whose first cell starts with the method's name and a colon,
// split into its cells.
std::vector<std::string> readme_row(std::string_view method) {
  std::ifstream readme(std::string(LIMBER_SOURCE_DIR) + "/README.md");
  std::string line;
  const std::string lead = "| " + std::string(method) + ":";
  while (std::getline(readme, line)) {
    if (line.rfind(lead, 0) != 0) continue;
    std::vector<std::string> cells;
    std::stringstream row(line.substr(1));
    for (std::string cell; std::getline(row, cell, '|');) cells.push_back(cell);
    return cells;
  }
  return {};
}

TEST(Capabilities, EachJointTypeCompilesExactlyWhereTheTableSaysSo) {
  for (const MethodCapabilities& entry : kMethodCapabilities) {
    for (const JointType type : kJointTypes) {
      EXPECT_EQ(compiles(entry.method, type), supports(entry.method, type))
          << method_name(entry.method) << ", " << joint_type_name(type);
    }
    EXPECT_EQ(compiles(entry.method, JointType::spherical, true), entry.single_precision) << method_name(entry.method) << " in float";
  }
}

// An actuator on the serial joint's second axis: a servo is refused at compile and a motor's
// non-zero control by set_controls (nothing changes) exactly where the table has no
// serial_actuators; a motor at control 0 loads everywhere the joint does.
TEST(Capabilities, ASerialAxisTakesAnActuatorExactlyWhereTheTableSaysSo) {
  for (const MethodCapabilities& entry : kMethodCapabilities) {
    if (!supports(entry.method, JointType::serial)) continue;
    const std::string name(method_name(entry.method));
    Model motor = two_rods(JointType::serial), servo = motor;
    motor.actuators.push_back({.name = "turn", .joint = 1, .axis = 1, .gear = 1, .control_range = {}});
    servo.actuators.push_back({.name = "hold", .joint = 1, .axis = 1, .kind = ActuatorKind::position, .gear = 1, .gain = 5, .control_range = {}});
    World world(motor, WorldOptions{.method = entry.method});
    const double on[] = {0.5};
    if (entry.serial_actuators) {
      EXPECT_NO_THROW(world.set_controls(on)) << name;
      EXPECT_NO_THROW(World(servo, WorldOptions{.method = entry.method})) << name;
    } else {
      EXPECT_THROW(world.set_controls(on), WorldError) << name;
      EXPECT_EQ(world.controls()[0], 0.0) << name << ": nothing changed";
      EXPECT_THROW(World(servo, WorldOptions{.method = entry.method}), ModelError) << name;
    }
  }
}

// A 0.4 × 0.2 × 0.1 m box lying on its middle face (0.2 m tall) on the floor: a method that
// collides it as itself holds its centre at 0.1 m; one that collides its capsule proxy (radius
// 0.05 m, along the longest side) lets it sink to 0.05 m.
TEST(Capabilities, ABoxRestsOnItsSideExactlyWhereTheTableSaysItCollidesAsItself) {
  for (const MethodCapabilities& entry : kMethodCapabilities) {
    Model model;
    model.name = "box on its side";
    model.ground = Ground{};
    model.settings.time_step = 1.0 / 240;
    Body box;
    box.name = "box";
    box.shape.type = ShapeType::box;
    box.shape.half_extents = Vector3(0.05, 0.1, 0.2);  // its longest side on the body's axis, as the importers put it
    box.mass = 1;
    box.axis = Vector3::UnitX();                        // lying along x, its 0.2 m side upright
    box.shape.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Vector3::UnitZ()));
    box.position = Vector3(0, 0, 0.1 + 1e-3);
    model.bodies.push_back(box);
    World world(model, WorldOptions{.method = entry.method});
    for (int n = 0; n < 240; ++n) ASSERT_EQ(world.step(), StepStatus::ok) << method_name(entry.method);
    std::vector<Pose> poses(1);
    world.poses(poses);
    EXPECT_NEAR(poses[0].position.z(), entry.true_shapes ? 0.1 : 0.05, 3e-3) << method_name(entry.method);
  }
}

TEST(Capabilities, TheReadmeStatusTableSaysWhatTheTableSays) {
  const std::pair<Method, std::string_view> rows[] = {
      {Method::particles, "particles"}, {Method::springs, "springs"}, {Method::lagrange, "lagrange"}, {Method::featherstone, "featherstone"}};
  for (const auto& [method, name] : rows) {
    const std::vector<std::string> cells = readme_row(name);
    ASSERT_GE(cells.size(), 6u) << "README.md has no status row for " << name;
    const std::string& joints = cells[1];
    for (const JointType type : kJointTypes) {
      const bool named = joints.find(joint_type_name(type)) != std::string::npos;
      EXPECT_EQ(named, supports(method, type)) << name << "'s joints cell, " << joint_type_name(type) << ": " << joints;
    }
    const bool serial_without_actuators = supports(method, JointType::serial) && !capabilities(method).serial_actuators;
    EXPECT_EQ(joints.find("take no actuator") != std::string::npos, serial_without_actuators) << name << "'s joints cell: " << joints;
    EXPECT_EQ(cells[3].find("boxes and ellipsoids as themselves") != std::string::npos, capabilities(method).true_shapes)
        << name << "'s contacts: " << cells[3];
    EXPECT_EQ(cells[4].find("float") != std::string::npos, capabilities(method).single_precision) << name << "'s precision: " << cells[4];
    EXPECT_EQ(cells[5].find("1–n") != std::string::npos, capabilities(method).threads) << name << "'s threads: " << cells[5];
  }
}

}  // namespace
}  // namespace limber
