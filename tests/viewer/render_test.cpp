// The viewer's pictures, rendered offscreen (run under Xvfb with Mesa's software OpenGL): the
// headless command writes the same PNG twice, the PNG is a picture, and the body's pixels are
// where the camera projects the body.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <gtest/gtest.h>
#include <stb_image.h>

#include "tests/support/test_directory.hpp"
#include "tools/cli/cli.hpp"
#include "tools/viewer/renderer.hpp"
#include "tools/viewer/scene_drawing.hpp"
#include "tools/viewer/view_app.hpp"
#include "tools/viewer/view_state.hpp"

namespace limber::viewer {
namespace {

const std::string kHumanoid = std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/humanoid.json";
constexpr int kWidth = 640, kHeight = 360;

std::string file_bytes(const std::string& path) {
  std::ostringstream bytes;
  bytes << std::ifstream(path, std::ios::binary).rdbuf();
  return bytes.str();
}

int view(const std::vector<std::string>& arguments, std::string* err_text = nullptr) {
  std::vector<const char*> argv{"limber", "view"};
  for (const std::string& argument : arguments) argv.push_back(argument.c_str());
  std::ostringstream out, err;
  const int code = cli::run_main(int(argv.size()), argv.data(), out, err, run_viewer);
  if (err_text) *err_text = err.str();
  return code;
}

TEST(HeadlessView, TheSameFrameRendersToTheSameNonBlankPng) {
  const std::string first = (limber::testing::test_directory() / "view_first.png").string(), second = (limber::testing::test_directory() / "view_second.png").string();
  std::string err;
  for (const std::string& path : {first, second}) {
    ASSERT_EQ(view({kHumanoid, "--frames", "40", "--width", std::to_string(kWidth), "--height", std::to_string(kHeight),
                    "--screenshot", path}, &err),
              cli::kSuccess)
        << err;
  }
  const std::string bytes = file_bytes(first);
  ASSERT_FALSE(bytes.empty());
  EXPECT_TRUE(bytes == file_bytes(second)) << "two renders of the same frame differ";

  int width = 0, height = 0, channels = 0;
  unsigned char* pixels = stbi_load(first.c_str(), &width, &height, &channels, 4);
  ASSERT_NE(pixels, nullptr);
  EXPECT_EQ(width, kWidth);
  EXPECT_EQ(height, kHeight);
  std::set<std::uint32_t> colours;
  for (int i = 0; i < width * height; ++i) {
    colours.insert(std::uint32_t(pixels[4 * i]) << 16 | std::uint32_t(pixels[4 * i + 1]) << 8 | pixels[4 * i + 2]);
  }
  stbi_image_free(pixels);
  EXPECT_GT(colours.size(), 200u);  // shading, floor, panels: not one flat colour
}

TEST(HeadlessView, ScreenshotOverTheSceneFileIsRefused) {
  std::string err;
  EXPECT_EQ(view({kHumanoid, "--frames", "1", "--screenshot", kHumanoid}, &err), cli::kBadInput);
  EXPECT_NE(err.find("is an input of this run"), std::string::npos) << err;
}

// The panels fit the frame sizes the README's pictures use and the common 1280x720, on the scene
// with the longest name: nothing cut off at the side (the title) or the bottom (the last
// sections). At 640x360 they cannot, and the run says so.
TEST(HeadlessView, ThePanelsFitAt960x540AndLarger) {
  const std::string ragdoll = std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/active_ragdoll.json";
  for (const auto& [width, height] : {std::pair{960, 540}, std::pair{1280, 720}, std::pair{1920, 1080}}) {
    std::vector<const char*> argv{"limber", "view"};
    const std::string w = std::to_string(width), h = std::to_string(height);
    for (const std::string* argument : {&ragdoll}) argv.push_back(argument->c_str());
    for (const char* argument : {"--frames", "1", "--width"}) argv.push_back(argument);
    argv.push_back(w.c_str()), argv.push_back("--height"), argv.push_back(h.c_str());
    std::ostringstream out, err;
    ASSERT_EQ(cli::run_main(int(argv.size()), argv.data(), out, err, run_viewer), cli::kSuccess) << err.str();
    EXPECT_EQ(out.str().find("cut off"), std::string::npos) << width << "x" << height << ": " << out.str();
  }
  std::vector<const char*> argv{"limber", "view", ragdoll.c_str(), "--frames", "1", "--width", "640", "--height", "360"};
  std::ostringstream out, err;
  ASSERT_EQ(cli::run_main(int(argv.size()), argv.data(), out, err, run_viewer), cli::kSuccess) << err.str();
  EXPECT_NE(out.str().find("the panels are cut off"), std::string::npos) << out.str();
}

// A hidden window's OpenGL 3.3 core context, for the renderer alone.
class Context : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(glfwInit()) << "no display: run under xvfb-run";
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
    window_ = glfwCreateWindow(kWidth, kHeight, "test", nullptr, nullptr);
    ASSERT_NE(window_, nullptr);
    glfwMakeContextCurrent(window_);
  }
  void TearDown() override {
    if (window_) glfwDestroyWindow(window_);
    glfwTerminate();
  }
  GLFWwindow* window_ = nullptr;
};

