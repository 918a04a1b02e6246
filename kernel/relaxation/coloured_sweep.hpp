// The coloured sweep's driver, internal to kernel/relaxation: a sweep is a sequence of stages
// (the overflow, then each colour, or the reverse), each stage a list of tasks of kSlotsPerTask
// slots that the BlockRunner hands to the threads. One driver for every kernel of
// batch_projection.hpp: the pbd projection, the rattle rule's position and velocity projections,
// and the pass that stores gradients.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "limber/kernel/relaxation/batch_projection.hpp"
#include "limber/kernel/particles/verlet_state.hpp"

namespace limber::coloured {

// Work handed to a thread at a time: 512 constraint slots (32 AVX-512 float blocks), or a range
// of particles for Jacobi's apply pass. Large enough to amortize a claim, small enough to
// balance two threads on a 10^4-link colour.
inline constexpr std::size_t kSlotsPerTask = 512;
inline constexpr std::size_t kParticlesPerTask = 4096;

/// What a coloured sweep does to each slot.
enum class Kernel : std::uint8_t {
  pbd,             ///< project_blocks: along the current gradient (thesis eq. 4.7)
  start_gradient,  ///< StartGradientCorrection: rattle's positions, along the stored start gradient
  velocity,        ///< VelocityCorrection: rattle's velocities, onto the tangent space
};

// One stage's work, as the BlockRunner hands it out: tasks of kSlotsPerTask slots of
// [begin, end), or of particle_tasks.
template <typename Scalar, typename Lanes, typename Positions, Kernel kKernel>
struct StageContext {
  const RelaxationPlan<Scalar>* plan;
  Positions positions;  ///< what the stage moves: positions, or (Kernel::velocity) velocities
  Scalar over_relaxation;
  std::size_t begin, end;
  CorrectionSums<Scalar> sums;
  GradientField<Scalar> gradients;

  std::size_t task_count() const { return (end - begin + kSlotsPerTask - 1) / kSlotsPerTask; }
  std::size_t task_begin(std::size_t task) const { return begin + task * kSlotsPerTask; }
  std::size_t task_end(std::size_t task) const { return std::min(end, task_begin(task) + kSlotsPerTask); }

