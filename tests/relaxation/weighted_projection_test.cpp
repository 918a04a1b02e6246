// The weighted projection (thesis eq. 4.7) against the midpoint rule (eq. 4.6), on one pair.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "limber/kernel/relaxation/distance_projection.hpp"

namespace limber {
namespace {

template <typename Scalar>
struct Pair {
  ParticleBuffer<Scalar> particles;
  DistanceConstraintBuffer<Scalar> constraints;
  Pair(double mass_i, double mass_j, Eigen::Vector3d x_i, Eigen::Vector3d x_j, double rest) {
    particles.resize(2);
    particles.set_position(0, x_i.cast<Scalar>());
    particles.set_position(1, x_j.cast<Scalar>());
    particles.set_previous(0, x_i.cast<Scalar>());
    particles.set_previous(1, x_j.cast<Scalar>());
    particles.inverse_mass[0] = mass_i > 0 ? Scalar(1 / mass_i) : Scalar(0);
    particles.inverse_mass[1] = mass_j > 0 ? Scalar(1 / mass_j) : Scalar(0);
    constraints.resize(1, particles.null_particle());
    constraints.particle_i[0] = 0, constraints.particle_j[0] = 1, constraints.rest_length[0] = Scalar(rest);
  }
  Eigen::Vector3d x(int k) const { return particles.position(k).template cast<double>(); }
  double project(RelaxationRule rule) { return project_distance_constraint(particles, constraints, 0, rule); }
};

template <typename Scalar>
class WeightedProjection : public ::testing::Test {
 protected:
  // Rounding allowance relative to the numbers involved.
  static constexpr double kEpsilon = std::is_same_v<Scalar, float> ? 2e-6 : 1e-13;
};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(WeightedProjection, Scalars);

TYPED_TEST(WeightedProjection, HeavierEndMovesTheLightShareOfTheGap) {
  const double heavy = 6.0, light = 2.0;
  Pair<TypeParam> pair(heavy, light, {0, 0, 0}, {1.5, 0, 0}, 1.0);  // gap 0.5 m
  pair.project(RelaxationRule::weighted);
  // Heavy end moves light/(heavy+light) of the gap, the light end the rest.
  EXPECT_NEAR(pair.x(0).x(), 0.5 * light / (heavy + light), this->kEpsilon);
  EXPECT_NEAR(1.5 - pair.x(1).x(), 0.5 * heavy / (heavy + light), this->kEpsilon);
  EXPECT_NEAR((pair.x(1) - pair.x(0)).norm(), 1.0, this->kEpsilon);
}

TYPED_TEST(WeightedProjection, KeepsCentreOfMassAndMomentumForAnyMassRatio) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> coordinate(-1, 1);
  for (double ratio : {1.0, 3.0, 670.0, 1e4}) {
    for (int trial = 0; trial < 20; ++trial) {
      const Eigen::Vector3d a(coordinate(random), coordinate(random), coordinate(random));
      const Eigen::Vector3d b(coordinate(random), coordinate(random), coordinate(random));
      const double m_i = 1.0, m_j = ratio;
      Pair<TypeParam> pair(m_i, m_j, a, b, 0.3 + 0.5 * std::abs(coordinate(random)));
      const Eigen::Vector3d before = (m_i * pair.x(0) + m_j * pair.x(1)) / (m_i + m_j);
      pair.project(RelaxationRule::weighted);
      const Eigen::Vector3d after = (m_i * pair.x(0) + m_j * pair.x(1)) / (m_i + m_j);
      EXPECT_LT((after - before).norm(), 4 * this->kEpsilon) << "mass ratio " << ratio;
      // Verlet momentum Σ m (x − x*) / Δt changes by Σ m Δx, the same quantity.
    }
  }
}

TYPED_TEST(WeightedProjection, MidpointRuleMovesCentreOfMassWhenMassesDiffer) {
  Pair<TypeParam> equal(2, 2, {0, 0, 0}, {1.5, 0, 0}, 1.0);
  Pair<TypeParam> unequal(1, 9, {0, 0, 0}, {1.5, 0, 0}, 1.0);
  equal.project(RelaxationRule::unweighted);
  unequal.project(RelaxationRule::unweighted);
  EXPECT_NEAR((equal.x(0) + equal.x(1)).x() / 2, 0.75, this->kEpsilon);    // equal masses: kept
  const double centre = (1 * unequal.x(0).x() + 9 * unequal.x(1).x()) / 10;  // was 1.35
  EXPECT_GT(std::abs(centre - 1.35), 0.1);                                  // unequal: moved by 0.2
  EXPECT_NEAR((unequal.x(1) - unequal.x(0)).norm(), 1.0, this->kEpsilon);  // but the length is met
}

TYPED_TEST(WeightedProjection, PinnedEndNeverMovesUnderEitherRule) {
  for (RelaxationRule rule : {RelaxationRule::weighted, RelaxationRule::unweighted}) {
    Pair<TypeParam> pair(0, 3, {0, 0, 0}, {0, 0, -2}, 1.0);
    pair.project(rule);
    EXPECT_EQ(pair.x(0), Eigen::Vector3d::Zero());
    EXPECT_NEAR(pair.x(1).z(), -1.0, this->kEpsilon);
  }
}

TYPED_TEST(WeightedProjection, ZeroLengthJointBringsEndsToTheMassWeightedPoint) {
  // The thesis's code: both ends go to (m1·p1 + m2·p2)/(m1 + m2).
  Pair<TypeParam> pair(3, 1, {0, 0, 0}, {0.4, 0.2, 0}, 0.0);
  pair.project(RelaxationRule::weighted);
  const Eigen::Vector3d expected = (3 * Eigen::Vector3d(0, 0, 0) + 1 * Eigen::Vector3d(0.4, 0.2, 0)) / 4;
  EXPECT_LT((pair.x(0) - expected).norm(), this->kEpsilon);
  EXPECT_LT((pair.x(1) - expected).norm(), this->kEpsilon);
}

TYPED_TEST(WeightedProjection, EqualMassesGiveTheMidpointRuleBitForBit) {
  Pair<TypeParam> weighted(2.5, 2.5, {0.1, 0.2, 0.3}, {1.7, -0.4, 0.9}, 0.8);
  Pair<TypeParam> unweighted = weighted;
  weighted.project(RelaxationRule::weighted);
  unweighted.project(RelaxationRule::unweighted);
  EXPECT_EQ(weighted.x(0), unweighted.x(0));
  EXPECT_EQ(weighted.x(1), unweighted.x(1));
}

}  // namespace
}  // namespace limber
