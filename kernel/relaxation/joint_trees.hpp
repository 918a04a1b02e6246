// The exact solve of each limb tree's joints (VerletSettings::joint_solve = JointSolve::tree), as
// one block of a block Gauss-Seidel iteration whose other rows — limb-internal constraints,
// limits, friction, drives, contacts — are the sweeps' (kernel/relaxation/README.md, "Joint
// trees").
//
// Why: a sweep projects a joint between a 63.5 kg torso and a 2.3 kg spine one row at a time,
// and mass ratios cost sweeps (the thesis's chapter 4; Jolt clamps them, Box3D softens them).
// Solved together, a ragdoll's joints close in one linear solve whatever its masses.
//
// How: each limb is a rigid cluster of its particles (head, tail, frame F⁺ F⁻, centre): mass m,
// centre of mass c, inertia I = Σ m_k(|r_k|²E − r_k r_kᵀ) about c (a stick, whose particles lie
// on its axis, gets S·u uᵀ added for the spin it cannot have: S = Σ m_k|r_k|²; nothing acts
// about that axis). A limb moves by Δp and Δφ: Δx_k = Δp + Δφ × r_k. Each pair of joined limbs
// (or a limb and the world) is one tree constraint of up to 6 rows:
//   point (3): C = Σ c_k x_k — a zero-length joint x_j − x_i, or a point row's anchors
//     (joint_rows.hpp) — with J = [σ E, −[ρ]×] on each side, σ = Σ c_k, ρ = Σ c_k r_k;
//   hinge axis (2): C = (t₁·e, t₂·e), t₁, t₂ ⟂ the axis fixed in A, e the axis fixed in B,
//     J_A = [0, (t_i × e)ᵀ], J_B = [0, (e × t_i)ᵀ];
//   a limit (1 each: swing, twist, hinge range): C its violation, J = [0, ∓ the axis B turns
//     about]; an idle limit keeps its row decoupled (J = 0, −A = −1: μ = 0).
// One Newton step solves, over every island's tree at once and in O(limbs),
//   [ M  Jᵀ ] [Δq]   [ 0 ]
//   [ J  0  ] [ μ] = [−C ]        M = diag(m E, I) per limb,
// the mass-weighted closest point to first order (the thesis's weighting, eq. 4.7, made exact
// for the whole tree): Baraff's elimination (kernel/numerics/tree_elimination.hpp, the same
// one the Lagrange method and the direct solver use; the components of one skeleton in SIMD
// lanes side by side, tree_packs.hpp), and moves each limb rigidly by the exact
// rotation R(Δφ), so the limb's internal distances stay as they were. What a step leaves is
// O(|Δφ|²·|r|): Newton's quadratic rate.
//
// Joints that close a loop, islands with a pinned limb particle or shared particles, and joints
// of other kinds (universal, fixed, drives) stay rows.
#pragma once

#include "limber/kernel/particles/verlet_state.hpp"

namespace limber {

/// Builds the limb trees of state's islands (called by prepare_relaxation_plan when
/// options.verlet.joint_solve is JointSolve::tree) and marks the constraints and rows they hold. Throws
/// std::invalid_argument for options it does not work with (a rule other than weighted, Jacobi,
/// the direct solver, the sequential sweep or an interleaved layout).
template <typename Scalar>
void prepare_joint_trees(VerletState<Scalar>& state);

/// Whether the sweeps skip distance constraint `constraint` (a joint tree holds it).
template <typename Scalar>
bool held_by_joint_tree(const VerletState<Scalar>& state, std::uint32_t constraint) {
  const auto& held = state.plan.joint_trees.tree_constraint;
  return !held.empty() && held[constraint];
}

/// Whether the trees run on the relaxation's threads: one task per pack (tree_packs.hpp; packs
/// share nothing a solve writes, so 1 and 2 threads give the same bits), when the runner has
/// more than one thread.
template <typename Scalar>
bool joint_trees_on_threads(const RelaxationPlan<Scalar>& plan) {
  return plan.joint_trees.active() && plan.runner.operator->() != nullptr && plan.runner->threads() > 1;
}

/// Starts a substep of dt s: the contacts the trees solve are gathered (begin_relaxation, after
/// the contact rows are built) and the counts start from zero.
template <typename Scalar>
void begin_joint_trees(VerletState<Scalar>& state, double dt);

/// What the trees did since the substep began, summed over every component.
template <typename Scalar>
JointTreeCounts joint_tree_counts(const VerletState<Scalar>& state);

/// Newton steps of every awake island's joint trees on the positions, components of one shape
/// side by side in SIMD lanes (tree_packs.hpp; a pack a task when joint_trees_on_threads), until
/// a step moves no particle by 1e-5 m or more (at most 4), each from a fresh factor; with
/// contacts, in rounds (tree_contacts.hpp). Returns the largest particle displacement made, m
/// (0 when there are no trees).
template <typename Scalar>
double project_joint_trees(VerletState<Scalar>& state);

/// The same trees on the velocities (the rattle rule's velocity stage): each limb's rigid
/// velocity (v of its centre, ω = I⁻¹ Σ m r × v) is projected so that J·(v, ω) = 0, and its
/// particles get Δv_k = Δv + Δω × r_k. Returns the largest |Δv|, m/s.
template <typename Scalar>
double project_joint_tree_velocities(VerletState<Scalar>& state);

extern template void prepare_joint_trees<float>(VerletState<float>&);
extern template void prepare_joint_trees<double>(VerletState<double>&);
extern template void begin_joint_trees<float>(VerletState<float>&, double);
extern template void begin_joint_trees<double>(VerletState<double>&, double);
extern template JointTreeCounts joint_tree_counts<float>(const VerletState<float>&);
extern template JointTreeCounts joint_tree_counts<double>(const VerletState<double>&);
extern template double project_joint_trees<float>(VerletState<float>&);
extern template double project_joint_trees<double>(VerletState<double>&);
extern template double project_joint_tree_velocities<float>(VerletState<float>&);
extern template double project_joint_tree_velocities<double>(VerletState<double>&);

}  // namespace limber
