// The joint-space inertia matrix H factored as LᵀDL in the sparsity its tree induces, and the
// Delassus matrix of constraint rows formed through that factor (Featherstone, "Rigid Body
// Dynamics Algorithms", 2008, §6.5, Tables 6.3 and 6.4; MuJoCo's mj_factorM, mj_solveM).
//
// Number the velocity coordinates (dofs) so that each comes after the one before it on its path
// to the root, λ(i) < i: a joint's own coordinates in order, each joint's after its parent
// body's (the order ArticulatedTree's velocity offsets already have). H_ij is then zero unless i
// and j lie on one path to the root (one is an ancestor of the other), and H = LᵀDL with L unit
// lower triangular has L_ij ≠ 0 only for j an ancestor of i: the factor fills nothing in,
// costs O(Σ_i depth_i²) and a solve O(Σ_i depth_i) — O(n) for a humanoid's shallow tree, where a
// dense Cholesky costs O(n³).
//
// With Y = J L⁻¹ (one back-substitution per row, touching only the row's dofs and their
// ancestors), the rows' Delassus matrix is A = J H⁻¹ Jᵀ = Y D⁻¹ Yᵀ: the constraint-space
// inverse inertia that projected solvers work on (MuJoCo's engine_solver.c forms its
// A = J M⁻¹ Jᵀ this way).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build
#include "limber/kernel/featherstone/articulated_tree.hpp"

namespace limber {

/// λ(i) for each velocity coordinate i of `tree` (nv entries): the coordinate before it on its
/// path to the root — its joint's previous coordinate, else the last coordinate of the nearest
/// ancestor body with any (a fixed joint has none), else −1. Every λ(i) < i.
std::vector<int> dof_parents(const ArticulatedTree& tree);

/// H = LᵀDL over a tree's coordinates (see above). Sized once by assign(); factor() and the
/// solves allocate nothing.
class JointSpaceFactor {
 public:
  /// Sizes the factor for coordinates with parents `dof_parent` (λ(i) < i, −1 for a root).
  /// Throws std::invalid_argument when a parent is not before its coordinate.
  void assign(const std::vector<int>& dof_parent);
  void assign(const ArticulatedTree& tree) { assign(dof_parents(tree)); }

  /// nv, the coordinates.
  int size() const { return static_cast<int>(parent_.size()); }
  /// λ(i).
  int parent(int i) const { return parent_[static_cast<std::size_t>(i)]; }

  /// Factors H (nv × nv, symmetric positive definite: the composite-rigid-body algorithm's
  /// mass_matrix). Only H_ii and H_ij with j an ancestor of i are read (the rest are zero in a
  /// joint-space inertia). O(Σ depth²). Throws std::invalid_argument for a wrong size and
  /// std::domain_error naming the coordinate when a pivot D_i is not > 0 (H not positive
  /// definite: a coordinate that moves no mass and has no armature).
  void factor(const Eigen::Ref<const Eigen::MatrixXd>& h);

  /// H_ij = H_ji = value for j = i or an ancestor of i (the sparse mass_matrix writes H this
  /// way); then factor() factors what was set. Throws std::invalid_argument for any other j.
  void set_inertia(int i, int j, double value);
  /// The slots of H_ij for i's ancestors j, nearest first (λ(i), λ(λ(i)), …; as many as i has),
  /// before factor(): what set_inertia(i, j) writes, laid out as the composite-rigid-body
  /// algorithm stores a column (mass_matrix). H_ii is set_inertia(i, i).
  double* inertia_path(int i) { return entries_.data() + begin_[static_cast<std::size_t>(i)]; }
  /// H_ij += value, as set_inertia (a penalty on a joint's coordinates: a held row).
  void add_inertia(int i, int j, double value);
  /// H on coordinates first…last − 1 (whole subtrees, as solve's range) copied from `from`, a
  /// factor of the same coordinates holding H, not yet factored.
  void copy_inertia(const JointSpaceFactor& from, int first, int last);
  /// Factors the H set by set_inertia (as factor(h)); on coordinates first…last − 1 only
  /// (whole subtrees), the rest left as they are. Returns −1, or the first coordinate (from the
  /// leaves in) whose pivot was not > 0: H was not positive definite there (a state gone
  /// non-finite), and the solves' answers are not to be used. Does not throw.
  int factor();
  int factor(int first, int last);