// Drawn with and without its limbs (no shadows), the frames differ exactly where the limbs are:
// every differing pixel lies inside the screen box of the limbs' projected bounding spheres.
TEST_F(Context, BodyPixelsSitWhereTheProjectedBodyIs) {
  ViewState state({kHumanoid});
  SceneDrawer drawer;
  DrawList with, without;
  drawer.draw(state, with);
  for (Solid& solid : with.solids) solid.casts_shadow = false;
  without = with;
  const std::size_t limbs = state.world().model().bodies.size();
  without.solids.erase(without.solids.begin(), without.solids.begin() + long(limbs));

  Renderer renderer(kWidth, kHeight);
  const CameraMatrices camera = state.camera.matrices(kWidth, kHeight);
  renderer.draw(with, camera);
  const std::vector<std::uint8_t> body = renderer.read_pixels();
  renderer.draw(without, camera);
  const std::vector<std::uint8_t> empty = renderer.read_pixels();
  ASSERT_EQ(body.size(), std::size_t(kWidth) * kHeight * 4);

  // The limbs' screen box, from the corners of each bounding sphere's cube.
  double left = kWidth, right = 0, top = kHeight, bottom = 0;
  for (const BodyId id : state.world().bodies()) {
    const Pose pose = state.world().pose(id);
    const BoundingSphere sphere = limb_sphere(state.world().body_description(id).shape, pose.position, pose.orientation);
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d offset((corner & 1) ? 1 : -1, (corner & 2) ? 1 : -1, (corner & 4) ? 1 : -1);
      const Eigen::Vector3d p = sphere.centre + sphere.radius * offset;
      const Eigen::Vector4f clip = camera.projection * camera.view * Eigen::Vector4f(float(p.x()), float(p.y()), float(p.z()), 1);
      const double x = (clip.x() / clip.w() + 1) * 0.5 * kWidth, y = (1 - clip.y() / clip.w()) * 0.5 * kHeight;
      left = std::min(left, x), right = std::max(right, x), top = std::min(top, y), bottom = std::max(bottom, y);
    }
  }
  long differing = 0, outside = 0;
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const std::size_t i = 4 * (std::size_t(y) * kWidth + x);
      if (std::equal(&body[i], &body[i] + 3, &empty[i])) continue;
      ++differing;
      if (x < left - 1 || x > right + 1 || y < top - 1 || y > bottom + 1) ++outside;
    }
  }
  EXPECT_GT(differing, 0.1 * (right - left) * (bottom - top));  // a thin figure still fills a tenth of its box
  EXPECT_EQ(outside, 0);
}

}  // namespace
}  // namespace limber::viewer
