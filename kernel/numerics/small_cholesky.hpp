// Cholesky factorization A = L·Lᵀ of a small symmetric positive definite matrix of fixed size N,
// with solves for fixed-size right-hand sides, written out so the compiler unrolls them; and
// the inverse of such a matrix. Numbers or SIMD lanes of numbers (lane_blocks.hpp: lane k gives
// the bits the same code gives on lane k's numbers).
//
// Why not Eigen::LLT: for N = 6 its fixed-size solve with a matrix right-hand side takes the
// general blocked triangular-solve path (packing included). In the Lagrange tree solve, where each
// body's 6×6 block is factored and solved against a joint's 6×3 block, Eigen's LLT factor and
// solves were a third of a chain step (perf, lagrange_bench).
#pragma once

#include <array>
#include <cmath>
#include <type_traits>

#include <Eigen/Core>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build
#include "limber/kernel/numerics/lane_blocks.hpp"

namespace limber {

template <int N, typename Value = double>
class SmallCholesky {
 public:
  using Matrix = Block<Value, N, N>;

  /// Factors `a` (N × N, any block type read by a(i, j); only its lower triangle is read).
  /// Returns false when a pivot is not positive in some lane (a not positive definite there);
  /// that lane's factor is then unusable.
  template <typename Square>
  bool compute(const Square& a) {
    using std::sqrt;  // and xsimd::sqrt for lanes, by argument-dependent lookup
    bool definite = true;
    for (int j = 0; j < N; ++j) {
      Value pivot = a(j, j);
      for (int k = 0; k < j; ++k) pivot -= lower_(j, k) * lower_(j, k);
      definite = all_lanes(pivot > Value(0)) && definite;
      const Value diagonal = sqrt(pivot);
      lower_(j, j) = diagonal;
      inverse_diagonal_(j, 0) = Value(1) / diagonal;
      for (int i = j + 1; i < N; ++i) {
        Value value = a(i, j);
        for (int k = 0; k < j; ++k) value -= lower_(i, k) * lower_(j, k);
        lower_(i, j) = value * inverse_diagonal_(j, 0);
      }
    }
    return definite;
  }

  /// Overwrites x (N × M) with A⁻¹·x: forward substitution with L, then back with Lᵀ.
  template <typename Right>
  void solve_in_place(Right& x) const {
    constexpr int M = columns<Right>();
    for (int i = 0; i < N; ++i) {
      for (int c = 0; c < M; ++c) {
        for (int k = 0; k < i; ++k) x(i, c) -= lower_(i, k) * x(k, c);
        x(i, c) *= inverse_diagonal_(i, 0);
      }
    }
    for (int i = N - 1; i >= 0; --i) {
      for (int c = 0; c < M; ++c) {
        for (int k = i + 1; k < N; ++k) x(i, c) -= lower_(k, i) * x(k, c);
        x(i, c) *= inverse_diagonal_(i, 0);
      }
    }
  }

  template <typename Right>
  Right solve(Right x) const {
    solve_in_place(x);
    return x;
  }

 private:
  template <typename Right>
  static constexpr int columns() {
    if constexpr (std::is_arithmetic_v<Value>) {
      return Right::ColsAtCompileTime;
    } else {
      return static_cast<int>(std::tuple_size_v<decltype(Right::entries)>) / N;
    }
  }
  Matrix lower_ = Matrix::Zero();  ///< L in the lower triangle
  Block<Value, N, 1> inverse_diagonal_ = Block<Value, N, 1>::Zero();
};

/// The inverse of a small symmetric positive definite N × N block `a`: cofactors up to 3×3 (six
/// of them: the inverse is symmetric by construction), a Cholesky factor's solve of the identity
/// beyond (SmallCholesky). `definite` is cleared when a lane's determinant or pivot is not
/// positive (that lane's inverse is then meaningless).
template <int N, typename Value, typename Square>
[[gnu::always_inline]] inline Block<Value, N, N> positive_definite_inverse(const Square& a, bool& definite) {
  Block<Value, N, N> inverse;
  if constexpr (N == 1) {
    definite = all_lanes(a(0, 0) > Value(0)) && definite;
    inverse(0, 0) = Value(1) / a(0, 0);
  } else if constexpr (N == 2) {
    const Value determinant = a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0);
    definite = all_lanes(determinant > Value(0)) && all_lanes(a(0, 0) > Value(0)) && definite;
    const Value r = Value(1) / determinant;
    inverse(0, 0) = a(1, 1) * r, inverse(1, 1) = a(0, 0) * r;
    inverse(0, 1) = inverse(1, 0) = -a(0, 1) * r;
  } else if constexpr (N == 3) {
    // inverse(i, j) = cofactor(j, i) / det, symmetric as `a` is: six cofactors.
    const Value c00 = a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1);
    const Value c01 = a(1, 2) * a(2, 0) - a(1, 0) * a(2, 2);
    const Value c02 = a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0);
    const Value determinant = a(0, 0) * c00 + a(0, 1) * c01 + a(0, 2) * c02;
    definite = all_lanes(determinant > Value(0)) && all_lanes(a(0, 0) > Value(0)) && definite;
    const Value r = Value(1) / determinant;
    inverse(0, 0) = c00 * r;
    inverse(0, 1) = inverse(1, 0) = c01 * r;
    inverse(0, 2) = inverse(2, 0) = c02 * r;
    inverse(1, 1) = (a(0, 0) * a(2, 2) - a(0, 2) * a(2, 0)) * r;
    inverse(1, 2) = inverse(2, 1) = (a(0, 1) * a(2, 0) - a(0, 0) * a(2, 1)) * r;
    inverse(2, 2) = (a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0)) * r;
  } else {
    SmallCholesky<N, Value> factor;
    definite = factor.compute(a) && definite;
    for (int i = 0; i < N; ++i) {
      for (int j = 0; j < N; ++j) inverse(i, j) = Value(i == j ? 1 : 0);
    }
    factor.solve_in_place(inverse);
  }
  return inverse;
}

/// The same for a caller that vouches for definiteness (Featherstone's joint inertia D = SᵀIᴬS).
template <int N, typename Scalar>
Eigen::Matrix<Scalar, N, N> positive_definite_inverse(const Eigen::Matrix<Scalar, N, N>& a) {
  bool definite = true;
  return positive_definite_inverse<N, Scalar>(a, definite);
}

}  // namespace limber
