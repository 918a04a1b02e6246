// The URDF loader (kernel/scene/urdf.hpp): small hand-written robots for each element and
// attribute it reads, checked as physical facts (anchors meet in the world, the inertia tensor is
// the file's one rotated, the arm swings keeping its energy), one bad file per refusal naming
// file, line and element, and the same arm written as MJCF giving the same Model.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>


#include <gtest/gtest.h>

#include "limber/kernel/scene/mjcf_document.hpp"
#include "limber/kernel/scene/mjcf_model.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/scene/urdf.hpp"
#include "limber/kernel/world/world.hpp"
#include "tests/support/test_directory.hpp"

namespace limber {
namespace {

constexpr double kHalfPi = std::numbers::pi / 2;

// A base cylinder welded to the world, an upper arm (0.5 m) and a forearm (0.4 m) along +x on
// hinges about y: the arm lies horizontal at q = 0. The upper arm's inertial is turned (rpy)
// and has products of inertia, so moving it into the body frame is a real rotation.
const std::string kArm = R"(<?xml version="1.0"?>
<robot name="arm">
  <material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>
  <link name="base">
    <inertial><mass value="2"/><inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.01"/></inertial>
    <visual><geometry><cylinder radius="0.1" length="0.2"/></geometry></visual>
    <collision><geometry><cylinder radius="0.1" length="0.2"/></geometry></collision>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/>
    <child link="upper"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/>
    <axis xyz="0 1 0"/>
    <limit lower="-1.5" upper="1.5" effort="10" velocity="2"/>
  </joint>
  <link name="upper">
    <inertial>
      <origin xyz="0.25 0 0" rpy="0.3 0.2 0.1"/>
      <mass value="1"/>
      <inertia ixx="0.021" ixy="0.001" ixz="-0.002" iyy="0.02" iyz="0.0005" izz="0.003"/>
    </inertial>
    <collision>
      <origin xyz="0.25 0 0" rpy="0 1.5707963267948966 0"/>
      <geometry><cylinder radius="0.03" length="0.5"/></geometry>
    </collision>
  </link>
  <joint name="elbow" type="revolute">
    <parent link="upper"/>
    <child link="lower"/>
    <origin xyz="0.5 0 0"/>
    <axis xyz="0 2 0"/>
    <limit lower="-2" upper="2"/>
    <dynamics damping="0.1" friction="0.05"/>
  </joint>
  <link name="lower">
    <inertial>
      <origin xyz="0.2 0 0" rpy="0 1.5707963267948966 0"/>
      <mass value="0.5"/>
      <inertia ixx="0.0067" ixy="0" ixz="0" iyy="0.0067" iyz="0" izz="0.0001"/>
    </inertial>
    <collision>
      <origin xyz="0.2 0 0" rpy="0 1.5707963267948966 0"/>
      <geometry><cylinder radius="0.02" length="0.4"/></geometry>
    </collision>
  </link>
  <transmission name="t"><type>SimpleTransmission</type></transmission>
  <gazebo reference="upper"/>
</robot>
)";

Model parse(const std::string& xml, std::vector<std::string>* notes = nullptr, bool floating_base = false) {
  std::vector<std::string> dropped;
  return parse_urdf(xml, "robot.urdf", notes ? *notes : dropped, floating_base);
}

// The loader's message for a bad file (empty when it loads).
std::string error_of(const std::string& xml) {
  try {
    parse(xml);
  } catch (const ModelError& error) {
    return error.what();
  }
  return "";
}

// `text` with its first `from` replaced by `to` (the bad variants of a good file).
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// The 1-based line of the first occurrence of `needle` in `text`.
int line_of(const std::string& text, const std::string& needle) {
  const std::size_t at = text.find(needle);
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

void expect_near(const Eigen::Vector3d& actual, const Eigen::Vector3d& expected, double tolerance = 1e-12) {
  EXPECT_LT((actual - expected).norm(), tolerance) << actual.transpose() << " vs " << expected.transpose();
}

// Where joint `joint`'s anchors lie in the world, seen from its inboard and its outboard body.
std::pair<Eigen::Vector3d, Eigen::Vector3d> anchors_in_world(const Model& model, const Joint& joint) {
  const Eigen::Vector3d inboard = joint.inboard == kWorld ? joint.inboard_anchor
                                                          : model.bodies[static_cast<std::size_t>(joint.inboard)].to_world(joint.inboard_anchor);
  return {inboard, model.bodies[static_cast<std::size_t>(joint.outboard)].to_world(joint.outboard_anchor)};
}

Eigen::Matrix3d rpy(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

TEST(UrdfArm, LinksBecomeBodiesAtTheirCollisionPosesWithTheInertialMasses) {
  const Model model = parse(kArm);
  EXPECT_EQ(model.name, "arm");
  ASSERT_EQ(model.bodies.size(), 3u);
  EXPECT_EQ(model.bodies[0].name, "base");
  EXPECT_EQ(model.bodies[1].name, "upper");
  EXPECT_EQ(model.bodies[2].name, "lower");
  EXPECT_EQ(model.bodies[0].mass, 2);
  EXPECT_EQ(model.bodies[1].mass, 1);
  EXPECT_EQ(model.bodies[2].mass, 0.5);
  expect_near(model.bodies[0].position, {0, 0, 0});
  expect_near(model.bodies[1].position, {0.25, 0, 0.1});
  expect_near(model.bodies[2].position, {0.7, 0, 0.1});
  expect_near(model.bodies[1].axis, {1, 0, 0});  // the cylinder's z, turned by pitch π/2
  EXPECT_EQ(model.bodies[1].shape.type, ShapeType::cylinder);
  EXPECT_EQ(model.bodies[1].shape.length, 0.5);
  EXPECT_EQ(model.bodies[1].shape.radius, 0.03);
  EXPECT_FALSE(model.settings.sleep.enabled);
  expect_near(model.settings.gravity, {0, 0, -9.81});
  EXPECT_EQ(model.settings.time_step, 1.0 / 240);
  EXPECT_FALSE(model.ground.has_value());
}

TEST(UrdfArm, InertiaAboutTheCentreIsTheFilesTensorRotatedIntoTheWorld) {
  const Model model = parse(kArm);
  const Body& upper = model.bodies[1];
  ASSERT_TRUE(upper.inertial.has_value());
  // The link frame is the world turned by nothing, moved to (0, 0, 0.1); the inertial frame is
  // rpy (0.3, 0.2, 0.1) at (0.25, 0, 0) in it.
  Eigen::Matrix3d file;
  file << 0.021, 0.001, -0.002, 0.001, 0.02, 0.0005, -0.002, 0.0005, 0.003;
  const Eigen::Matrix3d turn = rpy(0.3, 0.2, 0.1);
  const Eigen::Matrix3d expected = turn * file * turn.transpose();
  const Eigen::Matrix3d body_to_world = upper.orientation().toRotationMatrix();
  const Eigen::Matrix3d world = body_to_world * upper.inertial->inertia * body_to_world.transpose();
  EXPECT_LT((world - expected).cwiseAbs().maxCoeff(), 1e-15);
  expect_near(upper.to_world(upper.inertial->centre_of_mass), {0.25, 0, 0.1});
}

// A <box> collision is a box body: half its size as half_extents, the collision frame (here
// turned by pitch π/2, so the box's z is the world's x) as its shape frame, its body axis along
// its longest side; the link keeps its <inertial> exactly, and no note is made of the box.
TEST(UrdfArm, ABoxLinkIsABoxInTheCollisionFrameKeepingItsInertial) {
  const std::string xml = replaced(kArm, "<geometry><cylinder radius=\"0.02\" length=\"0.4\"/></geometry>", "<geometry><box size=\"0.05 0.04 0.4\"/></geometry>");
  std::vector<std::string> notes;
  const Model model = parse(xml, &notes);
  const Body& lower = model.bodies[2];
  EXPECT_EQ(lower.shape.type, ShapeType::box);
  EXPECT_EQ(lower.shape.half_extents, Eigen::Vector3d(0.025, 0.02, 0.2));
  EXPECT_EQ(lower.shape.length, 0);
  EXPECT_EQ(lower.shape.radius, 0);
  const Eigen::Matrix3d box_to_world = (lower.orientation() * lower.shape.rotation).toRotationMatrix();
  expect_near(box_to_world.col(2), {1, 0, 0});  // the box's z, its longest side, along the world's x
  expect_near(box_to_world.col(1), {0, 1, 0});
  expect_near(lower.axis, {1, 0, 0});
  expect_near(lower.position, {0.7, 0, 0.1});
  EXPECT_EQ(lower.mass, 0.5);
  ASSERT_TRUE(lower.inertial.has_value());
  expect_near(lower.to_world(lower.inertial->centre_of_mass), {0.7, 0, 0.1});
  EXPECT_EQ(std::count_if(notes.begin(), notes.end(), [](const std::string& note) { return note.find("<box>") != std::string::npos; }), 0);
}

TEST(UrdfArm, JointsAreRevoluteAtTheirOriginsWithAxesRangesDampingAndFriction) {
  const Model model = parse(kArm);
  ASSERT_EQ(model.joints.size(), 3u);
  const Joint& weld = model.joints[0];
  EXPECT_EQ(weld.name, "base.weld");
  EXPECT_EQ(weld.type, JointType::fixed);
  EXPECT_EQ(weld.inboard, kWorld);
  EXPECT_EQ(weld.outboard, 0);
  const Joint& shoulder = model.joints[1];
  EXPECT_EQ(shoulder.name, "shoulder");
  EXPECT_EQ(shoulder.type, JointType::revolute);
  EXPECT_EQ(shoulder.inboard, 0);
  EXPECT_EQ(shoulder.outboard, 1);
  expect_near(shoulder.axis, {0, 1, 0});
  ASSERT_TRUE(shoulder.limits.range.has_value());
  EXPECT_EQ(shoulder.limits.range->min, -1.5);
  EXPECT_EQ(shoulder.limits.range->max, 1.5);
  EXPECT_FALSE(shoulder.drive.has_value());
  const Joint& elbow = model.joints[2];
  expect_near(elbow.axis, {0, 1, 0});  // "0 2 0" normalized
  ASSERT_TRUE(elbow.drive.has_value());
  EXPECT_EQ(elbow.drive->damping, 0.1);
  EXPECT_EQ(elbow.drive->stiffness, 0);
  EXPECT_EQ(elbow.drive->target_velocity, 0);
  EXPECT_EQ(elbow.friction, 0.05);
  // Each joint's anchors meet, in the world, at the child link's origin.
  const Eigen::Vector3d origins[3] = {{0, 0, 0}, {0, 0, 0.1}, {0.5, 0, 0.1}};
  for (std::size_t j = 0; j < 3; ++j) {
    const auto [inboard, outboard] = anchors_in_world(model, model.joints[j]);
    expect_near(inboard, origins[j]);
    expect_near(outboard, origins[j]);
  }
}

TEST(UrdfArm, NotesNameWhatWasIgnored) {
  std::vector<std::string> notes;
  parse(kArm, &notes);
  const auto noted = [&](const std::string& what) {
    return std::any_of(notes.begin(), notes.end(), [&](const std::string& note) { return note.find(what) != std::string::npos; });
  };
  EXPECT_TRUE(noted("robot.urdf:3: <material>: ignored"));
  EXPECT_TRUE(noted("<visual>: ignored"));
  EXPECT_TRUE(noted("<limit effort>: ignored"));
  EXPECT_TRUE(noted("<limit velocity>: ignored"));
  EXPECT_TRUE(noted("<transmission>: ignored"));
  EXPECT_TRUE(noted("<gazebo>: ignored"));
}

// The arm with both hinges unlimited and undamped: a double pendulum.
std::string free_arm() {
  std::string text = replaced(replaced(kArm, "type=\"revolute\"", "type=\"continuous\""), "type=\"revolute\"", "type=\"continuous\"");
  return replaced(text, "<dynamics damping=\"0.1\" friction=\"0.05\"/>", "");
}

TEST(UrdfArm, SwingsUnderFeatherstoneKeepingItsEnergy) {
  const Model model = parse(free_arm());
  World world(model, WorldOptions{.method = Method::featherstone});
  const double start = world.observe().energy();
  double largest = 0, lowest = 1;
  for (int s = 0; s < 240; ++s) {
    ASSERT_EQ(world.step(), StepStatus::ok) << s;
    largest = std::max(largest, std::abs(world.observe().energy() - start));
    lowest = std::min(lowest, world.pose(world.body("lower")).position.z());
  }
  EXPECT_LT(lowest, 0.1 - 0.3) << "the arm swings down";
  EXPECT_LT(largest, 1e-3) << "of about 6 J of potential energy swapped";
  RecordProperty("energy_error_J", std::to_string(largest));
  EXPECT_LT(world.observe().max_joint_gap, 1e-9);
}

TEST(UrdfArm, RunsUnderEveryMethod) {
  // The springs method has no fixed joints: the arm welded to the world by its base is refused,
  // naming the weld; with the base a massless frame (the world), the shoulder is the world's.
  EXPECT_THROW(
      {
        try {
          World world(parse(free_arm()), WorldOptions{.method = Method::springs});
        } catch (const ModelError& error) {
          EXPECT_NE(std::string(error.what()).find("'base.weld'"), std::string::npos) << error.what();
          throw;
        }
      },
      ModelError);
  const std::string base_as_frame = replaced(free_arm(), R"(<link name="base">
    <inertial><mass value="2"/><inertia ixx="0.02" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.01"/></inertial>
    <visual><geometry><cylinder radius="0.1" length="0.2"/></geometry></visual>
    <collision><geometry><cylinder radius="0.1" length="0.2"/></geometry></collision>
  </link>)", "<link name=\"base\"/>");
  const Model model = parse(base_as_frame);
  ASSERT_EQ(model.bodies.size(), 2u);
  ASSERT_EQ(model.joints[0].inboard, kWorld);
  for (Method method : {Method::particles, Method::springs, Method::lagrange, Method::featherstone}) {
    WorldOptions options{.method = method};
    options.springs.integrator = Integrator::backward_euler;  // stiff springs on light links: implicit (SpringOptions)
    World world(model, options);
    double lowest = 1;
    for (int s = 0; s < 100; ++s) {
      ASSERT_EQ(world.step(), StepStatus::ok) << method_name(method) << " step " << s;
      lowest = std::min(lowest, world.pose(world.body("lower")).position.z());
    }
    EXPECT_LT(lowest, 0.1 - 0.2) << method_name(method) << ": the arm swings down";
  }
}

TEST(UrdfRpy, IsYawPitchRollAboutTheFixedAxes) {
  // rpy (π/2, π/2, 0) is R_y(π/2)·R_x(π/2): the default axis x goes to −z. The other order
  // (x, then y about the moving axes: R_x·R_y) would give +y.
  const std::string wheel = R"(<robot name="cart">
  <link name="world"/>
  <joint name="wheel_spin" type="continuous">
    <parent link="world"/><child link="wheel"/>
    <origin xyz="1 2 3" rpy="1.5707963267948966 1.5707963267948966 0"/>
    <limit effort="1" velocity="1"/>
  </joint>
  <link name="wheel">
    <inertial><mass value="3"/><inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.15"/></inertial>
    <collision><geometry><cylinder radius="0.3" length="0.1"/></geometry></collision>
  </link>
</robot>)";
  const Model model = parse(wheel);
  ASSERT_EQ(model.bodies.size(), 1u);
  ASSERT_EQ(model.joints.size(), 1u);
  const Joint& spin = model.joints[0];
  EXPECT_EQ(spin.type, JointType::revolute);
  EXPECT_FALSE(spin.limits.range.has_value()) << "continuous: unlimited";
  EXPECT_EQ(spin.inboard, kWorld) << "the massless root link is the world";
  expect_near(spin.axis, {0, 0, -1});
  expect_near(spin.inboard_anchor, {1, 2, 3});
  // The wheel's z (its cylinder axis) goes to R_y(π/2)·R_x(π/2)·z = R_y(π/2)·(0, −1, 0) = (0, −1, 0).
  expect_near(model.bodies[0].axis, {0, -1, 0});
  expect_near(model.bodies[0].position, {1, 2, 3});
}

TEST(UrdfJoints, PrismaticSliderHasItsTravelInMetres) {
  const std::string slider = R"(<robot name="slider">
  <link name="rail">
    <inertial><mass value="5"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="0.1"/></inertial>
    <collision><origin xyz="0 0 0.5"/><geometry><cylinder radius="0.05" length="1"/></geometry></collision>
  </link>
  <joint name="slide" type="prismatic">
    <parent link="rail"/><child link="carriage"/>
    <origin xyz="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit lower="-0.1" upper="0.7" effort="100" velocity="1"/>
    <dynamics damping="3"/>
  </joint>
  <link name="carriage">
    <inertial><mass value="1"/><inertia ixx="0.004" ixy="0" ixz="0" iyy="0.004" iyz="0" izz="0.004"/></inertial>
    <collision><geometry><sphere radius="0.1"/></geometry></collision>
  </link>
</robot>)";
  const Model model = parse(slider);
  ASSERT_EQ(model.joints.size(), 2u);
  const Joint& slide = model.joints[1];
  EXPECT_EQ(slide.type, JointType::prismatic);
  expect_near(slide.axis, {0, 0, 1});
  ASSERT_TRUE(slide.limits.range.has_value());
  EXPECT_EQ(slide.limits.range->min, -0.1);
  EXPECT_EQ(slide.limits.range->max, 0.7);
  EXPECT_EQ(slide.drive->damping, 3);
  const Body& carriage = model.bodies[1];
  EXPECT_EQ(carriage.shape.type, ShapeType::capsule) << "a sphere is a capsule of length 0";
  EXPECT_EQ(carriage.shape.length, 0);
  EXPECT_EQ(carriage.shape.radius, 0.1);
  expect_near(carriage.position, {0, 0, 0.2});
  const auto [inboard, outboard] = anchors_in_world(model, slide);
  expect_near(inboard, {0, 0, 0.2});
  expect_near(outboard, {0, 0, 0.2});
}

