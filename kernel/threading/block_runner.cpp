#include "limber/kernel/threading/block_runner.hpp"

#include <algorithm>
#include <stdexcept>
#include <thread>
#include <vector>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/parallel_reduce.h>
#include <oneapi/tbb/task_arena.h>

#include "limber/kernel/numerics/flush_denormals.hpp"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#endif

namespace limber {
namespace {

void spin_pause(int& spins) {
  // Spin briefly, then give the core away: on a shared 2-core machine a helper that only spins
  // would take the core from the thread doing the serial parts.
  if (++spins < 64) {
#if defined(__x86_64__) || defined(__i386__)
    _mm_pause();
#endif
  } else {
    std::this_thread::yield();
  }
}

}  // namespace

// Low half of a closed stage word: no block number reaches it.
constexpr std::uint64_t kClosed = 0xFFFFFFFFu;

struct BlockRunner::Shared {
  // Owner computes: a stage's blocks are split into one home range per thread, [t·n/T,
  // (t+1)·n/T), so each thread works on the same part of every colour — and of the particles —
  // from colour to colour, and a range is claimed through its own cursor: stage number (high
  // 32 bits) and next unclaimed block (low 32 bits). A successful compare-and-swap from (s, b)
  // to (s, b + k) gives blocks b … b+k−1 of stage s to the caller; it can only succeed while
  // stage s is current, and stage s stays current (its descriptor unchanged) until every
  // claimed block has completed. A thread that finishes its range steals from the others, so a
  // stage completes even if a helper never wakes.
  struct alignas(64) Cursor {
    std::atomic<std::uint64_t> word{0};
  };
  std::unique_ptr<Cursor[]> cursors;
  alignas(64) std::atomic<std::uint64_t> current{0};  // the published stage
  alignas(64) std::atomic<std::uint32_t> completed{0};
  // The stage descriptor, read on every claim: a line of its own, away from the counters.
  alignas(64) std::atomic<std::uint32_t> count{0};
  std::atomic<BlockFunction> function{nullptr};
  std::atomic<const void*> context{nullptr};
  std::atomic<unsigned> mode{0};  // the caller's floating-point mode, which each block runs in
  // Odd while a step runs (helpers spin and claim), even between steps (helpers sleep in
  // atomic wait); `exit` ends them.
  alignas(64) std::atomic<std::uint32_t> session{0};
  std::atomic<bool> exit{false};
  // Per helper: the largest value of the blocks it ran in `stage` (read by the caller once the
  // stage completed, before the next is published).
  struct alignas(64) Result {
    std::uint64_t stage = 0;
    double largest = 0;
  };
  std::vector<Result> results;
  std::uint64_t stage = 0;

  tbb::task_arena arena;     // parallel_for
  std::vector<std::thread> helpers;  // workers: created once, live as long as the runner

  explicit Shared(int threads)
      : cursors(std::make_unique<Cursor[]>(static_cast<std::size_t>(threads))),
        results(static_cast<std::size_t>(threads)),
        arena(threads) {}

  std::uint64_t range_begin(std::size_t t, std::uint64_t total) const { return t * total / results.size(); }

