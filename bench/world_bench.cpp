// What the World facade costs an engine: the humanoid (awake, hit by the ball) stepped through
// World::step, against the same method's step() on its state directly, and through the World
// with a force, a torque and an impulse each step. Compare the rows of one run as ratios (the
// machine is shared). The state is recompiled when the run is 2 s in, so every repetition times
// the same stretch of motion.
//   build/bench/world_bench --benchmark_min_time=0.5
#include <benchmark/benchmark.h>

#include <string>

#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "limber/kernel/methods/method.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/springs/step.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "limber/kernel/world/world.hpp"

namespace {

using namespace limber;

constexpr double kTimeStep = 1.0 / 240;
constexpr int kStepsPerRun = 480;  // 2 s: the ball hits, the body falls

Scene awake_humanoid() {
  Scene scene = load_scene_text(embedded_humanoid_scene(), "humanoid");
  scene.model.settings.sleep.start_asleep = false;
  scene.model.settings.sleep.enabled = false;  // a sleeping body would cost nothing
  return scene;
}

// The method's step() on its own state.
void BM_Direct(benchmark::State& run, Method method) {
  const Scene scene = awake_humanoid();
  const WorldOptions options = world_options(method, scene.methods);
  MethodState state = compile_method(scene.model, options);
  int steps = 0;
  for (auto _ : run) {
    if (steps++ == kStepsPerRun) {
      run.PauseTiming();
      state = compile_method(scene.model, options), steps = 1;
      run.ResumeTiming();
    }
    benchmark::DoNotOptimize(std::visit([](auto& s) { return step(s, kTimeStep).status; }, state));
  }
}

// World::step, with `loads` a force, a torque and an impulse on the torso each step.
void BM_World(benchmark::State& run, Method method, bool loads) {
  const Scene scene = awake_humanoid();
  World world(scene, method);
  BodyId torso = world.body("upper_torso");
  int steps = 0;
  for (auto _ : run) {
    if (steps++ == kStepsPerRun) {
      run.PauseTiming();
      world = World(scene, method), steps = 1;
      torso = world.body("upper_torso");  // a new World's handles are its own
      run.ResumeTiming();
    }
    if (loads) {
      const Eigen::Vector3d at = world.pose(torso).position;
      world.apply_force(torso, Eigen::Vector3d(1, 0, 0), at);
      world.apply_torque(torso, Eigen::Vector3d(0, 0, 0.1));
      world.apply_impulse(torso, Eigen::Vector3d(0, 0.001, 0), at);
    }
    benchmark::DoNotOptimize(world.step(kTimeStep));
  }
}

void register_all() {
  for (const Method method : {Method::particles, Method::springs, Method::lagrange, Method::featherstone}) {
    const std::string name(method_name(method));
    benchmark::RegisterBenchmark(("direct/" + name).c_str(), BM_Direct, method)->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("world/" + name).c_str(), BM_World, method, false)->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("world_with_loads/" + name).c_str(), BM_World, method, true)->Unit(benchmark::kMicrosecond);
  }
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