// The arm with a tool sphere welded to the forearm's tip, a massless frame (flange) on it, and
// a wrist hinge after the frame: the frame folds away and the wrist's pose composes through it.
std::string arm_with_tool() {
  return replaced(kArm, "  <transmission", R"(  <joint name="tool_weld" type="fixed">
    <parent link="lower"/><child link="tool"/><origin xyz="0.4 0 0"/>
  </joint>
  <link name="tool">
    <inertial><mass value="0.2"/><inertia ixx="0.0002" ixy="0" ixz="0" iyy="0.0002" iyz="0" izz="0.0002"/></inertial>
    <collision><geometry><sphere radius="0.05"/></geometry></collision>
  </link>
  <joint name="flange_mount" type="fixed">
    <parent link="tool"/><child link="flange"/><origin xyz="0.05 0 0" rpy="0 0 1.5707963267948966"/>
  </joint>
  <link name="flange"/>
  <joint name="wrist" type="revolute">
    <parent link="flange"/><child link="finger"/><origin xyz="0.1 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1"/>
  </joint>
  <link name="finger">
    <inertial><mass value="0.1"/><inertia ixx="0.0001" ixy="0" ixz="0" iyy="0.0001" iyz="0" izz="0.0001"/></inertial>
    <collision><geometry><sphere radius="0.02"/></geometry></collision>
  </link>
  <transmission)");
}

