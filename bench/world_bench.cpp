// What the World facade costs an engine: the humanoid (awake, hit by the ball) stepped through
// World::step, against the same method's step() on its state directly, and through the World
// with a force, a torque and an impulse each step. Compare the rows of one run as ratios (the
// machine is shared). The state is recompiled when the run is 2 s in, so every repetition times
// the same stretch of motion. The same for MuJoCo's 22_humanoids.xml under Featherstone at
// semi-implicit Euler (libmujoco-samples; 264 driven joint axes, which the World's divergence
// check observes after every step), its first 2 s at the file's 0.005 s.
//   build/bench/world_bench --benchmark_min_time=0.5
#include <benchmark/benchmark.h>

#include <filesystem>
#include <optional>
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

// 22_humanoids.xml under Featherstone, stepped directly (`world` false) or through the World.
void BM_Humanoids(benchmark::State& run, bool world) {
  const std::filesystem::path file = "/usr/share/mujoco/model/humanoid/22_humanoids.xml";
  if (!std::filesystem::exists(file)) return run.SkipWithError("22_humanoids.xml not found (libmujoco-samples)");
  const Scene scene = load_scene_file(file);
  WorldOptions options = world_options(Method::featherstone, scene.methods);
  options.featherstone.integrator = Integrator::semi_implicit_euler;
  options.featherstone.threads = 1;
  const double dt = scene.model.settings.time_step;
  const int steps_per_run = static_cast<int>(2.0 / dt);
  std::optional<World> through;
  MethodState state;
  const auto start = [&] {
    if (world) {
      through.emplace(scene.model, options);
    } else {
      state = compile_method(scene.model, options);
    }
  };
  start();
  int steps = 0;
  for (auto _ : run) {
    if (steps++ == steps_per_run) {
      run.PauseTiming();
      start(), steps = 1;
      run.ResumeTiming();
    }
    if (world) {
      benchmark::DoNotOptimize(through->step(dt));
    } else {
      benchmark::DoNotOptimize(std::visit([&](auto& s) { return step(s, dt).status; }, state));
    }
  }
}

void register_all() {
  for (const Method method : {Method::particles, Method::springs, Method::lagrange, Method::featherstone}) {
    const std::string name(method_name(method));
    benchmark::RegisterBenchmark(("direct/" + name).c_str(), BM_Direct, method)->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("world/" + name).c_str(), BM_World, method, false)->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("world_with_loads/" + name).c_str(), BM_World, method, true)->Unit(benchmark::kMicrosecond);
  }
  benchmark::RegisterBenchmark("direct/featherstone/22_humanoids", BM_Humanoids, false)->Unit(benchmark::kMicrosecond);
  benchmark::RegisterBenchmark("world/featherstone/22_humanoids", BM_Humanoids, true)->Unit(benchmark::kMicrosecond);
}

}  // namespace

int main(int argc, char** argv) {
  register_all();
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
