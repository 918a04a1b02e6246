// Contact manifolds (kernel/geometry/manifolds.hpp): where the points lie, how deep, and that the
// normal and depth are the ones that separate the shapes.
#include "limber/kernel/geometry/manifolds.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include <Eigen/Geometry>

#include "limber/kernel/geometry/golden_section.hpp"
#include "limber/kernel/geometry/separating_axis.hpp"
#include "tests/support/random_poses.hpp"

namespace limber {
namespace {

using Eigen::AngleAxisd;
using Eigen::Matrix3d;
using Eigen::Vector3d;
using testing::random_rotation;

constexpr double kTolerance = 1e-9;  // m

Obb box(const Vector3d& centre, const Vector3d& half, const Matrix3d& rotation = Matrix3d::Identity()) { return {centre, half, rotation}; }

double distance_to(const Obb& b, const Vector3d& p) { return (p - closest_point_on_obb(b, p)).norm(); }

// The two surface points of a manifold point: the first shape's and the second's.
Vector3d on_first(const Manifold& m, int i) {
  return m.points[static_cast<std::size_t>(i)].point + 0.5 * m.points[static_cast<std::size_t>(i)].separation * m.normal;
}
Vector3d on_second(const Manifold& m, int i) {
  return m.points[static_cast<std::size_t>(i)].point - 0.5 * m.points[static_cast<std::size_t>(i)].separation * m.normal;
}

double deepest(const Manifold& m) {
  double least = 1e300;
  for (int i = 0; i < m.count; ++i) least = std::min(least, m.points[static_cast<std::size_t>(i)].separation);
  return least;
}

std::set<std::uint32_t> ids(const Manifold& m) {
  std::set<std::uint32_t> result;
  for (int i = 0; i < m.count; ++i) result.insert(m.points[static_cast<std::size_t>(i)].id);
  return result;
}

// The distance from the segment a–b to the solid box, by golden-section search on the parameter
// (the distance to a convex set is convex along a line): a check, not the method.
double search_distance(const Vector3d& a, const Vector3d& b, const Obb& o) {
  const auto at = [&](double s) { return distance_to(o, a + s * (b - a)); };
  const GoldenBracket found = golden_section(at, 0.0, 1.0, 150, [](double, double) { return false; });
  return at(0.5 * (found.low + found.high));
}

TEST(BoxPlaneManifold, ABoxOnItsFaceTouchesAtTheFacesFourCorners) {
  const Plane ground{Vector3d::UnitZ(), 0, 0, 0};
  const Obb resting = box(Vector3d(0.3, -0.2, 0.099), Vector3d(0.2, 0.15, 0.1), Matrix3d(AngleAxisd(0.4, Vector3d::UnitZ())));
  const Manifold m = box_plane_manifold(resting, ground, 0.005);
  ASSERT_EQ(m.count, 4);
  EXPECT_EQ(m.normal, Vector3d::UnitZ());
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(m.points[static_cast<std::size_t>(i)].separation, -0.001, kTolerance);
    EXPECT_NEAR(on_second(m, i).z(), 0, kTolerance);                  // on the ground
    EXPECT_NEAR((on_first(m, i) - resting.centre).norm(), std::hypot(0.2, 0.15, 0.1), kTolerance);  // a corner
  }
  EXPECT_EQ(ids(m).size(), 4U);
}

TEST(BoxPlaneManifold, ABoxOnItsEdgeTouchesAtTheEdgesEndsAndALiftedOneNowhere) {
  const Plane ground{Vector3d::UnitZ(), 0, 0, 0};
  const double half_diagonal = 0.1 * std::sqrt(2.0);
  const Matrix3d on_edge(AngleAxisd(M_PI / 4, Vector3d::UnitX()));
  const Manifold m = box_plane_manifold(box(Vector3d(0, 0, half_diagonal - 0.002), Vector3d(0.3, 0.1, 0.1), on_edge), ground, 0.005);
  ASSERT_EQ(m.count, 2);
  EXPECT_NEAR(m.points[0].separation, -0.002, kTolerance);
  EXPECT_NEAR(m.points[1].separation, -0.002, kTolerance);
  EXPECT_NEAR(std::abs(m.points[0].point.x() - m.points[1].point.x()), 0.6, kTolerance);  // the edge's two ends
  EXPECT_EQ(box_plane_manifold(box(Vector3d(0, 0, half_diagonal + 0.006), Vector3d(0.3, 0.1, 0.1), on_edge), ground, 0.005).count, 0);
  const Manifold gap = box_plane_manifold(box(Vector3d(0, 0, half_diagonal + 0.004), Vector3d(0.3, 0.1, 0.1), on_edge), ground, 0.005);
  ASSERT_EQ(gap.count, 2);
  EXPECT_NEAR(gap.points[0].separation, 0.004, kTolerance);  // a speculative gap
}

TEST(BoxBoxManifold, ASmallBoxOnALargeOnesFaceTouchesAtItsFourLowerCorners) {
  const Obb table = box(Vector3d::Zero(), Vector3d(1, 1, 0.1));
  const Obb crate = box(Vector3d(0.2, 0.1, 0.1 + 0.05 - 0.001), Vector3d(0.1, 0.07, 0.05), Matrix3d(AngleAxisd(0.5, Vector3d::UnitZ())));
  const Manifold m = box_box_manifold(crate, table, 0.005);
  ASSERT_EQ(m.count, 4);
  EXPECT_NEAR((m.normal - Vector3d::UnitZ()).norm(), 0, 1e-12);  // from the table to the crate
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(m.points[static_cast<std::size_t>(i)].separation, -0.001, kTolerance);
    EXPECT_NEAR(on_second(m, i).z(), 0.1, kTolerance);  // the table's top
    EXPECT_NEAR((on_first(m, i) - crate.centre).norm(), std::hypot(0.1, 0.07, 0.05), kTolerance);  // a crate's corner
  }
  EXPECT_EQ(ids(m).size(), 4U);
  // The same features a little further on: the same ids, so a solver matches its warm start.
  Obb moved = crate;
  moved.centre += Vector3d(0.003, -0.002, 0.0004);
  EXPECT_EQ(ids(box_box_manifold(moved, table, 0.005)), ids(m));
}

