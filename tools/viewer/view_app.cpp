#include "tools/viewer/view_app.hpp"

#include <algorithm>
#include <cfloat>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <string>
#include <system_error>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
#include <stb_image_write.h>

#include "tools/cli/output_file.hpp"
#include "tools/viewer/panels.hpp"
#include "tools/viewer/renderer.hpp"
#include "tools/viewer/scene_drawing.hpp"
#include "tools/viewer/view_state.hpp"

namespace limber::viewer {
namespace {

// A failure the viewer reports as one line and exit code 2 (no display, a file it cannot write).
class ViewError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

constexpr double kFrameSeconds = 1.0 / 60;  // a headless frame, and the longest a window frame steps

// GLFW and its window, closed in reverse order whatever happens.
struct Window {
  GLFWwindow* handle = nullptr;
  Window(int width, int height, bool visible) {
    glfwSetErrorCallback(nullptr);
    if (!glfwInit()) {
      throw ViewError("view: cannot open a window: no display (headless: xvfb-run -a limber view SCENE --frames N --screenshot out.png)");
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_VISIBLE, visible ? GLFW_TRUE : GLFW_FALSE);
    handle = glfwCreateWindow(width, height, "limber", nullptr, nullptr);
    if (handle == nullptr) {
      glfwTerminate();
      throw ViewError("view: cannot create an OpenGL 3.3 core window (needs Mesa's libgl1-mesa-dri or a GPU driver)");
    }
    glfwMakeContextCurrent(handle);
  }
  ~Window() {
    glfwDestroyWindow(handle);
    glfwTerminate();
  }
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;
};

// Dear ImGui's context and its GLFW and OpenGL 3 backends.
struct Gui {
  Gui(GLFWwindow* window, bool interactive) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGuiIO& io = ImGui::GetIO();
    io.IniFilename = nullptr;  // no imgui.ini: the same panels every run
    io.LogFilename = nullptr;
    ImGui::StyleColorsDark();
    ImGui::GetStyle().Colors[ImGuiCol_WindowBg].w = 0.88f;
    // Its callbacks chain to the viewer's, installed before (interactive only).
    ImGui_ImplGlfw_InitForOpenGL(window, interactive);
    ImGui_ImplOpenGL3_Init("#version 330 core");
  }
  ~Gui() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  Gui(const Gui&) = delete;
  Gui& operator=(const Gui&) = delete;
};

// What the window's callbacks reach through glfwGetWindowUserPointer.
struct App {
  ViewState& view;
  int width = 0, height = 0;  // the framebuffer's, pixels
  double cursor_scale = 1;    // framebuffer pixels per window unit (HiDPI)
};

App& app_of(GLFWwindow* window) { return *static_cast<App*>(glfwGetWindowUserPointer(window)); }

std::optional<Key> key_of(int key) {
  if (key >= GLFW_KEY_F1 && key <= GLFW_KEY_F9) return Key(int(Key::f1) + key - GLFW_KEY_F1);
  switch (key) {
    case GLFW_KEY_LEFT: return Key::left;
    case GLFW_KEY_RIGHT: return Key::right;
    case GLFW_KEY_UP: return Key::up;
    case GLFW_KEY_DOWN: return Key::down;
    case GLFW_KEY_SPACE: return Key::space;
    case GLFW_KEY_PERIOD: return Key::step;
    case GLFW_KEY_R: return Key::reset;
    case GLFW_KEY_B: return Key::launch;
    case GLFW_KEY_S: return Key::slow_motion;
    default: return std::nullopt;
  }
}

void install_callbacks(GLFWwindow* window) {
  glfwSetKeyCallback(window, [](GLFWwindow* w, int key, int, int action, int) {
    if (key == GLFW_KEY_ESCAPE && action == GLFW_PRESS) glfwSetWindowShouldClose(w, GLFW_TRUE);
    const std::optional<Key> mapped = key_of(key);
    const bool released = action == GLFW_RELEASE;  // a release always passes, so no key sticks
    if (!mapped || action == GLFW_REPEAT || (!released && ImGui::GetIO().WantCaptureKeyboard)) return;
    App& app = app_of(w);
    app.view.handle(KeyEvent{*mapped, !released}, app.width, app.height);
  });
  glfwSetMouseButtonCallback(window, [](GLFWwindow* w, int button, int action, int) {
    App& app = app_of(w);
    const bool down = action == GLFW_PRESS;
    if (down && ImGui::GetIO().WantCaptureMouse) return;
    double x = 0, y = 0;
    glfwGetCursorPos(w, &x, &y);
    const Button which = button == GLFW_MOUSE_BUTTON_RIGHT ? Button::right : button == GLFW_MOUSE_BUTTON_MIDDLE ? Button::middle : Button::left;
    app.view.handle(ButtonEvent{which, down, app.cursor_scale * Eigen::Vector2d(x, y)}, app.width, app.height);
  });
  glfwSetCursorPosCallback(window, [](GLFWwindow* w, double x, double y) {
    App& app = app_of(w);
    app.view.handle(CursorEvent{app.cursor_scale * Eigen::Vector2d(x, y)}, app.width, app.height);
  });
  glfwSetScrollCallback(window, [](GLFWwindow* w, double, double dy) {
    if (ImGui::GetIO().WantCaptureMouse) return;
    App& app = app_of(w);
    app.view.handle(ScrollEvent{dy}, app.width, app.height);
  });
  glfwSetDropCallback(window, [](GLFWwindow* w, int count, const char** paths) {
    if (count > 0) app_of(w).view.reload({paths[0]});
  });
}

// One Dear ImGui frame over the drawn scene. Headless, time, size and mouse are fixed so the
// same state draws the same panels.
void draw_gui(ViewState& view, PanelState& panel, int width, int height, bool headless) {
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplGlfw_NewFrame();
  if (headless) {
    ImGuiIO& io = ImGui::GetIO();
    io.DeltaTime = float(kFrameSeconds);
    io.DisplaySize = ImVec2(float(width), float(height));
    io.DisplayFramebufferScale = ImVec2(1, 1);
    io.MousePos = ImVec2(-FLT_MAX, -FLT_MAX);
  }
  ImGui::NewFrame();
  draw_panels(view, panel, width, height);
  ImGui::Render();
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
}

// Writes RGBA pixels (top row first) as PNG through cli::OutputFile: beside the name, then
// renamed, so a failed write never leaves half an image, and never over an input or anything
// but a regular file.
void write_png(const std::string& path, const std::vector<std::filesystem::path>& inputs, const std::vector<std::uint8_t>& pixels,
               int width, int height) {
  cli::OutputFile file(path, "--screenshot", inputs);
  const auto write = [](void* context, void* data, int size) {
    static_cast<std::ostream*>(context)->write(static_cast<const char*>(data), size);
  };
  if (!stbi_write_png_to_func(write, &file.stream(), width, height, 4, pixels.data(), width * 4)) {
    throw ViewError("--screenshot: cannot encode '" + path + "'");
  }
  file.commit();
}

int run_headless(const cli::ViewRequest& request, ViewState& view, std::ostream& out) {
  Window window(request.width, request.height, false);
  Renderer renderer(request.width, request.height);
  Gui gui(window.handle, false);
  PanelState panel;
  panel.wall_clock = false;
  SceneDrawer drawer;
  DrawList list;
  for (long frame = 0; frame < request.frames; ++frame) {
    view.advance(kFrameSeconds);
    if (view.world().last_report().status != StepStatus::ok) break;
  }
  // Dear ImGui sizes its windows from the frame before: the panels settle on the third.
  for (int settle = 0; settle < 3; ++settle) {
    drawer.draw(view, list);
    renderer.draw(list, view.camera.matrices(request.width, request.height));
    if (!request.hide_ui) draw_gui(view, panel, request.width, request.height, true);
  }
  if (!request.screenshot.empty()) {
    write_png(request.screenshot, {view.scene_path()}, renderer.read_pixels(), request.width, request.height);
  }
  const bool ok = view.world().last_report().status == StepStatus::ok;
  out << "limber view: " << view.world().model().name << " (" << view.source() << "), " << request.frames << " frames, "
      << view.steps_taken() << " steps, t = " << view.world().time() << " s, " << (ok ? "ok" : "diverged");
  if (!request.screenshot.empty()) out << "; wrote " << request.screenshot << " (" << request.width << "x" << request.height << ")";
  if (!request.hide_ui && !panel.fits) out << "; the panels are cut off at this size";
  out << "\n";
  return ok ? cli::kSuccess : cli::kDiverged;
}

int run_window(const cli::ViewRequest& request, ViewState& view) {
  Window window(request.width, request.height, true);
  App app{view};
  glfwSetWindowUserPointer(window.handle, &app);
  install_callbacks(window.handle);
  glfwSwapInterval(1);
  glfwGetFramebufferSize(window.handle, &app.width, &app.height);
  Renderer renderer(std::max(app.width, 1), std::max(app.height, 1));
  Gui gui(window.handle, true);
  PanelState panel;
  SceneDrawer drawer;
  DrawList list;
  double last = glfwGetTime();
  while (!glfwWindowShouldClose(window.handle)) {
    glfwPollEvents();
    int window_width = 0, window_height = 0;
    glfwGetWindowSize(window.handle, &window_width, &window_height);
    glfwGetFramebufferSize(window.handle, &app.width, &app.height);
    if (app.width < 1 || app.height < 1) continue;  // minimised
    app.cursor_scale = double(app.width) / std::max(window_width, 1);
    if (renderer.width() != app.width || renderer.height() != app.height) renderer.resize(app.width, app.height);
    const double now = glfwGetTime();
    view.advance(std::min(now - last, 2 * kFrameSeconds));  // a stall slows the simulation, never floods it
    last = now;
    drawer.draw(view, list);
    renderer.draw(list, view.camera.matrices(app.width, app.height));
    if (!request.hide_ui) draw_gui(view, panel, app.width, app.height, false);
    renderer.present(app.width, app.height);
    glfwSwapBuffers(window.handle);
  }
  return cli::kSuccess;
}

}  // namespace

