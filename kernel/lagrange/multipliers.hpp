// The multipliers of the Lagrange method: the constraint forces that keep every joint closed.
//
// For a spherical joint C = p_i − p_j with p = x + r (r = R·r_body, the world lever), the
// velocity Jacobian is Ċ = J u, J = [G_i, −G_j], G = [E, −[r]×] (3×6 per body; thesis figure 3.5:
// each joint touches only the blocks of its two bodies), and J̇u = ω_i×(ω_i×r_i) − ω_j×(ω_j×r_j).
// With u̇ = M⁻¹(F + Jᵀλ) the joint stays closed when
//   J M⁻¹ Jᵀ λ = −(J M⁻¹ F + J̇u) − 2ω_b·Ċ − ω_b²·C          (thesis 3.1.4; Baumgarte terms optional)
// F holds the applied forces and, on the rotational rows, the gyroscopic torque −ω × Iω. Solved
// either by Baraff's tree-ordered factorization of [M Jᵀ; J 0] (lagrange_state.hpp, TreeSolver;
// linear time) or, for graphs with loops, by Eigen's sparse LDLᵀ of J M⁻¹ Jᵀ.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "kernel/lagrange/lagrange_state.hpp"

namespace limber {

/// Orders the body–joint graph for the tree solver (breadth-first from each component's joint to
/// the world, else its lowest body; eliminated in reverse) and sets state.uses_tree: false when
/// the joints close a loop — between bodies, or through the world by a second world joint in one
/// component — (the sparse path then serves) or when options ask for the sparse path. Throws ModelError when
/// options.solver is `tree` and a joint closes a loop, naming it.
void prepare_multiplier_solver(LagrangeState& state, const Model& model);

/// Computes state.inboard_lever, outboard_lever and world_inertia for state y: what the solves
/// below read. Call it whenever y changed.
void update_geometry(LagrangeState& state, const RigidBodyState& y);

/// The augmented solve at state y (update_geometry(state, y) must have run): given per-body right-hand sides (force, torque; 6 per body)
/// and per-joint right-hand sides c (m/s², 3 per joint), finds body accelerations
/// u̇ = M⁻¹(F + Jᵀλ) and the multipliers λ with J u̇ = c. Sleeping islands get u̇ = 0, λ = 0.
/// Writes `accelerations` (6 per body) and state.multipliers.
void solve_constrained(LagrangeState& state, const RigidBodyState& y, const std::vector<Eigen::Matrix<double, 6, 1>>& body_rhs,
                       const std::vector<Eigen::Vector3d>& joint_rhs, std::vector<Eigen::Matrix<double, 6, 1>>& accelerations);

/// Adds gravity, drag and the constraint forces Jᵀλ at state y to `forces` (the accumulate
/// function of the rigid integrators), with Baumgarte terms when stabilization asks for them.
void accumulate_constrained_forces(LagrangeState& state, const RigidBodyState& y, RigidForces& forces);

}  // namespace limber
