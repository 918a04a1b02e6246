// The multipliers of the Lagrange method: the constraint forces that keep every joint closed.
//
// Each constraint c has rows C_c with velocity Jacobian blocks J_c,b (rows × 6) on the bodies it
// joins (kernel/lagrange/constraints.hpp; thesis figure 3.5: each joint touches only the blocks of
// its two bodies). With u̇ = M⁻¹(F + Jᵀλ) the joints stay closed when
//   J M⁻¹ Jᵀ λ = −(J M⁻¹ F + J̇u) − 2ω_b·Ċ − ω_b²·C          (thesis 3.1.4; Baumgarte terms optional)
// F holds the applied forces and, on the rotational rows, the gyroscopic torque −ω × Iω. Solved
// either by Baraff's tree-ordered factorization of [M Jᵀ; J 0] (kernel/numerics/tree_elimination.hpp;
// linear time) or, for graphs with loops, by Eigen's sparse LDLᵀ of J M⁻¹ Jᵀ.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "limber/kernel/lagrange/lagrange_state.hpp"

namespace limber {

/// Orders the body–constraint graph for the tree solver (breadth-first from each component's
/// joint to the world, else its lowest body; eliminated in reverse) and sets state.uses_tree:
/// false when the constraints close a loop — between bodies (a gear between two axled wheels
/// does), or through the world by a second world joint in one component — (the sparse path then
/// serves) or when options ask for the sparse path. Throws ModelError when options.solver is
/// `tree` and a constraint closes a loop, naming it.
void prepare_multiplier_solver(LagrangeState& state, const Model& model);

/// Computes state.geometry (the constraints' levers and Jacobian blocks) and world_inertia for
/// state y: what the solves below read. Call it whenever y changed.
void update_geometry(LagrangeState& state, const RigidBodyState& y);

/// The augmented solve at state y (update_geometry(state, y) must have run): given per-body
/// right-hand sides (force, torque; 6 per body) and per-constraint right-hand sides c (its rows),
/// finds body accelerations u̇ = M⁻¹(F + Jᵀλ) and the multipliers λ with J u̇ = c. Sleeping
/// islands get u̇ = 0. Writes `accelerations` (6 per body) and state.multipliers.
void solve_constrained(LagrangeState& state, const RigidBodyState& y, const std::vector<Eigen::Matrix<double, 6, 1>>& body_rhs,
                       const std::vector<ConstraintVector>& constraint_rhs, std::vector<Eigen::Matrix<double, 6, 1>>& accelerations);

/// ω_b of Baumgarte stabilization for a step of dt (0 under projection), 1/s.
double baumgarte_frequency(const LagrangeState& state, double dt);

/// Adds scale·Jᵀλ (state.multipliers, at the geometry last computed) to `forces`.
void add_constraint_forces(LagrangeState& state, RigidForces& forces, double scale);

/// Adds gravity, drag and the constraint forces Jᵀλ at state y to `forces` (the accumulate
/// function of the rigid integrators), with Baumgarte terms when stabilization asks for them.
void accumulate_constrained_forces(LagrangeState& state, const RigidBodyState& y, RigidForces& forces);

}  // namespace limber
