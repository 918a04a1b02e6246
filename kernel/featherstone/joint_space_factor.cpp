#include "limber/kernel/featherstone/joint_space_factor.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace limber {

std::vector<int> dof_parents(const ArticulatedTree& tree) {
  std::vector<int> parent(static_cast<std::size_t>(tree.velocity_count()), -1);
  // The last coordinate of each body's path to the root, its own included (−1: none).
  std::vector<int> last(static_cast<std::size_t>(tree.body_count()), -1);
  for (int b = 0; b < tree.body_count(); ++b) {
    const int up = tree.body(b).parent;
    int before = up < 0 ? -1 : last[static_cast<std::size_t>(up)];
    const int offset = tree.velocity_offset(b);
    for (int k = 0; k < joint_velocity_count(tree.body(b).joint); ++k) {
      parent[static_cast<std::size_t>(offset + k)] = before;
      before = offset + k;
    }
    last[static_cast<std::size_t>(b)] = before;
  }
  return parent;
}

void JointSpaceFactor::assign(const std::vector<int>& dof_parent) {
  const auto n = static_cast<int>(dof_parent.size());
  for (int i = 0; i < n; ++i) {
    const int up = dof_parent[static_cast<std::size_t>(i)];
    if (up < -1 || up >= i) {
      throw std::invalid_argument("JointSpaceFactor: coordinate " + std::to_string(i) + "'s parent " + std::to_string(up) +
                                  " is not before it (expected -1 <= parent < " + std::to_string(i) + ")");
    }
  }
  parent_ = dof_parent;
  begin_.assign(static_cast<std::size_t>(n) + 1, 0);
  ancestor_.clear();
  for (int i = 0; i < n; ++i) {
    begin_[static_cast<std::size_t>(i)] = static_cast<int>(ancestor_.size());
    for (int j = parent_[static_cast<std::size_t>(i)]; j >= 0; j = parent_[static_cast<std::size_t>(j)]) ancestor_.push_back(j);
  }
  begin_[static_cast<std::size_t>(n)] = static_cast<int>(ancestor_.size());
  entries_.assign(ancestor_.size(), 0.0);
  pivot_.assign(static_cast<std::size_t>(n), 0.0);
  inverse_pivot_.assign(static_cast<std::size_t>(n), 0.0);
}

double JointSpaceFactor::lower(int i, int j) const {
  for (int e = begin_[static_cast<std::size_t>(i)]; e < begin_[static_cast<std::size_t>(i) + 1]; ++e) {
    if (ancestor_[static_cast<std::size_t>(e)] == j) return entries_[static_cast<std::size_t>(e)];
  }
  return 0.0;
}

void JointSpaceFactor::factor(const Eigen::Ref<const Eigen::MatrixXd>& h) {
  const int n = size();
  if (h.rows() != n || h.cols() != n) {
    throw std::invalid_argument("JointSpaceFactor::factor: H is " + std::to_string(h.rows()) + " x " + std::to_string(h.cols()) +
                                ", expected " + std::to_string(n) + " x " + std::to_string(n));
  }
  for (int i = 0; i < n; ++i) {
    pivot_[static_cast<std::size_t>(i)] = h(i, i);
    for (int e = begin_[static_cast<std::size_t>(i)]; e < begin_[static_cast<std::size_t>(i) + 1]; ++e) {
      entries_[static_cast<std::size_t>(e)] = h(i, ancestor_[static_cast<std::size_t>(e)]);
    }
  }
  const int bad = factor();
  if (bad >= 0) {
    throw std::domain_error("JointSpaceFactor::factor: pivot of coordinate " + std::to_string(bad) + " is not > 0 (H is not positive definite)");
  }
}