  // Claims and runs blocks of the current stage, its home range first, until none is left;
  // returns false when it ran none. `result` collects the largest value. Claims in the home
  // range take one block (the cursor is nobody else's until the range runs low); steals take
  // half of what is left of the other range.
  bool work(Result& result, std::size_t home) {
    const std::uint64_t s = current.load(std::memory_order_acquire);
    if (s == 0) return false;
    const std::uint64_t total = count.load(std::memory_order_acquire);
    const std::size_t threads = results.size();
    bool ran = false;
    for (std::size_t k = 0; k < threads; ++k) {
      const std::size_t t = (home + k) % threads;
      const std::uint64_t end = range_begin(t + 1, total);
      std::atomic<std::uint64_t>& cursor = cursors[t].word;
      std::uint64_t word = cursor.load(std::memory_order_acquire);
      for (;;) {
        const std::uint64_t next = word & 0xFFFFFFFFu;
        if ((word >> 32) != s || next >= end) break;
        const std::uint64_t take = t == home ? 1 : std::max<std::uint64_t>(1, (end - next) / 2);
        if (!cursor.compare_exchange_weak(word, word + take, std::memory_order_acq_rel, std::memory_order_acquire)) continue;
        const BlockFunction run_block = function.load(std::memory_order_relaxed);
        const void* run_context = context.load(std::memory_order_relaxed);
        const UseFloatingPointMode use(mode.load(std::memory_order_relaxed));
        double largest = result.stage == s ? result.largest : 0.0;
        for (std::uint64_t block = next; block < next + take; ++block) largest = std::max(largest, run_block(run_context, block));
        result.stage = s, result.largest = largest;
        completed.fetch_add(static_cast<std::uint32_t>(take), std::memory_order_release);
        ran = true;
        word = cursor.load(std::memory_order_acquire);
      }
    }
    return ran;
  }

  void helper_loop(std::size_t slot) {
    std::uint32_t seen = 0;
    for (;;) {
      session.wait(seen, std::memory_order_acquire);
      seen = session.load(std::memory_order_acquire);
      if (exit.load(std::memory_order_acquire)) return;
      if (seen % 2 == 0) continue;  // between steps: back to sleep
      int spins = 0;
      while (session.load(std::memory_order_acquire) == seen && !exit.load(std::memory_order_relaxed)) {
        if (work(results[slot], slot)) spins = 0;
        else spin_pause(spins);
      }
    }
  }
};

BlockRunner::BlockRunner(Threading threading, int threads, TaskSystem tasks) : threading_(threading), threads_(threads), tasks_(tasks) {
  if (threads < 1) throw std::invalid_argument("BlockRunner: threads must be at least 1");
  if (threading_ == Threading::tasks) {
    if (!tasks_.valid()) throw std::invalid_argument("BlockRunner: Threading::tasks needs a task system (enqueue and finish)");
    return;
  }
  if (threads == 1) threading_ = Threading::serial;
  if (threading_ == Threading::serial) return;
  shared_ = std::make_unique<Shared>(threads);
  if (threading_ == Threading::workers) {
    for (int k = 1; k < threads; ++k) {
      shared_->helpers.emplace_back([shared = shared_.get(), k] { shared->helper_loop(static_cast<std::size_t>(k)); });
    }
  }
}

BlockRunner::~BlockRunner() {
  if (!shared_) return;
  shared_->exit.store(true, std::memory_order_release);
  shared_->session.fetch_add(1, std::memory_order_acq_rel);
  shared_->session.notify_all();
  for (std::thread& helper : shared_->helpers) helper.join();
}

void BlockRunner::begin() {
  if (threading_ != Threading::workers || active_) return;
  active_ = true;
  shared_->session.fetch_add(1, std::memory_order_acq_rel);
  shared_->session.notify_all();
}

void BlockRunner::end() {
  if (!active_) return;
  // Every stage has completed, so no block is left to claim: the helpers go back to sleep.
  active_ = false;
  shared_->session.fetch_add(1, std::memory_order_acq_rel);
}

double BlockRunner::run_serial(std::size_t count, BlockFunction function, const void* context) {
  double largest = 0;
  for (std::size_t block = 0; block < count; ++block) largest = std::max(largest, function(context, block));
  return largest;
}

namespace {

// A stage handed to a task system: each block's result lands in its own slot, reduced after.
struct TaskStage {
  BlockRunner::BlockFunction function;
  const void* context;
  double* results;
  unsigned mode;  // the caller's floating-point mode
  static void run(std::size_t begin, std::size_t end, void* stage_pointer) {
    const auto& stage = *static_cast<const TaskStage*>(stage_pointer);
    const UseFloatingPointMode use(stage.mode);
    for (std::size_t block = begin; block < end; ++block) stage.results[block] = stage.function(stage.context, block);
  }
};

}  // namespace

TaskSystem tbb_task_system(tbb::task_arena& arena) {
  TaskSystem system;
  system.user_context = &arena;
  system.enqueue = [](TaskSystem::Work work, std::size_t count, void* work_context, void* user) -> void* {
    static_cast<tbb::task_arena*>(user)->execute([&] {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1),
                        [&](const tbb::blocked_range<std::size_t>& range) { work(range.begin(), range.end(), work_context); });
    });
    return nullptr;
  };
  system.finish = [](void*, void*) {};
  return system;
}

