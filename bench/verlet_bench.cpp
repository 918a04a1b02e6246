// Verlet + weighted relaxation: time per step on the thesis's experiments.
//
//   build/bench/verlet_bench                          all
//   build/bench/verlet_bench --benchmark_filter=Chain  one family
//
// Chains have no contacts, so every step does the same work and the time per step is stable
// without restarting from a saved state.
#include <cmath>
#include <string>

#include <benchmark/benchmark.h>

#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"

namespace limber {
namespace {

Model chain(long links) {
  Model model = load_scene_file(std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/chain.json", {.variant = {}, .links = links, .copies = {}}).model;
  model.settings.sleep.enabled = false;
  return model;
}

// chain.json's particle settings (its rule and substeps) with `iterations` sweeps.
VerletOptions chain_options(int iterations) {
  const Scene scene = load_scene_file(std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/chain.json");
  VerletOptions options;
  options.relaxation = scene.methods.relaxation;
  options.verlet = scene.methods.verlet;
  options.relaxation.iterations = iterations;
  return options;
}

// The thesis's 4.4.2 figure: 5 links at 5 and 1000 sweeps (597 and 30 frames/s on an Athlon XP
// 1800+, with rendering), and longer chains for the scaling of 4.8.
template <typename Scalar>
void BM_ChainStep(benchmark::State& run) {
  const long links = run.range(0);
  const int iterations = static_cast<int>(run.range(1));
  auto state = compile<Scalar>(chain(links), chain_options(iterations));
  for (int s = 0; s < 10; ++s) step(state);  // warm up: caches, first-step work
  const auto projections = state.counters.constraint_projections;
  for (auto _ : run) benchmark::DoNotOptimize(step(state));
  run.counters["links"] = static_cast<double>(links);
  run.counters["sweeps"] = iterations;
  run.counters["projections/s"] = benchmark::Counter(
      static_cast<double>(state.counters.constraint_projections - projections), benchmark::Counter::kIsRate);
  run.counters["steps/s"] = benchmark::Counter(static_cast<double>(run.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK_TEMPLATE(BM_ChainStep, float)->Args({5, 5})->Args({5, 1000})->Args({100, 100})->Args({1000, 100});
BENCHMARK_TEMPLATE(BM_ChainStep, double)->Args({5, 5})->Args({5, 1000})->Args({100, 100})->Args({1000, 100});

// The default run: the humanoid scene for its whole duration, from compile to the last step.
void BM_HumanoidRun(benchmark::State& run) {
  const Model model = load_scene_text(embedded_humanoid_scene(), "humanoid").model;
  const long steps = std::lround(model.settings.duration / model.settings.time_step);
  for (auto _ : run) {
    auto state = compile<double>(model);
    for (long s = 0; s < steps; ++s) step(state);
    benchmark::DoNotOptimize(state.particles.position_x.data());
  }
  run.counters["steps/s"] = benchmark::Counter(static_cast<double>(steps * run.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_HumanoidRun)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace limber

BENCHMARK_MAIN();
