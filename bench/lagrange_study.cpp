// The Lagrange method's constraint-error figure (bench/accuracy.md, "Lagrange multipliers"): the thesis's
// 5-link heavy-end chain (tools/scenes/chain.json) released horizontally and run for 10⁴ steps
// of 1/240 s (42 s, chaotic), under each integrator and stabilization. Every 12 steps (0.05 s) it
// records the largest joint gap (m) and the energy change since the start (J).
// Usage: lagrange_study; writes CSV to stdout.
#include <algorithm>
#include <cstdio>
#include <string>

#include "limber/kernel/lagrange/compile.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/scene/scene_file.hpp"

int main() {
  using namespace limber;
  const Model model = load_scene_file(std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/chain.json", {}).model;
  struct Configuration {
    const char* name;
    LagrangeOptions options;
  };
  const Configuration configurations[] = {
      {"semi-implicit Euler + Baumgarte", {.integrator = Integrator::semi_implicit_euler, .stabilization = Stabilization::baumgarte}},
      {"RK4 + Baumgarte", {.integrator = Integrator::rk4, .stabilization = Stabilization::baumgarte}},
      {"semi-implicit Euler + projection", {.integrator = Integrator::semi_implicit_euler, .stabilization = Stabilization::projection}},
      {"RK4 + projection", {.integrator = Integrator::rk4, .stabilization = Stabilization::projection}},
  };
  const double dt = 1.0 / 240;
  std::printf("configuration,time,largest_gap,energy_change\n");
  for (const Configuration& configuration : configurations) {
    LagrangeState state = compile_lagrange(model, configuration.options);
    const double start = observe(state).energy();
    double largest = 0;  // over the last interval
    for (int s = 1; s <= 10000; ++s) {
      const StepReport report = step(state, dt);
      if (report.status != StepStatus::ok) {
        std::fprintf(stderr, "%s: diverged at step %d\n", configuration.name, s);
        break;
      }
      largest = std::max(largest, report.constraint_error);
      if (s % 12 == 0) {
        std::printf("%s,%.4f,%.6e,%.6e\n", configuration.name, state.time, largest, observe(state).energy() - start);
        largest = 0;
      }
    }
  }
}