TEST(UrdfJoints, FixedToolIsWeldedAndAFrameLinkFoldsIntoItsParent) {
  std::vector<std::string> notes;
  const Model model = parse(arm_with_tool(), &notes);
  ASSERT_EQ(model.bodies.size(), 5u);
  EXPECT_EQ(model.find_body("flange"), -1) << "a frame is no body";
  const Joint& weld = model.joints[3];
  EXPECT_EQ(weld.name, "tool_weld");
  EXPECT_EQ(weld.type, JointType::fixed);
  EXPECT_EQ(weld.inboard, model.find_body("lower"));
  expect_near(model.bodies[static_cast<std::size_t>(model.find_body("tool"))].position, {0.9, 0, 0.1});
  // The wrist hangs from the tool's body, at the flange's origin moved by the wrist's origin in
  // the flange frame (turned by yaw π/2): (0.95, 0, 0.1) + R_z(π/2)·(0.1, 0, 0).
  const Joint& wrist = model.joints[4];
  EXPECT_EQ(wrist.name, "wrist");
  EXPECT_EQ(wrist.inboard, model.find_body("tool"));
  EXPECT_EQ(wrist.outboard, model.find_body("finger"));
  expect_near(wrist.axis, {0, 1, 0});
  const auto [inboard, outboard] = anchors_in_world(model, wrist);
  expect_near(inboard, {0.95, 0.1, 0.1});
  expect_near(outboard, {0.95, 0.1, 0.1});
  EXPECT_TRUE(std::any_of(notes.begin(), notes.end(), [](const std::string& note) {
    return note.find("<link name='flange'>: a frame") != std::string::npos && note.find("folded into 'tool'") != std::string::npos;
  }));
}

