// MJCF documents into limber's Model (kernel/scene/mjcf_model.hpp): compound bodies, spheres,
// joints of several axes, ranges and springs measured from ref, motors; and each refusal names
// the file, the line and the element. MuJoCo's own agreement is mjcf_featherstone_test.cpp.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/mass/mass_properties.hpp"
#include "limber/kernel/scene/mjcf_document.hpp"
#include "limber/kernel/scene/mjcf_model.hpp"
#include "limber/kernel/scene/scene_file.hpp"

namespace limber {
namespace {

Model model_of(const std::string& xml, std::vector<std::string>* notes = nullptr) {
  std::vector<std::string> kept;
  return model_from_mjcf(mjcf::parse_mjcf(xml, "test.xml"), notes ? *notes : kept);
}

std::string refusal(const std::string& xml) {
  try {
    model_of(xml);
  } catch (const ModelError& error) {
    return error.what();
  }
  return "(accepted)";
}

// A torso of two capsules floating, a leg on two hinges (the second off the first's point, with
// ref, springref, stiffness, damping, armature and a range), a welded sphere foot, and motors.
const char* kLeg = R"(<mujoco model="leg">
  <compiler angle="radian"/>
  <option timestep="0.004" gravity="0 0 -9"/>
  <worldbody>
    <geom name="floor" type="plane" size="0 0 1" friction="0.8"/>
    <body name="torso" pos="0 0 2">
      <freejoint/>
      <geom type="capsule" fromto="0 -0.1 0 0 0.1 0" size="0.05"/>
      <geom name="belly" type="capsule" fromto="0 -0.1 -0.2 0 0.1 -0.2" size="0.05"/>
      <body name="leg" pos="0 0 -0.3">
        <joint name="hip_x" type="hinge" axis="1 0 0" limited="true" range="-0.5 0.7" ref="0.2" springref="0.3" stiffness="4" damping="0.5" armature="0.01"/>
        <joint name="hip_y" type="hinge" axis="0 1 0" pos="0 0 0.02" frictionloss="0.1"/>
        <geom type="cylinder" fromto="0 0 0 0 0 -0.4" size="0.04"/>
        <body name="foot" pos="0 0 -0.45">
          <geom type="sphere" size="0.05"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor joint="hip_y" gear="30" ctrllimited="true" ctrlrange="-1 1"/>
    <motor name="abduct" joint="hip_x" gear="20"/>
  </actuator>
</mujoco>)";

TEST(MjcfModel, GeomsAreWeldedBodiesAndJointsKeepTheirAxes) {
  std::vector<std::string> notes;
  const Model model = model_of(kLeg, &notes);
  ASSERT_EQ(model.bodies.size(), 4u);  // torso, torso/belly, leg, foot
  EXPECT_EQ(model.bodies[0].name, "torso");
  EXPECT_EQ(model.bodies[1].name, "torso/belly");
  EXPECT_EQ(model.bodies[3].shape.type, ShapeType::capsule);
  EXPECT_EQ(model.bodies[3].shape.length, 0);  // the sphere
  EXPECT_NEAR(model.bodies[3].shape.radius, 0.05, 1e-15);
  // Each body's mass is its geom's: density 1000 times its volume.
  const double pi = 3.141592653589793;
  EXPECT_NEAR(model.bodies[3].mass, 1000 * 4.0 / 3.0 * pi * 0.05 * 0.05 * 0.05, 1e-12);
  EXPECT_NEAR(model.bodies[2].mass, 1000 * pi * 0.04 * 0.04 * 0.4, 1e-12);
  // The torso floats (no joint); the belly and the foot are welds; the leg's two hinges are one
  // serial joint whose axes meet the file: the first through the leg's origin, the second 0.02 up.
  ASSERT_EQ(model.joints.size(), 3u);
  EXPECT_EQ(model.joints[0].type, JointType::fixed);
  const Joint& hip = model.joints[1];
  ASSERT_EQ(hip.type, JointType::serial);
  EXPECT_EQ(hip.name, "hip_x+hip_y");
  ASSERT_EQ(hip.serial_axes.size(), 2u);
  EXPECT_LT((hip.serial_axes[0].point - Eigen::Vector3d(0, 0, 1.7)).norm(), 1e-14);
  EXPECT_LT((hip.serial_axes[1].point - Eigen::Vector3d(0, 0, 1.72)).norm(), 1e-14);
  EXPECT_LT((hip.serial_axes[1].axis - Eigen::Vector3d::UnitY()).norm(), 1e-15);
  // limber's coordinate is MuJoCo's q − ref: the range and the spring's rest move by ref.
  ASSERT_TRUE(hip.serial_axes[0].range.has_value());
  EXPECT_NEAR(hip.serial_axes[0].range->min, -0.7, 1e-15);
  EXPECT_NEAR(hip.serial_axes[0].range->max, 0.5, 1e-15);
  ASSERT_TRUE(hip.serial_axes[0].drive.has_value());
  EXPECT_NEAR(hip.serial_axes[0].drive->target, 0.1, 1e-15);
  EXPECT_EQ(hip.serial_axes[0].drive->stiffness, 4);
  EXPECT_EQ(hip.serial_axes[0].drive->damping, 0.5);
  EXPECT_EQ(hip.serial_axes[0].armature, 0.01);
  EXPECT_EQ(hip.serial_axes[1].friction, 0.1);
  EXPECT_FALSE(hip.serial_axes[1].range.has_value());
  EXPECT_EQ(model.joints[2].type, JointType::fixed);  // the foot, welded to the leg
  // The ground, the settings, the motors in file order on their axes.
  ASSERT_TRUE(model.ground.has_value());
  EXPECT_EQ(model.ground->height, 0);
  EXPECT_EQ(model.ground->friction, 1.0);  // the larger of the floor's 0.8 and the body geoms' 1
  EXPECT_EQ(model.settings.time_step, 0.004);
  EXPECT_EQ(model.settings.gravity, Eigen::Vector3d(0, 0, -9));
  ASSERT_EQ(model.actuators.size(), 2u);
  EXPECT_EQ(model.actuators[0].joint, 1);
  EXPECT_EQ(model.actuators[0].axis, 1);
  EXPECT_EQ(model.actuators[0].gear, 30);
  ASSERT_TRUE(model.actuators[0].control_range.has_value());
  EXPECT_EQ(model.actuators[1].name, "abduct");
  EXPECT_EQ(model.actuators[1].axis, 0);
  EXPECT_FALSE(model.actuators[1].control_range.has_value());
}

TEST(MjcfModel, ACompoundBodysMassCentreIsItsGeomsWeightedMean) {
  const Model model = model_of(kLeg);
  const Body& upper = model.bodies[0];
  const Body& belly = model.bodies[1];
  const Eigen::Vector3d centre =
      (upper.mass * upper.to_world(body_mass_properties(upper).centre_of_mass) + belly.mass * belly.to_world(body_mass_properties(belly).centre_of_mass)) /
      (upper.mass + belly.mass);
  EXPECT_LT((centre - Eigen::Vector3d(0, 0, 1.9)).norm(), 1e-14);  // two equal capsules at z 2 and 1.8
}

TEST(MjcfModel, WhatCannotBeRepresentedIsRefusedNamingFileLineAndElement) {
  const auto body_with = [](const std::string& inside) {
    return "<mujoco>\n<worldbody>\n<body name=\"b\">\n<freejoint/>\n" + inside + "\n</body>\n</worldbody>\n</mujoco>";
  };
  EXPECT_EQ(refusal(body_with("<geom type=\"box\" size=\"0.1 0.1 0.1\"/>")),
            "test.xml:5: <geom type=box>: not supported on a moving body yet (limber's bodies are capsules, cylinders and spheres)");
  EXPECT_EQ(refusal(body_with("<geom size=\"0.1\" contype=\"1\" conaffinity=\"2\"/>")).substr(0, 32), "test.xml:5: <geom type=sphere>: ");
  EXPECT_NE(refusal(body_with("<geom size=\"0.1\"/><geom size=\"0.1\" pos=\"0 0 1\"/><inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"1 1 1\"/>"))
                .find("test.xml:3: <body name='b'>: an <inertial> on a body of several geoms"),
            std::string::npos);
  const std::string hinge_off_ref =
      "<mujoco>\n<compiler angle=\"radian\"/>\n<worldbody>\n<body>\n<geom size=\"0.1\"/>\n"
      "<joint name=\"h\" limited=\"true\" range=\"0.1 0.5\"/>\n</body>\n</worldbody>\n</mujoco>";
  EXPECT_EQ(refusal(hinge_off_ref).substr(0, 55), "test.xml:6: <joint name='h'>: range [0.100000, 0.500000");
  const std::string position_actuator =
      "<mujoco>\n<worldbody>\n<body>\n<geom size=\"0.1\"/>\n<joint name=\"h\"/>\n</body>\n</worldbody>\n"
      "<actuator>\n<position joint=\"h\"/>\n</actuator>\n</mujoco>";
  EXPECT_EQ(refusal(position_actuator), "test.xml:9: <position>: position and velocity actuators are not supported yet (motors are)");
}

TEST(MjcfModel, MujocosShippedModelsLoadOrAreRefusedByName) {
  const std::filesystem::path models = "/usr/share/mujoco/model";
  if (!std::filesystem::exists(models / "humanoid/humanoid.xml")) GTEST_SKIP() << models << " is missing: install libmujoco-samples";
  const Scene humanoid = load_scene_file(models / "humanoid/humanoid.xml");
  EXPECT_EQ(humanoid.model.bodies.size(), 19u);  // 16 bodies, 20 geoms less the floor
  EXPECT_EQ(humanoid.model.actuators.size(), 21u);
  EXPECT_FALSE(humanoid.notes.empty());  // the lights, cameras, textures and soft-contact parameters
  EXPECT_NEAR(humanoid.model.body_mass(), 40.844021, 1e-6);
  const Scene crowd = load_scene_file(models / "humanoid/22_humanoids.xml");
  EXPECT_EQ(crowd.model.bodies.size(), 22u * 19u);
  EXPECT_EQ(body_islands(crowd.model).count, 22u);
  // Each refusal names the file and line of the first element limber cannot represent.
  const auto refused = [&](const char* file) {
    try {
      load_scene_file(models / file);
    } catch (const ModelError& error) {
      return std::string(error.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_NE(refused("humanoid100/humanoid100.xml").find("humanoid100.xml:"), std::string::npos);
  EXPECT_NE(refused("hammock/hammock.xml").find("hammock.xml:52: <composite>"), std::string::npos);
  EXPECT_NE(refused("tendon_arm/arm26.xml").find("arm26.xml:"), std::string::npos);
  EXPECT_NE(refused("slider_crank/slider_crank.xml").find("slider_crank.xml:"), std::string::npos);
  SceneOptions copies;
  copies.copies = 2;
  EXPECT_THROW(load_scene_file(models / "humanoid/humanoid.xml", copies), ModelError);
}

}  // namespace
}  // namespace limber
