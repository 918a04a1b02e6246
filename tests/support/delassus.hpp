// Random Delassus matrices for the tests of the constraint solvers (kernel/numerics).
#pragma once

#include <random>

#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace limber::testing {

/// A Delassus matrix J H⁻¹ Jᵀ of m rows on n coordinates, J and H's root drawn from [−1, 1] and
/// H = root·rootᵀ + ridge·I: symmetric positive semi-definite, definite for n ≥ m.
inline Eigen::MatrixXd random_delassus(std::mt19937& random, int m, int n, double ridge = 1) {
  std::uniform_real_distribution<double> draw(-1, 1);
  Eigen::MatrixXd j(m, n), root(n, n);
  for (int r = 0; r < m; ++r) for (int c = 0; c < n; ++c) j(r, c) = draw(random);
  for (int r = 0; r < n; ++r) for (int c = 0; c < n; ++c) root(r, c) = draw(random);
  const Eigen::MatrixXd h = root * root.transpose() + ridge * Eigen::MatrixXd::Identity(n, n);
  return j * h.llt().solve(j.transpose());
}

}  // namespace limber::testing