TEST(BoxBoxManifold, ABoxOverhangingAnEdgeTouchesOnlyWhereTheFacesOverlap) {
  const Obb table = box(Vector3d::Zero(), Vector3d(0.5, 0.5, 0.1));
  const Obb crate = box(Vector3d(0.5, 0.0, 0.1 + 0.05 - 0.001), Vector3d(0.2, 0.2, 0.05), Matrix3d(AngleAxisd(0.3, Vector3d::UnitZ())));
  const Manifold m = box_box_manifold(crate, table, 0.005);
  ASSERT_GE(m.count, 3);
  for (int i = 0; i < m.count; ++i) {
    EXPECT_LE(on_second(m, i).x(), 0.5 + kTolerance);  // over the table, not the air beyond its edge
    EXPECT_LE(distance_to(crate, on_first(m, i)), kTolerance);
    EXPECT_LE(distance_to(table, on_second(m, i)), kTolerance);
  }
}

// Random pairs, overlapping or within the margin: every point's two surface points lie on their
// boxes, and moving the first box along the normal by the deepest point's depth separates them
// — by no less: the depth is the least move along the normal that does.
TEST(BoxBoxManifold, RandomPairsTouchOnBothBoxesAndTheDepthIsWhatSeparatesThem) {
  std::mt19937 random(7);
  std::uniform_real_distribution<double> size(0.02, 0.3), place(-0.25, 0.25);
  int touching = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Obb a = box(Vector3d(place(random), place(random), place(random)), Vector3d(size(random), size(random), size(random)), random_rotation(random));
    const Obb b = box(Vector3d::Zero(), Vector3d(size(random), size(random), size(random)), random_rotation(random));
    const Manifold m = box_box_manifold(a, b, 0.01);
    const SeparatingAxisResult sat = separating_axis_test(a, b, true, 0.01);
    ASSERT_EQ(m.count > 0, sat.overlap) << trial;
    if (m.count == 0) continue;
    ++touching;
    EXPECT_EQ(ids(m).size(), static_cast<std::size_t>(m.count)) << trial;
    for (int i = 0; i < m.count; ++i) {
      EXPECT_LE(distance_to(a, on_first(m, i)), 1e-8) << trial;
      EXPECT_LE(distance_to(b, on_second(m, i)), 1e-8) << trial;
    }
    // Never deeper than the projections' overlap on the normal; shallower where the incident
    // box's deepest corner hangs beyond the reference face and slides off it as the box moves out.
    EXPECT_GE(deepest(m), -sat.depth - 1e-9) << trial;
    if (deepest(m) >= 0) continue;
    Obb moved = a;
    moved.centre = a.centre + (-deepest(m) + 1e-7) * m.normal;
    EXPECT_FALSE(overlaps(moved, b)) << trial;
    moved.centre = a.centre + (-deepest(m) - 1e-7) * m.normal;
    EXPECT_TRUE(overlaps(moved, b)) << trial;
  }
  EXPECT_GT(touching, 500);  // the draw reaches both kinds
}

