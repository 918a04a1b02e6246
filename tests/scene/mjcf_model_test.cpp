// MJCF documents into limber's Model (kernel/scene/mjcf_model.hpp): compound bodies, spheres,
// joints of several axes, ranges and springs measured from ref, motors; and each refusal names
// the file, the line and the element. MuJoCo's own agreement is mjcf_featherstone_test.cpp.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/mass/mass_properties.hpp"
#include "limber/kernel/scene/mjcf_document.hpp"
#include "limber/kernel/scene/mjcf_model.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "tests/support/test_directory.hpp"

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
    <position name="hold" joint="hip_x" gear="2" kp="50"/>
    <velocity name="spin" joint="hip_y" kv="3"/>
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
  ASSERT_EQ(model.actuators.size(), 4u);
  EXPECT_EQ(model.actuators[0].joint, 1);
  EXPECT_EQ(model.actuators[0].axis, 1);
  EXPECT_EQ(model.actuators[0].gear, 30);
  ASSERT_TRUE(model.actuators[0].control_range.has_value());
  EXPECT_EQ(model.actuators[1].name, "abduct");
  EXPECT_EQ(model.actuators[1].axis, 0);
  EXPECT_FALSE(model.actuators[1].control_range.has_value());
  EXPECT_EQ(model.actuators[2].kind, ActuatorKind::position);  // MuJoCo's length gear·qpos, qpos = limber's q + ref
  EXPECT_EQ(model.actuators[2].gain, 50);
  EXPECT_EQ(model.actuators[2].reference, 0.2);
  EXPECT_EQ(model.actuators[3].kind, ActuatorKind::velocity);
  EXPECT_EQ(model.actuators[3].gain, 3);
  EXPECT_EQ(model.actuators[3].gear, 1);
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
  EXPECT_EQ(refusal(body_with("<geom size=\"0.1\" contype=\"1\" conaffinity=\"2\"/>")).substr(0, 32), "test.xml:5: <geom type=sphere>: ");
  EXPECT_NE(refusal(body_with("<geom size=\"0.1\"/><geom size=\"0.1\" pos=\"0 0 1\"/><inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"1 1 1\"/>"))
                .find("test.xml:3: <body name='b'>: an <inertial> on a body of several geoms"),
            std::string::npos);
  const std::string hinge_off_ref =
      "<mujoco>\n<compiler angle=\"radian\"/>\n<worldbody>\n<body>\n<geom size=\"0.1\"/>\n"
      "<joint name=\"h\" limited=\"true\" range=\"0.1 0.5\"/>\n</body>\n</worldbody>\n</mujoco>";
  EXPECT_EQ(refusal(hinge_off_ref).substr(0, 55), "test.xml:6: <joint name='h'>: range [0.100000, 0.500000");
  const std::string force_limited =
      "<mujoco>\n<worldbody>\n<body>\n<geom size=\"0.1\"/>\n<joint name=\"h\"/>\n</body>\n</worldbody>\n"
      "<actuator>\n<position joint=\"h\" forcelimited=\"true\" forcerange=\"-1 1\"/>\n</actuator>\n</mujoco>";
  EXPECT_EQ(refusal(force_limited), "test.xml:9: <position>: forcerange is not supported yet (ctrlrange is)");
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
  const Scene hundred = load_scene_file(models / "humanoid100/humanoid100.xml");
  EXPECT_EQ(body_islands(hundred.model).count, 101u);  // the humanoid and 100 free objects
  EXPECT_NE(refused("hammock/hammock.xml").find("hammock.xml:52: <composite>"), std::string::npos);
  EXPECT_NE(refused("tendon_arm/arm26.xml").find("arm26.xml:"), std::string::npos);
  EXPECT_NE(refused("slider_crank/slider_crank.xml").find("slider_crank.xml:"), std::string::npos);
  SceneOptions copies;
  copies.copies = 2;
  EXPECT_THROW(load_scene_file(models / "humanoid/humanoid.xml", copies), ModelError);
}

