// Boxes at rest on boxes under each method that collides boxes as themselves (springs, Lagrange,
// Featherstone; the particle method's boxes are capsule proxies, which roll): a stack of 10 and a
// pyramid of 20, each box 0.3 × 0.2 × 0.1 m and 1 kg, 0.5 mm apart at the start, on a floor of
// friction 0.6, for 10 s at the step given (bench/collision.md, "Boxes as themselves").
//
//   build/bench/box_stacks [--dt S] [--seconds S]
//
// Per scene and method: the largest drift of a box between 1 s (settled) and the end, the
// deepest penetration over the run (the observers' measure), when every box was asleep (the
// islands' sleep, Settings::sleep), and the wall time per step.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "limber/kernel/model/capabilities.hpp"
#include "limber/kernel/world/world.hpp"

namespace limber {
namespace {

const Eigen::Vector3d kHalf(0.15, 0.1, 0.05);
constexpr double kGap = 5e-4;  // m between boxes at the start: none overlaps at the Model's poses

Body box(const std::string& name, const Eigen::Vector3d& centre) {
  Body body;
  body.name = name;
  body.shape.type = ShapeType::box;
  body.shape.half_extents = kHalf;
  body.mass = 1;
  body.position = centre;
  return body;
}

Model floor_model(double dt) {
  Model model;
  model.name = "boxes";
  model.ground = Ground{0.0, 0.0, 0.6};
  model.settings.time_step = dt;
  return model;
}

Model stack(double dt, int boxes) {
  Model model = floor_model(dt);
  for (int k = 0; k < boxes; ++k) model.bodies.push_back(box("box" + std::to_string(k), {0, 0, kHalf.z() + k * (2 * kHalf.z() + kGap)}));
  return model;
}

// Rows of 6, 5, 4, 3 and 2 boxes, each row's boxes over the gaps of the row below.
Model pyramid(double dt) {
  Model model = floor_model(dt);
  const double pitch = 2 * kHalf.x() + 0.01;
  for (int row = 0; row < 5; ++row) {
    const int count = 6 - row;
    for (int k = 0; k < count; ++k) {
      const double x = (k - 0.5 * (count - 1)) * pitch;
      model.bodies.push_back(box("box" + std::to_string(row) + "_" + std::to_string(k), {x, 0, kHalf.z() + row * (2 * kHalf.z() + kGap)}));
    }
  }
  return model;
}

void run(const char* scene, const Model& model, const WorldOptions& options, double seconds) {
  World world(model, options);
  const double dt = model.settings.time_step;
  const long steps = std::lround(seconds / dt), settle = std::lround(1.0 / dt);
  std::vector<Pose> settled(model.bodies.size()), now(model.bodies.size());
  double deepest = 0, asleep_at = -1, stepping = 0;
  for (long n = 0; n < steps; ++n) {
    const auto start = std::chrono::steady_clock::now();
    if (world.step() != StepStatus::ok) throw std::runtime_error(std::string(scene) + ": the step failed");
    stepping += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const Observation observation = world.observe();
    deepest = std::max(deepest, observation.penetration.depth);
    if (asleep_at < 0 && observation.body_sleeping) asleep_at = (n + 1) * dt;
    if (!observation.body_sleeping && asleep_at >= 0) asleep_at = -1;  // woke again
    if (n + 1 == settle) world.poses(settled);
  }
  world.poses(now);
  double drift = 0;
  for (std::size_t b = 0; b < now.size(); ++b) drift = std::max(drift, (now[b].position - settled[b].position).norm());
  char sleep[32];
  if (asleep_at >= 0) std::snprintf(sleep, sizeof sleep, "%.2f s", asleep_at); else std::snprintf(sleep, sizeof sleep, "awake");
  std::string method(method_name(options.method));
  if (options.method == Method::featherstone) method += std::string(", ") + integrator_name(options.featherstone.integrator);
  std::printf("| %-14s | %-36s | %9.3f | %9.3f | %-8s | %8.1f |\n", scene, method.c_str(), 1e3 * drift, 1e3 * deepest, sleep,
              1e6 * stepping / static_cast<double>(steps));
}

}  // namespace
}  // namespace limber

int main(int argc, char** argv) {
  using namespace limber;
  double dt = 1.0 / 240, seconds = 10;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string argument = argv[i];
      if (argument == "--dt" && i + 1 < argc) {
        dt = std::stod(argv[++i]);
      } else if (argument == "--seconds" && i + 1 < argc) {
        seconds = std::stod(argv[++i]);
      } else {
        throw std::invalid_argument("unknown argument " + argument + " (--dt S, --seconds S)");
      }
    }
    std::printf("Δt = %g s, %g s; drift: the largest move of a box from 1 s to the end\n\n", dt, seconds);
    std::printf("| scene          | method                               | drift mm  | deepest mm | asleep   | µs/step  |\n|---|---|---:|---:|---|---:|\n");
    std::vector<WorldOptions> runs;
    for (const MethodCapabilities& method : kMethodCapabilities) {
      if (!method.true_shapes) continue;  // the particles' capsule proxies roll off a stack
      runs.push_back(WorldOptions{.method = method.method});
      if (method.method != Method::featherstone) continue;
      runs.push_back(runs.back());  // and with its contacts solved before the move
      runs.back().featherstone.integrator = Integrator::semi_implicit_euler;
    }
    for (const WorldOptions& options : runs) {
      run("stack of 10", stack(dt, 10), options, seconds);
      run("pyramid of 20", pyramid(dt), options, seconds);
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "box_stacks: %s\n", error.what());
    return 1;
  }
  return 0;
}
