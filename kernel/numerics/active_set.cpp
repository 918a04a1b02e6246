#include "limber/kernel/numerics/active_set.hpp"

#include <algorithm>
#include <cmath>

namespace limber {

void ActiveSet::reserve(int m) {
  if (factor_.rows() < m) factor_.resize(m, m), inverse_diagonal_.resize(m), right_.resize(m), factored_known_ = false;
  held_.reserve(static_cast<std::size_t>(m)), factored_.reserve(static_cast<std::size_t>(m));
}

void ActiveSet::solve_held(const Eigen::Ref<const Eigen::MatrixXd>& a, const Eigen::Ref<const Eigen::VectorXd>& value,
                           const Eigen::Ref<const Eigen::VectorXd>& target, Eigen::Ref<Eigen::VectorXd> change) {
  const int n = static_cast<int>(held_.size());
  if (n == 0) return;
  // Right-hand side (t − x)_H − A_HR Δλ_R, with Δλ_R in `change` (A's rows read as its columns,
  // which are contiguous: A is symmetric).
  for (int k = 0; k < n; ++k) {
    const int i = held_[static_cast<std::size_t>(k)];
    right_[k] = target[i] - value[i] - a.col(i).dot(change);  // the held rows' change is 0 here
  }
  if (!factored_known_ || factored_ != held_) factor_held(a);
  for (int r = 0; r < n; ++r) {
    for (int k = 0; k < r; ++k) right_[r] -= factor_(r, k) * right_[k];
    right_[r] *= inverse_diagonal_[r];
  }
  for (int r = n - 1; r >= 0; --r) {
    for (int k = r + 1; k < n; ++k) right_[r] -= factor_(k, r) * right_[k];
    right_[r] *= inverse_diagonal_[r];
  }
  for (int k = 0; k < n; ++k) change[held_[static_cast<std::size_t>(k)]] = right_[k];
}

void ActiveSet::factor_held(const Eigen::Ref<const Eigen::MatrixXd>& a) {
  const int n = static_cast<int>(held_.size());
  double largest = 0;
  for (const int i : held_) largest = std::max(largest, a(i, i));
  const double ridge = 1e-12 * largest;
  // A_HH + ridge = L Lᵀ, in place in factor_'s lower triangle.
  for (int c = 0; c < n; ++c) {
    const int j = held_[static_cast<std::size_t>(c)];
    double pivot = a(j, j) + ridge;
    for (int k = 0; k < c; ++k) pivot -= factor_(c, k) * factor_(c, k);
    const double diagonal = std::sqrt(std::max(pivot, ridge));
    factor_(c, c) = diagonal;
    inverse_diagonal_[c] = 1 / diagonal;
    for (int r = c + 1; r < n; ++r) {
      double entry = a(held_[static_cast<std::size_t>(r)], j);
      for (int k = 0; k < c; ++k) entry -= factor_(r, k) * factor_(c, k);
      factor_(r, c) = entry * inverse_diagonal_[c];
    }
  }
  factored_ = held_, factored_known_ = true;
}

int ActiveSet::solve(const Eigen::Ref<const Eigen::MatrixXd>& a, const Eigen::Ref<const Eigen::VectorXd>& value,
                     const Eigen::Ref<const Eigen::VectorXd>& target, const Eigen::Ref<const Eigen::VectorXd>& accumulated,
                     std::vector<char>& active, double tolerance, Eigen::Ref<Eigen::VectorXd> change, int rounds) {
  const int m = static_cast<int>(value.size());
  reserve(m);
  for (int round = 1;; ++round) {
    held_.clear();
    for (int i = 0; i < m; ++i) {
      const auto index = static_cast<std::size_t>(i);
      if (!(a(i, i) > 0)) active[index] = 0;
      if (active[index]) {
        held_.push_back(i);
        change[i] = 0;
      } else {
        change[i] = -accumulated[i];  // a released row gives back what it had
      }
    }
    solve_held(a, value, target, change);
    bool changed = false;
    for (int i = 0; i < m; ++i) {
      const auto index = static_cast<std::size_t>(i);
      if (active[index]) {
        if (accumulated[i] + change[i] < 0) active[index] = 0, changed = true;  // it would pull
      } else if (a(i, i) > 0 && value[i] + a.col(i).dot(change) < target[i] - tolerance) {
        active[index] = 1, changed = true;  // left past its target
      }
    }
    if (!changed || round >= rounds) {
      for (int i = 0; i < m; ++i) change[i] = std::max(accumulated[i] + change[i], 0.0) - accumulated[i];
      return round;
    }
  }
}

}  // namespace limber