// The largest of the blocks' results, in block order: the same whoever ran them.
double BlockRunner::run_tasks(std::size_t count, BlockFunction function, const void* context) {
  if (block_results_.size() < count) block_results_.resize(count);  // grows to the largest stage once
  TaskStage stage{function, context, block_results_.data(), floating_point_mode()};
  void* task = tasks_.enqueue(&TaskStage::run, count, &stage, tasks_.user_context);
  tasks_.finish(task, tasks_.user_context);
  double largest = 0;
  for (std::size_t block = 0; block < count; ++block) largest = std::max(largest, block_results_[block]);
  return largest;
}

double run_stage(BlockRunner* runner, std::size_t count, BlockRunner::BlockFunction function, const void* context) {
  if (runner == nullptr || runner->threads() < 2 || count < 2) {
    double largest = 0;
    for (std::size_t block = 0; block < count; ++block) largest = std::max(largest, function(context, block));
    return largest;
  }
  const bool wake = !runner->active();
  if (wake) runner->begin();
  const double largest = runner->run(count, function, context);
  if (wake) runner->end();
  return largest;
}

double BlockRunner::run(std::size_t count, BlockFunction function, const void* context) {
  if (threading_ == Threading::serial || count <= 1) return run_serial(count, function, context);
  if (threading_ == Threading::tasks) return run_tasks(count, function, context);
  Shared& shared = *shared_;
  if (threading_ == Threading::parallel_for) {
    const unsigned mode = floating_point_mode();
    return shared.arena.execute([&] {
      return tbb::parallel_reduce(
          tbb::blocked_range<std::size_t>(0, count, 1), 0.0,
          [&](const tbb::blocked_range<std::size_t>& range, double largest) {
            const UseFloatingPointMode use(mode);
            for (std::size_t block = range.begin(); block != range.end(); ++block) {
              largest = std::max(largest, function(context, block));
            }
            return largest;
          },
          [](double a, double b) { return std::max(a, b); });
    });
  }
  // Close the previous stage's cursors first: a helper holding a stale word (previous stage,
  // block b) that reads the new, larger count must not be able to claim block b with it.
  const std::size_t threads = shared.results.size();
  for (std::size_t t = 0; t < threads; ++t) shared.cursors[t].word.store((shared.stage << 32) | kClosed, std::memory_order_release);
  // Publish the stage: descriptor, cursors, then the stage number (release).
  const std::uint64_t stage = ++shared.stage;
  shared.count.store(static_cast<std::uint32_t>(count), std::memory_order_release);
  shared.function.store(function, std::memory_order_relaxed);
  shared.context.store(context, std::memory_order_relaxed);
  shared.mode.store(floating_point_mode(), std::memory_order_relaxed);
  shared.completed.store(0, std::memory_order_relaxed);
  for (std::size_t t = 0; t < threads; ++t) {
    shared.cursors[t].word.store((stage << 32) | shared.range_begin(t, count), std::memory_order_release);
  }
  shared.current.store(stage, std::memory_order_release);
  Shared::Result& own = shared.results[0];
  own.largest = 0, own.stage = stage;
  shared.work(own, 0);
  int spins = 0;
  while (shared.completed.load(std::memory_order_acquire) != count) spin_pause(spins);
  double largest = own.largest;
  for (std::size_t k = 1; k < shared.results.size(); ++k) {
    if (shared.results[k].stage == stage) largest = std::max(largest, shared.results[k].largest);
  }
  return largest;
}

}  // namespace limber