// A box or ellipsoid geom on a moving body is a box or ellipsoid body: the geom's size its
// half_extents, the geom's frame its shape frame, and from that shape the geom's mass, centre and
// inertia. Every one-geom body of humanoid100.xml (capsules, ellipsoids, boxes, cylinders,
// spheres) carries the document's mass properties, which mjcf_mujoco_test.cpp checks against
// mj_loadXML, moved into the world; no note is made of the boxes and ellipsoids.
TEST(MjcfModel, BoxesAndEllipsoidsKeepTheirMassCentreAndInertia) {
  const std::filesystem::path file = "/usr/share/mujoco/model/humanoid100/humanoid100.xml";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " is missing: install libmujoco-samples";
  const mjcf::Document document = mjcf::load_mjcf(file);
  std::vector<std::string> notes;
  const Model model = model_from_mjcf(document, notes);
  int checked = 0, boxes_and_ellipsoids = 0;
  Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();
  for (std::size_t b = 0; b < document.bodies.size(); ++b) {
    const mjcf::Body& source = document.bodies[b];
    if (source.parent >= 0 || source.geoms.size() != 1) continue;  // the free objects: children of the world
    frame.linear() = source.orientation.normalized().toRotationMatrix();
    frame.translation() = source.position;
    const std::string name = source.name.empty() ? "body" + std::to_string(b + 1) : source.name;
    const auto body = std::find_if(model.bodies.begin(), model.bodies.end(), [&](const Body& each) { return each.name == name; });
    ASSERT_NE(body, model.bodies.end()) << name;
    SCOPED_TRACE(name);
    const MassProperties limber = body_mass_properties(*body);
    const Eigen::Matrix3d to_world = body->orientation().toRotationMatrix();
    EXPECT_LE(std::abs(limber.mass - source.mass), 1e-12 * source.mass);
    EXPECT_LE((body->to_world(limber.centre_of_mass) - frame * source.centre_of_mass).norm(), 1e-12);
    const Eigen::Matrix3d mujoco = frame.linear() * source.inertia * frame.linear().transpose();
    EXPECT_LE((to_world * limber.inertia * to_world.transpose() - mujoco).cwiseAbs().maxCoeff(), 1e-10 * mujoco.norm());
    const mjcf::Geom& geom = source.geoms.front();
    if (geom.type == mjcf::GeomType::box || geom.type == mjcf::GeomType::ellipsoid) {
      ++boxes_and_ellipsoids;
      EXPECT_EQ(body->shape.type, geom.type == mjcf::GeomType::box ? ShapeType::box : ShapeType::ellipsoid);
      EXPECT_EQ(body->shape.half_extents, geom.size) << "the geom's size";
      EXPECT_EQ(body->shape.length, 0);
      EXPECT_EQ(body->shape.radius, 0);
      const Eigen::Matrix3d geom_to_world = frame.linear() * geom.orientation.normalized().toRotationMatrix();
      EXPECT_LE((to_world * body->shape.rotation.toRotationMatrix() - geom_to_world).cwiseAbs().maxCoeff(), 1e-12) << "the geom's frame";
    }
    ++checked;
  }
  EXPECT_EQ(checked, 100);
  EXPECT_EQ(boxes_and_ellipsoids, 40);
  for (const std::string& note : notes) {
    EXPECT_EQ(note.find("capsule"), std::string::npos) << "no note stands a capsule in for a box or ellipsoid: " << note;
  }
}

}  // namespace
}  // namespace limber