int run_viewer(const cli::ViewRequest& request, std::ostream& out, std::ostream& err) {
  try {
    ViewState view(request.run_arguments);
    for (const std::string& overlay : request.overlays) {
      Overlays& o = view.overlays;
      (overlay == "bounding-spheres" ? o.bounding_volumes
       : overlay == "contacts"       ? o.contacts
       : overlay == "joint-gaps"     ? o.joint_gaps
       : overlay == "centre-of-mass" ? o.centre_of_mass
                                     : o.forces) = true;
    }
    if (request.camera.size() >= 3) {
      constexpr double kRadiansPerDegree = 3.14159265358979323846 / 180;
      view.camera.yaw = kRadiansPerDegree * request.camera[0], view.camera.pitch = kRadiansPerDegree * request.camera[1];
      view.camera.distance = request.camera[2];
      if (request.camera.size() == 6) view.camera.target = {request.camera[3], request.camera[4], request.camera[5]};
    }
    return request.frames >= 0 ? run_headless(request, view, out) : run_window(request, view);
  } catch (const ViewError& error) {
    err << "limber: " << error.what() << "\n";
  } catch (const RenderError& error) {
    err << "limber: view: " << error.what() << "\n";
  } catch (const std::exception& error) {
    err << "limber: " << error.what() << "\n";
  }
  return cli::kBadInput;
}

}  // namespace limber::viewer
