#include "limber/kernel/relaxation/gauss_seidel.hpp"

#include <algorithm>

#include "limber/kernel/relaxation/distance_projection.hpp"

namespace limber {
namespace {

template <typename Scalar, RelaxationRule rule>
Scalar sweep_range(ParticleBuffer<Scalar>& particles, const DistanceConstraintBuffer<Scalar>& constraints,
                   std::uint32_t begin, std::uint32_t end, bool forward, Scalar over_relaxation) {
  Scalar largest = 0;
  for (std::uint32_t n = begin; n < end; ++n) {
    const std::uint32_t c = forward ? n : end - 1 - (n - begin);
    largest = std::max(largest, project_distance_constraint(particles, constraints, c, rule, over_relaxation));
  }
  return largest;
}

// Calls project(c) for every constraint of the awake islands in sweep order; the largest result.
template <typename Scalar, typename Project>
Scalar sweep_awake(const VerletState<Scalar>& state, Project&& project) {
  Scalar largest = 0;
  const bool forward = state.options.direction == SweepDirection::pinned_first;
  for (std::size_t n = 0; n < state.awake_islands.size(); ++n) {
    const Island& island = state.islands[state.awake_islands[forward ? n : state.awake_islands.size() - 1 - n]];
    for (std::uint32_t k = island.constraint_begin; k < island.constraint_end; ++k) {
      largest = std::max(largest, project(forward ? k : island.constraint_end - 1 - (k - island.constraint_begin)));
    }
  }
  return largest;
}

}  // namespace

template <typename Scalar>
double gauss_seidel_sweep(VerletState<Scalar>& state, double over_relaxation) {
  const auto omega = static_cast<Scalar>(over_relaxation);
  if (uses_rattle(state)) {
    std::uint64_t fallbacks = 0;
    const Scalar largest = sweep_awake(state, [&](std::uint32_t c) {
      return project_distance_constraint_from_start(state.particles, state.constraints, c, state.options.rule, omega,
                                                    state.plan.constraint_gradient[c], fallbacks);
    });
    state.plan.fallbacks.value += fallbacks;
    return static_cast<double>(largest);
  }
  Scalar largest = 0;
  const bool forward = state.options.direction == SweepDirection::pinned_first;
  for (std::size_t n = 0; n < state.awake_islands.size(); ++n) {
    const Island& island = state.islands[state.awake_islands[forward ? n : state.awake_islands.size() - 1 - n]];
    // The rule is fixed per run: choose the loop once, not per constraint.
    const Scalar island_largest =
        state.options.rule == RelaxationRule::weighted
            ? sweep_range<Scalar, RelaxationRule::weighted>(state.particles, state.constraints,
                                                             island.constraint_begin, island.constraint_end, forward, omega)
            : sweep_range<Scalar, RelaxationRule::unweighted>(state.particles, state.constraints,
                                                               island.constraint_begin, island.constraint_end, forward, omega);
    largest = std::max(largest, island_largest);
  }
  return static_cast<double>(largest);
}

template <typename Scalar>
double gauss_seidel_velocity_sweep(VerletState<Scalar>& state) {
  return static_cast<double>(sweep_awake(state, [&](std::uint32_t c) {
    return project_distance_velocity(state.particles, state.constraints, c, state.options.rule);
  }));
}

template double gauss_seidel_sweep<float>(VerletState<float>&, double);
template double gauss_seidel_sweep<double>(VerletState<double>&, double);
template double gauss_seidel_velocity_sweep<float>(VerletState<float>&);
template double gauss_seidel_velocity_sweep<double>(VerletState<double>&);

}  // namespace limber
