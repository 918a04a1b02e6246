// The mutable state of the Lagrange-multiplier method (thesis 3.1.4, 3.1.7, 3.4, 4.2.1): limbs as
// rigid bodies in maximal coordinates (kernel/rigid/rigid_scene.hpp) whose joints are
// constraint equations; constraint forces are computed *before* a joint opens, from the
// constraint Jacobian. Built by compile_lagrange() (compile.hpp); stepped by step() (step.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "kernel/lagrange/constraints.hpp"
#include "kernel/numerics/small_cholesky.hpp"
#include "kernel/rigid/rigid_integration.hpp"
#include "kernel/rigid/rigid_scene.hpp"

namespace limber {

/// How the joints' drift (the constraint error integration leaves) is held down.
enum class Stabilization : std::uint8_t {
  baumgarte,   ///< C̈ = −2ω_b·Ċ − ω_b²·C in the acceleration solve (Baumgarte 1972)
  projection,  ///< after each step, positions then velocities projected back onto C = 0, Ċ = 0
               ///< through the mass matrix (post-stabilization, Cline & Pai 2003)
};

/// Which solve gives the multipliers.
enum class MultiplierSolver : std::uint8_t {
  automatic,  ///< tree when the joint graph has no loop, else sparse
  tree,       ///< Baraff's linear-time factorization of the tree-ordered system (1996)
  sparse,     ///< J M⁻¹ Jᵀ assembled and factored by Eigen's sparse LDLᵀ: any graph
};

struct LagrangeOptions {
  RigidIntegrator integrator = RigidIntegrator::semi_implicit_euler;
  Stabilization stabilization = Stabilization::baumgarte;
  MultiplierSolver solver = MultiplierSolver::automatic;
  /// ω_b of Baumgarte stabilization, 1/s; 0: 1/(4Δt), critically damped and four steps to
  /// correct an error.
  double baumgarte_frequency = 0;
  int projection_iterations = 2;  ///< Newton iterations of the position projection
};

/// Baraff's tree-ordered factorization (Baraff 1996, "Linear-time dynamics using Lagrange
/// multipliers", section 7): the augmented system
///   H = [M  Jᵀ; J  0],   H·(u̇, −λ) = (F, c),
/// as a graph whose nodes are the bodies (6×6 blocks M_b) and the constraints (m×m zero blocks,
/// m = 1…6 rows), with an edge of block J_cb wherever constraint c acts on body b. Without loops
/// this graph is a forest; eliminating its nodes children-first (each node's parent after it)
/// makes the block LDLᵀ factorization fill nothing, so factor and solve are O(bodies + joints).
struct TreeSolver {
  std::vector<std::int32_t> order;   ///< node elimination order: every node before its parent
  std::vector<std::int32_t> parent;  ///< per node, −1 for a root; nodes: bodies, then constraints
  /// Per node: the factored diagonal block D (a constraint's inverted when it is eliminated; a
  /// body's kept as its Cholesky factor in body_factor), and the block
  /// L = H_{parent,node}·D⁻¹ (top-left corners of fixed 6×6 storage: 6 rows/columns for bodies,
  /// m for constraints). Refilled at every solve; nothing is allocated.
  std::vector<Eigen::Matrix<double, 6, 6>> diagonal, to_parent;
  std::vector<Eigen::Matrix<double, 6, 1>> work;  ///< the right-hand side, then the solution
  std::vector<SmallCholesky<6>> body_factor;  ///< Cholesky of each body's D (positive definite)
};

struct LagrangeStepReport {
  StepStatus status = StepStatus::ok;
  int contacts = 0;
  double constraint_error = 0;  ///< largest |C| of a joint's point and slide rows after the step, m
  double angular_error = 0;     ///< largest |u·v| of a joint's angular rows after the step (≈ rad)
};

struct LagrangeState : RigidScene {
  JointAnchors joints;        ///< the Model's joints' anchors
  ConstraintSet constraints;  ///< the joints' rows, then the gears'
  LagrangeOptions options;
  bool uses_tree = true;  ///< the solver chosen at compile (tree, or sparse for graphs with loops)
  RigidIntegratorScratch scratch;
  TreeSolver tree;
  /// Multipliers of the last evaluation, per constraint (its rows). A joint's point rows are the
  /// force on the inboard body at its anchor, N; angular rows are torques, N·m.
  std::vector<ConstraintVector> multipliers;
  double time_step = 0;  ///< Δt of the step under way (Baumgarte's default frequency needs it)
  // Scratch for the solves, sized at compile.
  std::vector<Eigen::Matrix<double, 6, 1>> body_rhs, accelerations;
  std::vector<ConstraintVector> constraint_rhs;
  std::vector<ConstraintVector> projection_multipliers;  ///< the projections' own multipliers (scratch)
  /// The geometry of the state being solved, computed once per evaluation (update_geometry):
  /// the constraints' levers and Jacobian blocks and each body's world inertia tensor.
  ConstraintGeometry geometry;
  std::vector<Eigen::Matrix3d> world_inertia;
  LagrangeStepReport last_report;
};

}  // namespace limber