TEST(UrdfJoints, FloatingBaseLeavesTheRootFree) {
  const Model welded = parse(kArm);
  const Model floating = parse(kArm, nullptr, /*floating_base=*/true);
  EXPECT_EQ(floating.joints.size(), welded.joints.size() - 1);
  for (const Joint& joint : floating.joints) EXPECT_NE(joint.inboard, kWorld) << joint.name;
  World world(floating, WorldOptions{.method = Method::featherstone});
  for (int s = 0; s < 24; ++s) ASSERT_EQ(world.step(), StepStatus::ok);
  EXPECT_LT(world.pose(world.body("base")).position.z(), -0.01) << "the whole robot falls";
}

TEST(UrdfJoints, FloatingJointFromTheRootFrameMakesAFreeBody) {
  const std::string drone = R"(<robot name="drone">
  <link name="world"/>
  <joint name="free" type="floating"><parent link="world"/><child link="body"/><origin xyz="0 0 2"/></joint>
  <link name="body">
    <inertial><mass value="1"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
    <collision><geometry><sphere radius="0.1"/></geometry></collision>
  </link>
</robot>)";
  const Model model = parse(drone);
  ASSERT_EQ(model.bodies.size(), 1u);
  EXPECT_TRUE(model.joints.empty());
  expect_near(model.bodies[0].position, {0, 0, 2});
}

