// General convex pairs through libccd (kernel/geometry/convex_pairs.hpp), against depths known
// in closed form: boxes' least overlap over the separating axes, and curved shapes on a flat box.
#include "limber/kernel/geometry/convex_pairs.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "limber/kernel/geometry/separating_axis.hpp"
#include "tests/support/random_poses.hpp"

namespace limber {
namespace {

using Eigen::AngleAxisd;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using testing::random_rotation;

// EPA on a curved shape converges to a polytope inside it: µm, not round-off (convex_pairs.hpp).
constexpr double kCurvedTolerance = 1e-5;  // m
constexpr double kFlatTolerance = 1e-9;    // m, polyhedra: exact but for round-off

// Two boxes' least penetration depth: the least overlap of their projections over the 15 axes
// (3 + 3 faces, 9 edge crosses) — the separating-axis test's depth without its preference for
// faces, which may report up to 1/0.95 of it.
double least_box_depth(const Obb& a, const Obb& b) {
  std::vector<Vector3d> axes;
  for (int i = 0; i < 3; ++i) axes.push_back(a.rotation.col(i)), axes.push_back(b.rotation.col(i));
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const Vector3d cross = a.rotation.col(i).cross(b.rotation.col(j));
      if (cross.norm() > 1e-6) axes.push_back(cross.normalized());
    }
  }
  double least = 1e300;
  for (const Vector3d& axis : axes) {
    const double reach = (a.rotation.transpose() * axis).cwiseAbs().dot(a.half_extents) + (b.rotation.transpose() * axis).cwiseAbs().dot(b.half_extents);
    least = std::min(least, reach - std::abs(axis.dot(b.centre - a.centre)));
  }
  return least;
}

// A floor: a large flat box whose top face is z = 0.
const Obb kFloor{Vector3d(0, 0, -0.5), Vector3d(5, 5, 0.5), Matrix3d::Identity()};

TEST(ConvexPairs, SupportFunctionsReachTheShapesFarthestPoints) {
  const Matrix3d turn(AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()));
  const Ellipsoid ellipsoid{Vector3d(1, 2, 3), Vector3d(0.3, 0.2, 0.1), turn};
  const Cylinder cylinder{Vector3d(-1, 0, 0), 0.05, 0.2, turn};
  std::mt19937 random(3);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 200; ++trial) {
    const Vector3d d = Vector3d(normal(random), normal(random), normal(random)).normalized();
    // h(d) = max over the shape of d·x, by its own closed form.
    const Vector3d a_d = ellipsoid.semi_axes.cwiseProduct(turn.transpose() * d);
    EXPECT_NEAR(d.dot(support(ellipsoid, d) - ellipsoid.centre), a_d.norm(), 1e-12);
    const Vector3d local = turn.transpose() * d;
    EXPECT_NEAR(d.dot(support(cylinder, d) - cylinder.centre), 0.05 * std::hypot(local.x(), local.y()) + 0.2 * std::abs(local.z()), 1e-12);
    // On the shape's surface.
    const Vector3d on = turn.transpose() * (support(ellipsoid, d) - ellipsoid.centre);
    EXPECT_NEAR(on.cwiseQuotient(ellipsoid.semi_axes).norm(), 1, 1e-12);
  }
}

