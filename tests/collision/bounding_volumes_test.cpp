// Bounding volumes, overlap tests, contacts and the hierarchical test, each against a closed
// form or an independent brute-force reference (sweep and prune: tests/geometry).
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/geometry/bounding_volumes.hpp"

namespace limber {
namespace {

using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector3d;

Quaterniond random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  return Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng)).normalized();
}

Vector3d random_vector(std::mt19937& rng, double low, double high) {
  std::uniform_real_distribution<double> uniform(low, high);
  return Vector3d(uniform(rng), uniform(rng), uniform(rng));
}

Obb random_box(std::mt19937& rng, double spread) {
  return Obb{random_vector(rng, -spread, spread), random_vector(rng, 0.1, 1.0),
             random_rotation(rng).toRotationMatrix()};
}

Obb grown(Obb box, double margin) {
  box.half_extents.array() += margin;
  return box;
}

// ---- A reference for box overlap that shares nothing with the separating-axis test ----
// Two convex polyhedra meet iff their intersection has a vertex, and each vertex of the
// intersection is a vertex of one inside the other or an edge of one crossing a face of the
// other; either way an edge of one meets the other solid. Edges are clipped by slabs.

bool segment_meets_box(const Vector3d& from, const Vector3d& to, const Obb& box) {
  const Vector3d start = box.rotation.transpose() * (from - box.centre);
  const Vector3d direction = box.rotation.transpose() * (to - from);
  double low = 0, high = 1;
  for (int k = 0; k < 3; ++k) {
    const double h = box.half_extents[k];
    if (direction[k] == 0) {
      if (std::abs(start[k]) > h) return false;
      continue;
    }
    double enter = (-h - start[k]) / direction[k], leave = (h - start[k]) / direction[k];
    if (enter > leave) std::swap(enter, leave);
    low = std::max(low, enter);
    high = std::min(high, leave);
    if (low > high) return false;
  }
  return true;
}

Vector3d corner(const Obb& box, int bits) {
  const Vector3d signs((bits & 1) ? 1 : -1, (bits & 2) ? 1 : -1, (bits & 4) ? 1 : -1);
  return box.centre + box.rotation * signs.cwiseProduct(box.half_extents);
}

bool an_edge_meets(const Obb& box, const Obb& other) {
  for (int bits = 0; bits < 8; ++bits) {
    for (int axis = 0; axis < 3; ++axis) {
      const int neighbour = bits | (1 << axis);
      if (neighbour != bits && segment_meets_box(corner(box, bits), corner(box, neighbour), other)) return true;
    }
  }
  return false;
}

bool reference_boxes_overlap(const Obb& first, const Obb& second) {
  return an_edge_meets(first, second) || an_edge_meets(second, first);
}

// Overlap of the boxes' projections on the unit `axis`.
double projection_overlap(const Obb& first, const Obb& second, const Vector3d& axis) {
  const double first_radius = (first.rotation.transpose() * axis).cwiseAbs().dot(first.half_extents);
  const double second_radius = (second.rotation.transpose() * axis).cwiseAbs().dot(second.half_extents);
  return first_radius + second_radius - std::abs((second.centre - first.centre).dot(axis));
}

// Compares the separating-axis test with the reference on pairs made by `make_pair`; pairs
// within `margin` of touching (the reference disagrees with itself on grown and shrunk boxes)
// are skipped. Returns {overlapping, separated} counts.
template <typename MakePair>
std::pair<int, int> compare_with_reference(int pairs, MakePair make_pair) {
  constexpr double margin = 1e-6;
  int overlapping = 0, separated = 0;
  for (int i = 0; i < pairs; ++i) {
    const auto [first, second] = make_pair();
    const bool clearly_overlap = reference_boxes_overlap(grown(first, -margin), grown(second, -margin));
    const bool clearly_apart = !reference_boxes_overlap(grown(first, margin), grown(second, margin));
    if (clearly_overlap == clearly_apart) continue;  // within the margin of touching
    EXPECT_EQ(overlaps(first, second), clearly_overlap) << "pair " << i;
    EXPECT_EQ(contact(first, second).has_value(), clearly_overlap) << "pair " << i;
    (clearly_overlap ? overlapping : separated) += 1;
  }
  return {overlapping, separated};
}

TEST(SeparatingAxisTest, AgreesWithEdgeAgainstSolidReferenceOnRandomBoxes) {
  std::mt19937 rng(1);
  const auto [overlapping, separated] =
      compare_with_reference(3000, [&] { return std::pair{random_box(rng, 1.2), random_box(rng, 1.2)}; });
  // Both answers must be exercised for the agreement to mean anything.
  EXPECT_GT(overlapping, 600);
  EXPECT_GT(separated, 600);
}

