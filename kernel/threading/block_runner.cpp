#include "kernel/threading/block_runner.hpp"

#include <algorithm>
#include <stdexcept>
#include <thread>
#include <vector>

#include <oneapi/tbb/blocked_range.h>
#include <oneapi/tbb/parallel_reduce.h>
#include <oneapi/tbb/task_arena.h>

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
  // The stage word: stage number (high 32 bits) and next unclaimed block (low 32 bits). A
  // successful compare-and-swap from (s, b) to (s, b + 1) gives block b of stage s to the
  // caller; it can only succeed while stage s is current, and stage s stays current (its
  // descriptor unchanged) until every claimed block has completed.
  alignas(64) std::atomic<std::uint64_t> claim{0};
  alignas(64) std::atomic<std::uint32_t> completed{0};
  // The stage descriptor, read on every claim: a line of its own, away from the counters.
  alignas(64) std::atomic<std::uint32_t> count{0};
  std::atomic<BlockFunction> function{nullptr};
  std::atomic<const void*> context{nullptr};
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

  explicit Shared(int threads) : results(static_cast<std::size_t>(threads)), arena(threads) {}

  // Claims and runs blocks of the current stage until none is left; returns false when the
  // stage word did not name a runnable stage. `result` collects the largest value.
  // Claims are guided (OpenMP's schedule): a claim takes half of the remaining blocks' fair
  // share, so a stage costs a few contended compare-and-swaps instead of one per block.
  bool work(Result& result) {
    std::uint64_t word = claim.load(std::memory_order_acquire);
    const std::uint64_t s = word >> 32;
    bool ran = false;
    for (;;) {
      const std::uint64_t total = count.load(std::memory_order_acquire);
      const std::uint64_t next = word & 0xFFFFFFFFu;
      if ((word >> 32) != s || next >= total) break;
      const std::uint64_t take = std::max<std::uint64_t>(1, (total - next) / (2 * results.size()));
      if (!claim.compare_exchange_weak(word, word + take, std::memory_order_acq_rel, std::memory_order_acquire)) continue;
      const BlockFunction run_block = function.load(std::memory_order_relaxed);
      const void* run_context = context.load(std::memory_order_relaxed);
      double largest = result.stage == s ? result.largest : 0.0;
      for (std::uint64_t block = next; block < next + take; ++block) largest = std::max(largest, run_block(run_context, block));
      result.stage = s, result.largest = largest;
      completed.fetch_add(static_cast<std::uint32_t>(take), std::memory_order_release);
      ran = true;
      word = claim.load(std::memory_order_acquire);
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
        if (work(results[slot])) spins = 0;
        else spin_pause(spins);
      }
    }
  }
};

BlockRunner::BlockRunner(Threading threading, int threads) : threading_(threading), threads_(threads) {
  if (threads < 1) throw std::invalid_argument("BlockRunner: threads must be at least 1");
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

double BlockRunner::run(std::size_t count, BlockFunction function, const void* context) {
  if (threading_ == Threading::serial || count <= 1) return run_serial(count, function, context);
  Shared& shared = *shared_;
  if (threading_ == Threading::parallel_for) {
    return shared.arena.execute([&] {
      return tbb::parallel_reduce(
          tbb::blocked_range<std::size_t>(0, count, 1), 0.0,
          [&](const tbb::blocked_range<std::size_t>& range, double largest) {
            for (std::size_t block = range.begin(); block != range.end(); ++block) {
              largest = std::max(largest, function(context, block));
            }
            return largest;
          },
          [](double a, double b) { return std::max(a, b); });
    });
  }
  // Close the previous stage's word first: a helper holding a stale word (previous stage, block b)
  // that reads the new, larger count must not be able to claim block b with it.
  shared.claim.store((shared.stage << 32) | kClosed, std::memory_order_release);
  // Publish the stage: descriptor, then the stage word (release).
  const std::uint64_t stage = ++shared.stage;
  shared.count.store(static_cast<std::uint32_t>(count), std::memory_order_release);
  shared.function.store(function, std::memory_order_relaxed);
  shared.context.store(context, std::memory_order_relaxed);
  shared.completed.store(0, std::memory_order_relaxed);
  shared.claim.store(stage << 32, std::memory_order_release);
  Shared::Result& own = shared.results[0];
  own.largest = 0, own.stage = stage;
  shared.work(own);
  int spins = 0;
  while (shared.completed.load(std::memory_order_acquire) != count) spin_pause(spins);
  double largest = own.largest;
  for (std::size_t k = 1; k < shared.results.size(); ++k) {
    if (shared.results[k].stage == stage) largest = std::max(largest, shared.results[k].largest);
  }
  return largest;
}

}  // namespace limber