TEST(UrdfSceneFile, LoadSceneFileReadsUrdfWithItsNotesAndFloatingBase) {
  const std::filesystem::path file = limber::testing::test_directory() / "arm.urdf";
  std::ofstream(file) << kArm;
  const Scene welded = load_scene_file(file);
  EXPECT_EQ(welded.model.bodies.size(), 3u);
  EXPECT_EQ(welded.model.joints.size(), 3u);
  EXPECT_FALSE(welded.notes.empty());
  EXPECT_EQ(welded.notes.front().rfind(file.string() + ":3: <material>", 0), 0u) << welded.notes.front();
  SceneOptions floating;
  floating.floating_base = true;
  EXPECT_EQ(load_scene_file(file, floating).model.joints.size(), 2u);
  std::filesystem::remove(file);
  const std::filesystem::path json = std::filesystem::path(LIMBER_SOURCE_DIR) / "tools/scenes/chain.json";
  EXPECT_THROW(load_scene_file(json, floating), ModelError) << "a floating base is for URDF robots only";
}

// ---- refusals: one line naming file, line and element ----

void expect_refused(const std::string& xml, const std::string& line_text, const std::string& element, const std::string& problem) {
  const std::string message = error_of(xml);
  const std::string place = "robot.urdf:" + std::to_string(line_of(xml, line_text)) + ": " + element;
  EXPECT_NE(message.find(place), std::string::npos) << message << "\n  expected: " << place;
  EXPECT_NE(message.find(problem), std::string::npos) << message << "\n  expected: " << problem;
  EXPECT_EQ(message.find('\n'), std::string::npos) << "one line";
}