TEST(SeparatingAxisTest, AgreesWithReferenceWhenEdgesAreParallelOrNearlySo) {
  // Equal rotations make every edge of one parallel to three of the other (the cross products
  // vanish); rotations 1e-9 rad apart make them nearly so.
  std::mt19937 rng(2);
  std::normal_distribution<double> normal;
  int case_index = 0;
  const auto [overlapping, separated] = compare_with_reference(2000, [&] {
    Obb first = random_box(rng, 1.2), second = random_box(rng, 1.2);
    const double angle = (case_index++ % 2 == 0) ? 0.0 : 1e-9;
    const Vector3d axis = Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
    second.rotation = Eigen::AngleAxisd(angle, axis).toRotationMatrix() * first.rotation;
    return std::pair{first, second};
  });
  EXPECT_GT(overlapping, 400);
  EXPECT_GT(separated, 400);
}

TEST(SeparatingAxisTest, RoundingInParallelEdgeAxesNeverSeparatesBoxesAtRightAngles) {
  // The second box is the first turned by 90° or 180° about one of its axes, through a quaternion
  // product: their edges are parallel, and R = AᵀB is a signed permutation plus rounding noise
  // (~1e-16) in the zeros. Every edge–edge axis then has |L| ~ 1e-16 and its test compares noise
  // with noise — without Ericson's ε about a sixth of the overlapping pairs were reported apart. The face
  // axes decide such boxes, so each pair is made to overlap, or not, by 1 mm on them.
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> size(0.05, 2.0), fraction(-1, 1);
  for (int i = 0; i < 4000; ++i) {
    const Quaterniond turn(normal(rng), normal(rng), normal(rng), normal(rng));
    const Quaterniond first_rotation = turn.normalized();
    const double angle = i % 2 ? std::numbers::pi / 2 : std::numbers::pi;
    const Quaterniond second_rotation = first_rotation * Quaterniond(Eigen::AngleAxisd(angle, Vector3d::Unit(i % 3)));
    Obb first{Vector3d::Zero(), Vector3d(size(rng), size(rng), size(rng)), first_rotation.toRotationMatrix()};
    Obb second{Vector3d::Zero(), Vector3d(size(rng), size(rng), size(rng)), second_rotation.toRotationMatrix()};
    // Reach of both boxes along the first's axes; the second's centre lies 1 mm inside it on
    // every axis, or (for odd i / 2) 1 mm outside it on one.
    const Vector3d reach =
        first.half_extents + (first.rotation.transpose() * second.rotation).cwiseAbs() * second.half_extents;
    Vector3d offset;
    for (int k = 0; k < 3; ++k) offset[k] = fraction(rng) * (reach[k] - 1e-3);
    const bool apart = (i / 2) % 2 == 1;
    if (apart) offset[i % 3] = (fraction(rng) < 0 ? -1 : 1) * (reach[i % 3] + 1e-3);
    second.centre = first.rotation * offset;
    EXPECT_EQ(overlaps(first, second), !apart) << "pair " << i;
  }
}

// Two cubes of half-size 1 tilted 45° about y and about x: the first's top edge (along y, at
// z = √2) runs square below the second's bottom edge (along x, at z = height − √2). Only their
// cross product, z, separates them for heights between 2√2 ≈ 2.83 and 2√2 + 1 ≈ 3.83, where the
// face normals (projection radii 1 and 1 + 1/√2, centres height/√2 apart) separate them too.
std::pair<Obb, Obb> crossed_edges(double height) {
  Obb first{Vector3d::Zero(), Vector3d::Ones(),
            Eigen::AngleAxisd(std::numbers::pi / 4, Vector3d::UnitY()).toRotationMatrix()};
  Obb second{Vector3d(0, 0, height), Vector3d::Ones(),
             Eigen::AngleAxisd(std::numbers::pi / 4, Vector3d::UnitX()).toRotationMatrix()};
  return {first, second};
}

TEST(SeparatingAxisTest, CrossedEdgesAreSeparatedOnlyByTheirCrossProduct) {
  const double edge_gap_height = 2 * std::numbers::sqrt2;
  const auto [first_apart, second_apart] = crossed_edges(3.0);
  EXPECT_GT(projection_overlap(first_apart, second_apart, first_apart.rotation.col(0)), 0);  // faces overlap
  EXPECT_GT(projection_overlap(first_apart, second_apart, second_apart.rotation.col(1)), 0);
  EXPECT_FALSE(overlaps(first_apart, second_apart));

  const double height = 2.7;
  const auto [first, second] = crossed_edges(height);
  ASSERT_TRUE(overlaps(first, second));
  const auto hit = contact(first, second);
  ASSERT_TRUE(hit.has_value());
  // The first is below: the normal points down, from the second to the first.
  EXPECT_NEAR((hit->normal - Vector3d(0, 0, -1)).norm(), 0, 1e-12);
  EXPECT_NEAR(hit->depth, edge_gap_height - height, 1e-12);
  // The edges cross above the origin; the point is halfway between them.
  EXPECT_NEAR((hit->point - Vector3d(0, 0, 0.5 * height)).norm(), 0, 1e-12);
}

