// The block runner: every block of every stage runs exactly once, whichever strategy and thread
// count, and the stage's largest value comes back.
#include <atomic>
#include <chrono>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/numerics/flush_denormals.hpp"
#include "limber/kernel/threading/block_runner.hpp"

namespace limber {
namespace {

struct Stage {
  std::vector<std::atomic<int>>* runs;
  int offset;
};

double run_block(const void* context, std::size_t block) {
  const auto& stage = *static_cast<const Stage*>(context);
  (*stage.runs)[block].fetch_add(1, std::memory_order_relaxed);
  return static_cast<double>((block * 7919 + static_cast<std::size_t>(stage.offset)) % 1000);
}

TEST(BlockRunner, EveryBlockRunsOnceAndTheLargestValueReturns) {
  for (const Threading threading : {Threading::serial, Threading::parallel_for, Threading::workers}) {
    for (const int threads : {1, 2, 3}) {
      BlockRunner runner(threading, threads);
      for (int step = 0; step < 20; ++step) {
        runner.begin();
        for (int s = 0; s < 50; ++s) {
          const std::size_t count = static_cast<std::size_t>(1 + (step * 50 + s) % 97);
          std::vector<std::atomic<int>> runs(count);
          const Stage stage{&runs, s};
          double expected = 0;
          for (std::size_t b = 0; b < count; ++b) expected = std::max(expected, double((b * 7919 + std::size_t(s)) % 1000));
          ASSERT_EQ(runner.run(count, run_block, &stage), expected);
          for (std::size_t b = 0; b < count; ++b) ASSERT_EQ(runs[b].load(), 1) << "block " << b;
        }
        runner.end();
      }
    }
  }
}

TEST(BlockRunner, ShortStagesFollowingEachOtherNeverRunABlockTwice) {
  // Stage hand-over is where a helper holding the previous stage's word could claim a block of
  // the next (it did, before the word was closed between stages: a step then never finished).
  // Short stages of alternating size make hand-overs frequent.
  BlockRunner runner(Threading::workers, 2);
  runner.begin();
  std::vector<std::atomic<int>> runs(64);
  for (int s = 0; s < 200000; ++s) {
    const std::size_t count = s % 2 ? 64 : 2;
    for (std::size_t b = 0; b < count; ++b) runs[b].store(0, std::memory_order_relaxed);
    const Stage stage{&runs, s};
    runner.run(count, run_block, &stage);
    for (std::size_t b = 0; b < count; ++b) ASSERT_EQ(runs[b].load(), 1) << "stage " << s << " block " << b;
  }
  runner.end();
}

TEST(BlockRunner, RunsWithoutBeginAndStopsCleanly) {
  // Outside begin()/end() the workers sleep: the calling thread runs every block itself.
  BlockRunner runner(Threading::workers, 2);
  std::vector<std::atomic<int>> runs(10);
  const Stage stage{&runs, 0};
  EXPECT_GE(runner.run(10, run_block, &stage), 0.0);
  for (auto& r : runs) EXPECT_EQ(r.load(), 1);
  EXPECT_THROW(BlockRunner(Threading::workers, 0), std::invalid_argument);
}

TEST(BlockRunner, AwakeHelpersSpanTheirScopeAndLeaveAnOuterSessionOpen) {
  BlockRunner runner(Threading::workers, 2);
  {
    const AwakeHelpers awake(&runner);
    EXPECT_TRUE(runner.active());
    {
      const AwakeHelpers inner(&runner);  // a stage's own, inside the step's
      EXPECT_TRUE(runner.active());
    }
    EXPECT_TRUE(runner.active()) << "an inner scope must not end the step's session";
    std::vector<std::atomic<int>> runs(40);
    const Stage stage{&runs, 0};
    runner.run(40, run_block, &stage);
    for (auto& r : runs) EXPECT_EQ(r.load(), 1);
  }
  EXPECT_FALSE(runner.active());
  const AwakeHelpers none(nullptr);  // one thread: no runner, nothing to do
}

// 1 when the thread running the block computes a denormal where the caller's mode flushes it
// to zero. Each block dawdles, so the helpers claim some of them.
double block_without_the_callers_mode(const void*, std::size_t) {
  volatile float tiny = 1e-37f;
  const float half = tiny * 0.01f;  // 1e-39: a denormal, or 0 flushed
  std::this_thread::sleep_for(std::chrono::microseconds(200));
  return half != 0 ? 1.0 : 0.0;
}

// Denormals are flushed on the thread that steps (FlushDenormals); a block a helper runs must
// compute in that mode too, or 1 and 2 threads could give different bits.
TEST(BlockRunner, EveryBlockRunsInTheCallersFloatingPointMode) {
  if (floating_point_mode() == 0) GTEST_SKIP() << "no floating-point mode register on this machine";
  tbb::task_arena arena(2);
  for (const Threading threading : {Threading::parallel_for, Threading::workers, Threading::tasks}) {
    BlockRunner runner(threading, 2, threading == Threading::tasks ? tbb_task_system(arena) : TaskSystem{});
    runner.begin();
    {
      const FlushDenormals flush;
      EXPECT_EQ(runner.run(64, block_without_the_callers_mode, nullptr), 0.0) << "threading " << static_cast<int>(threading);
    }
    EXPECT_EQ(runner.run(64, block_without_the_callers_mode, nullptr), 1.0) << "the caller's mode restored, threading "
                                                                             << static_cast<int>(threading);
    runner.end();
  }
}

}  // namespace
}  // namespace limber
