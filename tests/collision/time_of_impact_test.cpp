// Time of impact of a moving sphere (kernel/geometry/time_of_impact.hpp): hand-made paths whose
// first touch is known in closed form, and random paths against every shape checked against the
// shape's own distance function sampled densely along the path.
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "limber/kernel/geometry/geometry.hpp"
#include "limber/kernel/geometry/time_of_impact.hpp"

namespace limber {
namespace {

using Eigen::Vector3d;

constexpr double kBall = 0.05;  // m, the thesis's ball

// ---- Known touches ----

TEST(TimeOfImpact, BallAt100MetresPerSecondTouchesAThinLimbWhereItsSurfaceMeetsTheLimbs) {
  // A 1/60 s step at 100 m/s (1.67 m) straight through a capsule limb 4 cm thick standing on z.
  const Vector3d head(0, 0, 0.2), tail(0, 0, -0.2);
  const Vector3d from(-1, 0, 0), to(100.0 / 60 - 1, 0, 0);
  const TimeOfImpact impact = sphere_limb_time_of_impact(from, to, kBall, head, tail, ShapeType::capsule, 0.02);
  ASSERT_TRUE(impact.hit);
  // The centre touches at x = −(0.05 + 0.02).
  EXPECT_NEAR(from.x() + impact.time * (to.x() - from.x()), -0.07, 1e-12);
  // Aimed 10 cm clear of the surface: no touch.
  const Vector3d aside(0, 0.17, 0);
  EXPECT_FALSE(sphere_limb_time_of_impact(from + aside, to + aside, kBall, head, tail, ShapeType::capsule, 0.02).hit);
  // The path stopping 1 mm short: no touch; starting touching: at once.
  EXPECT_FALSE(sphere_limb_time_of_impact(from, Vector3d(-0.071, 0, 0), kBall, head, tail, ShapeType::capsule, 0.02).hit);
  const TimeOfImpact touching = sphere_limb_time_of_impact(Vector3d(-0.07, 0, 0), to, kBall, head, tail, ShapeType::capsule, 0.02);
  EXPECT_TRUE(touching.hit);
  EXPECT_EQ(touching.time, 0);
}

TEST(TimeOfImpact, AlongTheAxisACapsuleIsMetAtItsCapAndACylinderAtItsFlatEnd) {
  const Vector3d head(0, 0, 0.2), tail(0, 0, -0.2);
  const Vector3d from(0, 0, 1), to(0, 0, -1);  // 2 m down the axis
  const TimeOfImpact capsule = sphere_limb_time_of_impact(from, to, kBall, head, tail, ShapeType::capsule, 0.02);
  const TimeOfImpact cylinder = sphere_limb_time_of_impact(from, to, kBall, head, tail, ShapeType::cylinder, 0.02);
  ASSERT_TRUE(capsule.hit);
  ASSERT_TRUE(cylinder.hit);
  EXPECT_NEAR(1 - 2 * capsule.time, 0.2 + 0.02 + kBall, 1e-12);  // the centre's height at the touch
  EXPECT_NEAR(1 - 2 * cylinder.time, 0.2 + kBall, 1e-9);
  EXPECT_GE(1 - 2 * cylinder.time, 0.2 + kBall - 1e-12) << "the search never passes the touch";
  // Past the cylinder's rim (1.5 cm off the axis, inside the capsule's cap): the flat end still.
  const Vector3d off(0.015, 0, 0);
  const TimeOfImpact rim = sphere_limb_time_of_impact(from + off, to + off, kBall, head, tail, ShapeType::cylinder, 0.02);
  ASSERT_TRUE(rim.hit);
  EXPECT_NEAR(1 - 2 * rim.time, 0.2 + kBall, 1e-9);
}

TEST(TimeOfImpact, ThinBoxIsMetAtItsFaceOrEdgeAndMissedBesideIt) {
  Obb box;  // a 2 cm plate, 1 m × 1 m, turned 30° about z
  box.half_extents = Vector3d(0.01, 0.5, 0.5);
  box.rotation = Eigen::AngleAxisd(std::numbers::pi / 6, Vector3d::UnitZ()).toRotationMatrix();
  box.centre = Vector3d(0.3, -0.2, 1);
  const Vector3d normal = box.rotation.col(0), along = box.rotation.col(1);
  // Head-on at 100 m/s over 1/60 s: the centre stops kBall in front of the face.
  const Vector3d from = box.centre - 1.0 * normal, to = box.centre + (100.0 / 60 - 1) * normal;
  const TimeOfImpact face = sphere_box_time_of_impact(from, to, kBall, box);
  ASSERT_TRUE(face.hit);
  EXPECT_NEAR((from + face.time * (to - from) - box.centre).dot(normal), -(0.01 + kBall), 1e-12);
  // Past the plate's side edge by 3 cm: the ball's surface meets the edge, 4 cm off the path's line.
  const Vector3d beside = box.centre + (0.5 + 0.03) * along;
  const TimeOfImpact edge = sphere_box_time_of_impact(beside - normal, beside + normal, kBall, box);
  ASSERT_TRUE(edge.hit);
  // On the edge capsule of radius kBall: the centre is √(0.05² − 0.03²) = 0.04 before the edge's face.
  EXPECT_NEAR(-1 + 2 * edge.time, -(0.01 + 0.04), 1e-12);
  // 6 cm beside: clear.
  const Vector3d clear = box.centre + (0.5 + 0.06) * along;
  EXPECT_FALSE(sphere_box_time_of_impact(clear - normal, clear + normal, kBall, box).hit);
}

TEST(TimeOfImpact, OneSidedTriangleIsMetFromItsFrontOnly) {
  const std::array<Vector3d, 3> triangle{Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)};
  const Vector3d normal = Vector3d::UnitZ();
  const Vector3d inside(0.2, 0.2, 0);
  const TimeOfImpact front = sphere_triangle_time_of_impact(inside + Vector3d(0, 0, 1), inside - Vector3d(0, 0, 1), kBall, triangle, normal);
  ASSERT_TRUE(front.hit);
  EXPECT_NEAR(1 - 2 * front.time, kBall, 1e-12);
  EXPECT_FALSE(sphere_triangle_time_of_impact(inside - Vector3d(0, 0, 1), inside + Vector3d(0, 0, 1), kBall, triangle, normal).hit);
  // Beside the hypotenuse, 3 cm out: met on that edge.
  const Vector3d beside = Vector3d(0.5, 0.5, 0) + 0.03 * Vector3d(1, 1, 0).normalized();
  const TimeOfImpact edge = sphere_triangle_time_of_impact(beside + Vector3d(0, 0, 1), beside - Vector3d(0, 0, 1), kBall, triangle, normal);
  ASSERT_TRUE(edge.hit);
  EXPECT_NEAR(1 - 2 * edge.time, 0.04, 1e-12);
}

TEST(TimeOfImpact, ATouchIsAnsweredWhereItHappensUnlessTheEndOfThePathAnswersIt) {
  // A ball flying along +x meets a surface facing −x at t = 0.5.
  const Vector3d path(0.4, 0, 0), normal(-1, 0, 0);
  const double inf = std::numeric_limits<double>::infinity();
  // Passed through (apart at the end, or not answered there): at the touch.
  EXPECT_TRUE(answer_at_touch(path, 0.5, normal, kBall, 0.01, Vector3d(1, 0, 0)));
  EXPECT_TRUE(answer_at_touch(path, 0.5, normal, kBall, inf, normal));
  // Ends 1 cm inside on the side it came from: the end's overlap answers it.
  EXPECT_FALSE(answer_at_touch(path, 0.5, normal, kBall, -0.01, normal));
  // Ends deeper than half its radius, or beyond the middle (the end's normal along the path): at the touch.
  EXPECT_TRUE(answer_at_touch(path, 0.5, normal, kBall, -0.03, normal));
  EXPECT_TRUE(answer_at_touch(path, 0.5, normal, kBall, -0.01, Vector3d(1, 0, 0)));
  // Sliding along the surface (no approach), or approaching by less than 1% of its radius: not a hit.
  EXPECT_FALSE(answer_at_touch(path, 0.5, Vector3d(0, 0, 1), kBall, 0.01, Vector3d(0, 0, 1)));
  EXPECT_FALSE(answer_at_touch(Vector3d(0.4, 0, -0.0009), 0.5, Vector3d(0, 0, 1), kBall, 0.01, Vector3d(0, 0, 1)));
}

// ---- Random paths against sampled distances ----

// A path and a separation function (sphere against the shape, m; one-sided shapes give +∞ where
// they do not answer), for one random trial.
struct Trial {
  Vector3d from, to;
  std::function<double(const Vector3d&)> separation;
  TimeOfImpact impact;
};

// The sampled first touch is never before the reported one, and the reported one is a touch:
// within the samples' spacing of it, and at separation ≈ 0 (or 0 with an overlapping start).
void expect_agrees_with_samples(const Trial& trial, const std::string& what) {
  constexpr int kSamples = 20000;
  const Vector3d path = trial.to - trial.from;
  double sampled = 2, closest = 1e300;
  for (int k = 0; k <= kSamples; ++k) {
    const double separation = trial.separation(trial.from + (double(k) / kSamples) * path);
    closest = std::min(closest, separation);
    if (separation <= 0) {
      sampled = double(k) / kSamples;
      break;
    }
  }
  const double spacing = path.norm() / kSamples;  // m between samples
  if (sampled > 1) {
    // No sample touches: a reported hit is a graze within a sample's reach.
    if (trial.impact.hit) {
      EXPECT_LT(closest, spacing) << what;
    }
    return;
  }
  ASSERT_TRUE(trial.impact.hit) << what << ": sampled touch at " << sampled;
  EXPECT_LE(trial.impact.time, sampled + 1e-12) << what;
  EXPECT_GE(trial.impact.time, sampled - 1.0 / kSamples - 1e-12) << what;
  if (trial.impact.time > 0) {
    EXPECT_NEAR(trial.separation(trial.from + trial.impact.time * path), 0, 1e-8) << what;
  }
}

Vector3d random_unit(std::mt19937& random) {
  std::normal_distribution<double> normal;
  return Vector3d(normal(random), normal(random), normal(random)).normalized();
}

// A path from 0.3–1.3 m out towards a point within 0.4 m of the origin, and on 0.5–3 m past it.
std::pair<Vector3d, Vector3d> random_path(std::mt19937& random) {
  std::uniform_real_distribution<double> unit(0, 1);
  const Vector3d aim = 0.4 * unit(random) * random_unit(random);
  const Vector3d direction = random_unit(random);
  return {aim - (0.3 + unit(random)) * direction, aim + (0.5 + 2.5 * unit(random)) * direction};
}

TEST(TimeOfImpact, RandomPathsAgreeWithTheShapesSampledDistance) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(0, 1);
  int hits = 0;
  for (int trial_index = 0; trial_index < 400; ++trial_index) {
    const auto [from, to] = random_path(random);
    const double radius = 0.01 + 0.1 * unit(random);
    // A limb through the origin, a capsule or a cylinder.
    const Vector3d axis = (0.05 + 0.5 * unit(random)) * random_unit(random);
    const double limb_radius = 0.005 + 0.1 * unit(random);
    for (const ShapeType shape : {ShapeType::capsule, ShapeType::cylinder}) {
      Trial trial{from, to, [&](const Vector3d& p) { return sphere_limb_contact(p, radius, axis, -axis, shape, limb_radius).separation; }, {}};
      trial.impact = sphere_limb_time_of_impact(from, to, radius, axis, -axis, shape, limb_radius);
      hits += trial.impact.hit ? 1 : 0;
      expect_agrees_with_samples(trial, "limb " + std::to_string(trial_index));
    }
    // A box about the origin.
    Obb box;
    box.half_extents = Vector3d(0.01 + 0.3 * unit(random), 0.01 + 0.3 * unit(random), 0.01 + 0.3 * unit(random));
    box.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi * unit(random), random_unit(random))).toRotationMatrix();
    Trial boxed{from, to, [&](const Vector3d& p) { return box_surface_point(box, p).distance - radius; }, {}};
    boxed.impact = sphere_box_time_of_impact(from, to, radius, box);
    hits += boxed.impact.hit ? 1 : 0;
    expect_agrees_with_samples(boxed, "box " + std::to_string(trial_index));
    // A triangle through the origin, one-sided: it answers a point in front of its plane only.
    const std::array<Vector3d, 3> triangle{0.5 * random_unit(random), 0.5 * random_unit(random), 0.5 * random_unit(random)};
    Vector3d normal = (triangle[1] - triangle[0]).cross(triangle[2] - triangle[0]).normalized();
    if (normal.dot(from - triangle[0]) < 0) normal = -normal;  // the path starts in front
    const std::array<Vector3d, 3> facing = normal.dot((triangle[1] - triangle[0]).cross(triangle[2] - triangle[0])) > 0
                                               ? triangle
                                               : std::array<Vector3d, 3>{triangle[0], triangle[2], triangle[1]};
    Trial faced{from, to, [&](const Vector3d& p) {
                  if (normal.dot(p - facing[0]) < 0) return 1e300;
                  return (p - closest_point_on_triangle(facing[0], facing[1], facing[2], p)).norm() - radius;
                }, {}};
    faced.impact = sphere_triangle_time_of_impact(from, to, radius, facing, normal);
    hits += faced.impact.hit ? 1 : 0;
    expect_agrees_with_samples(faced, "triangle " + std::to_string(trial_index));
  }
  EXPECT_GT(hits, 400) << "most random paths should hit something, or the test checks little";
}

}  // namespace
}  // namespace limber
