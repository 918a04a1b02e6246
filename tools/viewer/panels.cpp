#include "tools/viewer/panels.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <imgui.h>

#include "limber/kernel/world/world_internals.hpp"

namespace limber::viewer {
namespace {

constexpr std::array<const char*, 6> kMethods{"weighted", "unweighted", "springs-explicit", "springs-implicit", "lagrange", "featherstone"};
constexpr std::array<const char*, 4> kBodies{"the scene's", "thin", "medium", "wide"};
constexpr std::array<const char*, 2> kProjections{"pbd", "rattle"};
constexpr float kPanelWidth = 330;

// Reads the fields from the world when its method changed under the panel (start, reload).
void sync(const ViewState& view, PanelState& panel) {
  if (panel.shown_method == view.method_name()) return;
  panel.shown_method = view.method_name();
  panel.method = int(std::find(kMethods.begin(), kMethods.end(), view.method_name()) - kMethods.begin()) % int(kMethods.size());
  const World& world = view.world();
  std::visit(
      [&](const auto& state) {
        if constexpr (requires { state.options.relaxation; }) {  // the Verlet methods
          panel.iterations = state.options.relaxation.iterations;
          panel.substeps = state.options.relaxation.substeps;
          panel.projection = state.options.relaxation.projection == ProjectionRule::rattle ? 1 : 0;
        }
      },
      world.internals().state);
  if (world.model().ground) panel.friction = float(world.model().ground->friction);
}

// A collapsing section, open at the start when `open` says so.
bool section(const char* name, bool open) {
  ImGui::SetNextItemOpen(open, ImGuiCond_Once);
  return ImGui::CollapsingHeader(name);
}

void simulation_controls(ViewState& view) {
  const World& world = view.world();
  // The file's name, not its folders (a long path would widen the panel past the frame).
  const std::string& source = view.source();
  const std::string file = view.scene_path().empty() ? source : std::filesystem::path(view.scene_path()).filename().string();
  ImGui::PushTextWrapPos(kPanelWidth - 20);
  ImGui::TextWrapped("%s  (%s)", world.model().name.c_str(), file.c_str());
  ImGui::PopTextWrapPos();
  ImGui::Text("t = %.3f s   steps %ld   %s", world.time(), view.steps_taken(),
              world.last_report().status == StepStatus::ok ? "ok" : "DIVERGED");
  if (ImGui::Button(view.playing() ? "Pause (space)" : "Play (space)")) view.set_playing(!view.playing());
  ImGui::SameLine();
  if (ImGui::Button("Step (.)")) view.set_playing(false), view.request_step();
  ImGui::SameLine();
  if (ImGui::Button("Reset (R)")) view.reset();
  float speed = float(view.speed);
  if (ImGui::SliderFloat("speed", &speed, 0.05f, 2.0f, "%.2fx", ImGuiSliderFlags_Logarithmic)) view.speed = speed;
}

void method_controls(ViewState& view, PanelState& panel) {
  if (!section("Method", true)) return;
  ImGui::Combo("method", &panel.method, kMethods.data(), int(kMethods.size()));
  const bool verlet = panel.method < 2;
  if (verlet) {
    ImGui::InputInt("sweeps", &panel.iterations);
    ImGui::InputInt("substeps", &panel.substeps);
    ImGui::Combo("projection", &panel.projection, kProjections.data(), int(kProjections.size()));
    panel.iterations = std::clamp(panel.iterations, 1, 10000), panel.substeps = std::clamp(panel.substeps, 1, kMaxSubsteps);
  }
  if (ImGui::Button("Apply and reset")) {
    view.set_method(kMethods[std::size_t(panel.method)], panel.iterations, panel.substeps,
                    panel.projection == 1 ? ProjectionRule::rattle : ProjectionRule::pbd);
    panel.shown_method.clear();  // read back what the world took
  }
}

void scene_controls(ViewState& view, PanelState& panel) {
  if (!section("Scene", true)) return;
  if (ImGui::Combo("body", &panel.body, kBodies.data(), int(kBodies.size()))) {
    view.set_body(panel.body == 0 ? std::string() : kBodies[std::size_t(panel.body)]);
    panel.shown_method.clear();
  }
  if (view.world().model().ground) {
    ImGui::SliderFloat("friction", &panel.friction, 0.0f, 2.0f, "%.2f");
    if (ImGui::IsItemDeactivatedAfterEdit()) view.set_friction(panel.friction);
  }
  ImGui::InputText("file", panel.scene_path, sizeof panel.scene_path);
  ImGui::SameLine();
  if (ImGui::Button("Load")) view.reload({panel.scene_path}), panel.shown_method.clear();
  ImGui::TextDisabled("or drop a scene file on the window");
}

void ball_controls(ViewState& view, bool open) {
  if (!section("Ball", open)) return;
  Launcher& ball = view.launcher;
  float speed = float(ball.speed), radius = float(ball.radius), mass = float(ball.mass), restitution = float(ball.restitution);
  float direction[3] = {float(ball.direction.x()), float(ball.direction.y()), float(ball.direction.z())};
  if (ImGui::SliderFloat("speed m/s", &speed, 0.0f, 60.0f)) ball.speed = speed;
  if (ImGui::InputFloat3("direction", direction)) ball.direction = Eigen::Vector3f(direction[0], direction[1], direction[2]).cast<double>();
  if (ImGui::SliderFloat("radius m", &radius, 0.01f, 0.5f)) ball.radius = radius;
  if (ImGui::SliderFloat("mass kg", &mass, 0.1f, 100.0f, "%.2f", ImGuiSliderFlags_Logarithmic)) ball.mass = mass;
  if (ImGui::SliderFloat("elasticity", &restitution, 0.0f, 1.0f)) ball.restitution = restitution;
  if (ImGui::Button("Launch (B)")) view.launch();
  ImGui::SameLine();
  ImGui::TextDisabled("at the picked limb or the body");
}

void picking_controls(ViewState& view, bool open) {
  if (!section("Picking and overlays", open)) return;
  const World& world = view.world();
  ImGui::Text("picked: %s", view.picked() ? world.model().bodies[*view.picked()].name.c_str() : "none (F1-F8 or click)");
  float push = float(view.push_acceleration);
  if (ImGui::SliderFloat("push m/s^2", &push, 0.0f, 200.0f)) view.push_acceleration = push;
  ImGui::TextDisabled("arrows push; drag a limb to pull it");
  Overlays& overlays = view.overlays;
  ImGui::Checkbox("bounding spheres (F9)", &overlays.bounding_volumes);
  ImGui::Checkbox("contacts", &overlays.contacts);
  ImGui::SameLine();
  ImGui::Checkbox("joint gaps", &overlays.joint_gaps);
  ImGui::Checkbox("centre of mass", &overlays.centre_of_mass);
  ImGui::SameLine();
  ImGui::Checkbox("forces", &overlays.forces);
}

void plot(const char* label, const std::deque<float>& values, const char* format) {
  const std::vector<float> samples(values.begin(), values.end());
  char overlay[64] = "";
  if (!samples.empty()) std::snprintf(overlay, sizeof overlay, format, double(samples.back()));
  ImGui::PlotLines(label, samples.data(), int(samples.size()), 0, overlay, FLT_MAX, FLT_MAX, ImVec2(0, 60));
}

// Whether the current window's content fitted it in the last frame (nothing to scroll to).
bool window_fits() { return ImGui::GetScrollMaxX() <= 0 && ImGui::GetScrollMaxY() <= 0; }

void plots(const ViewState& view, PanelState& panel, int width) {
  ImGui::SetNextWindowPos(ImVec2(float(width) - kPanelWidth - 10, 10), ImGuiCond_Always);
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, 0), ImGuiCond_Always);
  ImGui::Begin("Plots", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize);
  const History& history = view.history();
  plot("energy", history.energy, "%.4g J");
  plot("joint gap", history.joint_gap, "%.3g / link");
  if (panel.wall_clock) plot("step", history.step_ms, "%.3f ms");
  panel.fits = panel.fits && window_fits();
  ImGui::End();
}

}  // namespace

void draw_panels(ViewState& view, PanelState& panel, int width, int height) {
  sync(view, panel);
  ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_Always);
  ImGui::SetNextWindowSizeConstraints(ImVec2(kPanelWidth, 0), ImVec2(kPanelWidth, float(height) - 20));
  ImGui::Begin("limber", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_AlwaysAutoResize);
  simulation_controls(view);
  method_controls(view, panel);
  scene_controls(view, panel);
  const bool tall = height >= kFullPanelHeight;
  ball_controls(view, tall);
  picking_controls(view, tall);
  if (!view.error().empty()) {
    ImGui::PushTextWrapPos(kPanelWidth - 20);
    ImGui::TextColored(ImVec4(1, 0.35f, 0.3f, 1), "%s", view.error().c_str());
    ImGui::PopTextWrapPos();
  }
  ImGui::TextDisabled("drag: orbit; right drag: pan; wheel: zoom");
  panel.fits = window_fits();
  ImGui::End();
  plots(view, panel, width);
}

}  // namespace limber::viewer
