// The MJCF reader on its own (no MuJoCo needed): one bad file per error, each message naming
// the file, the line and the element; notes for what it ignores; a 300-deep chain; and physical
// facts of what it reads (masses from volumes, defaults, includes). Its agreement with MuJoCo
// itself is tests/scene/mjcf_mujoco_test.cpp.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include "limber/kernel/scene/mjcf_document.hpp"
#include "tests/support/test_directory.hpp"

namespace {

using limber::ModelError;
using limber::mjcf::Document;
using limber::mjcf::load_mjcf;
using limber::mjcf::parse_mjcf;
using ::testing::HasSubstr;
using limber::testing::test_directory;
using std::numbers::pi;

std::filesystem::path write(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

// The 1-based line of the first occurrence of `needle` in `text`.
int line_of(const std::string& text, const std::string& needle) {
  const auto at = text.find(needle);
  EXPECT_NE(at, std::string::npos) << needle;
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

// The message of the ModelError loading `path` throws ("" if none).
std::string load_error(const std::filesystem::path& path) {
  try {
    load_mjcf(path);
  } catch (const ModelError& error) {
    return error.what();
  }
  return "";
}

// Loads one bad file and checks the message names "file:LINE" (the line holding `at`) and `element`.
void expect_error(const std::string& xml, const std::string& at, const std::string& element, const std::string& problem) {
  const auto file = write(test_directory() / "bad.xml", xml);
  const std::string message = load_error(file);
  EXPECT_THAT(message, HasSubstr(file.string() + ":" + std::to_string(line_of(xml, at)) + ": " + element)) << message;
  EXPECT_THAT(message, HasSubstr(problem)) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos) << "one line: " << message;
}

std::string model(const std::string& worldbody, const std::string& rest = "") {
  return "<mujoco model=\"test\">\n" + rest + "  <worldbody>\n" + worldbody + "  </worldbody>\n</mujoco>\n";
}

TEST(MjcfErrors, UnknownJointTypeNamesFileLineAndElement) {
  expect_error(model("    <body>\n      <geom size=\".1\"/>\n      <joint type=\"twist\"/>\n    </body>\n"),
               "type=\"twist\"", "<joint type>", "got 'twist'");
}

TEST(MjcfErrors, MissingGeomSize) {
  expect_error(model("    <body>\n      <geom type=\"capsule\"/>\n    </body>\n"), "type=\"capsule\"", "<geom size>",
               "missing: a capsule needs 2 positive numbers");
}

TEST(MjcfErrors, RangeWithoutLimitedIsAnErrorUnlessAutolimits) {
  const std::string body = "    <body>\n      <geom size=\".1\"/>\n      <joint range=\"-10 10\"/>\n    </body>\n";
  expect_error(model(body), "range=", "<joint range>", "autolimits");
  const auto file = write(test_directory() / "auto.xml", model(body, "  <compiler autolimits=\"true\"/>\n"));
  const Document document = load_mjcf(file);
  ASSERT_EQ(document.bodies.at(0).joints.size(), 1u);
  EXPECT_TRUE(document.bodies[0].joints[0].limited);
  EXPECT_DOUBLE_EQ(document.bodies[0].joints[0].range_max, 10 * pi / 180);  // degrees by default
}

TEST(MjcfErrors, IncludeCycleNamesTheIncludingFileAndLine) {
  const auto dir = test_directory();
  const std::string main = "<mujoco>\n  <include file=\"a.xml\"/>\n</mujoco>\n";
  const std::string a = "<mujoco>\n  <worldbody/>\n  <include file=\"main.xml\"/>\n</mujoco>\n";
  write(dir / "a.xml", a);
  const std::string message = load_error(write(dir / "main.xml", main));
  EXPECT_THAT(message, HasSubstr((dir / "a.xml").string() + ":3: <include file>")) << message;
  EXPECT_THAT(message, HasSubstr("already included")) << message;
}

TEST(MjcfErrors, FileIncludedTwice) {
  const auto dir = test_directory();
  write(dir / "part.xml", "<mujoco><worldbody/></mujoco>\n");
  const std::string main = "<mujoco>\n  <include file=\"part.xml\"/>\n  <include file=\"part.xml\"/>\n</mujoco>\n";
  EXPECT_THAT(load_error(write(dir / "main.xml", main)), HasSubstr("main.xml:3: <include file>"));
}

TEST(MjcfErrors, DanglingInclude) {
  expect_error("<mujoco>\n  <worldbody/>\n  <include file=\"nowhere.xml\"/>\n</mujoco>\n", "nowhere", "<include file>",
               "cannot read");
}

TEST(MjcfErrors, UnknownAttributeIsNamed) {
  expect_error(model("    <body>\n      <geom size=\".1\"/>\n      <joint stiffnes=\"1\"/>\n    </body>\n"), "stiffnes",
               "<joint stiffnes>", "unknown attribute");
}

TEST(MjcfErrors, UnknownElementIsNamed) {
  expect_error(model("    <body>\n      <geometry size=\".1\"/>\n    </body>\n"), "<geometry", "<geometry>", "unknown element");
}

TEST(MjcfErrors, TwoOrientations) {
  expect_error(model("    <body quat=\"1 0 0 0\" euler=\"0 0 90\">\n      <geom size=\".1\"/>\n    </body>\n"), "euler=",
               "<body euler>", "two orientations given (quat and euler)");
}

TEST(MjcfErrors, BadNumbersQuoteTheText) {
  expect_error(model("    <body>\n      <geom size=\".1\"/>\n      <joint limited=\"true\" range=\"a b\"/>\n    </body>\n"),
               "range=", "<joint range>", "expected 2 numbers, got 'a b'");
  expect_error(model("    <body pos=\"0 0\">\n      <geom size=\".1\"/>\n    </body>\n"), "pos=", "<body pos>",
               "expected 3 numbers, got '0 0'");
}

TEST(MjcfErrors, RefusedElementsSayNotSupported) {
  expect_error(model("    <body>\n      <composite type=\"grid\" count=\"2 2 1\"/>\n    </body>\n"), "<composite",
               "<composite>", "not supported");
  expect_error(model("", "  <tendon>\n    <fixed name=\"t\"/>\n  </tendon>\n"), "<fixed", "<fixed>", "not supported: tendons");
  expect_error(model("    <body>\n      <geom type=\"mesh\" mesh=\"m\"/>\n    </body>\n"), "type=\"mesh\"", "<geom type>",
               "not supported: mesh");
  expect_error(model("", "  <compiler coordinate=\"global\"/>\n"), "coordinate", "<compiler coordinate>", "not supported");
  expect_error(model("    <body>\n      <geom size=\".1\"/>\n      <joint name=\"j\"/>\n    </body>\n",
                     "  <actuator>\n    <general joint=\"j\"/>\n  </actuator>\n") ,
               "<general", "<general>", "not supported");
}

TEST(MjcfErrors, ErrorInAnIncludedFileNamesThatFile) {
  const auto dir = test_directory();
  const std::string part = "<mujoco>\n  <worldbody>\n    <body>\n      <geom type=\"box\" size=\".1 .1\"/>\n    </body>\n  </worldbody>\n</mujoco>\n";
  write(dir / "part.xml", part);
  const std::string message = load_error(write(dir / "main.xml", "<mujoco>\n  <include file=\"part.xml\"/>\n</mujoco>\n"));
  EXPECT_THAT(message, HasSubstr((dir / "part.xml").string() + ":4: <geom size>")) << message;
}

TEST(MjcfErrors, XmlSyntaxErrorNamesTheLine) {
  const auto file = write(test_directory() / "broken.xml", "<mujoco>\n  <worldbody>\n    <body>\n  </worldbody>\n</mujoco>\n");
  EXPECT_THAT(load_error(file), HasSubstr(file.string() + ":"));
  EXPECT_THAT(load_error(file), HasSubstr("XML error"));
  EXPECT_THAT(load_error(test_directory() / "absent.xml"), HasSubstr("absent.xml: cannot read"));
}

TEST(MjcfDocument, ThreeHundredDeepChainLoads) {
  std::string bodies;
  const int depth = 300;
  for (int i = 0; i < depth; ++i) bodies += "<body pos=\"0 0 -.1\"><joint axis=\"0 1 0\"/><geom size=\".02\"/>";
  for (int i = 0; i < depth; ++i) bodies += "</body>";
  const Document document = parse_mjcf(model(bodies), "chain.xml");
  ASSERT_EQ(document.bodies.size(), static_cast<std::size_t>(depth));
  const double sphere = 1000 * 4.0 / 3.0 * pi * 0.02 * 0.02 * 0.02;
  for (int i = 0; i < depth; ++i) {
    EXPECT_EQ(document.bodies[i].parent, i - 1);
    EXPECT_NEAR(document.bodies[i].mass, sphere, 1e-15);
  }
}

TEST(MjcfDocument, NotesListIgnoredElementsOncePerKind) {
  const std::string xml = model(
      "    <light pos=\"0 0 3\"/>\n    <light pos=\"0 0 4\"/>\n    <camera name=\"c\"/>\n"
      "    <body>\n      <site name=\"s\"/>\n      <geom size=\".1\" rgba=\"1 0 0 1\" solref=\".02 1\"/>\n    </body>\n",
      "  <asset>\n    <texture name=\"t\" builtin=\"flat\"/>\n  </asset>\n  <visual/>\n  <option integrator=\"RK4\"/>\n");
  const Document document = parse_mjcf(xml, "notes.xml");
  auto count = [&](const std::string& what) {
    return std::count_if(document.notes.begin(), document.notes.end(),
                         [&](const std::string& note) { return note.find(what) != std::string::npos; });
  };
  EXPECT_EQ(count("<light>: ignored"), 1);
  EXPECT_EQ(count("notes.xml:" + std::to_string(line_of(xml, "<light")) + ": <light>"), 1);
  for (const char* what : {"<camera>: ignored", "<site>: ignored", "<asset>: ignored", "<visual>: ignored",
                           "<geom rgba>: ignored", "<geom solref>: ignored", "<option integrator>: ignored"}) {
    EXPECT_EQ(count(what), 1) << what;
  }
}

TEST(MjcfDocument, GeomMassIsDensityTimesVolume) {
  const std::string xml = model(
      "    <body>\n      <geom type=\"capsule\" size=\".05 .2\" density=\"500\"/>\n    </body>\n"
      "    <body>\n      <geom type=\"box\" size=\".1 .2 .3\" mass=\"7\"/>\n    </body>\n"
      "    <body>\n      <geom type=\"cylinder\" fromto=\"0 0 0 0 0 .4\" size=\".1\"/>\n    </body>\n");
  const Document document = parse_mjcf(xml, "mass.xml");
  ASSERT_EQ(document.bodies.size(), 3u);
  const double r = 0.05, h = 0.4;
  EXPECT_NEAR(document.bodies[0].mass, 500 * (pi * r * r * h + 4.0 / 3.0 * pi * r * r * r), 1e-12);
  EXPECT_DOUBLE_EQ(document.bodies[1].mass, 7);
  // A box's moment about x: m (b² + c²) / 3 with half-sizes.
  EXPECT_NEAR(document.bodies[1].inertia(0, 0), 7 * (0.2 * 0.2 + 0.3 * 0.3) / 3, 1e-12);
  // fromto: centre at the midpoint, half-length 0.2.
  EXPECT_NEAR(document.bodies[2].centre_of_mass.z(), 0.2, 1e-15);
  EXPECT_NEAR(document.bodies[2].geoms[0].size(1), 0.2, 1e-15);
  EXPECT_NEAR(document.bodies[2].mass, 1000 * pi * 0.01 * 0.4, 1e-12);
}

TEST(MjcfDocument, TwoSpheresCombineByTheParallelAxisTheorem) {
  const std::string xml = model(
      "    <body>\n      <geom size=\".1\" pos=\"-.5 0 0\"/>\n      <geom size=\".1\" pos=\".5 0 0\" density=\"3000\"/>\n    </body>\n");
  const Document document = parse_mjcf(xml, "spheres.xml");
  const double m = 1000 * 4.0 / 3.0 * pi * 0.001;
  const auto& body = document.bodies.at(0);
  EXPECT_NEAR(body.mass, 4 * m, 1e-12);
  const double centre = (-0.5 * m + 0.5 * 3 * m) / (4 * m);
  EXPECT_NEAR(body.centre_of_mass.x(), centre, 1e-15);
  const double own = 2.0 / 5.0 * 0.01;  // 2/5 r² per kg
  EXPECT_NEAR(body.inertia(0, 0), 4 * m * own, 1e-15);
  EXPECT_NEAR(body.inertia(1, 1), 4 * m * own + m * std::pow(-0.5 - centre, 2) + 3 * m * std::pow(0.5 - centre, 2), 1e-14);
  EXPECT_NEAR(body.inertia(0, 1), 0, 1e-15);
}

TEST(MjcfDocument, DefaultsChildclassClassAndFreejoint) {
  const std::string defaults =
      "  <default>\n    <joint damping=\"1\"/>\n    <default class=\"limb\">\n      <joint stiffness=\"5\" armature=\".1\"/>\n"
      "      <geom friction=\".5\" type=\"capsule\" size=\".1 .3 .7\"/>\n      <default class=\"stiff\">\n"
      "        <joint stiffness=\"50\"/>\n      </default>\n    </default>\n  </default>\n";
  const std::string bodies =
      "    <body childclass=\"limb\">\n      <freejoint/>\n      <geom size=\".2\"/>\n"
      "      <body>\n        <joint name=\"a\"/>\n        <joint name=\"b\" class=\"stiff\" damping=\"3\"/>\n"
      "        <geom type=\"sphere\" friction=\".9 .1\"/>\n      </body>\n    </body>\n";
  const Document document = parse_mjcf(model(bodies, defaults), "defaults.xml");
  ASSERT_EQ(document.bodies.size(), 2u);
  const auto& free = document.bodies[0].joints.at(0);
  EXPECT_EQ(free.type, limber::mjcf::JointType::free);
  EXPECT_EQ(free.damping, 0);  // a freejoint takes no defaults
  // Partial size: the leading number overrides, the rest keep the class's.
  EXPECT_EQ(document.bodies[0].geoms[0].size, Eigen::Vector3d(0.2, 0.3, 0.7));
  const auto& a = document.bodies[1].joints.at(0);
  const auto& b = document.bodies[1].joints.at(1);
  EXPECT_EQ(a.stiffness, 5);
  EXPECT_EQ(a.damping, 1);  // inherited from main through limb
  EXPECT_EQ(a.armature, 0.1);
  EXPECT_EQ(b.stiffness, 50);
  EXPECT_EQ(b.damping, 3);
  EXPECT_EQ(document.bodies[1].geoms[0].friction, Eigen::Vector3d(0.9, 0.1, 0.0001));
}

TEST(MjcfDocument, IncludeSplicesBodiesInPlaceAndSectionsApplyInMujocosOrder) {
  const auto dir = test_directory();
  std::filesystem::create_directories(dir / "parts");
  write(dir / "parts" / "arm.xml", "<mujoco>\n  <body name=\"arm\">\n    <joint name=\"elbow\" range=\"0 1\" limited=\"true\"/>\n"
                                  "    <geom size=\".1\"/>\n  </body>\n</mujoco>\n");
  const std::string main =
      "<mujoco>\n  <worldbody>\n    <body name=\"first\">\n      <geom size=\".1\"/>\n    </body>\n"
      "    <include file=\"parts/arm.xml\"/>\n    <body name=\"last\">\n      <geom size=\".1\"/>\n    </body>\n"
      "  </worldbody>\n  <compiler angle=\"radian\"/>\n</mujoco>\n";
  const Document document = load_mjcf(write(dir / "main.xml", main));
  ASSERT_EQ(document.bodies.size(), 3u);
  EXPECT_EQ(document.bodies[1].name, "arm");
  EXPECT_EQ(document.bodies[1].at.file, (dir / "parts" / "arm.xml").string());
  EXPECT_EQ(document.bodies[1].at.line, 2);
  EXPECT_EQ(document.bodies[2].name, "last");
  // <compiler> after <worldbody> still applies: the range is in radians.
  EXPECT_EQ(document.bodies[1].joints.at(0).range_max, 1);
}

}  // namespace
