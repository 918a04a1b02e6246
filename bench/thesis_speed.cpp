// Steps per second against the number of links, stiff springs and weighted Verlet in one run:
// the thesis's figures 4.7 (springs) and 4.8 (Verlet), redone without rendering.
//
//   build/bench/thesis_speed --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
//       --benchmark_out=thesis_speed.json --benchmark_out_format=json
//   /usr/bin/python3 tools/plot_thesis.py speed thesis_speed.json bench/figures
//
// The thesis's setting, as far as its text and code printouts (appendices A and B) give it:
// - the chain of section 4.4 (tools/scenes/chain.json: 20 cm links, the end link double mass,
//   pinned, released horizontally), lengthened by the scene's chain generator;
// - springs: each joint a damped spring between the inboard tail and the outboard head, and the
//   printed integrator IDynamic::Update, v += a·Δt then x += v·Δt — the symplectic Euler step
//   (Integrator::semi_implicit_euler) although the text calls it forward Euler; forward and
//   symplectic Euler cost the same per step. Implicit springs (backward Euler, 2 Newton
//   iterations) are measured too;
// - Verlet: 5 sweeps a step, the setting of the thesis's 597 frames/s (the printed chain demo
//   loops 1000, the humanoid demo 100; both are measured as well).
// Chains have no contacts and sleeping is off, so every step does the same work.
#include <functional>
#include <string>

#include <benchmark/benchmark.h>

#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/springs/compile.hpp"
#include "limber/kernel/springs/step.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"

namespace limber {
namespace {

Scene chain_scene(long links) {
  Scene scene = load_scene_file(std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/chain.json", {.variant = {}, .links = links, .copies = {}});
  scene.model.settings.sleep.enabled = false;
  return scene;
}
Model chain(long links) { return chain_scene(links).model; }

// Steps the chain from its released pose, and again from it after every simulated second
// (240 steps; the restart is not timed). Long chains on k = 2·10⁴ N/m tear — each joint carries
// the weight below it — and explicit springs then diverge after a few seconds; restarting keeps
// every method on the same first second of the same motion, and the timings off NaN arithmetic.
template <typename State>
void time_steps(benchmark::State& run, const std::function<State()>& compile_state) {
  constexpr int kStepsPerRestart = 240;
  State state = compile_state();
  bool diverged = false;
  int steps = 0;
  for (auto _ : run) {
    if (steps == kStepsPerRestart) {
      run.PauseTiming();
      state = compile_state(), steps = 0;
      run.ResumeTiming();
    }
    diverged |= step(state).status != StepStatus::ok;
    ++steps;
  }
  run.counters["links"] = static_cast<double>(run.range(0));
  run.counters["steps/s"] = benchmark::Counter(static_cast<double>(run.iterations()), benchmark::Counter::kIsRate);
  run.counters["diverged"] = diverged;  // must stay 0: a diverged run times NaN arithmetic
}

// Figure 4.7: stiff springs, integrated as the thesis's program did (see the top of the file).
void BM_SpringsExplicit(benchmark::State& run) {
  const Model model = chain(run.range(0));
  time_steps<SpringState>(run, [&] { return compile_springs(model, {.integrator = Integrator::semi_implicit_euler}); });
}

// The same springs under linearized backward Euler plus one Newton iteration (thesis 3.3,
// eq. 3.16–3.22): a sparse LDLᵀ solve a step, linear in the links on a chain.
void BM_SpringsImplicit(benchmark::State& run) {
  const Model model = chain(run.range(0));
  time_steps<SpringState>(run, [&] {
    return compile_springs(model, {.integrator = Integrator::backward_euler, .newton_iterations = 2});
  });
}

// Figure 4.8: Verlet with weighted relaxation (eq. 4.7), range(1) sweeps a step. range(2) = 1:
// the thesis's loop (sequential Gauss-Seidel, scalar) instead of the default coloured SIMD sweep.
void BM_WeightedVerlet(benchmark::State& run) {
  const Scene scene = chain_scene(run.range(0));
  const Model& model = scene.model;
  VerletOptions options{.rule = RelaxationRule::weighted};
  options.relaxation = scene.methods.relaxation;  // chain.json's rule and substeps
  options.relaxation.iterations = static_cast<int>(run.range(1));
  options.relaxation.over_relaxation = 1;  // the thesis's plain Gauss-Seidel (chain.json ships 1.5)
  if (run.range(2) == 1) options.order = SweepOrder::sequential, options.simd = false;
  time_steps<VerletState<double>>(run, [&] { return compile<double>(model, options); });
  run.counters["sweeps"] = static_cast<double>(run.range(1));
}

const long kLinks[] = {1, 2, 5, 10, 20, 40, 80, 160, 320, 640, 1280};

void links(benchmark::internal::Benchmark* b) {
  for (long n : kLinks) b->Args({n});
}
void links_and_sweeps(benchmark::internal::Benchmark* b) {
  for (long n : kLinks) b->Args({n, 5, 0});
  for (long n : kLinks) b->Args({n, 100, 0});
  // Thesis 4.4.2: 5 against 1000 sweeps on the 5-link chain (597 against 30 frames/s), on the
  // default sweep and on the thesis's own loop.
  b->Args({5, 1000, 0})->Args({5, 5, 1})->Args({5, 1000, 1});
}
BENCHMARK(BM_SpringsExplicit)->Apply(links)->ArgNames({"links"});
BENCHMARK(BM_SpringsImplicit)->Apply(links)->ArgNames({"links"});
BENCHMARK(BM_WeightedVerlet)->Apply(links_and_sweeps)->ArgNames({"links", "sweeps", "thesis_loop"});

}  // namespace
}  // namespace limber

BENCHMARK_MAIN();