TEST(ObbContact, DepthIsTheOverlapOfABoxRestingOnABox) {
  // A small box (first) overlapping the top face of a larger one (second) by 0.1, offset along
  // x so that the faces share x ∈ [0.4, 1].
  const Obb first{Vector3d(0.9, 0, 1.4), Vector3d::Constant(0.5), Matrix3d::Identity()};
  const Obb second{Vector3d::Zero(), Vector3d::Ones(), Matrix3d::Identity()};
  const auto hit = contact(first, second);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR((hit->normal - Vector3d::UnitZ()).norm(), 0, 1e-15);
  EXPECT_NEAR(hit->depth, 0.1, 1e-15);
  EXPECT_NEAR(hit->point.z(), 0.95, 1e-15);  // middle of the overlap slab z ∈ [0.9, 1]
  EXPECT_GE(hit->point.x(), 0.4);
  EXPECT_LE(hit->point.x(), 1.0);
  EXPECT_NEAR(hit->point.y(), 0, 1e-15);

  // Swapping the boxes flips the normal only.
  const auto swapped = contact(second, first);
  ASSERT_TRUE(swapped.has_value());
  EXPECT_NEAR((swapped->normal + Vector3d::UnitZ()).norm(), 0, 1e-15);
  EXPECT_NEAR(swapped->depth, 0.1, 1e-15);
}

TEST(ObbContact, MovingTheFirstBoxByDepthAlongTheNormalSeparatesThem) {
  std::mt19937 rng(3);
  int tested = 0;
  for (int i = 0; i < 2000; ++i) {
    Obb first = random_box(rng, 0.8);
    const Obb second = random_box(rng, 0.8);
    const auto hit = contact(first, second);
    if (!hit) continue;
    ++tested;
    EXPECT_NEAR(hit->normal.norm(), 1, 1e-12);
    EXPECT_GE(hit->depth, 0);
    EXPECT_GE(hit->normal.dot(first.centre - second.centre), -1e-12);  // from second towards first
    // No face normal overlaps less than the reported depth (edge normals may, but only if chosen).
    for (int k = 0; k < 3; ++k) {
      EXPECT_LE(hit->depth, projection_overlap(first, second, first.rotation.col(k)) + 1e-12);
      EXPECT_LE(hit->depth, projection_overlap(first, second, second.rotation.col(k)) + 1e-12);
    }
    first.centre += (hit->depth + 1e-6) * hit->normal;
    EXPECT_FALSE(overlaps(first, second)) << "pair " << i;
  }
  EXPECT_GT(tested, 1000);
}

// ---- Segments and capsules ----

// The point of segment a–b nearest `point` (for the references only).
Vector3d nearest_on_segment(const Vector3d& point, const Vector3d& a, const Vector3d& b) {
  const Vector3d d = b - a;
  const double length_squared = d.squaredNorm();
  if (length_squared == 0) return a;
  return a + std::clamp((point - a).dot(d) / length_squared, 0.0, 1.0) * d;
}

// min over s of the distance from p(s) to the second segment: convex in s, found by ternary search.
double ternary_segment_distance(const Vector3d& p0, const Vector3d& p1, const Vector3d& q0, const Vector3d& q1) {
  const auto at = [&](double s) {
    const Vector3d p = p0 + s * (p1 - p0);
    return (p - nearest_on_segment(p, q0, q1)).norm();
  };
  double low = 0, high = 1;
  for (int i = 0; i < 200; ++i) {
    const double a = low + (high - low) / 3, b = high - (high - low) / 3;
    if (at(a) < at(b)) {
      high = b;
    } else {
      low = a;
    }
  }
  return at(0.5 * (low + high));
}

TEST(SegmentClosestPoints, DistanceIsTheMinimumOverDenseSamples) {
  std::mt19937 rng(4);
  constexpr int samples = 300;
  for (int pair = 0; pair < 40; ++pair) {
    const Vector3d p0 = random_vector(rng, -1, 1), p1 = random_vector(rng, -1, 1);
    const Vector3d q0 = random_vector(rng, -1, 1), q1 = random_vector(rng, -1, 1);
    const SegmentClosestPoints closest = closest_points_between_segments(p0, p1, q0, q1);
    double sampled = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= samples; ++i) {
      const Vector3d p = p0 + (double(i) / samples) * (p1 - p0);
      for (int j = 0; j <= samples; ++j) {
        sampled = std::min(sampled, (p - (q0 + (double(j) / samples) * (q1 - q0))).norm());
      }
    }
    // Samples overestimate the minimum by at most half a step along each segment.
    const double step_bound = ((p1 - p0).norm() + (q1 - q0).norm()) / (2.0 * samples);
    EXPECT_LE(closest.distance, sampled + 1e-12);
    EXPECT_GE(closest.distance, sampled - step_bound);
    EXPECT_NEAR(closest.distance, ternary_segment_distance(p0, p1, q0, q1), 1e-9);
    // The reported points are on the segments, at the reported parameters.
    EXPECT_GE(closest.s, 0);
    EXPECT_LE(closest.s, 1);
    EXPECT_GE(closest.t, 0);
    EXPECT_LE(closest.t, 1);
    EXPECT_NEAR((closest.on_first - (p0 + closest.s * (p1 - p0))).norm(), 0, 1e-15);
    EXPECT_NEAR((closest.on_second - (q0 + closest.t * (q1 - q0))).norm(), 0, 1e-15);
    EXPECT_NEAR((closest.on_first - closest.on_second).norm(), closest.distance, 1e-15);
  }
}