namespace limber {
namespace {

// kLeg written by hand in limber's JSON scene format: each geom a body at its centre, its axis
// the geom's z (MuJoCo's fromto runs it from `to` to `from`), anchors in the bodies' frames (the
// body frame is the shortest turn of z onto the axis: the torso's, about +x, takes world (0,0,-0.3)
// to local (0,-0.3,0)), contype and conaffinity 1 as group and mask 1, ranges and the spring's
// rest less ref, the motors on the hip's axes.
const char* kLegJson = R"({
  "limber_scene": 1, "name": "leg",
  "settings": {"gravity": [0, 0, -9], "time_step": 0.004, "duration": 5, "limb_friction": 1, "sleep": {"enabled": false}},
  "ground": {"height": 0, "restitution": 0, "friction": 1},
  "bodies": [
    {"name": "torso", "shape": {"type": "capsule", "length": 0.2, "radius": 0.05}, "density": 1000, "position": [0, 0, 2], "axis": [0, -1, 0], "collision": {"group": 1, "mask": 1}},
    {"name": "torso/belly", "shape": {"type": "capsule", "length": 0.2, "radius": 0.05}, "density": 1000, "position": [0, 0, 1.8], "axis": [0, -1, 0], "collision": {"group": 1, "mask": 1}},
    {"name": "leg", "shape": {"type": "cylinder", "length": 0.4, "radius": 0.04}, "density": 1000, "position": [0, 0, 1.5], "axis": [0, 0, 1], "collision": {"group": 1, "mask": 1}},
    {"name": "foot", "shape": {"type": "capsule", "length": 0, "radius": 0.05}, "density": 1000, "position": [0, 0, 1.25], "axis": [0, 0, 1], "collision": {"group": 1, "mask": 1}}
  ],
  "joints": [
    {"name": "torso/belly.weld", "type": "fixed", "inboard": "torso", "outboard": "torso/belly",
     "inboard_anchor": [0, -0.2, 0], "outboard_anchor": [0, 0, 0]},
    {"name": "hip_x+hip_y", "type": "serial", "inboard": "torso", "outboard": "leg",
     "inboard_anchor": [0, -0.3, 0], "outboard_anchor": [0, 0, 0.22],
     "serial_axes": [
       {"name": "hip_x", "axis": [1, 0, 0], "point": [0, 0, 1.7], "range": [-0.7, 0.5],
        "drive": {"stiffness": 4, "damping": 0.5, "target": 0.1}, "armature": 0.01},
       {"name": "hip_y", "axis": [0, 1, 0], "point": [0, 0, 1.72], "friction": 0.1}]},
    {"name": "foot.weld", "type": "fixed", "inboard": "leg", "outboard": "foot",
     "inboard_anchor": [0, 0, -0.25], "outboard_anchor": [0, 0, 0]}
  ],
  "actuators": [
    {"name": "actuator0", "joint": "hip_x+hip_y", "axis": "hip_y", "gear": 30, "control_range": [-1, 1]},
    {"name": "abduct", "joint": "hip_x+hip_y", "axis": "hip_x", "gear": 20},
    {"name": "hold", "joint": "hip_x+hip_y", "axis": "hip_x", "kind": "position", "gear": 2, "gain": 50, "reference": 0.2},
    {"name": "spin", "joint": "hip_x+hip_y", "axis": "hip_y", "kind": "velocity", "gear": 1, "gain": 3}
  ]
})";

void expect_near(const Vector3& a, const Vector3& b, const std::string& what) { EXPECT_LT((a - b).norm(), 1e-12) << what; }

void expect_same_drive(const std::optional<JointDrive>& a, const std::optional<JointDrive>& b, const std::string& what) {
  ASSERT_EQ(a.has_value(), b.has_value()) << what;
  if (!a) return;
  EXPECT_NEAR(a->stiffness, b->stiffness, 1e-12) << what;
  EXPECT_NEAR(a->damping, b->damping, 1e-12) << what;
  EXPECT_NEAR(a->target, b->target, 1e-12) << what;
  EXPECT_NEAR(a->target_velocity, b->target_velocity, 1e-12) << what;
}

void expect_same_range(const std::optional<Range>& a, const std::optional<Range>& b, const std::string& what) {
  ASSERT_EQ(a.has_value(), b.has_value()) << what;
  if (!a) return;
  EXPECT_NEAR(a->min, b->min, 1e-12) << what;
  EXPECT_NEAR(a->max, b->max, 1e-12) << what;
}