TEST(UrdfErrors, RevoluteWithoutLimit) {
  const std::string xml = replaced(kArm, "<limit lower=\"-2\" upper=\"2\"/>", "");
  expect_refused(xml, "<joint name=\"elbow\"", "<joint name='elbow'>", "needs a <limit lower upper>");
}

TEST(UrdfErrors, LimitWithoutLowerWouldLockTheJoint) {
  const std::string xml = replaced(kArm, "<limit lower=\"-2\" upper=\"2\"/>", "<limit upper=\"2\"/>");
  expect_refused(xml, "<limit upper=\"2\"/>", "<limit lower>", "missing");
}

TEST(UrdfErrors, RangeMustHoldTheFilePoseAndStayInsidePi) {
  expect_refused(replaced(kArm, "lower=\"-2\" upper=\"2\"", "lower=\"0.5\" upper=\"2\""), "lower=\"0.5\"", "<limit>", "does not hold 0");
  expect_refused(replaced(kArm, "lower=\"-2\" upper=\"2\"", "lower=\"-2\" upper=\"3.2\""), "upper=\"3.2\"", "<limit>", "±π");
}

TEST(UrdfErrors, MeshGeometryNamesItsFile) {
  const std::string xml =
      replaced(kArm, "<geometry><cylinder radius=\"0.02\" length=\"0.4\"/></geometry>", "<geometry><mesh filename=\"package://arm/forearm.stl\"/></geometry>");
  expect_refused(xml, "<mesh", "<mesh filename='package://arm/forearm.stl'>", "meshes are not supported yet");
}


