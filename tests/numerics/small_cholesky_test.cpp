// SmallCholesky (kernel/numerics/small_cholesky.hpp): the factor A = L·Lᵀ, and
// positive_definite_inverse (which uses it past 3×3), solve A·x = b to rounding for symmetric
// positive definite blocks of every size they serve (1–6: a limb's 6 × 6 articulated inertia, a
// hinge's 5 × 5 joint block), well to badly conditioned; the factor refuses a block that is not
// positive definite.
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "limber/kernel/numerics/small_cholesky.hpp"

namespace limber {
namespace {

// A random symmetric positive definite N × N matrix whose eigenvalues span about `spread`:
// Q·diag(λ)·Qᵀ with Q orthonormal (from a QR-free Gram–Schmidt of random columns).
template <int N>
Eigen::Matrix<double, N, N> positive_definite(std::mt19937& random, double spread) {
  std::uniform_real_distribution<double> draw(-1, 1);
  Eigen::Matrix<double, N, N> q;
  for (int c = 0; c < N; ++c) {
    Eigen::Matrix<double, N, 1> column;
    for (int r = 0; r < N; ++r) column[r] = draw(random);
    for (int k = 0; k < c; ++k) column -= column.dot(q.col(k)) * q.col(k);
    q.col(c) = column.normalized();
  }
  Eigen::Matrix<double, N, 1> eigenvalues;
  for (int k = 0; k < N; ++k) eigenvalues[k] = N == 1 ? 1.0 : std::pow(spread, double(k) / (N - 1));
  return q * eigenvalues.asDiagonal() * q.transpose();
}

template <int N>
void expect_solves(double spread) {
  std::mt19937 random(N);
  std::uniform_real_distribution<double> draw(-1, 1);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Matrix<double, N, N> a = positive_definite<N>(random, spread);
    Eigen::Matrix<double, N, 3> x;
    for (int r = 0; r < N; ++r) {
      for (int c = 0; c < 3; ++c) x(r, c) = draw(random);
    }
    SmallCholesky<N> factor;
    ASSERT_TRUE(factor.compute(a));
    const Eigen::Matrix<double, N, 3> solved = factor.solve(Eigen::Matrix<double, N, 3>(a * x));
    // Backward-stable: the error is rounding times the condition number (≈ spread).
    EXPECT_LT((solved - x).norm(), 1e-14 * spread * x.norm()) << "N = " << N << ", trial " << trial;
    // positive_definite_inverse: cofactors up to 3×3, the factor beyond; A⁻¹·A = I to rounding
    // times the condition number (over 200 trials the 3×3 cofactors lost up to 143 roundings,
    // the factor up to 5: the bound leaves room for both).
    const Eigen::Matrix<double, N, N> identity = positive_definite_inverse<N, double>(a) * a;
    EXPECT_LT((identity - Eigen::Matrix<double, N, N>::Identity()).norm(), 1e-12 * spread) << "N = " << N << ", trial " << trial;
  }
}

TEST(SmallCholesky, SolvesPositiveDefiniteBlocksOfEverySizeToRounding) {
  for (const double spread : {1.0, 1e3, 1e6}) {  // well to badly conditioned
    SCOPED_TRACE("eigenvalue spread " + std::to_string(spread));
    expect_solves<1>(spread);
    expect_solves<2>(spread);
    expect_solves<3>(spread);
    expect_solves<4>(spread);
    expect_solves<5>(spread);
    expect_solves<6>(spread);
  }
}

TEST(SmallCholesky, RefusesABlockThatIsNotPositiveDefinite) {
  std::mt19937 random(1);
  Eigen::Matrix<double, 6, 6> a = positive_definite<6>(random, 10);
  SmallCholesky<6> factor;
  ASSERT_TRUE(factor.compute(a));
  // Minus twice the smallest eigenvalue's worth along its direction makes it indefinite.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eigen(a);
  const Eigen::Matrix<double, 6, 1> v = eigen.eigenvectors().col(0);
  a -= 2 * eigen.eigenvalues()[0] * v * v.transpose();
  EXPECT_FALSE(factor.compute(a));
  EXPECT_FALSE(factor.compute(Eigen::Matrix<double, 6, 6>::Zero()));  // singular
  Eigen::Matrix<double, 6, 6> nan = Eigen::Matrix<double, 6, 6>::Identity();
  nan(3, 3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(factor.compute(nan));
}

}  // namespace
}  // namespace limber