TEST(MjcfModel, TheSameModelFromMjcfAndFromItsJson) {
  const Model mjcf = model_of(kLeg);
  const Model json = load_scene_text(kLegJson, "leg.json").model;
  EXPECT_EQ(json.name, mjcf.name);
  ASSERT_EQ(json.bodies.size(), mjcf.bodies.size());
  for (std::size_t b = 0; b < mjcf.bodies.size(); ++b) {
    const Body &x = mjcf.bodies[b], &y = json.bodies[b];
    const std::string what = "bodies[" + std::to_string(b) + "] " + x.name;
    EXPECT_EQ(y.name, x.name);
    EXPECT_EQ(y.shape.type, x.shape.type) << what;
    EXPECT_NEAR(y.shape.length, x.shape.length, 1e-12) << what;
    EXPECT_NEAR(y.shape.radius, x.shape.radius, 1e-12) << what;
    EXPECT_NEAR(y.mass, x.mass, 1e-12 * x.mass) << what;
    EXPECT_EQ(y.inertial.has_value(), x.inertial.has_value()) << what;
    EXPECT_EQ(y.point_masses.size(), x.point_masses.size()) << what;
    expect_near(y.position, x.position, what + " position");
    expect_near(y.axis, x.axis, what + " axis");
    EXPECT_EQ(y.collision.group, x.collision.group) << what;
    EXPECT_EQ(y.collision.mask, x.collision.mask) << what;
  }
  ASSERT_EQ(json.joints.size(), mjcf.joints.size());
  for (std::size_t j = 0; j < mjcf.joints.size(); ++j) {
    const Joint &x = mjcf.joints[j], &y = json.joints[j];
    const std::string what = "joints[" + std::to_string(j) + "] " + x.name;
    EXPECT_EQ(y.name, x.name);
    EXPECT_EQ(y.type, x.type) << what;
    EXPECT_EQ(y.inboard, x.inboard) << what;
    EXPECT_EQ(y.outboard, x.outboard) << what;
    expect_near(y.inboard_anchor, x.inboard_anchor, what + " inboard_anchor");
    expect_near(y.outboard_anchor, x.outboard_anchor, what + " outboard_anchor");
    EXPECT_EQ(y.friction, x.friction) << what;
    EXPECT_EQ(y.armature, x.armature) << what;
    expect_same_drive(y.drive, x.drive, what);
    EXPECT_EQ(y.limits.any(), x.limits.any()) << what;
    ASSERT_EQ(y.serial_axes.size(), x.serial_axes.size()) << what;
    for (std::size_t a = 0; a < x.serial_axes.size(); ++a) {
      const SerialAxis &p = x.serial_axes[a], &q = y.serial_axes[a];
      const std::string axis = what + " axis " + p.name;
      EXPECT_EQ(q.name, p.name) << axis;
      EXPECT_EQ(q.slide, p.slide) << axis;
      expect_near(q.axis, p.axis, axis + " axis");
      expect_near(q.point, p.point, axis + " point");
      expect_same_range(q.range, p.range, axis + " range");
      expect_same_drive(q.drive, p.drive, axis + " drive");
      EXPECT_NEAR(q.friction, p.friction, 1e-15) << axis;
      EXPECT_NEAR(q.armature, p.armature, 1e-15) << axis;
    }
  }
  ASSERT_EQ(json.actuators.size(), mjcf.actuators.size());
  for (std::size_t a = 0; a < mjcf.actuators.size(); ++a) {
    const Actuator &x = mjcf.actuators[a], &y = json.actuators[a];
    EXPECT_EQ(y.name, x.name);
    EXPECT_EQ(y.joint, x.joint) << x.name;
    EXPECT_EQ(y.axis, x.axis) << x.name;
    EXPECT_EQ(y.gear, x.gear) << x.name;
    EXPECT_EQ(y.kind, x.kind) << x.name;
    EXPECT_EQ(y.gain, x.gain) << x.name;
    EXPECT_EQ(y.reference, x.reference) << x.name;
    expect_same_range(y.control_range, x.control_range, x.name);
  }
  ASSERT_TRUE(json.ground && mjcf.ground);
  EXPECT_EQ(json.ground->height, mjcf.ground->height);
  EXPECT_EQ(json.ground->friction, mjcf.ground->friction);
  EXPECT_EQ(json.ground->restitution, mjcf.ground->restitution);
  EXPECT_EQ(json.settings.gravity, mjcf.settings.gravity);
  EXPECT_EQ(json.settings.time_step, mjcf.settings.time_step);
  EXPECT_EQ(json.settings.duration, mjcf.settings.duration);
  EXPECT_EQ(json.settings.limb_friction, mjcf.settings.limb_friction);
  EXPECT_EQ(json.settings.sleep.enabled, mjcf.settings.sleep.enabled);
  EXPECT_TRUE(json.colliders.empty() && mjcf.colliders.empty());
}