TEST(UrdfErrors, SeveralCollisionShapes) {
  const std::string xml = replaced(kArm, "  </link>\n  <joint name=\"elbow\"",
                                   "    <collision><geometry><sphere radius=\"0.05\"/></geometry></collision>\n  </link>\n  <joint name=\"elbow\"");
  expect_refused(xml, "<collision><geometry><sphere", "<collision> of link 'upper'", "several collision shapes on one link are not supported yet");
}

TEST(UrdfErrors, LinkWithMassButNoGeometry) {
  const std::string xml = replaced(kArm, R"(    <collision>
      <origin xyz="0.2 0 0" rpy="0 1.5707963267948966 0"/>
      <geometry><cylinder radius="0.02" length="0.4"/></geometry>
    </collision>
)", "");
  expect_refused(xml, "<link name=\"lower\"", "<link name='lower'>", "a link without collision geometry is not supported yet");
}

TEST(UrdfErrors, MimicJoint) {
  const std::string xml = replaced(kArm, "<dynamics damping", "<mimic joint=\"shoulder\" multiplier=\"1\"/>\n    <dynamics damping");
  expect_refused(xml, "<mimic", "<mimic>", "couples two joints");
}

TEST(UrdfErrors, LoopNamesBothJoints) {
  const std::string xml = replaced(kArm, "  <transmission", R"(  <joint name="closing" type="fixed"><parent link="base"/><child link="lower"/></joint>
  <transmission)");
  expect_refused(xml, "<joint name=\"closing\"", "<joint name='closing'>", "two parent joints, 'elbow' (line ");
}

TEST(UrdfErrors, UnknownLink) {
  const std::string xml = replaced(kArm, "<child link=\"lower\"/>", "<child link=\"forearm\"/>");
  expect_refused(xml, "<child link=\"forearm\"/>", "<child link>", "unknown link 'forearm'");
}

TEST(UrdfErrors, PlanarJoint) {
  const std::string xml = replaced(kArm, "<joint name=\"elbow\" type=\"revolute\">", "<joint name=\"elbow\" type=\"planar\">");
  expect_refused(xml, "type=\"planar\"", "<joint name='elbow'>", "a planar joint is not supported yet");
}

TEST(UrdfErrors, MalformedNumberIsQuoted) {
  const std::string xml = replaced(kArm, "<origin xyz=\"0.5 0 0\"/>", "<origin xyz=\"0.5 0 zero\"/>");
  expect_refused(xml, "zero", "<origin xyz>", "expected 3 numbers, got '0.5 0 zero'");
}

TEST(UrdfErrors, SeveralRootsAndUnknownElements) {
  const std::string two_roots = replaced(kArm, "  <transmission", R"(  <link name="spare">
    <inertial><mass value="1"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
    <collision><geometry><sphere radius="0.1"/></geometry></collision>
  </link>
  <transmission)");
  expect_refused(two_roots, "<robot", "<robot>", "several root links ('base', 'spare')");
  expect_refused(replaced(kArm, "<dynamics damping", "<spring k=\"1\"/>\n    <dynamics damping"), "<spring", "<spring>",
                 "unknown element");
  expect_refused(replaced(kArm, "<link name=\"lower\">", "<link name=\"lower\" colour=\"red\">"), "colour", "<link colour>",
                 "unknown attribute");
}

TEST(UrdfErrors, MovingJointIntoAFrame) {
  const std::string xml = replaced(arm_with_tool(), "<joint name=\"flange_mount\" type=\"fixed\">", "<joint name=\"flange_mount\" type=\"continuous\">");
  expect_refused(xml, "<joint name=\"flange_mount\"", "<joint name='flange_mount'>", "a frame (no mass, no collision geometry)");
}

TEST(UrdfErrors, UnreadableFileAndBadXml) {
  std::vector<std::string> notes;
  EXPECT_THROW(load_urdf("/nonexistent/robot.urdf", notes), ModelError);
  expect_refused("<robot name=\"x\">\n  <link name=\"a\">\n</robot>\n", "</robot>", "XML error", "");
  expect_refused("<mujoco/>", "<mujoco", "<mujoco>", "not a URDF file");
}

// ---- the same arm as MJCF ----