double& JointSpaceFactor::inertia(int i, int j) {
  if (j == i) return pivot_[static_cast<std::size_t>(i)];
  // i's ancestors are listed nearest first, one a level: an ancestor j with a ancestors of its own
  // is i's (count(i) − count(j) − 1)-th. The composite-rigid-body algorithm stores O(Σ depth)
  // entries, so a search along the path would make it O(Σ depth²).
  const auto count = [&](int k) { return begin_[static_cast<std::size_t>(k) + 1] - begin_[static_cast<std::size_t>(k)]; };
  if (j >= 0 && j < i) {
    const int e = begin_[static_cast<std::size_t>(i)] + count(i) - count(j) - 1;
    if (e >= begin_[static_cast<std::size_t>(i)] && ancestor_[static_cast<std::size_t>(e)] == j) return entries_[static_cast<std::size_t>(e)];
  }
  throw std::invalid_argument("JointSpaceFactor: coordinate " + std::to_string(j) + " is not on coordinate " + std::to_string(i) + "'s path to the root");
}

void JointSpaceFactor::set_inertia(int i, int j, double value) { inertia(i, j) = value; }
void JointSpaceFactor::add_inertia(int i, int j, double value) { inertia(i, j) += value; }

void JointSpaceFactor::copy_inertia(const JointSpaceFactor& from, int first, int last) {
  const auto entry = [&](int i) { return static_cast<std::ptrdiff_t>(begin_[static_cast<std::size_t>(i)]); };
  std::copy(from.entries_.begin() + entry(first), from.entries_.begin() + entry(last), entries_.begin() + entry(first));
  std::copy(from.pivot_.begin() + first, from.pivot_.begin() + last, pivot_.begin() + first);
}

int JointSpaceFactor::factor() { return factor(0, size()); }

int JointSpaceFactor::factor(int first, int last) {
  int bad = -1;
  // Table 6.3, from the leaves in: coordinate k's row divides by its pivot and updates the rows
  // of its ancestors (k's ancestors are each ancestor's own ancestors, nearest first, so the
  // entry of i = ancestor e of k at its ancestor f of k sits at a fixed offset in i's row).
  for (int k = last - 1; k >= first; --k) {
    const double d = pivot_[static_cast<std::size_t>(k)];
    if (!(d > 0) && bad < 0) bad = k;
    const double inverse = 1 / d;  // one division a coordinate; the solves and responses multiply
    inverse_pivot_[static_cast<std::size_t>(k)] = inverse;
    const int begin = begin_[static_cast<std::size_t>(k)], end = begin_[static_cast<std::size_t>(k) + 1];
    for (int e = begin; e < end; ++e) {
      const auto i = static_cast<std::size_t>(ancestor_[static_cast<std::size_t>(e)]);
      const double h_ki = entries_[static_cast<std::size_t>(e)];
      const double l_ki = h_ki * inverse;
      pivot_[i] -= l_ki * h_ki;
      // i's ancestors are k's after e, in the same order, at the start of i's row.
      double* row_i = entries_.data() + begin_[i];
      for (int f = e + 1; f < end; ++f) row_i[f - e - 1] -= l_ki * entries_[static_cast<std::size_t>(f)];
      entries_[static_cast<std::size_t>(e)] = l_ki;
    }
  }
  return bad;
}

namespace {

// Lᵀ z = y on coordinates first…last − 1 (whole subtrees), from the leaves in: z_k is final once
// every descendant has given its part.
void transposed_lower_solve(const std::vector<int>& begin, const std::vector<int>& ancestor, const std::vector<double>& entries,
                            Eigen::Ref<Eigen::VectorXd> y, int first, int last) {
  for (int k = last - 1; k >= first; --k) {
    const double y_k = y[k];
    if (y_k == 0) continue;
    for (int e = begin[static_cast<std::size_t>(k)]; e < begin[static_cast<std::size_t>(k) + 1]; ++e) {
      y[ancestor[static_cast<std::size_t>(e)]] -= entries[static_cast<std::size_t>(e)] * y_k;
    }
  }
}

}  // namespace

void JointSpaceFactor::solve_transposed_lower(Eigen::Ref<Eigen::VectorXd> y) const { transposed_lower_solve(begin_, ancestor_, entries_, y, 0, size()); }

