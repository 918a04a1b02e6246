// Gauss-Seidel relaxation of distance constraints (thesis 3.2.2, 4.3).
//
// One sweep projects every constraint of the awake islands once, in storage order, each
// projection seeing the positions the previous ones left (that is what makes it Gauss-Seidel
// rather than Jacobi). Storage order is breadth-first from each island's root (compile.cpp),
// so on a chain hanging from a pin a sweep runs from the pin down.
#pragma once

#include "limber/kernel/particles/verlet_state.hpp"

namespace limber {

/// One sequential Gauss-Seidel sweep over the constraints of the awake islands with
/// `state.options.rule`, in storage order (or its reverse, SweepDirection::pinned_last), with
/// the over-relaxation factor ω (1: plain projections) — along the current gradients (pbd) or
/// the start gradients in state.plan.constraint_gradient (rattle). Returns the largest particle
/// displacement it made, m. The coloured sweep is relaxation.hpp's.
template <typename Scalar>
double gauss_seidel_sweep(VerletState<Scalar>& state, double over_relaxation);

/// The rattle rule's velocity sweep in the same order (project_distance_velocity). Returns the
/// largest velocity change, m/s.
template <typename Scalar>
double gauss_seidel_velocity_sweep(VerletState<Scalar>& state);

extern template double gauss_seidel_sweep<float>(VerletState<float>&, double);
extern template double gauss_seidel_sweep<double>(VerletState<double>&, double);
extern template double gauss_seidel_velocity_sweep<float>(VerletState<float>&);
extern template double gauss_seidel_velocity_sweep<double>(VerletState<double>&);

}  // namespace limber
