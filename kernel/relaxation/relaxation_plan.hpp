// What a coloured relaxation sweep needs besides the particles: the awake constraints in
// colour batches, Jacobi's accumulators, the interleaved particle copy for the AoS/AoSoA
// layouts, and the threads. Rebuilt (not re-coloured) when islands sleep or wake.
#pragma once

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "kernel/threading/block_runner.hpp"
#include "layouts/aligned_array.hpp"
#include "layouts/constraints/constraint_batches.hpp"
#include "layouts/particles/interleaved_particles.hpp"

namespace limber {

/// Owns a BlockRunner; copying a state gives the copy its own runner (threads are not shared).
class RunnerHandle {
 public:
  RunnerHandle() = default;
  RunnerHandle(const RunnerHandle& other) { *this = other; }
  RunnerHandle& operator=(const RunnerHandle& other) {
    if (this != &other) runner_ = other.runner_ ? std::make_unique<BlockRunner>(other.runner_->threading(), other.runner_->threads()) : nullptr;
    return *this;
  }
  RunnerHandle(RunnerHandle&&) noexcept = default;
  RunnerHandle& operator=(RunnerHandle&&) noexcept = default;
  void reset(Threading threading, int threads) { runner_ = std::make_unique<BlockRunner>(threading, threads); }
  BlockRunner& operator*() const { return *runner_; }
  BlockRunner* operator->() const { return runner_.get(); }

 private:
  std::unique_ptr<BlockRunner> runner_;
};

template <typename Scalar>
struct RelaxationPlan {
  ConstraintBatches<Scalar> batches;
  /// Jacobi: per particle, the sum of this sweep's corrections (m) and 1/(number of constraints
  /// on it), 0 for a particle no constraint moves.
  AlignedArray<Scalar> sum_x, sum_y, sum_z, inverse_count;
  /// The particles in the AoS or AoSoA layout, when the options ask for one.
  InterleavedParticles<Scalar, 1> array_of_structures;
  InterleavedParticles<Scalar, kLanesPerLine<Scalar>> blocked_structures;
  /// Jacobi's apply pass: the awake particles as [begin, end) ranges of at most a task's size.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> particle_tasks;
  RunnerHandle runner;
  /// The layout relaxation runs over (VerletOptions::layout, with automatic resolved).
  ParticleLayout layout = ParticleLayout::soa;
  /// Whether a stage is large enough to split across threads: slots ≥ parallel_minimum_slots.
  std::uint32_t parallel_minimum_slots = 0;
  /// Constraints of the awake islands this step (the work counter a sweep adds).
  std::uint64_t awake_constraints = 0;
  /// state.awake_generation the batches were built for (rebuilt when it changes).
  std::uint64_t built_for = ~std::uint64_t{0};
};

}  // namespace limber
