// The data-oriented core under load: coloured relaxation on chains, trees, a particle grid, a
// pile of humanoids and a heavy-end chain, for every path (scalar, SIMD, SIMD on two threads,
// float and double, three layouts), next to a streaming benchmark that measures the machine's
// memory bandwidth in the same run (float and double, 1 and 2 threads), and the direct solver's
// elimination in constraint space (Solve/<workload>/<scalar type>/direct) with its bytes.
//
//   build/bench/relaxation_bench                                  everything (several minutes)
//   build/bench/relaxation_bench --benchmark_filter='Sweep/chain' one family
//   tools/relaxation_report.py                                    runs it and prints the README tables
//
// Names: Colour/<workload> (colouring alone), <kind>/<workload>/<scalar type>/<path>, path =
// scalar (one lane over SoA: the reference) | simd (the default: automatic layout) |
// simd_2t_workers | simd_2t_parallel_for | simd_soa | simd_aos | simd_aosoa | scalar_aos |
// jacobi_simd | jacobi_simd_2t_workers | rattle_simd | rattle_simd_2t_workers (the rattle
// rule's position sweep, along the stored start gradients) | rattle_velocity_simd |
// rattle_velocity_simd_2t_workers (its velocity sweep).
// "Sweep" times one relaxation iteration over every constraint; "Step" one full step (Verlet
// integration + 10 sweeps + sleep bookkeeping; rattle: + 10 velocity sweeps). Counters:
// constraints, projections/s, and bytes/s of the data a sweep must stream (see streamed_bytes).
//
//   build/bench/relaxation_bench --benchmark_filter='Sweep/chain_1000000?/.*/(simd|rattle_simd)(_2t_workers)?$'
// compares the rattle sweep with today's pbd sweep on 10^5 and 10^6 links, float and double,
// 1 and 2 threads, in one run (bench/speed.md).
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/partitioner.h>
#include <oneapi/tbb/task_arena.h>

#include "limber/kernel/relaxation/relaxation.hpp"
#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "limber/layouts/graph/constraint_colouring.hpp"

