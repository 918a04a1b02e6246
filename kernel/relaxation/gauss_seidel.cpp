#include "kernel/relaxation/gauss_seidel.hpp"

#include <algorithm>

#include "kernel/relaxation/distance_projection.hpp"

namespace limber {
namespace {

template <typename Scalar, RelaxationRule rule>
Scalar sweep_range(ParticleBuffer<Scalar>& particles, const DistanceConstraintBuffer<Scalar>& constraints,
                   std::uint32_t begin, std::uint32_t end, Scalar over_relaxation) {
  Scalar largest = 0;
  for (std::uint32_t c = begin; c < end; ++c) {
    largest = std::max(largest, project_distance_constraint(particles, constraints, c, rule, over_relaxation));
  }
  return largest;
}

}  // namespace

template <typename Scalar>
double gauss_seidel_sweep(VerletState<Scalar>& state, double over_relaxation) {
  Scalar largest = 0;
  std::uint64_t projections = 0;
  const auto omega = static_cast<Scalar>(over_relaxation);
  for (std::uint32_t k : state.awake_islands) {
    const Island& island = state.islands[k];
    // The rule is fixed per run: choose the loop once, not per constraint.
    const Scalar island_largest =
        state.options.rule == RelaxationRule::weighted
            ? sweep_range<Scalar, RelaxationRule::weighted>(state.particles, state.constraints,
                                                             island.constraint_begin, island.constraint_end, omega)
            : sweep_range<Scalar, RelaxationRule::unweighted>(state.particles, state.constraints,
                                                               island.constraint_begin, island.constraint_end, omega);
    largest = std::max(largest, island_largest);
    projections += island.constraint_end - island.constraint_begin;
  }
  state.counters.constraint_projections += projections;
  return static_cast<double>(largest);
}

template double gauss_seidel_sweep<float>(VerletState<float>&, double);
template double gauss_seidel_sweep<double>(VerletState<double>&, double);

}  // namespace limber