  /// x ← H⁻¹ x (nv): x ← L⁻¹ D⁻¹ L⁻ᵀ x. O(Σ depth).
  void solve(Eigen::Ref<Eigen::VectorXd> x) const;
  /// y ← L⁻ᵀ y for a y (nv × 3) non-zero only on `coordinates`, which must hold every ancestor
  /// of each (a union of paths to the root) in descending order: O(their entries of L). The
  /// half rows of a contact, Y = L⁻ᵀ Jᵀ, stay on its paths.
  void solve_transposed_lower(Eigen::Ref<Eigen::Matrix<double, Eigen::Dynamic, 3>> y, const std::vector<int>& coordinates) const;
  /// The same for one column (nv; a limit row's).
  void solve_transposed_lower_column(Eigen::Ref<Eigen::VectorXd> y, const std::vector<int>& coordinates) const;
  /// x ← L⁻¹ x (nv), the last part of solve() (after L⁻ᵀ and D⁻¹). O(Σ depth).
  void solve_lower(Eigen::Ref<Eigen::VectorXd> x) const;
  /// The same on coordinates first…last − 1 only (whole subtrees, as solve's range).
  void solve_lower(Eigen::Ref<Eigen::VectorXd> x, int first, int last) const;
  /// The same on coordinates first…last − 1 only, which must hold whole subtrees (an island's:
  /// no coordinate in the range has its parent outside it unless that parent is −1); x outside
  /// the range is neither read nor written. H is block diagonal over such ranges.
  void solve(Eigen::Ref<Eigen::VectorXd> x, int first, int last) const;

  /// y ← L⁻ᵀ y (nv), the first half of solve(): for a row j of a Jacobian (1 × nv), y = jᵀ
  /// becomes (j L⁻¹)ᵀ, non-zero only on j's coordinates and their ancestors.
  void solve_transposed_lower(Eigen::Ref<Eigen::VectorXd> y) const;

  /// The Delassus matrix A = J H⁻¹ Jᵀ (m × m, symmetric positive semi-definite; written to `a`,
  /// resized) of the rows of `jacobian` (m × nv, velocity coordinates to constraint rates), as
  /// Y D⁻¹ Yᵀ with Y = J L⁻¹. `half` is scratch (nv × m afterwards: (Y D^(−1/2))ᵀ). O(m·Σ depth + m²·nv).
  void delassus(const Eigen::Ref<const Eigen::MatrixXd>& jacobian, Eigen::MatrixXd& a, Eigen::MatrixXd& half) const;

  /// D_i, the pivots (> 0 once factored).
  double pivot(int i) const { return pivot_[static_cast<std::size_t>(i)]; }
  /// 1 / D_i, once factored.
  double inverse_pivot(int i) const { return inverse_pivot_[static_cast<std::size_t>(i)]; }
  /// L_ij for j an ancestor of i (j = λ(i), λ(λ(i)), …); 0 for any other j < i.
  double lower(int i, int j) const;

 private:
  double& inertia(int i, int j);  // H_ij's slot (j = i or an ancestor), before factor(); O(1)

  std::vector<int> parent_;      // λ
  std::vector<int> begin_;       // per coordinate: its ancestors' entries in entries_, nearest first (nv + 1)
  std::vector<int> ancestor_;    // the ancestors j of each coordinate i, nearest first
  std::vector<double> entries_;  // H_ij, then L_ij, for those (i, j)
  std::vector<double> pivot_;    // H_ii, then D_i
  std::vector<double> inverse_pivot_;  // 1 / D_i
};

}  // namespace limber