namespace limber {
namespace {

struct Workload {
  std::string name;
  std::function<Model()> build;
  /// The generated chains, trees and the grid join links by one particle a joint; the
  /// humanoids as their scene does (zero-length constraints).
  ParticleJoints joints = ParticleJoints::shared_particle;
};

Model without_sleep(Model model) {
  model.settings.sleep.enabled = false;
  return model;
}

// Ten sweeps a step, the workload's joints.
VerletOptions workload_options(const Workload& workload) {
  VerletOptions options;
  options.relaxation.iterations = 10;
  options.verlet.joints = workload.joints;
  return options;
}

std::vector<Workload> workloads() {
  std::vector<Workload> list;
  for (std::size_t links : {10u, 100u, 1000u, 10000u, 100000u, 1000000u}) {
    list.push_back({"chain_" + std::to_string(links), [links] {
                      ChainSpec spec;
                      spec.links = links;
                      return without_sleep(make_chain_model(spec));
                    }});
    list.push_back({"tree_" + std::to_string(links), [links] {
                      TreeSpec spec;
                      spec.links = links;
                      return without_sleep(make_tree_model(spec));
                    }});
  }
  list.push_back({"grid_100x100", [] { return without_sleep(make_grid_model(GridSpec{})); }});
  list.push_back({"humanoids_160", [] { return without_sleep(make_humanoid_pile(160)); }, ParticleJoints::zero_length_constraint});
  list.push_back({"heavy_end_chain_1000", [] {
                    ChainSpec spec;
                    spec.links = 1000;
                    spec.end_mass_ratio = 670;
                    return without_sleep(make_chain_model(spec));
                  }});
  return list;
}

// Compiled states are cached per workload and scalar type: compiling 10^6 links takes seconds.
template <typename Scalar>
const VerletState<Scalar>& compiled(const Workload& workload) {
  static std::map<std::string, std::unique_ptr<VerletState<Scalar>>> cache;
  auto& slot = cache[workload.name];
  if (!slot) {
    slot = std::make_unique<VerletState<Scalar>>(compile<Scalar>(workload.build(), workload_options(workload)));
    for (int s = 0; s < 3; ++s) step(*slot);  // settle the first-step work
  }
  return *slot;
}

struct Path {
  std::string name;
  VerletOptions options;
  ProjectionRule projection = ProjectionRule::pbd;
  bool velocity = false;  ///< time the rattle rule's velocity sweep instead of the position sweep
};

std::vector<Path> paths() {
  auto make = [](const char* name, bool simd, int threads, Threading threading, ParticleLayout layout,
                 RelaxationSolver solver) {
    VerletOptions options;
    options.simd = simd, options.threads = threads, options.threading = threading, options.layout = layout;
    options.solver = solver;
    // Always split across threads when asked to: the crossover is what the benchmark measures.
    options.parallel_minimum_slots = 1;
    return Path{name, options};
  };
  auto rattle = [](Path path, bool velocity) {
    path.projection = ProjectionRule::rattle, path.velocity = velocity;
    return path;
  };
  const auto gs = RelaxationSolver::gauss_seidel, jacobi = RelaxationSolver::jacobi;
  const auto automatic = ParticleLayout::automatic, soa = ParticleLayout::soa;
  return {
      make("scalar", false, 1, Threading::serial, soa, gs),  // the reference: scalar over SoA
      make("simd", true, 1, Threading::serial, automatic, gs),
      make("simd_2t_workers", true, 2, Threading::workers, automatic, gs),
      make("simd_2t_parallel_for", true, 2, Threading::parallel_for, automatic, gs),
      make("simd_soa", true, 1, Threading::serial, soa, gs),
      make("simd_aos", true, 1, Threading::serial, ParticleLayout::aos, gs),
      make("simd_aosoa", true, 1, Threading::serial, ParticleLayout::aosoa, gs),
      make("scalar_aos", false, 1, Threading::serial, ParticleLayout::aos, gs),
      make("jacobi_simd", true, 1, Threading::serial, automatic, jacobi),
      make("jacobi_simd_2t_workers", true, 2, Threading::workers, automatic, jacobi),
      rattle(make("rattle_simd", true, 1, Threading::serial, automatic, gs), false),
      rattle(make("rattle_simd_2t_workers", true, 2, Threading::workers, automatic, gs), false),
      rattle(make("rattle_velocity_simd", true, 1, Threading::serial, automatic, gs), true),
      rattle(make("rattle_velocity_simd_2t_workers", true, 2, Threading::workers, automatic, gs), true),
  };
}

// The data one sweep must move at least once: the batch arrays (two indices, rest length, two
// shares per slot) and the positions of the particles they touch, read and written.
template <typename Scalar>
double streamed_bytes(const VerletState<Scalar>& state) {
  const auto& batches = state.plan.batches;
  const double slot_bytes = 2.0 * sizeof(typename ConstraintBatches<Scalar>::Index) + 3.0 * sizeof(Scalar);
  return static_cast<double>(batches.slot_count()) * slot_bytes + 2.0 * 3.0 * sizeof(Scalar) * static_cast<double>(state.particles.size());
}

template <typename Scalar>
VerletState<Scalar> prepared(const Workload& workload, const Path& path) {
  VerletState<Scalar> state = compiled<Scalar>(workload);
  const VerletOptions compiled_with = state.options;  // its relaxation and particle settings
  state.options = path.options;
  state.options.relaxation = compiled_with.relaxation, state.options.verlet = compiled_with.verlet;
  state.options.relaxation.projection = path.projection;
  prepare_relaxation_plan(state);
  return state;
}

template <typename Scalar>
void sweep_benchmark(benchmark::State& run, const Workload& workload, const Path& path) {
  VerletState<Scalar> state = prepared<Scalar>(workload, path);
  begin_relaxation(state, 1.0 / 60);
  if (path.velocity) {
    end_relaxation(state);
    begin_velocity_projection(state);
    for (auto _ : run) benchmark::DoNotOptimize(velocity_sweep(state));
    end_velocity_projection(state);
  } else {
    for (auto _ : run) benchmark::DoNotOptimize(relaxation_sweep(state, 1.0));
    end_relaxation(state);
  }
  const double constraints = static_cast<double>(state.constraints.size());
  run.counters["constraints"] = constraints;
  run.counters["colours"] = state.colour_count;
  run.counters["projections/s"] = benchmark::Counter(constraints * static_cast<double>(run.iterations()), benchmark::Counter::kIsRate);
  run.counters["bytes/s"] = benchmark::Counter(streamed_bytes(state) * static_cast<double>(run.iterations()), benchmark::Counter::kIsRate);
}

template <typename Scalar>
void step_benchmark(benchmark::State& run, const Workload& workload, const Path& path) {
  VerletState<Scalar> state = prepared<Scalar>(workload, path);
  step(state);  // the first step builds the batches and touches their pages
  for (auto _ : run) benchmark::DoNotOptimize(step(state));
  run.counters["constraints"] = static_cast<double>(state.constraints.size());
  run.counters["steps/s"] = benchmark::Counter(static_cast<double>(run.iterations()), benchmark::Counter::kIsRate);
}

// Colouring alone (constraint_colouring.hpp) on the compiled constraints, as compile() runs it.
void colouring_benchmark(benchmark::State& run, const Workload& workload) {
  const VerletState<float>& state = compiled<float>(workload);
  const auto& constraints = state.constraints;
  std::vector<bool> movable(state.particles.size());
  for (std::size_t p = 0; p < movable.size(); ++p) movable[p] = state.particles.inverse_mass[p] > 0;
  std::vector<std::uint32_t> order;
  for (std::uint32_t c = 0; c < constraints.size(); ++c) {
    if (movable[constraints.particle_i[c]] && movable[constraints.particle_j[c]]) order.push_back(c);
  }
  std::uint32_t colours = 0;
  for (auto _ : run) {
    const ConstraintColouring colouring = colour_constraints({constraints.particle_i.data(), constraints.size()},
                                                             {constraints.particle_j.data(), constraints.size()}, order,
                                                             movable, 16);
    colours = colouring.colour_count();
    benchmark::DoNotOptimize(colouring.colour.data());
  }
  run.counters["constraints"] = static_cast<double>(constraints.size());
  run.counters["colours"] = colours;
}

// The machine's streaming bandwidth: a[i] = b[i] + s·c[i] over three arrays of 256 MiB (far
// beyond every cache these VMs have reported, up to a 480 MB L3), counted as 3 arrays moved (the
// write-allocate read of `a` is not counted, as STREAM), on 1 or 2 threads (each its half).
template <typename Scalar>
void BM_StreamTriad(benchmark::State& run) {
  const std::size_t n = (std::size_t{256} << 20) / sizeof(Scalar);
  const auto threads = static_cast<int>(run.range(0));
  AlignedArray<Scalar> a(n, Scalar(0)), b(n, Scalar(1)), c(n, Scalar(2));
  tbb::task_arena arena(threads);
  const auto triad = [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) a[i] = b[i] + Scalar(0.5) * c[i];
  };
  for (auto _ : run) {
    if (threads == 1) {
      triad(0, n);
    } else {
      arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, n / static_cast<std::size_t>(threads)),
                          [&](const tbb::blocked_range<std::size_t>& range) { triad(range.begin(), range.end()); }, tbb::static_partitioner());
      });
    }
    benchmark::DoNotOptimize(a.data());
    benchmark::ClobberMemory();
  }
  run.counters["bytes/s"] = benchmark::Counter(3.0 * sizeof(Scalar) * static_cast<double>(n) * static_cast<double>(run.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_StreamTriad<float>)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->MinTime(0.5);
BENCHMARK(BM_StreamTriad<double>)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->MinTime(0.5);

// The direct solver's elimination in constraint space (constraint_elimination.hpp) over every
// component of the workload, as one Newton step of the pbd rule needs it: a factor from the
// directions of a step in flight, then one solve. Its bytes: the elimination's arrays
// (storage_bytes) and the inputs the factor reads (a direction per constraint, an inverse mass
// per particle through its index).
template <typename Scalar>
void solve_benchmark(benchmark::State& run, const Workload& workload) {
  VerletOptions options = workload_options(workload);
  options.solver = RelaxationSolver::direct, options.newton_iterations = 1;
  VerletState<Scalar> state = compile<Scalar>(workload.build(), options);
  step(state);  // directions of a chain in motion
  DirectProjection<Scalar>& direct = state.plan.direct;
  ConstraintElimination<Scalar>& solver = direct.constraint_space;
  const std::size_t components = direct.in_constraint_space.size();
  for (std::size_t k = 0; k < components; ++k) {
    if (!direct.in_constraint_space[k]) {
      run.SkipWithError("a component is solved in particle blocks");
      return;
    }
  }
  const auto weight = [&](std::size_t body) { return state.particles.inverse_mass[direct.particle_of_body[body]]; };
  const auto direction = [&](std::size_t c) -> const Eigen::Matrix<Scalar, 3, 1>& { return direct.direction[c]; };
  const auto compliance = [](std::size_t) { return Scalar(0); };
  for (auto _ : run) {
    bool definite = true;
    for (std::size_t k = 0; k < components; ++k) {
      definite = solver.factor(k, weight, direction, compliance) && definite;
      solver.solve(k);
    }
    benchmark::DoNotOptimize(definite);
  }
  const double constraints = static_cast<double>(state.constraints.size());
  const double bytes = static_cast<double>(solver.storage_bytes()) + constraints * 3.0 * sizeof(Scalar) +
                       static_cast<double>(direct.particle_of_body.size()) * (sizeof(Scalar) + sizeof(std::uint32_t));
  run.counters["constraints"] = constraints;
  run.counters["bytes/constraint"] = bytes / constraints;
  run.counters["ns/constraint"] = benchmark::Counter(constraints * static_cast<double>(run.iterations()) * 1e-9,
                                                     benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  run.counters["bytes/s"] = benchmark::Counter(bytes * static_cast<double>(run.iterations()), benchmark::Counter::kIsRate);
}

void register_all() {
  for (const Workload& workload : workloads()) {
    benchmark::RegisterBenchmark(("Colour/" + workload.name).c_str(), colouring_benchmark, workload)
        ->MinTime(0.05)->Unit(benchmark::kMillisecond);
    if (workload.name.rfind("chain_", 0) == 0 || workload.name.rfind("tree_", 0) == 0) {
      benchmark::RegisterBenchmark(("Solve/" + workload.name + "/float/direct").c_str(), solve_benchmark<float>, workload)
          ->MinTime(0.05)->Unit(benchmark::kMicrosecond);
      benchmark::RegisterBenchmark(("Solve/" + workload.name + "/double/direct").c_str(), solve_benchmark<double>, workload)
          ->MinTime(0.05)->Unit(benchmark::kMicrosecond);
    }
    for (const Path& path : paths()) {
      for (const bool use_float : {true, false}) {
        const std::string type = use_float ? "float" : "double";
        // AoSoA, scalar-AoS and Jacobi variants in float only.
        const bool main_path = path.name == "scalar" || path.name == "simd" || path.name == "simd_soa" ||
                               path.name == "simd_aos" || path.name.rfind("simd_2t", 0) == 0 ||
                               path.name.rfind("rattle_simd", 0) == 0;
        if (!use_float && !main_path) continue;
        const std::string suffix = workload.name + "/" + type + "/" + path.name;
        if (use_float) {
          benchmark::RegisterBenchmark(("Sweep/" + suffix).c_str(), sweep_benchmark<float>, workload, path)
              ->MinTime(0.05)->Unit(benchmark::kMicrosecond);
          if (main_path && !path.velocity) benchmark::RegisterBenchmark(("Step/" + suffix).c_str(), step_benchmark<float>, workload, path)
              ->MinTime(0.05)->Unit(benchmark::kMicrosecond);
        } else {
          benchmark::RegisterBenchmark(("Sweep/" + suffix).c_str(), sweep_benchmark<double>, workload, path)
              ->MinTime(0.05)->Unit(benchmark::kMicrosecond);
          if (!path.velocity) benchmark::RegisterBenchmark(("Step/" + suffix).c_str(), step_benchmark<double>, workload, path)
              ->MinTime(0.05)->Unit(benchmark::kMicrosecond);
        }
      }
    }
  }
}

}  // namespace
}  // namespace limber

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  limber::register_all();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