// kArm in MuJoCo's words: bodies at the URDF joint origins, hinges at their body origins, geoms at
// the collision poses, and the URDF inertials as <inertial> in each body's frame (fullinertia:
// the file's tensor turned by the inertial's rpy, computed below).
std::string arm_as_mjcf() {
  const Eigen::Matrix3d turn = rpy(0.3, 0.2, 0.1);
  Eigen::Matrix3d file;
  file << 0.021, 0.001, -0.002, 0.001, 0.02, 0.0005, -0.002, 0.0005, 0.003;
  const Eigen::Matrix3d upper = turn * file * turn.transpose();
  char full[256];
  std::snprintf(full, sizeof full, "%.17g %.17g %.17g %.17g %.17g %.17g", upper(0, 0), upper(1, 1), upper(2, 2), upper(0, 1),
                upper(0, 2), upper(1, 2));
  // The forearm's inertial rpy (0, π/2, 0) swaps its x and z moments.
  return std::string(R"(<mujoco model="arm">
  <compiler angle="radian"/>
  <worldbody>
    <body name="base">
      <inertial pos="0 0 0" mass="2" diaginertia="0.02 0.02 0.01"/>
      <geom type="cylinder" size="0.1 0.1"/>
      <body name="upper" pos="0 0 0.1">
        <joint name="shoulder" axis="0 1 0" limited="true" range="-1.5 1.5"/>
        <inertial pos="0.25 0 0" mass="1" fullinertia=")") +
         full + R"("/>
        <geom type="cylinder" size="0.03 0.25" pos="0.25 0 0" euler="0 1.5707963267948966 0"/>
        <body name="lower" pos="0.5 0 0">
          <joint name="elbow" axis="0 1 0" limited="true" range="-2 2" damping="0.1" frictionloss="0.05"/>
          <inertial pos="0.2 0 0" mass="0.5" diaginertia="0.0001 0.0067 0.0067"/>
          <geom type="cylinder" size="0.02 0.2" pos="0.2 0 0" euler="0 1.5707963267948966 0"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
)";
}

TEST(UrdfAgreesWithMjcf, TheSameArmGivesTheSameModel) {
  std::vector<std::string> notes;
  const Model from_urdf = parse(kArm);
  const Model from_mjcf = model_from_mjcf(mjcf::parse_mjcf(arm_as_mjcf(), "arm.xml"), notes);
  ASSERT_EQ(from_urdf.bodies.size(), from_mjcf.bodies.size());
  for (std::size_t b = 0; b < from_urdf.bodies.size(); ++b) {
    const Body &u = from_urdf.bodies[b], &m = from_mjcf.bodies[b];
    SCOPED_TRACE(u.name);
    EXPECT_EQ(u.name, m.name);
    EXPECT_DOUBLE_EQ(u.mass, m.mass);
    expect_near(u.position, m.position, 1e-12);
    expect_near(u.axis, m.axis, 1e-12);
    EXPECT_EQ(u.shape.type, m.shape.type);
    EXPECT_NEAR(u.shape.length, m.shape.length, 1e-15);
    EXPECT_EQ(u.shape.radius, m.shape.radius);
    ASSERT_TRUE(u.inertial && m.inertial);
    expect_near(u.inertial->centre_of_mass, m.inertial->centre_of_mass, 1e-12);
    EXPECT_LT((u.inertial->inertia - m.inertial->inertia).cwiseAbs().maxCoeff(), 1e-12);
  }
  ASSERT_EQ(from_urdf.joints.size(), from_mjcf.joints.size());
  for (std::size_t j = 0; j < from_urdf.joints.size(); ++j) {
    const Joint &u = from_urdf.joints[j], &m = from_mjcf.joints[j];
    SCOPED_TRACE(u.name);
    EXPECT_EQ(u.name, m.name);
    EXPECT_EQ(u.type, m.type);
    EXPECT_EQ(u.inboard, m.inboard);
    EXPECT_EQ(u.outboard, m.outboard);
    expect_near(u.inboard_anchor, m.inboard_anchor, 1e-12);
    expect_near(u.outboard_anchor, m.outboard_anchor, 1e-12);
    if (u.type == JointType::revolute) {
      expect_near(u.axis, m.axis, 1e-12);
      ASSERT_TRUE(u.limits.range && m.limits.range);
      EXPECT_DOUBLE_EQ(u.limits.range->min, m.limits.range->min);
      EXPECT_DOUBLE_EQ(u.limits.range->max, m.limits.range->max);
      EXPECT_EQ(u.drive.has_value(), m.drive.has_value());
      if (u.drive) {
        EXPECT_EQ(u.drive->damping, m.drive->damping);
      }
      EXPECT_EQ(u.friction, m.friction);
    }
  }
}

}  // namespace
}  // namespace limber
