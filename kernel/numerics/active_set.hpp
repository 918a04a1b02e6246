// Unilateral rows held exactly: an active-set solve of the linear complementarity problem of a
// few rows that push and never pull — joint limits — against their Delassus matrix.
//
// Rows i = 0…m−1 have values x_i (a rate, or a displacement), targets t_i and accumulated
// impulses λ_i ≥ 0; a change Δλ moves the values by A·Δλ, A (m × m) the rows' Delassus matrix
// J H⁻¹ Jᵀ (symmetric positive semi-definite). Wanted: λ' = λ + Δλ with
//   λ' ≥ 0,   x + AΔλ ≥ t,   λ'_i·(x + AΔλ − t)_i = 0
// (Cottle, Pang & Stone, "The Linear Complementarity Problem", 1992, §4.1). The rows held (the
// active set) reach their targets exactly: A_HH Δλ_H = (t − x)_H − A_HR Δλ_R, where the rows
// released give back what they had (Δλ_R = −λ_R); then a held row whose λ' would pull is
// released and a released row left past its target is held, and the solve repeats — block
// principal pivoting (Júdice & Pires 1994, "A block principal pivoting algorithm for
// large-scale strictly monotone linear complementarity problems"), a few rounds for the handful
// of limits at once on a tree. Sequential (Gauss–Seidel) impulses took hundreds of passes on
// neighbouring joints both at their limits: each row's impulse undoes the other's.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// The rows of one solve; sized by reserve(), so solve() allocates nothing for m within it.
class ActiveSet {
 public:
  /// Room for m rows (grows, never shrinks).
  void reserve(int m);

  /// The LCP above for the m rows whose Delassus matrix is `a` (m × m, symmetric), values `value`, targets `target` and accumulated
  /// impulses `accumulated` (≥ 0). `active` (m, in/out) says which rows start held; on return,
  /// which are. A row with a_ii ≤ 0 (it moves nothing) is never held. Writes Δλ to `change`
  /// (m), with λ + Δλ ≥ 0. `tolerance` is how far past its target a released row may stay (the
  /// values' units). At most `rounds` solves; returns how many it took. A_HH is factored with a
  /// ridge of 10⁻¹² times its largest diagonal entry, so dependent rows held together (a joint
  /// locked at both ends) share the impulse instead of failing.
  /// Successive solves on one matrix reuse A_HH's factor while the same rows are held (the passes
  /// of a step: its limits' Delassus matrix is formed once): call forget() whenever `a` changes.
  int solve(const Eigen::Ref<const Eigen::MatrixXd>& a, const Eigen::Ref<const Eigen::VectorXd>& value,
            const Eigen::Ref<const Eigen::VectorXd>& target, const Eigen::Ref<const Eigen::VectorXd>& accumulated,
            std::vector<char>& active, double tolerance, Eigen::Ref<Eigen::VectorXd> change, int rounds = 8);
  /// The next solve's matrix is a new one: its held rows are factored again.
  void forget() { factored_known_ = false; }

 private:
  // Δλ_H for the rows in held_ (the rest at −λ), by Cholesky of A_HH in factor_.
  void solve_held(const Eigen::Ref<const Eigen::MatrixXd>& a, const Eigen::Ref<const Eigen::VectorXd>& value,
                  const Eigen::Ref<const Eigen::VectorXd>& target, Eigen::Ref<Eigen::VectorXd> change);
  // A_HH + ridge = L Lᵀ for the rows in held_, into factor_.
  void factor_held(const Eigen::Ref<const Eigen::MatrixXd>& a);

  Eigen::MatrixXd factor_;    // L of A_HH, top-left
  Eigen::VectorXd inverse_diagonal_;  // 1 / L_rr: the solves multiply (a division's latency chains them)
  Eigen::VectorXd right_;     // its right-hand side, then Δλ_H
  std::vector<int> held_;     // the held rows, in order
  std::vector<int> factored_; // the held rows whose A_HH factor_ holds, when factored_known_
  bool factored_known_ = false;
};

}  // namespace limber