TEST(SegmentClosestPoints, ParallelSegmentsMeetMidwayAlongTheirSharedLength) {
  // Shared length x ∈ [1, 2], in either direction of the second.
  for (const bool reversed : {false, true}) {
    const Vector3d q0(1, 1, 0), q1(3, 1, 0);
    const auto closest = reversed ? closest_points_between_segments({0, 0, 0}, {2, 0, 0}, q1, q0)
                                  : closest_points_between_segments({0, 0, 0}, {2, 0, 0}, q0, q1);
    EXPECT_NEAR(closest.distance, 1, 1e-15);
    EXPECT_NEAR((closest.on_first - Vector3d(1.5, 0, 0)).norm(), 0, 1e-15);
    EXPECT_NEAR((closest.on_second - Vector3d(1.5, 1, 0)).norm(), 0, 1e-15);
  }
  // Collinear and apart: the facing ends.
  const auto apart = closest_points_between_segments({0, 0, 0}, {1, 0, 0}, {3, 0, 0}, {2, 0, 0});
  EXPECT_NEAR(apart.distance, 1, 1e-15);
  EXPECT_NEAR((apart.on_first - Vector3d(1, 0, 0)).norm(), 0, 1e-15);
  EXPECT_NEAR((apart.on_second - Vector3d(2, 0, 0)).norm(), 0, 1e-15);
  // Parallel capsules: the normal is square to them, from the second to the first.
  const auto hit = contact(Capsule{{0, 0, 0}, {2, 0, 0}, 0.3}, Capsule{{1, 0.5, 0}, {3, 0.5, 0}, 0.3});
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR((hit->normal - Vector3d(0, -1, 0)).norm(), 0, 1e-15);
  EXPECT_NEAR(hit->depth, 0.1, 1e-15);
  EXPECT_NEAR((hit->point - Vector3d(1.5, 0.25, 0)).norm(), 0, 1e-15);
}

TEST(SegmentClosestPoints, ZeroLengthSegmentsAreTreatedAsPoints) {
  const Vector3d point(0.5, 2, 0);
  const auto point_first = closest_points_between_segments(point, point, {0, 0, 0}, {1, 0, 0});
  EXPECT_NEAR(point_first.distance, 2, 1e-15);
  EXPECT_NEAR((point_first.on_second - Vector3d(0.5, 0, 0)).norm(), 0, 1e-15);
  const auto point_second = closest_points_between_segments({0, 0, 0}, {1, 0, 0}, point, point);
  EXPECT_NEAR(point_second.distance, 2, 1e-15);
  EXPECT_NEAR(point_second.s, 0.5, 1e-15);
  const auto two_points = closest_points_between_segments(point, point, {3.5, 6, 0}, {3.5, 6, 0});
  EXPECT_NEAR(two_points.distance, 5, 1e-15);
  EXPECT_TRUE(std::isfinite(two_points.s) && std::isfinite(two_points.t));

  // A capsule with no length is a sphere.
  const Capsule limb{{0, 0, 0}, {1, 0, 0}, 0.5};
  const auto as_capsule = contact(Capsule{point, point, 1.6}, limb);
  const auto as_sphere = contact(BoundingSphere{point, 1.6}, limb);
  ASSERT_TRUE(as_capsule && as_sphere);
  EXPECT_NEAR(as_capsule->depth, 0.1, 1e-15);
  EXPECT_NEAR(as_sphere->depth, 0.1, 1e-15);
  EXPECT_NEAR((as_capsule->normal - Vector3d::UnitY()).norm(), 0, 1e-15);
  EXPECT_NEAR((as_sphere->normal - Vector3d::UnitY()).norm(), 0, 1e-15);
  EXPECT_NEAR((as_capsule->point - as_sphere->point).norm(), 0, 1e-15);
}

TEST(CapsuleContact, CrossingAxesTakeTheNormalAcrossBoth) {
  const auto hit = contact(Capsule{{-1, 0, 0}, {1, 0, 0}, 0.2}, Capsule{{0, -1, 0}, {0, 1, 0}, 0.1});
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(std::abs(hit->normal.z()), 1, 1e-15);
  EXPECT_NEAR(hit->depth, 0.3, 1e-15);
  // Both rounded ends of the overlap, ∓0.2 and ±0.1 along the normal, average to 0.05 off centre.
  EXPECT_NEAR((hit->point + 0.05 * hit->normal).norm(), 0, 1e-15);
  EXPECT_TRUE(overlaps(Capsule{{-1, 0, 0}, {1, 0, 0}, 0.2}, Capsule{{0, -1, 0}, {0, 1, 0}, 0.1}));
  EXPECT_FALSE(overlaps(Capsule{{-1, 0, 0}, {1, 0, 0}, 0.2}, Capsule{{0, -1, 0.31}, {0, 1, 0.31}, 0.1}));
}

// ---- Spheres, boxes and upright cylinders ----