  // The correction of one block, for the rattle kernels.
  auto correction(std::size_t slot, const LanePositions<Lanes>& a, const LanePositions<Lanes>& b) const {
    if constexpr (kKernel == Kernel::start_gradient) {
      return StartGradientCorrection<Lanes, Scalar>(plan->batches, gradients, slot, a, b, Lanes::broadcast(over_relaxation));
    } else {
      return VelocityCorrection<Lanes, Scalar>(plan->batches, slot, a, b);
    }
  }
  static double project(const void* context, std::size_t task) {
    const auto& stage = *static_cast<const StageContext*>(context);
    const auto& batches = stage.plan->batches;
    if constexpr (kKernel == Kernel::pbd) {
      return project_blocks<Lanes>(batches, stage.task_begin(task), stage.task_end(task), stage.positions, stage.over_relaxation);
    } else {
      return project_blocks_with<Lanes>(batches, stage.task_begin(task), stage.task_end(task), stage.positions,
                                        [&](std::size_t slot, const auto& a, const auto& b) { return stage.correction(slot, a, b); });
    }
  }
  static double accumulate(const void* context, std::size_t task) {
    const auto& stage = *static_cast<const StageContext*>(context);
    const auto& batches = stage.plan->batches;
    if constexpr (kKernel == Kernel::pbd) {
      accumulate_blocks<Lanes>(batches, stage.task_begin(task), stage.task_end(task), stage.positions, stage.sums);
    } else {
      accumulate_blocks_with<Lanes>(batches, stage.task_begin(task), stage.task_end(task), stage.positions, stage.sums,
                                    [&](std::size_t slot, const auto& a, const auto& b) { return stage.correction(slot, a, b); });
    }
    return 0;
  }
  // Stores the unit gradients at `positions` (store_gradients).
  static double store(const void* context, std::size_t task) {
    const auto& stage = *static_cast<const StageContext*>(context);
    store_gradients<Lanes>(stage.plan->batches, stage.gradients, stage.task_begin(task), stage.task_end(task), stage.positions);
    return 0;
  }
  // Jacobi's apply pass over one range of particles: x += ω·(sum)/(count), sum ← 0.
  static double apply(const void* context, std::size_t task) {
    const auto& stage = *static_cast<const StageContext*>(context);
    const RelaxationPlan<Scalar>& plan = *stage.plan;
    const auto [begin, end] = plan.particle_tasks[task];
    Scalar largest = 0;
    std::uint32_t p = begin;
    if constexpr (std::is_same_v<Positions, SoaPositions<Scalar>> && Lanes::size > 1) {
      // Consecutive particles in consecutive lanes: the same arithmetic as the loop below.
      using V = typename Lanes::value;
      const V omega = Lanes::broadcast(stage.over_relaxation);
      V lanes_largest = Lanes::broadcast(Scalar(0));
      const V zero = Lanes::broadcast(Scalar(0));
      for (; p + Lanes::size <= end; p += Lanes::size) {
        const V factor = omega * Lanes::load_unaligned(&plan.inverse_count[p]);
        const V dx = factor * Lanes::load_unaligned(stage.sums.x + p), dy = factor * Lanes::load_unaligned(stage.sums.y + p),
                dz = factor * Lanes::load_unaligned(stage.sums.z + p);
        Lanes::store_unaligned(Lanes::load_unaligned(stage.positions.x + p) + dx, stage.positions.x + p);
        Lanes::store_unaligned(Lanes::load_unaligned(stage.positions.y + p) + dy, stage.positions.y + p);
        Lanes::store_unaligned(Lanes::load_unaligned(stage.positions.z + p) + dz, stage.positions.z + p);
        Lanes::store_unaligned(zero, stage.sums.x + p), Lanes::store_unaligned(zero, stage.sums.y + p);
        Lanes::store_unaligned(zero, stage.sums.z + p);
        lanes_largest = Lanes::max(lanes_largest, Lanes::sqrt(dx * dx + dy * dy + dz * dz));
      }
      largest = Lanes::reduce_max(lanes_largest);
    }
    for (; p < end; ++p) {
      const Scalar factor = stage.over_relaxation * plan.inverse_count[p];
      const Scalar dx = factor * stage.sums.x[p], dy = factor * stage.sums.y[p], dz = factor * stage.sums.z[p];
      const auto offset = Positions::offset(p);
      stage.positions.x[offset] += dx, stage.positions.y[offset] += dy, stage.positions.z[offset] += dz;
      stage.sums.x[p] = stage.sums.y[p] = stage.sums.z[p] = 0;
      largest = std::max(largest, std::sqrt(dx * dx + dy * dy + dz * dz));
    }
    return largest;
  }
};

// Runs a stage on the runner's threads when it is large enough to pay for them, else here.
template <typename Scalar>
double run_stage(RelaxationPlan<Scalar>& plan, std::size_t slots, std::size_t tasks, BlockRunner::BlockFunction function,
                 const void* context) {
  if (slots >= plan.parallel_minimum_slots) return plan.runner->run(tasks, function, context);
  double largest = 0;
  for (std::size_t task = 0; task < tasks; ++task) largest = std::max(largest, function(context, task));
  return largest;
}

// The batches' gradient fields and the fallback counter.
template <typename Scalar>
GradientField<Scalar> gradient_field(RelaxationPlan<Scalar>& plan) {
  return {plan.batches.gradient_x.data(), plan.batches.gradient_y.data(), plan.batches.gradient_z.data(), &plan.fallbacks.value};
}

/// One sweep of `kKernel` over the awake batches: Gauss-Seidel (colour after colour, the
/// overflow first or last) or Jacobi (accumulate every colour, then apply). Returns the largest
/// particle displacement (m) or velocity change (m/s).
template <typename Scalar, typename Lanes, Kernel kKernel, typename Positions>
double coloured_sweep(VerletState<Scalar>& state, Positions positions, Scalar over_relaxation) {
  RelaxationPlan<Scalar>& plan = state.plan;
  const ConstraintBatches<Scalar>& batches = plan.batches;
  using Simd = StageContext<Scalar, Lanes, Positions, kKernel>;
  using Scalar1 = StageContext<Scalar, ScalarLanes<Scalar>, Positions, kKernel>;
  const CorrectionSums<Scalar> sums{plan.sum_x.data(), plan.sum_y.data(), plan.sum_z.data()};
  const GradientField<Scalar> gradients = gradient_field(plan);
  const std::size_t colours = batches.colour_count();
  const Scalar1 overflow{&plan, positions, over_relaxation, batches.overflow_begin(), batches.slot_count(), sums, gradients};
  double largest = 0;

  if (state.options.solver == RelaxationSolver::jacobi) {
    for (std::size_t k = 0; k < colours; ++k) {
      const Simd colour{&plan, positions, over_relaxation, batches.colour_begin[k], batches.colour_begin[k + 1], sums, gradients};
      run_stage(plan, colour.end - colour.begin, colour.task_count(), &Simd::accumulate, &colour);
    }
    for (std::size_t task = 0; task < overflow.task_count(); ++task) Scalar1::accumulate(&overflow, task);
    const Simd apply{&plan, positions, over_relaxation, 0, 0, sums, gradients};
    return run_stage(plan, batches.slot_count(), plan.particle_tasks.size(), &Simd::apply, &apply);
  }

  const auto project_overflow = [&] {
    for (std::size_t task = 0; task < overflow.task_count(); ++task) {
      largest = std::max(largest, Scalar1::project(&overflow, task));
    }
  };
  const bool pinned_first = state.options.direction == SweepDirection::pinned_first;
  if (pinned_first) project_overflow();
  for (std::size_t n = 0; n < colours; ++n) {
    const std::size_t k = pinned_first ? n : colours - 1 - n;
    const Simd colour{&plan, positions, over_relaxation, batches.colour_begin[k], batches.colour_begin[k + 1], sums, gradients};
    largest = std::max(largest, run_stage(plan, colour.end - colour.begin, colour.task_count(), &Simd::project, &colour));
  }
  if (!pinned_first) project_overflow();
  return largest;
}

/// Stores the unit gradients at `positions` into every awake slot's gradient field (colours in
/// parallel stages, then the overflow). Slots that fell back to pbd in the last substep get
/// their gradient back.
template <typename Scalar, typename Lanes, typename Positions>
void store_all_gradients(VerletState<Scalar>& state, Positions positions) {
  RelaxationPlan<Scalar>& plan = state.plan;
  const ConstraintBatches<Scalar>& batches = plan.batches;
  using Simd = StageContext<Scalar, Lanes, Positions, Kernel::pbd>;
  using Scalar1 = StageContext<Scalar, ScalarLanes<Scalar>, Positions, Kernel::pbd>;
  const GradientField<Scalar> gradients = gradient_field(plan);
  for (std::size_t k = 0; k < batches.colour_count(); ++k) {
    const Simd colour{&plan, positions, 1, batches.colour_begin[k], batches.colour_begin[k + 1], CorrectionSums<Scalar>(nullptr, nullptr, nullptr), gradients};
    run_stage(plan, colour.end - colour.begin, colour.task_count(), &Simd::store, &colour);
  }
  const Scalar1 overflow{&plan, positions, 1, batches.overflow_begin(), batches.slot_count(), CorrectionSums<Scalar>(nullptr, nullptr, nullptr), gradients};
  for (std::size_t task = 0; task < overflow.task_count(); ++task) Scalar1::store(&overflow, task);
}

}  // namespace limber::coloured