TEST(CapsuleBoxManifold, ACapsuleLyingOnABoxTouchesAtBothEndsOfWhatIsOverIt) {
  const Obb crate = box(Vector3d::Zero(), Vector3d(0.2, 0.2, 0.1));
  const Capsule lying{Vector3d(-0.1, 0.05, 0.1 + 0.03 - 0.001), Vector3d(0.4, 0.07, 0.1 + 0.03 - 0.001), 0.03};
  const Manifold m = capsule_box_manifold(lying, crate, 0.005);
  ASSERT_EQ(m.count, 2);
  EXPECT_NEAR((m.normal - Vector3d::UnitZ()).norm(), 0, 1e-12);
  const double left = std::min(on_second(m, 0).x(), on_second(m, 1).x()), right = std::max(on_second(m, 0).x(), on_second(m, 1).x());
  EXPECT_NEAR(left, -0.1, kTolerance);  // the capsule's end
  EXPECT_NEAR(right, 0.2, kTolerance);  // the crate's edge: beyond it the capsule is over nothing
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(m.points[static_cast<std::size_t>(i)].separation, -0.001, kTolerance);
  // Standing on its end, one point, a gap within the margin.
  const Manifold standing = capsule_box_manifold({Vector3d(0, 0, 0.134), Vector3d(0, 0, 0.5), 0.03}, crate, 0.005);
  ASSERT_EQ(standing.count, 1);
  EXPECT_NEAR(standing.points[0].separation, 0.004, kTolerance);
}

// Random capsules near a box: the surface points lie on both shapes, the separation of a capsule
// apart from the box is the exact distance less the radius, and moving an overlapping capsule by
// its depth along the normal leaves its core at least its radius from the box.
TEST(CapsuleBoxManifold, RandomCapsulesTouchOnBothShapesAtTheirExactDistance) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> size(0.03, 0.3), place(-0.35, 0.35), radius(0.005, 0.08);
  int apart = 0, overlapping = 0;
  for (int trial = 0; trial < 1000; ++trial) {
    const Obb b = box(Vector3d::Zero(), Vector3d(size(random), size(random), size(random)), random_rotation(random));
    const Vector3d a0(place(random), place(random), place(random)), a1(place(random), place(random), place(random));
    const Capsule c{a0, a1, radius(random)};
    const Manifold m = capsule_box_manifold(c, b, 0.02);
    const double distance = search_distance(a0, a1, b);
    if (distance - c.radius > 0.02 + 1e-6) {
      EXPECT_EQ(m.count, 0) << trial;
      continue;
    }
    if (distance - c.radius < 0.02 - 1e-6) ASSERT_GT(m.count, 0) << trial;
    if (m.count == 0) continue;
    // The capsule's surface points are on it; apart, the box's are on the box (overlapping, a
    // point's foot along the normal may fall beside the box: the depth is what the test asserts).
    for (int i = 0; i < m.count; ++i) {
      const Vector3d core = on_first(m, i) + c.radius * m.normal;  // back on the core
      EXPECT_LE(closest_points_between_segments(core, core, a0, a1).distance, 1e-8) << trial;
      if (distance > 1e-9) EXPECT_LE(distance_to(b, on_second(m, i)), 1e-8) << trial;
    }
    if (distance > 1e-9) {
      ++apart;
      EXPECT_NEAR(deepest(m), distance - c.radius, 1e-9) << trial;
    } else {
      ++overlapping;
      const Vector3d shift = (-deepest(m) + 1e-9) * m.normal;
      EXPECT_GE(search_distance(a0 + shift, a1 + shift, b), c.radius - 1e-6) << trial;
    }
  }
  EXPECT_GT(apart, 50);
  EXPECT_GT(overlapping, 50);
}

TEST(CapsuleBoxManifold, ASphereIsACapsuleWhoseEndsCoincide) {
  const Obb crate = box(Vector3d::Zero(), Vector3d(0.2, 0.2, 0.1), Matrix3d(AngleAxisd(0.3, Vector3d::UnitY())));
  const Vector3d centre = crate.centre + crate.rotation * Vector3d(0.05, -0.1, 0.1 + 0.04);  // 1 cm into the top face
  const Manifold m = capsule_box_manifold({centre, centre, 0.05}, crate, 0.005);
  ASSERT_EQ(m.count, 1);
  EXPECT_NEAR(m.points[0].separation, -0.01, kTolerance);
  EXPECT_NEAR((m.normal - crate.rotation.col(2)).norm(), 0, 1e-12);
}

}  // namespace
}  // namespace limber