TEST(ConvexPairs, TwoBoxesDepthIsTheirLeastOverlapAndAGapWithinTheMarginIsTheGap) {
  std::mt19937 random(5);
  std::uniform_real_distribution<double> size(0.03, 0.2), place(-0.2, 0.2);
  int overlapping = 0;
  for (int trial = 0; trial < 500; ++trial) {
    const Obb a{Vector3d(place(random), place(random), place(random)), Vector3d(size(random), size(random), size(random)), random_rotation(random)};
    const Obb b{Vector3d::Zero(), Vector3d(size(random), size(random), size(random)), random_rotation(random)};
    const SeparatingAxisResult exact = separating_axis_test(a, b, true);
    const Manifold m = convex_manifold(a, b, 0.0);
    ASSERT_EQ(m.count > 0, exact.overlap) << trial;
    if (m.count == 0) continue;
    ++overlapping;
    // The least translation that separates them: the boxes' exact depth.
    EXPECT_NEAR(-m.points[0].separation, least_box_depth(a, b), kFlatTolerance) << trial;
    // Moving the first out along the normal by the depth separates them.
    Obb moved = a;
    moved.centre += (-m.points[0].separation + 1e-7) * m.normal;
    EXPECT_FALSE(overlaps(moved, b)) << trial;
  }
  // Apart by a gap within the margin: the gap, as a positive separation.
  for (int trial = 0; trial < 100; ++trial) {
    const Obb resting{Vector3d(0, 0, 0.1), Vector3d(0.1, 0.1, 0.1), Matrix3d(AngleAxisd(0.1 * trial, Vector3d::UnitZ()))};
    const double gap = 0.001 + 0.0002 * trial / 10.0;
    Obb lifted = resting;
    lifted.centre.z() += gap;
    const Manifold m = convex_manifold(lifted, kFloor, 0.01);
    ASSERT_EQ(m.count, 1);
    EXPECT_NEAR(m.points[0].separation, gap, kCurvedTolerance);  // grown by the margin, the boxes are rounded: curved
    EXPECT_NEAR((m.normal - Vector3d::UnitZ()).norm(), 0, 1e-6);
  }
  EXPECT_GT(overlapping, 100);
}

// Curved shapes pressed into a floor at random orientations: the depth is the shape's reach
// below its centre, h(−z), less the centre's height; the normal is up.
TEST(ConvexPairs, CurvedShapesOnAFloorSinkByTheirReachBelowTheirCentre) {
  std::mt19937 random(9);
  std::uniform_real_distribution<double> size(0.02, 0.2), sink(0.0005, 0.01);
  for (int trial = 0; trial < 100; ++trial) {
    const Matrix3d turn = random_rotation(random);
    const double depth = sink(random);
    Ellipsoid ellipsoid{Vector3d::Zero(), Vector3d(size(random), size(random), size(random)), turn};
    ellipsoid.centre.z() = ellipsoid.semi_axes.cwiseProduct(turn.transpose() * Vector3d::UnitZ()).norm() - depth;
    Cylinder cylinder{Vector3d::Zero(), size(random), size(random), turn};
    const Vector3d axis = turn.transpose() * Vector3d::UnitZ();
    cylinder.centre.z() = cylinder.radius * std::hypot(axis.x(), axis.y()) + cylinder.half_length * std::abs(axis.z()) - depth;
    for (const Manifold& m : {convex_manifold(ellipsoid, kFloor, 0.005), convex_manifold(cylinder, kFloor, 0.005)}) {
      ASSERT_EQ(m.count, 1) << trial;
      EXPECT_NEAR(m.points[0].separation, -depth, kCurvedTolerance) << trial;
      EXPECT_NEAR((m.normal - Vector3d::UnitZ()).norm(), 0, 1e-3) << trial;
    }
  }
}

// A hull of a box's eight corners is the box: the same depth against another box, to round-off.
TEST(ConvexPairs, AHullOfABoxsCornersCollidesAsTheBox) {
  const Vector3d half(0.1, 0.06, 0.03);
  std::vector<Vector3d> corners;
  for (int k = 0; k < 8; ++k) corners.emplace_back((k & 1) ? half.x() : -half.x(), (k & 2) ? half.y() : -half.y(), (k & 4) ? half.z() : -half.z());
  std::mt19937 random(17);
  std::uniform_real_distribution<double> place(-0.12, 0.12);
  int touching = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Matrix3d turn = random_rotation(random);
    const Vector3d centre(place(random), place(random), place(random));
    const Obb other{Vector3d::Zero(), Vector3d(0.08, 0.05, 0.04), random_rotation(random)};
    const Manifold as_hull = convex_manifold(ConvexHull{centre, turn, corners}, other, 0.0);
    const SeparatingAxisResult exact = separating_axis_test(Obb{centre, half, turn}, other, true);
    ASSERT_EQ(as_hull.count > 0, exact.overlap) << trial;
    if (as_hull.count == 0) continue;
    ++touching;
    EXPECT_NEAR(-as_hull.points[0].separation, least_box_depth(Obb{centre, half, turn}, other), kFlatTolerance) << trial;
  }
  EXPECT_GT(touching, 50);
}

}  // namespace
}  // namespace limber
