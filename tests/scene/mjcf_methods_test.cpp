// MuJoCo's humanoid.xml under every method that can represent it, with the settings its import
// gives (scene.methods): it falls to the floor with its joints closed, its limits held and no
// energy made; the stiff springs refuse it by name. Skipped without Debian's libmujoco-samples.
#include <filesystem>
#include <fstream>
#include <vector>
#include <string>

#include <gtest/gtest.h>

#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/world/world.hpp"
#include "tests/support/test_directory.hpp"

namespace limber {
namespace {

const std::filesystem::path kHumanoid = "/usr/share/mujoco/model/humanoid/humanoid.xml";

#define SKIP_WITHOUT_HUMANOID()                                                                                         \
  if (!std::filesystem::exists(kHumanoid)) GTEST_SKIP() << kHumanoid << " is missing: install libmujoco-samples " \
                                                                         "(tools/install_packages.sh tests)"

class MjcfHumanoidFalls : public ::testing::TestWithParam<Method> {};

// 2 s of the fall at the file's 5 ms step. MuJoCo's joints are closed by construction: the
// issue's bar for a maximal-coordinate method is 10⁻⁴ of a link (the particles' trees close
// them to rounding); Lagrange's Baumgarte rows close them to the verdict's 10⁻² of a link, its
// contacts and limits solved through the joints (kernel/lagrange/contacts.hpp). No method sinks a
// limb deeper than MuJoCo's soft contacts do on this fall, 14 mm.
TEST_P(MjcfHumanoidFalls, ToTheFloorWithJointsClosedAndNoEnergyMade) {
  SKIP_WITHOUT_HUMANOID();
  const Method method = GetParam();
  const Scene scene = load_scene_file(kHumanoid);
  World world(scene.model, world_options(method, scene.methods));
  const Observation start = world.observe();
  double largest_gap = 0, highest_energy = start.energy(), largest_violation = 0, deepest = 0;
  for (int n = 0; n < 400; ++n) {
    ASSERT_EQ(world.step(), StepStatus::ok) << "step " << n;
    const Observation now = world.observe();
    largest_gap = std::max(largest_gap, now.max_joint_gap);
    largest_violation = std::max(largest_violation, now.joints.limit_violation);
    highest_energy = std::max(highest_energy, now.energy());
    deepest = std::max(deepest, now.penetration.depth);
  }
  const Observation end = world.observe();
  EXPECT_LT(end.body_centre_of_mass.z(), 0.4) << "it lies on the floor (its centre of mass started at 1.07 m)";
  EXPECT_LE(highest_energy, start.energy() + 1e-6 * std::abs(start.energy()));
  EXPECT_LT(largest_gap, method == Method::lagrange ? 1e-2 : 1e-4) << "of a link";
  EXPECT_LT(largest_violation, method == Method::particles ? 0.01 : 0.1) << "rad";
  EXPECT_LT(deepest, 0.014) << "m";
}

INSTANTIATE_TEST_SUITE_P(Methods, MjcfHumanoidFalls, ::testing::Values(Method::particles, Method::lagrange, Method::featherstone),
                         [](const auto& info) { return std::string(method_name(info.param)); });

// A box and an ellipsoid, each turned about z and a little tilted, dropped on the floor under
// every method that runs free bodies: each settles on its largest face at its shortest
// half-size — the rigid methods' shapes themselves, the particles' capsule proxies
// (capsule_proxy.hpp), which rest there too. An ellipsoid rocks before it settles (a rounded
// body on its stable side): 6 s of MuJoCo's 2 ms steps.
class MjcfBoxAndEllipsoidSettle : public ::testing::TestWithParam<Method> {};

TEST_P(MjcfBoxAndEllipsoidSettle, OnTheirLargestFacesAtTheirHalfHeights) {
  const std::string xml = R"(<mujoco>
  <worldbody>
    <geom type="plane" size="5 5 .1"/>
    <body name="box" pos="0 0 0.3" euler="3 -2 30"><freejoint/><geom type="box" size="0.15 0.1 0.05"/></body>
    <body name="egg" pos="1 0 0.3" euler="-2 3 70"><freejoint/><geom type="ellipsoid" size="0.15 0.1 0.07"/></body>
  </worldbody>
</mujoco>)";
  const auto file = limber::testing::test_directory() / "box_and_ellipsoid.xml";
  std::ofstream(file) << xml;
  const Scene scene = load_scene_file(file);
  World world(scene.model, world_options(GetParam(), scene.methods));
  for (int n = 0; n < 3000; ++n) ASSERT_EQ(world.step(), StepStatus::ok) << "step " << n;
  std::vector<Pose> poses(2);
  world.poses(poses);
  EXPECT_NEAR(poses[0].position.z(), 0.05, 2e-3) << "the box's centre, m";
  EXPECT_LT(std::abs((poses[0].orientation * Eigen::Vector3d::UnitZ()).z()), 0.03) << "the box's longest axis (the body frame's z) lies flat";
  // The ellipsoid may still rock (Featherstone's contacts take little energy out of a rolling
  // contact): it lies on its largest side and touches the floor, its lowest point — the support
  // along −z of its semi-axes turned into the world — at the floor's height.
  const Shape& egg = world.body_description(world.body("egg")).shape;
  const Eigen::Matrix3d turn = (poses[1].orientation * egg.rotation).toRotationMatrix();
  const double lowest = poses[1].position.z() - turn.row(2).transpose().cwiseProduct(egg.half_extents).norm();
  EXPECT_NEAR(lowest, 0.0, 1e-3) << "the ellipsoid's lowest point, m";
  EXPECT_NEAR(poses[1].position.z(), 0.07, 2e-3) << "the ellipsoid's centre, m";
  EXPECT_LT(std::abs((poses[1].orientation * Eigen::Vector3d::UnitZ()).z()), 0.1) << "the ellipsoid's longest axis lies near flat";
}

INSTANTIATE_TEST_SUITE_P(Methods, MjcfBoxAndEllipsoidSettle,
                         ::testing::Values(Method::particles, Method::springs, Method::lagrange, Method::featherstone),
                         [](const auto& info) { return std::string(method_name(info.param)); });

// humanoid100.xml (the humanoid among 100 free capsules, ellipsoids, boxes, cylinders and
// spheres, in a walled pen): a second of it under each method that represents it.
TEST_P(MjcfHumanoidFalls, AmongAHundredObjectsInHumanoid100) {
  const std::filesystem::path file = "/usr/share/mujoco/model/humanoid100/humanoid100.xml";
  if (!std::filesystem::exists(file)) GTEST_SKIP() << file << " is missing: install libmujoco-samples";
  const Scene scene = load_scene_file(file);
  World world(scene.model, world_options(GetParam(), scene.methods));
  const double start = world.observe().energy();
  for (int n = 0; n < 200; ++n) ASSERT_EQ(world.step(), StepStatus::ok) << "step " << n;
  EXPECT_LE(world.observe().energy(), start + 1e-6 * std::abs(start)) << "no energy made";
}

TEST(MjcfHumanoidRefused, TheStiffSpringsSayWhy) {
  SKIP_WITHOUT_HUMANOID();
  const Scene scene = load_scene_file(kHumanoid);
  try {
    World world(scene.model, world_options(Method::springs, scene.methods));
    FAIL() << "the springs method compiled humanoid.xml";
  } catch (const ModelError& error) {
    EXPECT_NE(std::string(error.what()).find("the springs method does not support"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace limber
