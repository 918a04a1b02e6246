// Draws a DrawList with OpenGL 3.3 core into an offscreen framebuffer of a fixed size, which the
// window shows (present) and the headless mode reads back (read_pixels). Needs a current OpenGL
// 3.3 core context (GLFW's) for its whole life. The same DrawList and camera give the same
// pixels on the same OpenGL implementation: no time, no randomness, no state kept between frames.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <vector>

#include "tools/viewer/draw_list.hpp"

namespace limber::viewer {

/// An OpenGL failure (a shader that does not compile, an incomplete framebuffer): one line.
class RenderError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Renderer {
 public:
  /// Compiles the shaders, builds the unit meshes and a width × height framebuffer (colour RGBA8,
  /// depth 24, 4× multisampled where the implementation offers it, resolved on read). Throws
  /// RenderError.
  Renderer(int width, int height);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  /// Resizes the framebuffer (pixels, ≥ 1 each). Throws RenderError.
  void resize(int width, int height);
  int width() const { return width_; }
  int height() const { return height_; }

  /// Clears the framebuffer and draws `list` seen by `camera`: floor and grid, shadows, solids,
  /// meshes, lines, then the on-top lines. Leaves the framebuffer bound, so Dear ImGui can draw
  /// over it before present() or read_pixels().
  void draw(const DrawList& list, const CameraMatrices& camera);

  /// Copies the framebuffer to the window's default framebuffer of the given size (pixels).
  void present(int window_width, int window_height);

  /// The framebuffer's pixels: width × height × 4 bytes, RGBA, top row first, alpha 255.
  std::vector<std::uint8_t> read_pixels();

 private:
  struct Gl;  // the OpenGL objects (renderer.cpp)
  Gl* gl_ = nullptr;
  int width_ = 0, height_ = 0;
};

}  // namespace limber::viewer