// A JSON scene that wraps kLeg: the model file's bodies, joints and actuators, the wrapper's name
// and settings over the file's (the rest kept), and its errors named by field.
TEST(MjcfModel, ASceneFileWrapsAModelFileWithLimbersSettings) {
  const auto dir = limber::testing::test_directory();
  std::filesystem::create_directories(dir / "models");
  std::ofstream(dir / "models" / "leg.xml") << kLeg;
  const auto write = [&](const std::string& text) {
    std::ofstream(dir / "wrap.json") << text;
    return dir / "wrap.json";
  };
  const Scene plain = load_scene_file(dir / "models" / "leg.xml");
  const Scene wrapped = load_scene_file(write(R"({"limber_scene": 1, "model": "models/leg.xml", "name": "leg, finer",
    "settings": {"time_step": 0.001, "limb_friction": 0.3, "relaxation": {"iterations": 8}}})"));
  EXPECT_EQ(wrapped.model.name, "leg, finer");
  EXPECT_EQ(wrapped.model.bodies.size(), plain.model.bodies.size());
  EXPECT_EQ(wrapped.model.joints.size(), plain.model.joints.size());
  EXPECT_EQ(wrapped.model.actuators.size(), plain.model.actuators.size());
  EXPECT_EQ(wrapped.model.settings.time_step, 0.001);
  EXPECT_EQ(wrapped.model.settings.limb_friction, 0.3);
  EXPECT_EQ(wrapped.model.settings.gravity, plain.model.settings.gravity) << "the file's, kept";
  EXPECT_EQ(wrapped.methods.relaxation.iterations, 8);
  EXPECT_EQ(wrapped.methods.relaxation.substeps, plain.methods.relaxation.substeps) << "the import's, kept";
  EXPECT_EQ(wrapped.methods.verlet.joint_solve, JointSolve::tree);
  EXPECT_EQ(wrapped.notes, plain.notes);
  const auto refusal_of = [&](const std::string& text) {
    try {
      load_scene_file(write(text));
    } catch (const ModelError& error) {
      return std::string(error.what());
    }
    return std::string("(accepted)");
  };
  const std::string wrap = (dir / "wrap.json").string();
  EXPECT_EQ(refusal_of(R"({"limber_scene": 1, "model": "models/leg.xml", "bodies": []})"),
            wrap + ": bodies: a scene that wraps a model file takes only limber_scene, name, description, model, floating_base and settings");
  EXPECT_EQ(refusal_of(R"({"limber_scene": 1, "model": "models/leg.json"})"),
            wrap + ": model: must name an MJCF (.xml) or URDF (.urdf) file, got \"models/leg.json\"");
  EXPECT_NE(refusal_of(R"({"limber_scene": 1, "model": "models/leg.xml", "settings": {"time_step": -1}})").find(wrap + ": settings.time_step:"),
            std::string::npos);
  EXPECT_NE(refusal_of(R"({"limber_scene": 1, "model": "models/arm.xml"})").find("models/arm.xml: cannot read"), std::string::npos);
  EXPECT_NE(refusal_of(R"({"limber_scene": 1, "model": "models/leg.xml", "floating_base": true})").find("only a URDF robot"), std::string::npos);
}

TEST(MjcfModel, TheJsonFormatRefusesABadSerialJointOrActuatorByField) {
  const auto refusal_of = [](std::string json) {
    try {
      load_scene_text(json, "leg.json");
    } catch (const ModelError& error) {
      return std::string(error.what());
    }
    return std::string("(accepted)");
  };
  const std::string leg = kLegJson;
  const auto replaced = [&](const std::string& from, const std::string& to) {
    std::string text = leg;
    text.replace(text.find(from), from.size(), to);
    return text;
  };
  EXPECT_EQ(refusal_of(replaced(R"("axis": "hip_y")", R"("axis": "hip_z")")),
            "leg.json: actuators[0].axis: joint \"hip_x+hip_y\" has no axis named \"hip_z\"");
  EXPECT_EQ(refusal_of(replaced(R"("joint": "hip_x+hip_y", "axis": "hip_x")", R"("joint": "knee", "axis": "hip_x")")),
            "leg.json: actuators[1].joint: no joint named \"knee\"");
  EXPECT_EQ(refusal_of(replaced(R"("type": "serial",)", R"("type": "revolute", "axis": [1, 0, 0],)")),
            "leg.json: joints[1].serial_axes: is for serial joints only");
  EXPECT_EQ(refusal_of(replaced(R"("gear": 20})", R"("gear": 20, "gain": 1})")), "leg.json: actuators[1].gain: a motor has none (its force is gear x control)");
  EXPECT_NE(refusal_of(replaced(R"("kind": "velocity", "gear": 1, "gain": 3)", R"("kind": "velocity", "gear": 1)")).find("actuators[3].gain"),
            std::string::npos);
  EXPECT_NE(refusal_of(replaced(R"("range": [-0.7, 0.5])", R"("range": [0.1, 0.5])")).find("joints[1].serial_axes[0].range"), std::string::npos);
}

}  // namespace
}  // namespace limber
