// The viewer without a window: its frames step the World as `limber run` does, and its input
// events (keys, clicks, drags) act on the picked limb through the World API.
#include "tools/viewer/view_state.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/support/test_directory.hpp"
#include "tools/cli/cli.hpp"
#include "tools/viewer/scene_drawing.hpp"

namespace limber::viewer {
namespace {

const std::string kHumanoid = std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/humanoid.json";
constexpr int kWidth = 1280, kHeight = 720;
constexpr std::size_t kUpperTorso = 2;  // humanoid.json's third body: F3

std::string file_text(const std::string& path) {
  std::ostringstream text;
  text << std::ifstream(path).rdbuf();
  return text.str();
}

// Where a world point lands on the screen (pixels, top left origin), through the camera's matrices.
Eigen::Vector2d project(const OrbitCamera& camera, const Eigen::Vector3d& point) {
  const CameraMatrices m = camera.matrices(kWidth, kHeight);
  const Eigen::Vector4f clip = m.projection * m.view * Eigen::Vector4f(float(point.x()), float(point.y()), float(point.z()), 1);
  return {(clip.x() / clip.w() + 1) * 0.5 * kWidth, (1 - clip.y() / clip.w()) * 0.5 * kHeight};
}

Eigen::Vector3d torso_position(const ViewState& view) { return view.world().pose(view.world().bodies()[kUpperTorso]).position; }
Eigen::Vector3d torso_velocity(const ViewState& view) { return view.world().motion(view.world().bodies()[kUpperTorso]).linear; }

class ViewerFrames : public ::testing::TestWithParam<const char*> {};

// 30 frames of 1/60 s at Δt = 1/240 s are 120 steps, and give `limber run --steps 120`'s
// trajectory to the last bit of every point of every step (the CSV is lossless).
TEST_P(ViewerFrames, TakeTheStepsOfLimberRunBitForBit) {
  const std::string method = GetParam();
  const std::string viewed = (limber::testing::test_directory() / ("view_" + method + ".csv")).string();
  const std::string ran = (limber::testing::test_directory() / ("run_" + method + ".csv")).string();
  std::filesystem::remove(viewed);
  {
    ViewState view({kHumanoid, "--method", method, "--out", viewed});
    for (int frame = 0; frame < 30; ++frame) view.advance(1.0 / 60);
    ASSERT_EQ(view.steps_taken(), 120);
    EXPECT_FALSE(std::filesystem::exists(viewed)) << "the trajectory is renamed into place only when the view ends";
  }

  const std::vector<std::string> arguments{"limber", "run", kHumanoid, "--method", method, "--steps", "120", "--out", ran};
  std::vector<const char*> argv;
  for (const std::string& argument : arguments) argv.push_back(argument.c_str());
  std::ostringstream out, err;
  ASSERT_EQ(cli::run_main(int(argv.size()), argv.data(), out, err), cli::kSuccess) << err.str();
  const std::string expected = file_text(ran);
  EXPECT_EQ(std::count(expected.begin(), expected.end(), '\n'), 122);  // header, start, 120 steps
  EXPECT_EQ(file_text(viewed), expected);
}
INSTANTIATE_TEST_SUITE_P(EveryMethod, ViewerFrames,
                         ::testing::Values("weighted", "unweighted", "springs-explicit", "springs-implicit", "lagrange", "featherstone"));

TEST(ViewState, SlowMotionTakesAQuarterOfTheSteps) {
  ViewState view({kHumanoid});
  view.handle(KeyEvent{Key::slow_motion, true}, kWidth, kHeight);
  for (int frame = 0; frame < 8; ++frame) view.advance(1.0 / 60);
  EXPECT_EQ(view.steps_taken(), 8);  // 4 steps a frame at full speed
}

TEST(ViewState, SpacePausesAndStepAdvancesOneStep) {
  ViewState view({kHumanoid});
  view.handle(KeyEvent{Key::space, true}, kWidth, kHeight);
  EXPECT_FALSE(view.playing());
  EXPECT_EQ(view.advance(1.0 / 60), 0);
  view.handle(KeyEvent{Key::step, true}, kWidth, kHeight);
  EXPECT_EQ(view.advance(1.0 / 60), 1);
  EXPECT_EQ(view.advance(1.0 / 60), 0);
}

// The standing humanoid sleeps; F3 and a held arrow key push its upper torso to the camera's
// right, through World::apply_force, and releasing the key stops the push.
TEST(ViewState, ArrowKeyPushesThePickedLimbToTheCameraRight) {
  ViewState view({kHumanoid, "--ball-speed", "0"});
  view.handle(KeyEvent{Key::f3, true}, kWidth, kHeight);
  ASSERT_EQ(view.picked(), kUpperTorso);
  view.handle(KeyEvent{Key::right, true}, kWidth, kHeight);
  for (int frame = 0; frame < 3; ++frame) view.advance(1.0 / 60);
  ASSERT_EQ(view.last_loads().size(), 1u);
  const Eigen::Vector3d forward = view.camera.target - view.camera.eye();
  const Eigen::Vector3d right = Eigen::Vector3d(forward.x(), forward.y(), 0).normalized().cross(Eigen::Vector3d::UnitZ());
  const Eigen::Vector3d force = view.last_loads().front().second;
  EXPECT_NEAR(force.normalized().dot(right), 1.0, 1e-12);
  EXPECT_GT(torso_velocity(view).dot(right), 0.05);  // 3 frames of 30 m/s² on a body held by its joints

  view.handle(KeyEvent{Key::right, false}, kWidth, kHeight);
  view.advance(1.0 / 60);
  EXPECT_TRUE(view.last_loads().empty());
}

TEST(ViewState, ClickPicksTheLimbUnderTheCursorAndNothingClears) {
  ViewState view({kHumanoid});
  const Eigen::Vector2d at = project(view.camera, torso_position(view));
  view.handle(ButtonEvent{Button::left, true, at}, kWidth, kHeight);
  EXPECT_EQ(view.picked(), kUpperTorso);
  view.handle(ButtonEvent{Button::left, false, at}, kWidth, kHeight);
  view.handle(ButtonEvent{Button::left, true, Eigen::Vector2d(5, 5)}, kWidth, kHeight);  // the sky
  EXPECT_FALSE(view.picked().has_value());
}

// Dragging the torso sideways pulls the grabbed point after the cursor.
TEST(ViewState, DragPullsTheLimbTowardTheCursor) {
  ViewState view({kHumanoid, "--ball-speed", "0"});
  const Eigen::Vector2d at = project(view.camera, torso_position(view));
  view.handle(ButtonEvent{Button::left, true, at}, kWidth, kHeight);
  view.handle(CursorEvent{at + Eigen::Vector2d(120, 0)}, kWidth, kHeight);
  ASSERT_TRUE(view.drag().has_value());
  const ViewState::Drag drag = *view.drag();
  ASSERT_EQ(drag.body, kUpperTorso);
  auto grabbed = [&] {
    const Pose pose = view.world().pose(view.world().bodies()[kUpperTorso]);
    return Eigen::Vector3d(pose.position + pose.orientation * drag.local_point);
  };
  const double before = (drag.target - grabbed()).norm();
  ASSERT_GT(before, 0.1);
  for (int frame = 0; frame < 15; ++frame) view.advance(1.0 / 60);
  EXPECT_LT((drag.target - grabbed()).norm(), 0.5 * before);
  view.handle(ButtonEvent{Button::left, false, at}, kWidth, kHeight);
  EXPECT_FALSE(view.drag().has_value());
}

TEST(ViewState, LaunchThrowsTheLauncherBallAtThePickedLimb) {
  ViewState view({kHumanoid});
  const std::size_t balls = view.world().balls().size();
  view.handle(KeyEvent{Key::f3, true}, kWidth, kHeight);
  view.launcher.speed = 7, view.launcher.direction = {0, 2, 0};
  view.handle(KeyEvent{Key::launch, true}, kWidth, kHeight);
  ASSERT_EQ(view.world().balls().size(), balls + 1);
  const BallMotion ball = view.world().ball(view.world().balls().back());
  EXPECT_TRUE(ball.velocity.isApprox(Eigen::Vector3d(0, 7, 0)));
  const Eigen::Vector3d to_target = torso_position(view) - ball.position;
  EXPECT_NEAR(to_target.normalized().dot(Eigen::Vector3d::UnitY()), 1.0, 1e-12);
}

TEST(ViewState, MethodSwitchResetsUnderTheNewMethodAndABadOneChangesNothing) {
  ViewState view({kHumanoid});
  view.advance(1.0 / 60);
  ASSERT_TRUE(view.set_method("lagrange", 100, 1, ProjectionRule::pbd));
  EXPECT_EQ(view.world().method(), Method::lagrange);
  EXPECT_EQ(view.method_name(), "lagrange");
  EXPECT_EQ(view.world().time(), 0.0);
  EXPECT_FALSE(view.set_method("verlet-please", 100, 1, ProjectionRule::pbd));
  EXPECT_THAT(view.error(), ::testing::HasSubstr("verlet-please"));
  EXPECT_EQ(view.world().method(), Method::lagrange);
}

TEST(ViewState, BodyVariantReloadsTheSceneAndAnUnknownOneIsRefused) {
  ViewState view({kHumanoid});
  const double medium = view.world().model().body_mass();
  ASSERT_TRUE(view.set_body("wide"));
  EXPECT_GT(view.world().model().body_mass(), medium);
  EXPECT_FALSE(view.set_body("giant"));
  EXPECT_THAT(view.error(), ::testing::HasSubstr("giant"));
}

TEST(ViewState, FrictionResetsOnTheNewGroundAndABadValueChangesNothing) {
  ViewState view({kHumanoid});
  ASSERT_TRUE(view.set_friction(0.1));
  EXPECT_EQ(view.world().model().ground->friction, 0.1);
  EXPECT_FALSE(view.set_friction(-1));
  EXPECT_THAT(view.error(), ::testing::HasSubstr("friction"));
  EXPECT_EQ(view.world().model().ground->friction, 0.1);
}

// The camera's ray through a point's pixel passes through the point (matrices and rays agree).
TEST(OrbitCamera, RayThroughAProjectedPointPassesThroughIt) {
  OrbitCamera camera;
  camera.orbit(130, -40), camera.pan(25, 10, kHeight), camera.zoom(2);
  const Eigen::Vector3d point(0.3, -0.2, 1.1);
  const Eigen::Vector2d pixel = project(camera, point);
  const Ray ray = camera.ray(pixel.x() - 0.5, pixel.y() - 0.5, kWidth, kHeight);  // ray() takes the pixel's corner
  const Eigen::Vector3d off = (point - ray.origin) - (point - ray.origin).dot(ray.direction) * ray.direction;
  EXPECT_LT(off.norm(), 1e-4);
}

// What the viewer draws: each limb and ball once; contacts only where shapes touch.
TEST(SceneDrawer, DrawsEveryLimbAndBallAndTheContactsOfALandedBody) {
  ViewState view({kHumanoid});
  view.overlays.contacts = true;
  SceneDrawer drawer;
  DrawList list;
  drawer.draw(view, list);
  EXPECT_EQ(list.solids.size(), view.world().model().bodies.size() + view.world().balls().size());
  ASSERT_TRUE(list.floor.has_value());
  // Standing: the feet touch the ground, nothing else touches.
  const std::vector<ShownContact>& standing = drawer.contacts(view.world());
  ASSERT_FALSE(standing.empty());
  for (const ShownContact& contact : standing) EXPECT_NEAR(contact.point.z(), 0.0, 1e-9);
}

// A box body is drawn as a box and an ellipsoid as the unit sphere scaled by its semi-axes, each
// in its shape frame: the body's pose turned by the shape's rotation.
TEST(SceneDrawer, DrawsBoxesAndEllipsoidsAsThemselvesInTheirShapeFrames) {
  const std::filesystem::path scene = limber::testing::test_directory() / "box_and_ellipsoid.json";
  std::ofstream(scene) << R"({
  "limber_scene": 1, "name": "box_and_ellipsoid",
  "settings": {"gravity": [0, 0, -9.81], "time_step": 0.01, "duration": 1},
  "bodies": [
    {"name": "crate", "shape": {"type": "box", "half_extents": [0.1, 0.2, 0.3], "rotation": [0.9238795325112867, 0, 0, 0.3826834323650898]},
     "mass": 2, "position": [0, 0, 1], "axis": [1, 0, 1]},
    {"name": "egg", "shape": {"type": "ellipsoid", "half_extents": [0.05, 0.04, 0.08]}, "mass": 1, "position": [1, 0, 1], "axis": [0, 1, 0]}
  ]
})";
  ViewState view({scene.string()});
  SceneDrawer drawer;
  DrawList list;
  drawer.draw(view, list);
  ASSERT_EQ(list.solids.size(), 2u);
  const SolidKind kinds[2] = {SolidKind::box, SolidKind::ellipsoid};
  for (std::size_t i = 0; i < 2; ++i) {
    const Shape& shape = view.world().model().bodies[i].shape;
    const Pose pose = view.world().pose(view.world().bodies()[i]);
    const Solid& solid = list.solids[i];
    SCOPED_TRACE(std::string(shape_type_name(shape.type)));
    EXPECT_EQ(solid.kind, kinds[i]);
    EXPECT_EQ(solid.half_extents, shape.half_extents.cast<float>());
    const Eigen::Matrix3f turn = (pose.orientation * shape.rotation).toRotationMatrix().cast<float>();
    EXPECT_LT((solid.placement.linear() - turn).cwiseAbs().maxCoeff(), 1e-6f);
    EXPECT_LT((solid.placement.translation() - pose.position.cast<float>()).norm(), 1e-6f);
  }
  // The box's 45° turn about its body axis is drawn: its shape x is not its body frame's x.
  const Eigen::Vector3f body_x = (view.world().pose(view.world().bodies()[0]).orientation * Eigen::Vector3d::UnitX()).cast<float>();
  EXPECT_NEAR(list.solids[0].placement.linear().col(0).dot(body_x), std::cos(std::numbers::pi_v<float> / 4), 1e-6f);
}

TEST(SceneDrawer, GapColourGoesFromGreenToRedAsTheGapGrows) {
  EXPECT_GT(gap_colour(1e-6).g, 0.8f);
  EXPECT_LT(gap_colour(1e-6).r, 0.05f);
  EXPECT_GT(gap_colour(0.5).r, 0.95f);
  EXPECT_LT(gap_colour(0.5).g, 0.05f);
  double last_red = -1;
  for (double gap = 1e-5; gap < 1; gap *= 2) {
    EXPECT_GE(gap_colour(gap).r, last_red);
    last_red = gap_colour(gap).r;
  }
}

}  // namespace
}  // namespace limber::viewer
