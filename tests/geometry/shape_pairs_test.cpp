// The shape-pair table (kernel/geometry/shape_pairs.hpp): every pair answered, mirrored pairs
// the same manifold with the normal turned, ellipsoids against planes and box faces at their
// closed-form depths, and two capsules refused (the collision world's own pair).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "limber/kernel/geometry/shape_pairs.hpp"
#include "tests/support/random_poses.hpp"

namespace limber {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

// How far below its centre an ellipsoid reaches along −n: √(nᵀ R A² Rᵀ n) (its support function).
double ellipsoid_reach(const Ellipsoid& ellipsoid, const Vector3d& n) {
  const Matrix3d shape = ellipsoid.rotation * ellipsoid.semi_axes.cwiseAbs2().asDiagonal() * ellipsoid.rotation.transpose();
  return std::sqrt(n.dot(shape * n));
}

TEST(ShapePairs, AnEllipsoidMeetsAPlaneAtItsSupportPointExactly) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> uniform(-1, 1);
  for (int trial = 0; trial < 200; ++trial) {
    const Ellipsoid egg{Vector3d(uniform(random), uniform(random), 0.2 + 0.05 * uniform(random)), Vector3d(0.15, 0.1, 0.07),
                        limber::testing::random_rotation(random)};
    const Plane floor{Vector3d::UnitZ(), 0.05 * uniform(random)};
    const Manifold manifold = collide(egg, floor, 0.5);
    ASSERT_EQ(manifold.count, 1);
    const double exact = egg.centre.z() - ellipsoid_reach(egg, Vector3d::UnitZ()) - floor.offset;
    EXPECT_NEAR(manifold.points[0].separation, exact, 1e-12) << "trial " << trial;
    EXPECT_NEAR(manifold.points[0].point.z(), floor.offset + 0.5 * exact, 1e-12) << "midway between the surfaces";
  }
}

TEST(ShapePairs, AnEllipsoidOverABoxFaceIsAtItsClosedFormDepthByGjkAndEpa) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> uniform(-1, 1);
  const Obb table{Vector3d(0, 0, -0.5), Vector3d(2, 2, 0.5), Matrix3d::Identity()};  // top face at z = 0
  for (int trial = 0; trial < 100; ++trial) {
    Ellipsoid egg{Vector3d::Zero(), Vector3d(0.15, 0.1, 0.07), limber::testing::random_rotation(random)};
    const double exact = 0.01 * uniform(random);  // from 1 cm deep to a 1 cm gap
    egg.centre = Vector3d(0.5 * uniform(random), 0.5 * uniform(random), ellipsoid_reach(egg, Vector3d::UnitZ()) + exact);
    const Manifold manifold = collide(egg, table, 0.02);
    ASSERT_EQ(manifold.count, 1) << "trial " << trial;
    // EPA on a curved pair: within 9 µm and 2° (convex_pairs.hpp).
    EXPECT_NEAR(manifold.points[0].separation, exact, 1e-5) << "trial " << trial;
    EXPECT_GT(manifold.normal.z(), std::cos(2.5 * M_PI / 180)) << "trial " << trial;
  }
}

TEST(ShapePairs, SwappedPairsGiveTheSameManifoldWithTheNormalTurned) {
  std::mt19937 random(3);
  std::uniform_real_distribution<double> uniform(-1, 1);
  int compared = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Obb box{Vector3d::Zero(), Vector3d(0.2, 0.1, 0.05), limber::testing::random_rotation(random)};
    const Vector3d c(0.2 * uniform(random), 0.2 * uniform(random), 0.2 * uniform(random));
    const Vector3d d = 0.1 * Vector3d(uniform(random), uniform(random), uniform(random));
    const Capsule capsule{c - d, c + d, 0.05};
    const Manifold forward = collide(capsule, box, 0.01), backward = collide(box, capsule, 0.01);
    ASSERT_EQ(forward.count, backward.count) << "trial " << trial;
    if (forward.count == 0) continue;
    ++compared;
    EXPECT_TRUE(forward.normal.isApprox(-backward.normal, 1e-12)) << "trial " << trial;
    for (int k = 0; k < forward.count; ++k) {
      EXPECT_TRUE(forward.points[k].point.isApprox(backward.points[k].point, 1e-12)) << "trial " << trial;
      EXPECT_EQ(forward.points[k].separation, backward.points[k].separation);
      EXPECT_EQ(forward.points[k].id, backward.points[k].id);
    }
    // Through GJK/EPA both ways: the same depth and opposite normals, to EPA's accuracy.
    const Ellipsoid egg{c, Vector3d(0.1, 0.06, 0.04), limber::testing::random_rotation(random)};
    const Manifold there = collide(egg, box, 0.01), back = collide(box, egg, 0.01);
    if (there.count == 0 || back.count == 0) continue;
    EXPECT_NEAR(there.points[0].separation, back.points[0].separation, 2e-5) << "trial " << trial;
    EXPECT_GT(there.normal.dot(-back.normal), std::cos(3 * M_PI / 180)) << "trial " << trial;
  }
  EXPECT_GT(compared, 50) << "enough pairs touched to compare";
}

TEST(ShapePairs, AnEllipsoidAgainstAWallsCapsuleTouchesAtItsOwnDeepestPoint) {
  // A wall as MuJoCo's humanoid100 has one: a capsule of radius 0.4 m along x, 6 m long; the
  // contact must be where the ellipsoid is, not anywhere along the capsule's side (EPA's point).
  std::mt19937 random(5);
  std::uniform_real_distribution<double> uniform(-1, 1);
  const Capsule wall{Vector3d(-3, 3, 0), Vector3d(3, 3, 0), 0.4};
  for (int trial = 0; trial < 50; ++trial) {
    const Ellipsoid egg{Vector3d(2 * uniform(random), 2.5 + 0.02 * uniform(random), 0.1), Vector3d(0.15, 0.1, 0.07),
                        limber::testing::random_rotation(random)};
    const Manifold manifold = collide(egg, wall, 0.05);
    if (manifold.count == 0) continue;
    const Vector3d deepest = support(egg, -manifold.normal);
    EXPECT_LT((manifold.points[0].point - (deepest - 0.5 * manifold.points[0].separation * manifold.normal)).norm(), 1e-12) << "trial " << trial;
    EXPECT_NEAR(manifold.points[0].point.x(), egg.centre.x(), 0.15) << "trial " << trial << ": beside the ellipsoid, m";
  }
}

TEST(ShapePairs, TwoCapsulesAreTheCollisionWorldsPair) {
  const Capsule a{Vector3d::Zero(), Vector3d::UnitX(), 0.1}, b{Vector3d(0, 0, 0.1), Vector3d(1, 0, 0.1), 0.1};
  EXPECT_THROW(collide(a, b, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace limber
