// How a relaxation's stages are split across threads (VerletOptions::threading) and an engine's
// own task system, apart from the runner that uses them (block_runner.hpp): options name them
// without including oneTBB.
#pragma once

#include <cstddef>
#include <cstdint>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// serial, oneTBB's parallel_for, long-lived workers, or the engine's tasks (block_runner.hpp).
enum class Threading : std::uint8_t { serial, parallel_for, workers, tasks };

/// An engine's task system (Box2D v3's enqueueTask/finishTask): limber hands it each stage as
/// `count` independent blocks; the engine runs work(begin, end, work_context) over ranges that
/// cover [0, count) once, on whatever threads and in whatever order it likes, and finish()
/// returns once all have run. The results are the same bits however it splits and orders them.
struct TaskSystem {
  using Work = void (*)(std::size_t begin, std::size_t end, void* work_context);
  /// Starts a stage; returns a handle for finish (may be null, e.g. when it ran the stage already).
  void* (*enqueue)(Work work, std::size_t count, void* work_context, void* user_context) = nullptr;
  void (*finish)(void* task, void* user_context) = nullptr;
  void* user_context = nullptr;
  bool valid() const { return enqueue != nullptr && finish != nullptr; }
};

}  // namespace limber
