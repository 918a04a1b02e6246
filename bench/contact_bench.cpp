#pragma GCC diagnostic ignored "-Wmismatched-new-delete"  // operator delete frees what the counting operator new mallocs
// What collision costs the particle method (bench/collision.md, "Collision: contact sweeps, the cost
// of collision, tunnelling"), ratios inside one run:
//
//   build/bench/contact_bench --benchmark_filter=Sweep    the pile's rows: SIMD against scalar lanes
//   build/bench/contact_bench --benchmark_filter=Chain    a chain without collision against the same
//                                                        chain with collision on and nothing near
//   build/bench/contact_bench --benchmark_filter=Pile     the pile's whole step, and its contact stages
//
// The pile is tools/scenes/ragdoll_pile.json compiled as `limber run` compiles it (the scene's
// method settings: 100 sweeps, 1 substep, pbd; double unless a name says float), then stepped
// kSnapshotSteps steps (2 s: the pile has landed, some 550 contact rows); results are
// the same bits for every lane width and thread count, so one snapshot serves every variant.
//
// Sweep/<rows>/<scalar>/<lanes>: kSweeps sweeps (one substep's) over the snapshot's contact rows
// (the batches its last substep built), its joint rows, or relaxation_sweep (the distance
// constraints, then the joint rows), one thread, in thread CPU time. Each iteration first
// puts back the positions and zeroes the accumulated impulses, untimed, so every iteration
// projects the same rows from the same start. (The contact projection is branch-free, so its
// time does not depend on how far the rows have converged; only a place no lane moves skips its
// scatter, which depends on the masses alone.) ns/row: per row and sweep, rows without padding.
//
// Allocations (allocs/step): operator new and posix_memalign (the SIMD buffers' allocator),
// counted in the timed steps; the link wraps posix_memalign (bench/CMakeLists.txt).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <ctime>
#include <cstdlib>
#include <map>
#include <memory>
#include <new>
#include <string>

#include <benchmark/benchmark.h>

#include "limber/kernel/collision/limb_contacts.hpp"
#include "limber/kernel/methods/method.hpp"
#include "limber/kernel/relaxation/contact_relaxation.hpp"
#include "limber/kernel/relaxation/joint_relaxation.hpp"
#include "limber/kernel/relaxation/relaxation.hpp"
#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "thread_time.hpp"

// ---------------------------------------------------------------------------------------------
// Allocation counting.

namespace {
std::atomic<std::uint64_t> allocations{0};
}  // namespace

extern "C" int __real_posix_memalign(void** out, std::size_t alignment, std::size_t size);
extern "C" int __wrap_posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  allocations.fetch_add(1, std::memory_order_relaxed);
  return __real_posix_memalign(out, alignment, size);
}

void* operator new(std::size_t size) {
  allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return ::operator new(size); }
