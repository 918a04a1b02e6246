#include "kernel/relaxation/gauss_seidel.hpp"

#include <algorithm>

#include "kernel/relaxation/distance_projection.hpp"

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

}  // namespace

template <typename Scalar>
double gauss_seidel_sweep(VerletState<Scalar>& state, double over_relaxation) {
  Scalar largest = 0;
  const auto omega = static_cast<Scalar>(over_relaxation);
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

template double gauss_seidel_sweep<float>(VerletState<float>&, double);
template double gauss_seidel_sweep<double>(VerletState<double>&, double);

}  // namespace limber