TEST(SphereContact, DepthAndNormalOfTwoSpheres) {
  const auto hit = contact(BoundingSphere{{1, 0, 0}, 0.6}, BoundingSphere{{0, 0, 0}, 0.5});
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR((hit->normal - Vector3d::UnitX()).norm(), 0, 1e-15);
  EXPECT_NEAR(hit->depth, 0.1, 1e-15);
  EXPECT_NEAR((hit->point - Vector3d(0.45, 0, 0)).norm(), 0, 1e-15);  // overlap x ∈ [0.4, 0.5]
  EXPECT_FALSE(contact(BoundingSphere{{1, 0, 0}, 0.4}, BoundingSphere{{0, 0, 0}, 0.5}).has_value());
  const auto touching = contact(BoundingSphere{{0, 0, 1}, 0.5}, BoundingSphere{{0, 0, 0}, 0.5});
  ASSERT_TRUE(touching.has_value());
  EXPECT_EQ(touching->depth, 0);
  EXPECT_TRUE(overlaps(BoundingSphere{{0, 0, 1}, 0.5}, BoundingSphere{{0, 0, 0}, 0.5}));
  EXPECT_FALSE(overlaps(BoundingSphere{{0, 0, 1}, 0.49}, BoundingSphere{{0, 0, 0}, 0.5}));
}

TEST(SphereContact, SphereAgainstRotatedBoxMeetsFaceCornerOrLeavesThroughNearestFace) {
  // A box of half-extents (1, 0.5, 0.5) turned 30° about z; positions are given in its frame.
  const Matrix3d rotation = Eigen::AngleAxisd(std::numbers::pi / 6, Vector3d::UnitZ()).toRotationMatrix();
  const Obb box{Vector3d(0.2, -0.3, 0.1), Vector3d(1, 0.5, 0.5), rotation};
  const auto world = [&](const Vector3d& local) -> Vector3d { return box.centre + rotation * local; };

  const auto face = contact(BoundingSphere{world({1.2, 0.1, 0}), 0.3}, box);
  ASSERT_TRUE(face.has_value());
  EXPECT_NEAR((face->normal - rotation.col(0)).norm(), 0, 1e-15);
  EXPECT_NEAR(face->depth, 0.1, 1e-14);
  EXPECT_NEAR((face->point - world({0.95, 0.1, 0})).norm(), 0, 1e-14);  // overlap x ∈ [0.9, 1]

  const auto edge = contact(BoundingSphere{world({1.3, 0.9, 0}), 0.6}, box);  // 0.5 from the edge (1, 0.5, z)
  ASSERT_TRUE(edge.has_value());
  EXPECT_NEAR((edge->normal - rotation * Vector3d(0.6, 0.8, 0)).norm(), 0, 1e-14);
  EXPECT_NEAR(edge->depth, 0.1, 1e-14);
  EXPECT_FALSE(contact(BoundingSphere{world({1.3, 0.9, 0}), 0.49}, box).has_value());
  EXPECT_FALSE(overlaps(BoundingSphere{world({1.3, 0.9, 0}), 0.49}, box));
  EXPECT_TRUE(overlaps(BoundingSphere{world({1.3, 0.9, 0}), 0.51}, box));

  const auto inside = contact(BoundingSphere{world({0.9, 0, 0.05}), 0.3}, box);
  ASSERT_TRUE(inside.has_value());
  EXPECT_NEAR((inside->normal - rotation.col(0)).norm(), 0, 1e-15);
  EXPECT_NEAR(inside->depth, 0.3 + 0.1, 1e-14);
  EXPECT_NEAR((inside->point - world({0.8, 0, 0.05})).norm(), 0, 1e-14);  // from 0.6 to the face at 1
}

TEST(OverlapTests, AxisAlignedVolumesTouchingCountAsOverlapping) {
  const Aabb unit{Vector3d::Zero(), Vector3d::Ones()};
  EXPECT_TRUE(overlaps(unit, Aabb{Vector3d(1, 0.5, 0.5), Vector3d(2, 2, 2)}));   // face to face
  EXPECT_TRUE(overlaps(unit, Aabb{Vector3d(1, 1, 1), Vector3d(2, 2, 2)}));       // corner to corner
  EXPECT_FALSE(overlaps(unit, Aabb{Vector3d(1.01, 0, 0), Vector3d(2, 1, 1)}));
  EXPECT_FALSE(overlaps(unit, Aabb{Vector3d(0, 0, -2), Vector3d(1, 1, -0.01)}));
  // The sphere centre is 0.5 from the box's corner edge (1, 1, z): (0.3, 0.4).
  EXPECT_TRUE(overlaps(BoundingSphere{{1.3, 1.4, 0.5}, 0.5}, unit));
  EXPECT_FALSE(overlaps(BoundingSphere{{1.3, 1.4, 0.5}, 0.49}, unit));
  EXPECT_TRUE(overlaps(BoundingSphere{{0.5, 0.5, 0.5}, 0.01}, unit));  // inside
}