void* operator new(std::size_t size, std::align_val_t alignment) {
  allocations.fetch_add(1, std::memory_order_relaxed);
  const auto align = static_cast<std::size_t>(alignment);
  if (void* p = std::aligned_alloc(align, (std::max<std::size_t>(size, 1) + align - 1) / align * align)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size, std::align_val_t alignment) { return ::operator new(size, alignment); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

namespace limber {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// The one-thread timings use thread_seconds (thread_time.hpp): this shared 2-core machine
// preempted the process (load 3–6 while these ran).

// ---------------------------------------------------------------------------------------------
// The pile.

constexpr int kSnapshotSteps = 480;  // 2 s: the pile has landed
constexpr int kSweeps = 100;         // the scene's sweeps per substep

const Scene& pile_scene() {
  static const Scene scene = load_scene_file(std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/ragdoll_pile.json");
  return scene;
}

// `limber run`'s options for the pile: the scene's method settings (tools/cli/cli.cpp,
// verlet_options), with `threads` (the CLI's default, 0, gives 1 here: no colour is big enough).
VerletOptions pile_options(bool simd, int threads) {
  VerletOptions options = world_options(Method::particles, pile_scene().methods).particles;
  options.simd = simd;
  options.threads = threads;
  return options;
}

// The pile, compiled and stepped `steps` steps (one thread, SIMD; the same bits as any other).
template <typename Scalar>
const VerletState<Scalar>& pile_at(int steps) {
  static std::map<int, std::unique_ptr<VerletState<Scalar>>> cache;
  auto& state = cache[steps];
  if (!state) {
    state = std::make_unique<VerletState<Scalar>>(compile<Scalar>(pile_scene().model, pile_options(true, 1)));
    for (int s = 0; s < steps; ++s) step(*state);
  }
  return *state;
}

const char* lanes_name(bool simd) { return simd ? "simd" : "scalar"; }
template <typename Scalar>
const char* scalar_name() {
  return sizeof(Scalar) == 4 ? "float" : "double";
}

// ---------------------------------------------------------------------------------------------
// Sweeps over the pile's rows, SIMD against scalar lanes, one thread.

// relaxation: one relaxation_sweep, what step() sweeps before the contacts: the distance
// constraints (links and joints' zero-length constraints) and then the joint rows.
enum RowKind : int { contact_rows, joint_rows, relaxation };
const char* kind_name(int kind) {
  constexpr const char* names[] = {"contacts", "joints", "relaxation"};
  return names[kind];
}

template <typename Scalar>
void zero_contact_impulses(ContactRowBatches<Scalar>& batches) {
  for (auto* array : {&batches.lambda, &batches.tangent_x, &batches.tangent_y, &batches.tangent_z}) std::fill(array->begin(), array->end(), Scalar(0));
}

template <typename Scalar>
void BM_Sweep(benchmark::State& run, int kind, bool simd) {
  VerletState<Scalar> state = pile_at<Scalar>(kSnapshotSteps);
  state.options.simd = simd;
  const double h = state.settings.time_step / state.options.relaxation.substeps;
  // Joint rows and distance constraints sweep between begin_ and end_relaxation (their batches).
  if (kind != contact_rows) begin_relaxation(state, h);
  const ParticleBuffer<Scalar> start = state.particles;
  double rows = 0, slots = 0;
  if (kind == contact_rows) {
    rows = static_cast<double>(state.contact_rows.rows.size());
    slots = static_cast<double>(state.plan.contact_batches.slot_count());
  } else if (kind == joint_rows) {
    rows = static_cast<double>(state.joint_rows.rows.size());
    slots = static_cast<double>(state.plan.joint_batches.slot_count());
  } else {
    rows = static_cast<double>(state.constraints.size() + state.joint_rows.rows.size());
    slots = static_cast<double>(state.plan.batches.slot_count() + state.plan.joint_batches.slot_count());
  }
  for (auto _ : run) {
    state.particles = start;
    if (kind == contact_rows) zero_contact_impulses(state.plan.contact_batches);
    if (kind == joint_rows) begin_joint_rows(state, h);
    const double begin = thread_seconds();
    double largest = 0;
    for (int sweep = 0; sweep < kSweeps; ++sweep) {
      largest += kind == contact_rows ? contact_position_sweep(state)
                 : kind == joint_rows  ? joint_position_sweep(state)
                                       : relaxation_sweep(state, 1.0);
    }
    run.SetIterationTime(thread_seconds() - begin);
    benchmark::DoNotOptimize(largest);
  }
  if (kind != contact_rows) end_relaxation(state);
  run.SetLabel(std::string(kind_name(kind)) + "/" + scalar_name<Scalar>() + "/" + lanes_name(simd));
  run.counters["rows"] = rows;
  run.counters["slots"] = slots;
  run.counters["colours"] = static_cast<double>(kind == contact_rows ? state.plan.contact_batches.colour_count()
                                                : kind == joint_rows ? state.plan.joint_batches.colour_count()
                                                                     : state.plan.batches.colour_count());
  if (kind == contact_rows) {  // rows the colouring could not place: projected one lane at a time
    const auto& batches = state.plan.contact_batches;
    run.counters["overflow"] = static_cast<double>(batches.slot_count() - batches.overflow_begin());
    // Limb–limb rows move four particles; limb–static rows two, the ball's one. The kernel
    // gathers two places in a colour's blocks of limb–static rows alone, four in the rest
    // (four_place_slots, padding included: limb–limb blocks and each colour's mixed block).
    run.counters["limb_limb"] = static_cast<double>(std::count_if(state.contact_rows.rows.begin(), state.contact_rows.rows.end(),
                                                                  [](const ContactRow& row) { return row.coefficient[2] != 0; }));
    double four_place = 0;
    for (std::size_t colour = 0; colour < batches.colour_count(); ++colour) four_place += batches.colour_begin[colour + 1] - batches.pair_begin[colour];
    run.counters["four_place_slots"] = four_place;
  }
  run.counters["ns/row"] = benchmark::Counter(rows * kSweeps, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

// ---------------------------------------------------------------------------------------------
// A chain: collision inactive against active with nothing near.

enum ChainVariant : int { inactive, far_box, limb_pairs };
const char* chain_variant_name(int variant) {
  constexpr const char* names[] = {"inactive", "far_box", "limb_pairs"};
  return names[variant];
}

// A chain of `links` links of 0.1 m released horizontally (generated: its links are in
// kLinkCollisionGroup and never collide); far_box adds a static box 100 m away; limb_pairs puts
// the links in the default group, so every pair of links not joined (nor overlapping at the
// start) is tested.
Model chain(long links, int variant) {
  Model model = make_chain_model({.links = static_cast<std::size_t>(links)});
  if (variant == far_box) {
    StaticCollider box;
    box.name = "far_box", box.type = ColliderType::box, box.position = Vector3(100, 100, -100), box.half_extents = Vector3(1, 1, 1);
    model.colliders.push_back(box);
  }
  if (variant == limb_pairs) {
    for (Body& body : model.bodies) body.collision = CollisionFilter{};
  }
  return model;
}

constexpr int kChainSteps = 240;  // 1 s, then the chain starts again from its release

void BM_Chain(benchmark::State& run) {
  const long links = run.range(0);
  const int variant = static_cast<int>(run.range(1));
  VerletOptions options;  // the defaults: 100 sweeps, 1 substep, pbd, one thread, SIMD
  const VerletState<double> released = compile<double>(chain(links, variant), options);
  // One untimed run first, so the buffers have grown to what the run needs (a copy keeps only
  // what it holds, and copy-assigning keeps the capacity that the target already has).
  VerletState<double> state = released;
  for (int s = 0; s < kChainSteps; ++s) step(state);
  state = released;
  std::uint64_t allocated = 0, steps = 0, rows = 0;
  int since_release = 0;
  for (auto _ : run) {
    if (since_release++ == kChainSteps) {
      run.PauseTiming();
      state = released, since_release = 1;
      run.ResumeTiming();
    }
    const std::uint64_t before = allocations.load(std::memory_order_relaxed);
    benchmark::DoNotOptimize(step(state));
    allocated += allocations.load(std::memory_order_relaxed) - before;
    rows += state.contact_rows.rows.size();
    ++steps;
  }
  // Whether detection ran: it fills the limb segments on its first call (compile only reserves them).
  run.counters["detection_ran"] = state.limb_segments.empty() ? 0 : 1;
  // What one detection costs at the end of the run (step() calls it once a substep when collision
  // is active; never for the inactive chain, where this call returns at once).
  constexpr int kDetections = 100;
  const double begin = thread_seconds();
  for (int k = 0; k < kDetections; ++k) detect_limb_contacts(state, state.settings.time_step);
  run.counters["detect_us"] = 1e6 * (thread_seconds() - begin) / kDetections;
  run.counters["collision_active"] = state.collisions.active() ? 1 : 0;
  run.counters["rows/step"] = static_cast<double>(rows) / static_cast<double>(std::max<std::uint64_t>(steps, 1));
  run.counters["allocs/step"] = static_cast<double>(allocated) / static_cast<double>(std::max<std::uint64_t>(steps, 1));
  run.counters["steps/s"] = benchmark::Counter(static_cast<double>(run.iterations()), benchmark::Counter::kIsRate);
  run.SetLabel(chain_variant_name(variant));
}

// The far box moves nothing: the inactive and far_box chains give the same bits after 1 s.
void BM_ChainSameBits(benchmark::State& run) {
  const long links = run.range(0);
  bool same = true;
  for (auto _ : run) {
    VerletState<double> plain = compile<double>(chain(links, inactive), {});
    VerletState<double> boxed = compile<double>(chain(links, far_box), {});
    for (int s = 0; s < kChainSteps; ++s) step(plain), step(boxed);
    same = plain.particles.position_x == boxed.particles.position_x && plain.particles.position_y == boxed.particles.position_y &&
           plain.particles.position_z == boxed.particles.position_z;
  }
  run.counters["same_bits"] = same ? 1 : 0;
}

// ---------------------------------------------------------------------------------------------
// The pile's whole step, and its contact stages by parts.

constexpr int kRunSteps = 720;  // the scene's 3 s, as `limber run tools/scenes/ragdoll_pile.json`

// The scene's run from its start: steps/s, contact rows per step and time per row.
// Each iteration compiles the scene afresh (untimed): a copied state would allocate in its first
// steps, since a copy keeps the sizes of compile's buffers but not the capacity it reserved.
template <typename Scalar>
void BM_PileRun(benchmark::State& run, bool simd, int threads) {
  double rows = 0, touching = 0, steps = 0, seconds = 0, cpu_seconds = 0, runner_threads = 0, largest_colour = 0;
  std::uint64_t allocated = 0;
  for (auto _ : run) {
    VerletState<Scalar> state = compile<Scalar>(pile_scene().model, pile_options(simd, threads));
    runner_threads = state.plan.runner->threads();
    const std::uint64_t before = allocations.load(std::memory_order_relaxed);
    const double cpu_begin = static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
    const auto begin = Clock::now();
    for (int s = 0; s < kRunSteps; ++s) {
      const StepReport report = step(state);
      rows += static_cast<double>(state.contact_rows.rows.size());
      touching += report.contacts;
    }
    const double elapsed = seconds_since(begin);
    cpu_seconds += static_cast<double>(std::clock()) / CLOCKS_PER_SEC - cpu_begin;
    allocated += allocations.load(std::memory_order_relaxed) - before;
    run.SetIterationTime(elapsed);
    largest_colour = 0;  // of the batches the last step swept
    for (const auto* begins : {&state.plan.batches.colour_begin, &state.plan.joint_batches.colour_begin}) {
      for (std::size_t k = 0; k + 1 < begins->size(); ++k) largest_colour = std::max<double>(largest_colour, (*begins)[k + 1] - (*begins)[k]);
    }
    seconds += elapsed, steps += kRunSteps;
  }
  run.SetLabel(std::string(scalar_name<Scalar>()) + "/" + lanes_name(simd) + "/" + std::to_string(threads) + "t");
  run.counters["threads"] = runner_threads;
  // The most slots a distance or joint colour has: a colour is split across threads only from
  // VerletOptions::parallel_minimum_slots (16,384 by default), in tasks of 512 slots.
  run.counters["largest_colour"] = largest_colour;
  run.counters["steps/s"] = steps / seconds;
  run.counters["cpu_ms/step"] = 1e3 * cpu_seconds / steps;  // the process's, every thread's
  run.counters["rows/step"] = rows / steps;
  run.counters["touching/step"] = touching / steps;
  run.counters["us/row"] = 1e6 * seconds / rows;  // step time over the rows it had
  run.counters["allocs/step"] = static_cast<double>(allocated) / steps;
}

// At the snapshot, one thread, in thread CPU time: one whole step, and the contact stages it
// runs, by parts, each on its own copy of the snapshot — detection and colouring (once per substep), kSweeps contact sweeps,
// the restitution pass. Detection runs here on the snapshot's positions, not a substep's
// prediction: the same work up to what it finds.
template <typename Scalar>
void BM_PileStages(benchmark::State& run, bool simd) {
  VerletState<Scalar> snapshot = pile_at<Scalar>(kSnapshotSteps);
  snapshot.options.simd = simd;
  const double h = snapshot.settings.time_step / snapshot.options.relaxation.substeps;
  double step_s = 0, detect_s = 0, sweeps_s = 0, restitution_s = 0, rows = 0;
  // Copies that have stepped once, so their buffers have the capacity a step needs: assigning
  // the snapshot to them keeps it (a fresh copy would allocate in its first step).
  VerletState<Scalar> stepped = snapshot, parts = snapshot;
  step(stepped), step(parts);
  for (auto _ : run) {
    stepped = snapshot;
    double begin = thread_seconds();
    benchmark::DoNotOptimize(step(stepped));
    const double whole = thread_seconds() - begin;
    parts = snapshot;
    begin = thread_seconds();
    detect_limb_contacts(parts, h);
    build_contact_batches(parts);
    detect_s += thread_seconds() - begin;
    begin = thread_seconds();
    double largest = 0;
    for (int sweep = 0; sweep < kSweeps; ++sweep) largest += contact_position_sweep(parts);
    sweeps_s += thread_seconds() - begin;
    benchmark::DoNotOptimize(largest);
    begin = thread_seconds();
    apply_contact_row_restitution(parts, h);
    restitution_s += thread_seconds() - begin;
    rows += static_cast<double>(parts.contact_rows.rows.size());
    run.SetIterationTime(whole);
    step_s += whole;
  }
  const double n = static_cast<double>(run.iterations());
  run.SetLabel(std::string(scalar_name<Scalar>()) + "/" + lanes_name(simd));
  run.counters["rows"] = rows / n;
  run.counters["step_us"] = 1e6 * step_s / n;
  run.counters["detect_us"] = 1e6 * detect_s / n;
  run.counters["sweeps_us"] = 1e6 * sweeps_s / n;
  run.counters["restitution_us"] = 1e6 * restitution_s / n;
  run.counters["contact_share"] = (detect_s + sweeps_s + restitution_s) / step_s;
}

void register_all() {
  for (const int kind : {contact_rows, joint_rows, relaxation}) {
    for (const bool simd : {true, false}) {
      const std::string name = std::string("Sweep/") + kind_name(kind) + "/";
      benchmark::RegisterBenchmark((name + "float/" + lanes_name(simd)).c_str(), BM_Sweep<float>, kind, simd)
          ->UseManualTime()->Unit(benchmark::kMicrosecond);
      benchmark::RegisterBenchmark((name + "double/" + lanes_name(simd)).c_str(), BM_Sweep<double>, kind, simd)
          ->UseManualTime()->Unit(benchmark::kMicrosecond);
    }
  }
  for (const long links : {64L, 1000L}) {
    for (const int variant : {inactive, far_box, limb_pairs}) {
      benchmark::RegisterBenchmark("Chain", BM_Chain)->Args({links, variant})->Unit(benchmark::kMicrosecond);
    }
    benchmark::RegisterBenchmark("ChainSameBits", BM_ChainSameBits)->Args({links})->Iterations(1)->Unit(benchmark::kMillisecond);
  }
  for (const bool simd : {true, false}) {
    benchmark::RegisterBenchmark((std::string("PileStages/double/") + lanes_name(simd)).c_str(), BM_PileStages<double>, simd)
        ->UseManualTime()->Unit(benchmark::kMicrosecond);
  }
  for (const int threads : {1, 2}) {
    for (const bool simd : {true, false}) {
      const std::string name = std::string("PileRun/double/") + lanes_name(simd) + "/" + std::to_string(threads) + "t";
      benchmark::RegisterBenchmark(name.c_str(), BM_PileRun<double>, simd, threads)
          ->UseManualTime()->Iterations(1)->Unit(benchmark::kMillisecond);
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