namespace {

// y ← L⁻ᵀ y on `coordinates` (descending, closed under ancestors), y's rows one to three values.
template <typename Rows>
void transposed_lower_solve_on(const std::vector<int>& begin, const std::vector<int>& ancestor, const std::vector<double>& entries,
                               Rows& y, const std::vector<int>& coordinates) {
  for (const int k : coordinates) {
    const auto y_k = y.row(k).eval();
    for (int e = begin[static_cast<std::size_t>(k)]; e < begin[static_cast<std::size_t>(k) + 1]; ++e) {
      y.row(ancestor[static_cast<std::size_t>(e)]) -= entries[static_cast<std::size_t>(e)] * y_k;
    }
  }
}

}  // namespace

void JointSpaceFactor::solve_transposed_lower(Eigen::Ref<Eigen::Matrix<double, Eigen::Dynamic, 3>> y, const std::vector<int>& coordinates) const {
  transposed_lower_solve_on(begin_, ancestor_, entries_, y, coordinates);
}

void JointSpaceFactor::solve_transposed_lower_column(Eigen::Ref<Eigen::VectorXd> y, const std::vector<int>& coordinates) const {
  transposed_lower_solve_on(begin_, ancestor_, entries_, y, coordinates);
}

namespace {

// L x = z on coordinates first…last − 1 (whole subtrees), from the root out.
void lower_solve(const std::vector<int>& begin, const std::vector<int>& ancestor, const std::vector<double>& entries,
                 Eigen::Ref<Eigen::VectorXd> x, int first, int last) {
  for (int i = first; i < last; ++i) {
    double sum = x[i];
    for (int e = begin[static_cast<std::size_t>(i)]; e < begin[static_cast<std::size_t>(i) + 1]; ++e) {
      sum -= entries[static_cast<std::size_t>(e)] * x[ancestor[static_cast<std::size_t>(e)]];
    }
    x[i] = sum;
  }
}

}  // namespace

void JointSpaceFactor::solve_lower(Eigen::Ref<Eigen::VectorXd> x) const { lower_solve(begin_, ancestor_, entries_, x, 0, size()); }
void JointSpaceFactor::solve_lower(Eigen::Ref<Eigen::VectorXd> x, int first, int last) const {
  lower_solve(begin_, ancestor_, entries_, x, first, last);
}

void JointSpaceFactor::solve(Eigen::Ref<Eigen::VectorXd> x, int first, int last) const {
  transposed_lower_solve(begin_, ancestor_, entries_, x, first, last);
  for (int i = first; i < last; ++i) x[i] *= inverse_pivot_[static_cast<std::size_t>(i)];
  lower_solve(begin_, ancestor_, entries_, x, first, last);
}

void JointSpaceFactor::solve(Eigen::Ref<Eigen::VectorXd> x) const {
  if (x.size() != size()) throw std::invalid_argument("JointSpaceFactor::solve: x has " + std::to_string(x.size()) + " entries, expected " + std::to_string(size()));
  solve(x, 0, size());
}

void JointSpaceFactor::delassus(const Eigen::Ref<const Eigen::MatrixXd>& jacobian, Eigen::MatrixXd& a, Eigen::MatrixXd& half) const {
  if (jacobian.cols() != size()) {
    throw std::invalid_argument("JointSpaceFactor::delassus: the Jacobian has " + std::to_string(jacobian.cols()) + " columns, expected " + std::to_string(size()));
  }
  const auto m = jacobian.rows();
  // Y = J L⁻¹, scaled by D^(-1/2) so that A = Y Yᵀ; stored transposed (nv × m) for its columns.
  half = jacobian.transpose();
  for (Eigen::Index r = 0; r < m; ++r) {
    solve_transposed_lower(half.col(r));
    for (int i = 0; i < size(); ++i) half(i, r) /= std::sqrt(pivot_[static_cast<std::size_t>(i)]);
  }
  a.noalias() = half.transpose() * half;
}

}  // namespace limber