TEST(OverlapTests, UprightCylindersNeedBothVerticalAndHorizontalOverlap) {
  const UprightCylinder standing{Vector3d::Zero(), 0.5, 1.0};
  EXPECT_TRUE(overlaps(standing, UprightCylinder{{0.9, 0, 1.9}, 0.5, 1.0}));
  EXPECT_FALSE(overlaps(standing, UprightCylinder{{0.9, 0, 2.1}, 0.5, 1.0}));  // above
  EXPECT_FALSE(overlaps(standing, UprightCylinder{{1.1, 0, 0}, 0.5, 1.0}));    // beside
  // Diagonal: their boxes would overlap, their circles (0.8·√2 ≈ 1.13 > 1 apart) do not.
  EXPECT_FALSE(overlaps(standing, UprightCylinder{{0.8, 0.8, 0}, 0.5, 1.0}));
  EXPECT_TRUE(overlaps(standing, UprightCylinder{{0.6, 0.8, -2}, 0.5, 1.0}));  // touching at a rim
}

TEST(OverlapTests, SphereAgainstCapsuleIsDistanceToItsSegment) {
  const Capsule capsule{{0, 0, -1}, {0, 0, 1}, 0.2};
  EXPECT_TRUE(overlaps(BoundingSphere{{0.5, 0, 0.3}, 0.3}, capsule));
  EXPECT_FALSE(overlaps(BoundingSphere{{0.5, 0, 0.3}, 0.29}, capsule));
  EXPECT_TRUE(overlaps(BoundingSphere{{0.3, 0, 1.4}, 0.3}, capsule));  // 0.5 from the end point
  EXPECT_FALSE(overlaps(BoundingSphere{{0.3, 0, 1.4}, 0.29}, capsule));
  const auto hit = contact(BoundingSphere{{0.3, 0, 1.4}, 0.4}, capsule);
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR((hit->normal - Vector3d(0.6, 0, 0.8)).norm(), 0, 1e-15);
  EXPECT_NEAR(hit->depth, 0.1, 1e-15);
}

// ---- Fitting a limb ----

// Points on a limb's surface (its body frame), including its end rims and the faces' insides.
std::vector<Vector3d> surface_samples(const Shape& shape) {
  std::vector<Vector3d> points;
  const double half = 0.5 * shape.length, r = shape.radius;
  for (int i = 0; i < 48; ++i) {
    const double angle = 2 * std::numbers::pi * i / 48;
    const Vector3d radial(std::cos(angle), std::sin(angle), 0);
    for (int j = 0; j <= 8; ++j) points.push_back(r * radial + Vector3d(0, 0, -half + shape.length * j / 8));
    for (int j = 1; j <= 6; ++j) {
      const double elevation = (std::numbers::pi / 2) * j / 6;
      for (const double side : {-1.0, 1.0}) {
        if (shape.type == ShapeType::capsule) {
          const Vector3d outward = std::cos(elevation) * radial + side * std::sin(elevation) * Vector3d::UnitZ();
          points.push_back(Vector3d(0, 0, side * half) + r * outward);
        } else {
          points.push_back(Vector3d(0, 0, side * half) + (r * j / 6) * radial);  // the flat faces
        }
      }
    }
  }
  return points;
}

// A box's or ellipsoid's bounding sphere and tight box, its shape frame turned by shape.rotation
// inside a turned body: every corner (box) or surface sample (ellipsoid) inside both; the box's
// farthest corner on the sphere; along each world axis the farthest corner, or the ellipsoid's
// support point H²d/|Hd| (d the axis in the shape frame, H the semi-axes), on the box's face.
TEST(LimbFitting, BoxAndEllipsoidVolumesHoldTheShapeAndTouchIt) {
  std::mt19937 rng(7);
  for (int i = 0; i < 40; ++i) {
    Shape shape;
    shape.type = i % 2 == 0 ? ShapeType::box : ShapeType::ellipsoid;
    shape.half_extents = random_vector(rng, 0.05, 0.5);
    shape.rotation = random_rotation(rng);
    const Vector3d position = random_vector(rng, -1, 1);
    const Quaterniond orientation = random_rotation(rng);
    const Matrix3d to_world = (orientation * shape.rotation).toRotationMatrix();
    std::vector<Vector3d> surface;  // shape frame
    if (shape.type == ShapeType::box) {
      for (int corner = 0; corner < 8; ++corner) {
        surface.push_back(Vector3d(corner & 1 ? 1 : -1, corner & 2 ? 1 : -1, corner & 4 ? 1 : -1).cwiseProduct(shape.half_extents));
      }
    } else {
      for (int j = 0; j <= 24; ++j) {
        for (int k = 0; k < 48; ++k) {
          const double polar = std::numbers::pi * j / 24, around = 2 * std::numbers::pi * k / 48;
          const Vector3d unit(std::sin(polar) * std::cos(around), std::sin(polar) * std::sin(around), std::cos(polar));
          surface.push_back(unit.cwiseProduct(shape.half_extents));
        }
      }
    }
    const BoundingSphere sphere = limb_sphere(shape, position, orientation);
    const Aabb aabb = limb_aabb(shape, position, orientation);
    double farthest = 0;
    for (const Vector3d& local : surface) {
      const Vector3d point = position + to_world * local;
      EXPECT_LE((point - sphere.centre).norm(), sphere.radius + 1e-12);
      farthest = std::max(farthest, (point - sphere.centre).norm());
      EXPECT_TRUE((point.array() >= aabb.min.array() - 1e-12).all());
      EXPECT_TRUE((point.array() <= aabb.max.array() + 1e-12).all());
    }
    if (shape.type == ShapeType::box) {
      EXPECT_NEAR(farthest, sphere.radius, 1e-12) << "a corner on the sphere";
    }
    for (int k = 0; k < 3; ++k) {
      for (const double sign : {-1.0, 1.0}) {
        const Vector3d along = to_world.transpose() * (sign * Vector3d::Unit(k));  // the world axis in the shape frame
        double reach = -std::numeric_limits<double>::infinity();
        if (shape.type == ShapeType::box) {
          for (const Vector3d& local : surface) reach = std::max(reach, sign * (position + to_world * local)[k]);
        } else {
          const Vector3d h2d = shape.half_extents.cwiseProduct(shape.half_extents).cwiseProduct(along);
          const Vector3d support = h2d / shape.half_extents.cwiseProduct(along).norm();
          EXPECT_NEAR(support.cwiseQuotient(shape.half_extents).norm(), 1, 1e-12) << "on the surface";
          reach = sign * (position + to_world * support)[k];
        }
        EXPECT_NEAR(reach, sign > 0 ? aabb.max[k] : -aabb.min[k], 1e-12) << shape_type_name(shape.type) << ", axis " << k << " side " << sign;
      }
    }
  }
}

