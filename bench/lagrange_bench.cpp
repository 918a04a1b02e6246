// Time per step of the Lagrange method against the number of links: Baraff's tree-ordered solve
// is linear; the general sparse path (Eigen's LDLT of J M⁻¹ Jᵀ) shown beside it. A pinned chain
// hanging at 10° from vertical (it swings, it does not tumble), Δt = 1/240 s, symplectic Euler
// with Baumgarte stabilization.
//   build/bench/lagrange_bench --benchmark_min_time=0.2
#include <benchmark/benchmark.h>

#include <cmath>

#include "limber/kernel/lagrange/compile.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "limber/kernel/scene/generators.hpp"

namespace {

using namespace limber;

void step_chain(benchmark::State& bench, MultiplierSolver solver) {
  const auto links = static_cast<std::size_t>(bench.range(0));
  Model model = make_chain_model({.links = links, .direction = Vector3(std::sin(0.17), 0, -std::cos(0.17))});
  LagrangeState state = compile_lagrange(model, {.solver = solver});
  for (int s = 0; s < 5; ++s) step(state);  // warm up
  for (auto _ : bench) benchmark::DoNotOptimize(step(state).constraint_error);
  bench.counters["links"] = static_cast<double>(links);
  bench.counters["ns_per_link"] = benchmark::Counter(static_cast<double>(links), benchmark::Counter::kIsIterationInvariantRate |
                                                                                    benchmark::Counter::kInvert);
}

void BM_LagrangeStepTree(benchmark::State& bench) { step_chain(bench, MultiplierSolver::tree); }
void BM_LagrangeStepSparse(benchmark::State& bench) { step_chain(bench, MultiplierSolver::sparse); }

BENCHMARK(BM_LagrangeStepTree)->RangeMultiplier(10)->Range(10, 100000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_LagrangeStepSparse)->RangeMultiplier(10)->Range(10, 10000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
