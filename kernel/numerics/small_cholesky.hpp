// Cholesky factorization A = L·Lᵀ of a small symmetric positive definite matrix of fixed size N,
// with solves for fixed-size right-hand sides, written out so the compiler unrolls them.
//
// Why not Eigen::LLT: for N = 6 its fixed-size solve with a matrix right-hand side takes the
// general blocked triangular-solve path (packing included). In the Lagrange tree solve, where each
// body's 6×6 block is factored and solved against a joint's 6×3 block, Eigen's LLT factor and
// solves were a third of a chain step (perf, lagrange_bench).
#pragma once

#include <cmath>

#include <Eigen/Core>
#include <Eigen/LU>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

template <int N, typename Scalar = double>
class SmallCholesky {
 public:
  using Matrix = Eigen::Matrix<Scalar, N, N>;

  /// Factors `a` (only its lower triangle is read). Returns false when a pivot is not positive
  /// (a not positive definite); the factor is then unusable.
  bool compute(const Matrix& a) {
    for (int j = 0; j < N; ++j) {
      Scalar pivot = a(j, j);
      for (int k = 0; k < j; ++k) pivot -= lower_(j, k) * lower_(j, k);
      if (!(pivot > 0)) return false;
      const Scalar diagonal = std::sqrt(pivot);
      lower_(j, j) = diagonal;
      inverse_diagonal_[j] = 1 / diagonal;
      for (int i = j + 1; i < N; ++i) {
        Scalar value = a(i, j);
        for (int k = 0; k < j; ++k) value -= lower_(i, k) * lower_(j, k);
        lower_(i, j) = value * inverse_diagonal_[j];
      }
    }
    return true;
  }

  /// Overwrites x (N × M) with A⁻¹·x: forward substitution with L, then back with Lᵀ.
  template <int M>
  void solve_in_place(Eigen::Matrix<Scalar, N, M>& x) const {
    for (int i = 0; i < N; ++i) {
      for (int k = 0; k < i; ++k) x.row(i) -= lower_(i, k) * x.row(k);
      x.row(i) *= inverse_diagonal_[i];
    }
    for (int i = N - 1; i >= 0; --i) {
      for (int k = i + 1; k < N; ++k) x.row(i) -= lower_(k, i) * x.row(k);
      x.row(i) *= inverse_diagonal_[i];
    }
  }

  template <int M>
  Eigen::Matrix<Scalar, N, M> solve(Eigen::Matrix<Scalar, N, M> x) const {
    solve_in_place(x);
    return x;
  }

 private:
  Matrix lower_ = Matrix::Zero();  ///< L in the lower triangle
  Eigen::Matrix<Scalar, N, 1> inverse_diagonal_ = Eigen::Matrix<Scalar, N, 1>::Zero();
};

/// The inverse of a small symmetric positive definite N × N matrix: Eigen's closed form up to
/// 4×4 (cheaper than a factor's square roots and triangular solves), a SmallCholesky factor
/// beyond (Eigen's LLT would solve the identity by its general blocked path). The caller
/// vouches for definiteness; a matrix that is not gives a meaningless result.
template <int N, typename Scalar>
Eigen::Matrix<Scalar, N, N> positive_definite_inverse(const Eigen::Matrix<Scalar, N, N>& a) {
  using Square = Eigen::Matrix<Scalar, N, N>;
  if constexpr (N <= 4) {
    return a.inverse();
  } else {
    SmallCholesky<N, Scalar> factor;
    factor.compute(a);
    return factor.solve(Square(Square::Identity()));
  }
}

}  // namespace limber