TEST(LimbFitting, FittedVolumesContainTheLimb) {
  std::mt19937 rng(5);
  for (int i = 0; i < 40; ++i) {
    const ShapeType type = i % 2 == 0 ? ShapeType::cylinder : ShapeType::capsule;
    const Shape shape{type, 0.2 + 0.05 * (i % 7), 0.03 + 0.01 * (i % 5)};
    const Vector3d position = random_vector(rng, -1, 1);
    const Quaterniond orientation = random_rotation(rng);
    const BoundingSphere sphere = limb_sphere(shape, position, orientation);
    const Aabb aabb = limb_aabb(shape, position, orientation);
    const Obb obb = limb_obb(shape, position, orientation);
    const Capsule capsule = limb_capsule(shape, position, orientation);
    for (const Vector3d& local : surface_samples(shape)) {
      const Vector3d point = position + orientation * local;
      EXPECT_LE((point - sphere.centre).norm(), sphere.radius + 1e-12);
      EXPECT_TRUE((point.array() >= aabb.min.array() - 1e-12).all());
      EXPECT_TRUE((point.array() <= aabb.max.array() + 1e-12).all());
      const Vector3d in_box = obb.rotation.transpose() * (point - obb.centre);
      EXPECT_TRUE((in_box.cwiseAbs().array() <= obb.half_extents.array() + 1e-12).all());
      EXPECT_LE((point - nearest_on_segment(point, capsule.a, capsule.b)).norm(), capsule.radius + 1e-12);
    }
    // The capsule runs head (+z) to tail.
    EXPECT_NEAR((capsule.a - (position + orientation * Vector3d(0, 0, 0.5 * shape.length))).norm(), 0, 1e-15);
  }
}

TEST(LimbFitting, TightAabbOfRotatedLimbTouchesItsSurface) {
  // For each world axis the farthest surface point is found by search over the end rims (a
  // cylinder) or taken as the cap sphere's pole (a capsule), and must lie on the box's face.
  std::mt19937 rng(6);
  for (int i = 0; i < 40; ++i) {
    const Shape shape{i % 2 == 0 ? ShapeType::cylinder : ShapeType::capsule, 0.4, 0.07};
    const Vector3d position = random_vector(rng, -1, 1);
    const Quaterniond orientation = random_rotation(rng);
    const Aabb box = limb_aabb(shape, position, orientation);
    const Vector3d u = orientation * Vector3d::UnitZ();
    const Vector3d v1 = orientation * Vector3d::UnitX(), v2 = orientation * Vector3d::UnitY();
    for (int k = 0; k < 3; ++k) {
      for (const double sign : {-1.0, 1.0}) {
        double farthest = -std::numeric_limits<double>::infinity();
        for (const double end : {-1.0, 1.0}) {
          const Vector3d end_centre = position + end * 0.5 * shape.length * u;
          if (shape.type == ShapeType::capsule) {
            farthest = std::max(farthest, sign * end_centre[k] + shape.radius);
            continue;
          }
          const auto reach = [&](double angle) {
            return sign * (end_centre + shape.radius * (std::cos(angle) * v1 + std::sin(angle) * v2))[k];
          };
          // Coarse samples, then golden-section search about the best (a sinusoid: unimodal there).
          constexpr int coarse = 64;
          int best = 0;
          for (int j = 1; j < coarse; ++j) {
            if (reach(2 * std::numbers::pi * j / coarse) > reach(2 * std::numbers::pi * best / coarse)) best = j;
          }
          double low = 2 * std::numbers::pi * (best - 1) / coarse, high = 2 * std::numbers::pi * (best + 1) / coarse;
          const double ratio = (std::sqrt(5.0) - 1) / 2;
          for (int step = 0; step < 80; ++step) {
            const double a = high - ratio * (high - low), b = low + ratio * (high - low);
            if (reach(a) < reach(b)) {
              low = a;
            } else {
              high = b;
            }
          }
          farthest = std::max(farthest, reach(0.5 * (low + high)));
        }
        const double face = sign > 0 ? box.max[k] : -box.min[k];
        EXPECT_NEAR(farthest, face, 1e-9) << "axis " << k << " side " << sign;
      }
    }
  }
}

