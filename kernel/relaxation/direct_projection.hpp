// The direct solver of the Verlet family: an exact global projection of the distance constraints
// instead of relaxation sweeps (RelaxationSolver::direct).
//
// Each Newton step linearizes every constraint at the current positions x and solves
//   (J W Jᵀ + α̃) Δλ = −C(x) − α̃·λ,    Δx = W Jᵀ Δλ,    λ += Δλ
// exactly (XPBD's update, Macklin, Müller, Chentanez 2016, eq. 18, solved for all constraints at
// once as in Deul, Kugelstadt, Weiler, Bender, "Direct position-based solver for stiff rods",
// 2018). W holds the inverse masses, so the correction is the thesis's weighting (eq. 4.7) made
// exact: the mass-weighted closest point, to first order, rather than the result of a sweep
// order; α̃ = α/Δt² is the compliance (0: rigid). A distance constraint has one row,
// C = |x_i − x_j| − d; a zero-length joint three, C = x_i − x_j (linear: one step closes it).
//
// The system is solved by Baraff's elimination over the particle–constraint tree
// (kernel/numerics/tree_elimination.hpp, shared with the Lagrange method), O(n) per step: a
// chain's matrix is block tridiagonal. A component whose particles carry at most 19 rows each
// (every generated chain and tree) is solved in constraint space instead
// (kernel/numerics/constraint_elimination.hpp: tridiagonal on a chain of distance constraints),
// its factor kept while its rows' directions and compliances stay the same bits.
// Constraints that close a loop are left out of the tree and projected one by one
// (Gauss-Seidel) after each Newton step.
//
// Warm start (VerletOptions::warm_start): the previous step's multipliers, rescaled to this Δt,
// are applied before the first Newton step — the tension of a hanging chain persists from step
// to step like gravity, so the first linearization starts near the solution.
#pragma once

#include "limber/kernel/particles/verlet_state.hpp"

namespace limber {

/// Orders each island's particle–constraint graph for elimination (called by compile() when the
/// solver is direct). Throws std::invalid_argument when newton_iterations < 1 or compliance < 0.
template <typename Scalar>
void prepare_direct_projection(VerletState<Scalar>& state);

/// Starts a step's projection: applies the warm start (or clears the multipliers). dt in s.
template <typename Scalar>
void begin_direct_projection(VerletState<Scalar>& state, double dt);

/// One Newton step over the awake islands, then the loop-closing constraints. Under the rattle
/// rule the rows are linearized at the substep's start (SHAKE's gradients, held for the
/// substep: a chord iteration, J₀ W J₀ᵀ Δλ = −C(x), Δx = W J₀ᵀ Δλ), a row falling back to the
/// current gradient as the sweeps do. Returns the largest particle displacement it made, m.
template <typename Scalar>
double direct_projection_step(VerletState<Scalar>& state);

/// The rattle rule's velocity stage, exact: solves J W Jᵀ μ = −J v at the current positions and
/// sets v += W Jᵀ μ, so every tree constraint's rate is zero after one call; loop-closing
/// constraints are then projected once each (Gauss-Seidel). Returns the largest |Δv|, m/s.
template <typename Scalar>
double direct_velocity_projection(VerletState<Scalar>& state);

/// The rattle rule's velocity stage for compliant constraints (VerletOptions::compliance α > 0),
/// which are springs rather than rigid rows: instead of a projection of their rate, the second
/// half kick of velocity Verlet by the force the position stage found, F = 2λ/Δt² (its
/// compliance is 2α/Δt² under rattle, begin_direct_projection), along each constraint's
/// gradient at the current positions: Δv_i = +w_i·(λ/Δt)·n, Δv_j = −w_j·(λ/Δt)·n (w the rule's
/// weight), so a spring holding a weight at rest leaves it at rest. dt: the substep, s.
template <typename Scalar>
void kick_compliant_constraints(VerletState<Scalar>& state, double dt);

extern template void prepare_direct_projection<float>(VerletState<float>&);
extern template void prepare_direct_projection<double>(VerletState<double>&);
extern template void begin_direct_projection<float>(VerletState<float>&, double);
extern template void begin_direct_projection<double>(VerletState<double>&, double);
extern template double direct_projection_step<float>(VerletState<float>&);
extern template double direct_projection_step<double>(VerletState<double>&);
extern template double direct_velocity_projection<float>(VerletState<float>&);
extern template double direct_velocity_projection<double>(VerletState<double>&);
extern template void kick_compliant_constraints<float>(VerletState<float>&, double);
extern template void kick_compliant_constraints<double>(VerletState<double>&, double);

}  // namespace limber
