// Model files' values that the readers turn into others (sizes into volumes, masses and
// inertias; frames composed down a tree) and names: a value whose derived quantity overflows is
// refused at the file, line and attribute that caused it, never as a Model field of inf or nan
// with no place; a name that is not UTF-8 is refused at load, where the file is, not later where
// a caller reads it as text (Python's str).
#include <filesystem>
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "limber/kernel/scene/scene_file.hpp"
#include "tests/support/test_directory.hpp"

namespace limber {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;
namespace fs = std::filesystem;

// `text` as a file of this test's directory named `name`.
fs::path write_named(const std::string& name, const std::string& text) {
  const fs::path dir = limber::testing::test_directory();
  std::ofstream(dir / name, std::ios::binary) << text;
  return dir / name;
}

// The message of loading `path`; fails the test when it loads.
std::string load_error(const fs::path& path) {
  try {
    load_scene_file(path);
  } catch (const ModelError& error) {
    return error.what();
  }
  ADD_FAILURE() << path << " loaded";
  return "";
}

// An MJCF file whose worldbody holds `bodies`; line 3 is the first of them.
std::string mjcf(const std::string& bodies) { return "<mujoco>\n  <worldbody>\n" + bodies + "  </worldbody>\n</mujoco>\n"; }

// One hinged body (line 3) with `geoms` (line 5 the first).
std::string mjcf_body(const std::string& geoms, const std::string& name = "b") {
  return mjcf("    <body name=\"" + name + "\">\n      <joint type=\"hinge\"/>\n" + geoms + "    </body>\n");
}

// ---- MJCF: derived quantities that overflow

TEST(ModelValues, AnMjcfGeomSizeThatOverflowsIsRefusedAtItsAttribute) {
  const fs::path file = write_named("big.xml", mjcf_body("      <geom type=\"sphere\" size=\"1e308\"/>\n"));
  EXPECT_EQ(load_error(file), file.string() + ":5: <geom size>: gives a volume that is not finite: it overflows (no geom is that large)");
  const fs::path moment = write_named("moment.xml", mjcf_body("      <geom type=\"sphere\" size=\"1e100\"/>\n"));
  EXPECT_EQ(load_error(moment),
            moment.string() + ":5: <geom size>: gives a moment of inertia (mass × size²) that is not finite: it overflows (no geom is that large)");
}

TEST(ModelValues, AnMjcfMassThatOverflowsTheInertiaIsRefusedAtItsAttribute) {
  const fs::path file = write_named("mass.xml", mjcf_body("      <geom type=\"sphere\" size=\"1e100\" mass=\"1e300\"/>\n"));
  EXPECT_EQ(load_error(file),
            file.string() + ":5: <geom mass>: gives a moment of inertia (mass × size²) that is not finite: it overflows (no geom is that large)");
}

TEST(ModelValues, AnMjcfFromtoThatOverflowsIsRefusedAtItsAttribute) {
  const fs::path file = write_named("fromto.xml", mjcf_body("      <geom type=\"capsule\" size=\".1\" fromto=\"-1e308 0 0 1e308 0 0\"/>\n"));
  EXPECT_EQ(load_error(file), file.string() + ":5: <geom fromto>: gives a size that is not finite: it overflows (no geom is that large)");
}

TEST(ModelValues, AnMjcfDensityThatOverflowsTheMassIsRefusedAtItsAttribute) {
  const fs::path file = write_named("density.xml", mjcf_body("      <geom type=\"sphere\" size=\"1e100\" density=\"1e300\"/>\n"));
  EXPECT_EQ(load_error(file),
            file.string() + ":5: <geom density>: density × volume, the geom's mass, is not finite: it overflows (no geom is that large)");
}

TEST(ModelValues, GeomMassesThatOverflowWhenSummedAreRefusedAtTheirBody) {
  // Each box's mass and inertia are finite; their sum is not.
  const std::string box = "      <geom type=\"box\" size=\".1 .1 .1\" mass=\"1e308\"/>\n";
  const fs::path file = write_named("sum.xml", mjcf_body(box + box));
  EXPECT_THAT(load_error(file), StartsWith(file.string() + ":3: <body>: its geoms' total mass, centre of mass or inertia is not finite"));
}

TEST(ModelValues, PositionsThatOverflowDownTheTreeAreRefusedAtTheGeom) {
  const fs::path file = write_named("far.xml", mjcf("    <body name=\"a\" pos=\"1e308 0 0\">\n      <geom size=\".1\"/>\n"
                                              "      <body name=\"b\" pos=\"1e308 0 0\">\n        <geom size=\".1\"/>\n"
                                              "      </body>\n    </body>\n"));
  EXPECT_EQ(load_error(file), file.string() + ":6: <geom type=sphere>: its world position is not finite: the pos of its body and "
                                              "the bodies above overflow when added up");
}

TEST(ModelValues, WhatTheModelsChecksFindInAModelFileNamesTheElement) {
  // An <inertial> finite as written whose tensor overflows in the body frame (its symmetrizing
  // sum): only the assembled Model shows it, and the message still names the file and element.
  const fs::path file = write_named("inertial.xml", mjcf("    <body name=\"b\">\n      <joint type=\"hinge\"/>\n"
                                                   "      <inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"1.7e308 1.7e308 1.7e308\"/>\n"
                                                   "      <geom type=\"sphere\" size=\".1\"/>\n    </body>\n"));
  EXPECT_EQ(load_error(file), file.string() + ":3: <body name='b'>: bodies[0].inertial.inertia: must be finite");
}

// ---- URDF: derived quantities that overflow

// A URDF robot: a root link, and `more` (joints and links).
std::string urdf(const std::string& root_inertia, const std::string& more = "") {
  return "<robot name=\"r\">\n  <link name=\"a\">\n    <inertial><mass value=\"1\"/><inertia " + root_inertia +
         "/></inertial>\n    <collision><geometry><sphere radius=\"0.1\"/></geometry></collision>\n  </link>\n" + more + "</robot>\n";
}

const std::string kInertia = "ixx=\"0.01\" ixy=\"0\" ixz=\"0\" iyy=\"0.01\" iyz=\"0\" izz=\"0.01\"";

std::string urdf_link(const std::string& name, const std::string& parent, const std::string& xyz) {
  return "  <joint name=\"to_" + name + "\" type=\"fixed\">\n    <parent link=\"" + parent + "\"/><child link=\"" + name +
         "\"/>\n    <origin xyz=\"" + xyz + "\"/>\n  </joint>\n  <link name=\"" + name + "\">\n    <inertial><mass value=\"1\"/><inertia " +
         kInertia + "/></inertial>\n    <collision><geometry><sphere radius=\"0.1\"/></geometry></collision>\n  </link>\n";
}

TEST(ModelValues, AUrdfInertiaThatOverflowsInTheBodyFrameIsRefusedAtItsInertial) {
  const fs::path file = write_named("inertia.urdf", urdf("ixx=\"1.7e308\" ixy=\"0\" ixz=\"0\" iyy=\"1.7e308\" iyz=\"0\" izz=\"1.7e308\""));
  EXPECT_EQ(load_error(file), file.string() + ":3: <inertial> of link 'a': its <inertia> or <origin> is not finite in the body's frame: "
                                              "the values overflow when turned into it");
}

TEST(ModelValues, UrdfOriginsThatOverflowDownTheTreeAreRefusedAtTheLink) {
  // Link c's frame is 2e308 m out: b (line 10) is the last that is finite; c is on line 18.
  const fs::path file = write_named("far.urdf", urdf(kInertia, urdf_link("b", "a", "1e308 0 0") + urdf_link("c", "b", "1e308 0 0")));
  EXPECT_EQ(load_error(file), file.string() + ":18: <link name='c'>: its frame's position is not finite: the joints' <origin xyz> "
                                              "from the root overflow when added up");
}

// ---- Names must be UTF-8

TEST(ModelValues, ALatin1NameIsRefusedAtLoad) {
  const std::string problem = "not valid UTF-8 (byte 0xE9 at byte 4 of the value): limber reads XML files as UTF-8; save the file as UTF-8";
  const fs::path mjcf_file = write_named("latin1.xml", mjcf_body("      <geom type=\"sphere\" size=\".1\"/>\n", "caf\xE9"));
  EXPECT_EQ(load_error(mjcf_file), mjcf_file.string() + ":3: <body name>: " + problem);
  std::string robot = urdf(kInertia);
  robot.replace(robot.find("name=\"a\""), 8, "name=\"caf\xE9\"");
  const fs::path urdf_file = write_named("latin1.urdf", robot);
  EXPECT_EQ(load_error(urdf_file), urdf_file.string() + ":2: <link name>: " + problem);
}

TEST(ModelValues, EveryMalformedUtf8FormIsRefusedAndUtf8Loads) {
  // Overlong '/', a surrogate, a sequence cut short by the value's end, a stray continuation byte.
  for (const std::string bad : {"\xC0\xAF", "\xED\xA0\x80", "\xE2\x82", "\x80"}) {
    const fs::path file = write_named("bad.xml", mjcf_body("      <geom name=\"g" + bad + "\" type=\"sphere\" size=\".1\"/>\n"));
    EXPECT_THAT(load_error(file), StartsWith(file.string() + ":5: <geom name>: not valid UTF-8 (byte 0x")) << "bytes of " << bad.size();
  }
  // Two, three and four bytes; a Latin-1 comment is not read, so not refused.
  const fs::path good = write_named("good.xml", "<!-- caf\xE9 -->\n" + mjcf_body("      <geom type=\"sphere\" size=\".1\"/>\n",
                                                                          "caf\xC3\xA9-\xE2\x82\xAC-\xF0\x9D\x84\x9E"));
  const Scene scene = load_scene_file(good);
  ASSERT_EQ(scene.model.bodies.size(), 1u);
  EXPECT_EQ(scene.model.bodies[0].name, "caf\xC3\xA9-\xE2\x82\xAC-\xF0\x9D\x84\x9E");
}

}  // namespace
}  // namespace limber
