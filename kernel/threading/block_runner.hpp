// Runs a relaxation's stages — each a list of independent blocks (the blocks of one colour) —
// on one or more threads, with three strategies to compare:
//
// - serial: the calling thread runs every block; no synchronization at all.
// - parallel_for: oneTBB's parallel_reduce over each stage; a fork and join per stage.
// - workers: long-lived helper threads (created with the runner, asleep between steps) that
//   spin during a step and claim blocks with compare-and-swaps, as Box2D v3's solver stages
//   do: each thread first from its own share of the stage (owner computes: the same share of
//   every colour, so its particles stay in its cache), then from the others'. The calling
//   thread claims blocks too and never waits for a
//   helper to *start*, so a stage completes even if a helper is descheduled; it only waits for
//   blocks already claimed. (A oneTBB task as the helper was tried first: a task spawned from
//   arena.execute() stayed in the caller's pool and ran only when the caller waited for it.)
//
// - tasks: the engine's own task system (TaskSystem: Box2D v3's enqueueTask/finishTask), or a
//   oneTBB arena the engine owns (tbb_task_system): limber starts no thread of its own.
//
// Blocks of a stage must be independent (different colours' blocks are not). Which thread runs
// a block never changes its result, so results are the same bits for any thread count.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <oneapi/tbb/task_arena.h>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build
#include "limber/kernel/threading/task_system.hpp"

namespace limber {

/// A TaskSystem that runs each stage with tbb::parallel_for inside `arena` (the engine's: its
/// threads, its concurrency limit), for Threading::tasks. The arena must outlive its users.
TaskSystem tbb_task_system(tbb::task_arena& arena);

class BlockRunner {
 public:
  /// Runs block `block` of a stage with `context`; returns a value to maximize over the stage.
  using BlockFunction = double (*)(const void* context, std::size_t block);

  /// `threads` ≥ 1 (1 makes every strategy but tasks serial). Threading::tasks runs on `tasks`,
  /// which must be valid. Throws std::invalid_argument otherwise.
  BlockRunner(Threading threading, int threads, TaskSystem tasks = {});
  ~BlockRunner();
  BlockRunner(const BlockRunner&) = delete;
  BlockRunner& operator=(const BlockRunner&) = delete;

  Threading threading() const { return threading_; }
  int threads() const { return threads_; }
  const TaskSystem& tasks() const { return tasks_; }

  /// Brackets the stages of one step: wakes the helper threads and sends them back to sleep
  /// (workers only; otherwise no-ops).
  void begin();
  void end();
  /// Whether the helpers are awake: between begin() and end() (workers only).
  bool active() const { return active_; }

  /// Runs blocks [0, count) and returns the largest value they returned (0 when count is 0).
  double run(std::size_t count, BlockFunction function, const void* context);

 private:
  struct Shared;
  double run_serial(std::size_t count, BlockFunction function, const void* context);
  double run_tasks(std::size_t count, BlockFunction function, const void* context);
  Threading threading_;
  int threads_;
  TaskSystem tasks_;
  std::vector<double> block_results_;  ///< Threading::tasks: one per block of the largest stage yet
  bool active_ = false;
  std::unique_ptr<Shared> shared_;
};

/// A stage of `count` independent blocks on `runner`'s threads, its helpers woken for the stage
/// unless they are awake already; on the calling thread, in block order, when `runner` is null,
/// has one thread, or the stage has fewer than two blocks. Returns the largest value, as
/// BlockRunner::run.
double run_stage(BlockRunner* runner, std::size_t count, BlockRunner::BlockFunction function, const void* context);

/// run_stage of a callable: block(n) runs block n (the callable outlives the call).
template <typename Block>
void run_stage(BlockRunner* runner, std::size_t count, const Block& block) {
  run_stage(
      runner, count,
      [](const void* context, std::size_t n) {
        (*static_cast<const Block*>(context))(n);
        return 0.0;
      },
      &block);
}

/// The blocks of `per_block` items (> 0) that cover `count` items: ⌈count / per_block⌉.
constexpr std::size_t block_count(std::size_t count, std::size_t per_block) { return (count + per_block - 1) / per_block; }

/// run_stage over `count` items in blocks of `per_block`: item(i) for every i in [0, count), for
/// loops whose item i writes only its own entries.
template <typename Item>
void run_blocks(BlockRunner* runner, std::size_t count, std::size_t per_block, const Item& item) {
  run_stage(runner, block_count(count, per_block), [&](std::size_t block) {
    const std::size_t end = std::min(count, (block + 1) * per_block);
    for (std::size_t i = block * per_block; i < end; ++i) item(i);
  });
}

/// Keeps `runner`'s helpers awake from construction to destruction (BlockRunner::begin/end), so a
/// step of many short stages pays the helpers' wake-up once rather than at every stage (a
/// helper woken for a stage of a few 5 µs blocks arrives when most are done). No-op for a null
/// runner.
class AwakeHelpers {
 public:
  explicit AwakeHelpers(BlockRunner* runner) : runner_(runner != nullptr && !runner->active() ? runner : nullptr) {
    if (runner_ != nullptr) runner_->begin();
  }
  ~AwakeHelpers() {
    if (runner_ != nullptr) runner_->end();
  }
  AwakeHelpers(const AwakeHelpers&) = delete;
  AwakeHelpers& operator=(const AwakeHelpers&) = delete;

 private:
  BlockRunner* runner_;
};

/// Owns a BlockRunner; copying a state gives the copy its own runner (threads are not shared).
class RunnerHandle {
 public:
  RunnerHandle() = default;
  RunnerHandle(const RunnerHandle& other) { *this = other; }
  RunnerHandle& operator=(const RunnerHandle& other) {
    if (this != &other) {
      runner_ = other.runner_ ? std::make_unique<BlockRunner>(other.runner_->threading(), other.runner_->threads(), other.runner_->tasks())
                              : nullptr;
    }
    return *this;
  }
  RunnerHandle(RunnerHandle&&) noexcept = default;
  RunnerHandle& operator=(RunnerHandle&&) noexcept = default;
  void reset(Threading threading, int threads, TaskSystem tasks = {}) { runner_ = std::make_unique<BlockRunner>(threading, threads, tasks); }
  BlockRunner& operator*() const { return *runner_; }
  BlockRunner* operator->() const { return runner_.get(); }
  BlockRunner* get() const { return runner_.get(); }  ///< null: none (one thread)

 private:
  std::unique_ptr<BlockRunner> runner_;
};

}  // namespace limber