// ---- The hierarchical test ----

PlacedLimb random_limb(std::mt19937& rng, ShapeType type, double spread) {
  std::uniform_real_distribution<double> length(0.2, 0.6), radius(0.03, 0.12);
  return PlacedLimb{Shape{type, length(rng), radius(rng)}, random_vector(rng, -spread, spread), random_rotation(rng)};
}

bool inside_limb(const PlacedLimb& limb, const Vector3d& point) {
  const Vector3d local = limb.orientation.conjugate() * (point - limb.position);
  const double half = 0.5 * limb.shape.length;
  if (limb.shape.type == ShapeType::capsule) {
    const Vector3d on_axis(0, 0, std::clamp(local.z(), -half, half));
    return (local - on_axis).norm() <= limb.shape.radius;
  }
  return std::abs(local.z()) <= half && local.head<2>().norm() <= limb.shape.radius;
}

// Whether some point of the first limb's solid (a grid over radius, angle and length) lies in
// the second: a witness that they touch (finding none proves nothing).
bool sampled_witness_of_contact(const PlacedLimb& first, const PlacedLimb& second) {
  const double half = 0.5 * first.shape.length;
  for (int a = 0; a <= 10; ++a) {
    for (int r = 0; r <= 3; ++r) {
      for (int q = 0; q < 8; ++q) {
        const double angle = 2 * std::numbers::pi * q / 8;
        const double radial = first.shape.radius * r / 3;
        const Vector3d local(radial * std::cos(angle), radial * std::sin(angle), -half + first.shape.length * a / 10);
        if (inside_limb(second, first.position + first.orientation * local)) return true;
      }
    }
  }
  return false;
}

TEST(HierarchicalTest, DistantPairsNeverReachTheFineTest) {
  std::mt19937 rng(7);
  HierarchicalTestCounts counts;
  for (int i = 0; i < 500; ++i) {
    const PlacedLimb first = random_limb(rng, i % 2 ? ShapeType::capsule : ShapeType::cylinder, 1.0);
    PlacedLimb second = random_limb(rng, i % 3 ? ShapeType::capsule : ShapeType::cylinder, 1.0);
    // Move the second so the spheres are 1 mm apart along a random direction.
    const double reach = limb_sphere(first.shape, first.position, first.orientation).radius +
                         limb_sphere(second.shape, second.position, second.orientation).radius;
    second.position = first.position + (reach + 1e-3) * random_vector(rng, -1, 1).normalized();
    EXPECT_FALSE(limb_pair_contact(first, second, &counts).has_value());
  }
  EXPECT_EQ(counts.sphere_tests, 500u);
  EXPECT_EQ(counts.fine_tests, 0u);
}

TEST(HierarchicalTest, AgreesWithTheFineTestAloneAndNeverMissesATouchingPair) {
  std::mt19937 rng(8);
  HierarchicalTestCounts counts;
  int contacts = 0, witnessed = 0;
  constexpr int pairs = 3000;
  for (int i = 0; i < pairs; ++i) {
    const ShapeType first_type = i % 3 == 0 ? ShapeType::cylinder : ShapeType::capsule;
    const ShapeType second_type = i % 3 == 1 ? ShapeType::capsule : first_type;
    const PlacedLimb first = random_limb(rng, first_type, 0.4), second = random_limb(rng, second_type, 0.4);
    const auto hierarchical = limb_pair_contact(first, second, &counts);
    const auto fine = limb_pair_fine_contact(first, second);
    const bool spheres_overlap = overlaps(limb_sphere(first.shape, first.position, first.orientation),
                                          limb_sphere(second.shape, second.position, second.orientation));
    if (first_type == ShapeType::capsule && second_type == ShapeType::capsule) {
      EXPECT_EQ(hierarchical.has_value(), fine.has_value()) << "pair " << i;
    } else {
      // A box's corners stick out of the sphere: the hierarchy may drop what only they reach.
      EXPECT_EQ(hierarchical.has_value(), fine.has_value() && spheres_overlap) << "pair " << i;
    }
    if (hierarchical && fine) {
      EXPECT_EQ(hierarchical->normal, fine->normal);
      EXPECT_EQ(hierarchical->point, fine->point);
      EXPECT_EQ(hierarchical->depth, fine->depth);
    }
    if (sampled_witness_of_contact(first, second)) {
      ++witnessed;
      EXPECT_TRUE(hierarchical.has_value()) << "pair " << i << " touches but was rejected";
    }
    contacts += hierarchical.has_value();
  }
  EXPECT_EQ(counts.sphere_tests, std::uint64_t{pairs});
  // Some pairs must be rejected early, some must touch, for the comparison to mean something.
  EXPECT_GT(counts.fine_tests, pairs / 10u);
  EXPECT_LT(counts.fine_tests, pairs * 9u / 10u);
  EXPECT_GT(witnessed, pairs / 20);
  EXPECT_GE(contacts, witnessed);
}

}  // namespace
}  // namespace limber
