// ActiveSet (kernel/numerics/active_set.hpp): the rows it returns satisfy the linear
// complementarity problem — no row pulls, none is left past its target, and a row that pushes
// ends exactly on it — and agree with the unique answer found by trying every active set, on
// random Delassus matrices J H⁻¹ Jᵀ; rows that depend on each other (a joint locked at both
// ends) are held without failing.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include "limber/kernel/numerics/active_set.hpp"
#include "tests/support/delassus.hpp"

namespace limber {
namespace {

using testing::random_delassus;

struct Problem {
  Eigen::MatrixXd a;
  Eigen::VectorXd value, target, accumulated;
};

Problem random_problem(std::mt19937& random, int m) {
  std::uniform_real_distribution<double> draw(-1, 1), positive(0, 1);
  Problem p{random_delassus(random, m, m + 3), Eigen::VectorXd(m), Eigen::VectorXd(m), Eigen::VectorXd(m)};
  for (int i = 0; i < m; ++i) {
    p.value[i] = draw(random), p.target[i] = draw(random);
    p.accumulated[i] = positive(random) < 0.5 ? 0.0 : positive(random);
  }
  return p;
}

// The LCP's answer by trying every active set: A_HH Δλ_H = (t − x)_H − A_HR Δλ_R with
// Δλ_R = −λ_R, accepted when λ + Δλ ≥ 0 on H and x + AΔλ ≥ t off it.
Eigen::VectorXd every_active_set(const Problem& p) {
  const int m = static_cast<int>(p.value.size());
  for (int mask = 0; mask < (1 << m); ++mask) {
    std::vector<int> held;
    Eigen::VectorXd change = -p.accumulated;
    for (int i = 0; i < m; ++i) {
      if (mask & (1 << i)) held.push_back(i), change[i] = 0;
    }
    const int n = static_cast<int>(held.size());
    Eigen::MatrixXd block(n, n);
    Eigen::VectorXd right(n);
    for (int r = 0; r < n; ++r) {
      right[r] = p.target[held[r]] - p.value[held[r]] - p.a.row(held[r]).dot(change);
      for (int c = 0; c < n; ++c) block(r, c) = p.a(held[r], held[c]);
    }
    const Eigen::VectorXd solved = block.llt().solve(right);
    for (int r = 0; r < n; ++r) change[held[r]] = solved[r];
    const Eigen::VectorXd after = p.value + p.a * change;
    bool complementary = true;
    for (int i = 0; i < m; ++i) {
      if (mask & (1 << i)) complementary = complementary && p.accumulated[i] + change[i] >= -1e-12;
      else complementary = complementary && after[i] >= p.target[i] - 1e-12;
    }
    if (complementary) return change;
  }
  ADD_FAILURE() << "no active set solves the problem";
  return Eigen::VectorXd::Zero(m);
}

TEST(ActiveSet, SolvesTheComplementarityProblemOfRandomDelassusMatrices) {
  std::mt19937 random(7);
  ActiveSet solver;
  for (int trial = 0; trial < 200; ++trial) {
    const int m = 1 + trial % 8;
    const Problem p = random_problem(random, m);
    std::vector<char> active(static_cast<std::size_t>(m), 0);
    for (int i = 0; i < m; ++i) active[static_cast<std::size_t>(i)] = p.accumulated[i] > 0 || p.value[i] < p.target[i];
    Eigen::VectorXd change(m);
    solver.forget();  // a new matrix
    solver.solve(p.a, p.value, p.target, p.accumulated, active, 0.0, change, /*rounds=*/64);
    const Eigen::VectorXd impulse = p.accumulated + change, after = p.value + p.a * change;
    for (int i = 0; i < m; ++i) {
      EXPECT_GE(impulse[i], 0) << "trial " << trial << " row " << i;
      EXPECT_GE(after[i], p.target[i] - 1e-10) << "trial " << trial << " row " << i;
      EXPECT_LE(impulse[i] * std::abs(after[i] - p.target[i]), 1e-9) << "trial " << trial << " row " << i;
    }
    EXPECT_LE((change - every_active_set(p)).lpNorm<Eigen::Infinity>(), 1e-9) << "trial " << trial;
  }
}

TEST(ActiveSet, ReusesItsFactorOnTheSameMatrixUntilForgotten) {
  // A step's passes solve one Delassus matrix again and again: the held rows' factor carries over
  // between them, and forget() drops it when the matrix changes. Each answer equals a fresh
  // solver's, bit for bit.
  std::mt19937 random(11);
  ActiveSet reused;
  for (int trial = 0; trial < 50; ++trial) {
    const int m = 1 + trial % 6;
    const Problem first = random_problem(random, m);
    reused.forget();
    for (int pass = 0; pass < 3; ++pass) {
      Problem p = first;
      if (pass > 0) p.value = first.value + 0.1 * pass * Eigen::VectorXd::Ones(m);  // the next pass's values, the same matrix
      std::vector<char> held(static_cast<std::size_t>(m), 1), fresh_held = held;
      Eigen::VectorXd change(m), expected(m);
      reused.solve(p.a, p.value, p.target, p.accumulated, held, 0.0, change, 64);
      ActiveSet fresh;
      fresh.solve(p.a, p.value, p.target, p.accumulated, fresh_held, 0.0, expected, 64);
      EXPECT_EQ(change, expected) << "trial " << trial << " pass " << pass;
      EXPECT_EQ(held, fresh_held) << "trial " << trial << " pass " << pass;
    }
  }
}

TEST(ActiveSet, HoldsDependentRowsTogether) {
  // A joint locked at both ends: the same row twice (min and max), both pushed past.
  std::mt19937 random(3);
  Eigen::MatrixXd a = random_delassus(random, 3, 5);
  a.row(1) = a.row(0), a.col(1) = a.col(0);  // row 1 duplicates row 0
  const Eigen::VectorXd value = Eigen::Vector3d(-1, -1, 0.5), target = Eigen::Vector3d(0, 0, 0), accumulated = Eigen::Vector3d::Zero();
  std::vector<char> active{1, 1, 0};
  Eigen::VectorXd change(3);
  ActiveSet solver;
  solver.solve(a, value, target, accumulated, active, 0.0, change);
  ASSERT_TRUE(change.allFinite());
  const Eigen::VectorXd after = value + a * change;
  EXPECT_NEAR(after[0], 0, 1e-9);
  EXPECT_NEAR(after[1], 0, 1e-9);
  EXPECT_GE(after[2], -1e-9);
}

}  // namespace
}  // namespace limber
