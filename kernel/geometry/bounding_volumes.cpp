#include "limber/kernel/geometry/bounding_volumes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "limber/kernel/geometry/geometry.hpp"
#include "limber/kernel/geometry/separating_axis.hpp"

namespace limber {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

// A segment whose squared length is at most this (m²) is treated as a point.
constexpr double kPointLengthSquared = 1e-24;
// Segments with sin²(angle) below this are parallel (ae − b² ≤ this · ae).
constexpr double kParallelSineSquared = 1e-12;
// |n·axis| below this: the box's extent along `axis` is a tie, so its support feature spans it.
constexpr double kSupportTie = 1e-9;

// `normal` flipped, if need be, to point from `second_reference` towards `first_reference`.
Vector3d oriented(const Vector3d& normal, const Vector3d& first_reference, const Vector3d& second_reference) {
  return normal.dot(first_reference - second_reference) < 0 ? Vector3d(-normal) : normal;
}

// Two volumes reduced to their cores (a point or a point on a segment) with radii: the contact
// lies on the line between the core points. `fallback_normal` is used when they coincide.
Contact rounded_contact(const Vector3d& first_core, double first_radius, const Vector3d& second_core,
                        double second_radius, double distance, const Vector3d& fallback_normal) {
  Contact contact;
  contact.normal = distance > 0 ? Vector3d((first_core - second_core) / distance) : fallback_normal;
  contact.depth = first_radius + second_radius - distance;
  // Midway between the first's deepest point into the second and the second's into the first.
  contact.point = 0.5 * ((first_core - first_radius * contact.normal) + (second_core + second_radius * contact.normal));
  return contact;
}

// The centre of a box's support feature in `direction` (the face, edge or vertex furthest along
// it): ± the half-extent on axes that `direction` leans along, 0 on those it is square to.
Vector3d support_feature_centre(const Obb& box, const Vector3d& direction) {
  Vector3d local = Vector3d::Zero();
  for (int k = 0; k < 3; ++k) {
    const double lean = direction.dot(box.rotation.col(k));
    if (lean > kSupportTie) local[k] = box.half_extents[k];
    if (lean < -kSupportTie) local[k] = -box.half_extents[k];
  }
  return box.centre + box.rotation * local;
}

// Radius of a box's projection onto the unit `direction`.
double projected_radius(const Obb& box, const Vector3d& direction) {
  return (box.rotation.transpose() * direction).cwiseAbs().dot(box.half_extents);
}

}  // namespace

// ---- Overlap tests ----

bool overlaps(const BoundingSphere& first, const BoundingSphere& second) {
  const double reach = first.radius + second.radius;
  return (first.centre - second.centre).squaredNorm() <= reach * reach;
}

bool overlaps(const BoundingSphere& sphere, const Aabb& box) {
  const Vector3d closest = sphere.centre.cwiseMax(box.min).cwiseMin(box.max);
  return (sphere.centre - closest).squaredNorm() <= sphere.radius * sphere.radius;
}

bool overlaps(const Aabb& first, const Aabb& second) {
  return (first.min.array() <= second.max.array()).all() && (second.min.array() <= first.max.array()).all();
}

bool overlaps(const UprightCylinder& first, const UprightCylinder& second) {
  const Vector3d offset = first.centre - second.centre;
  const double reach = first.radius + second.radius;
  return std::abs(offset.z()) <= first.half_height + second.half_height &&
         offset.head<2>().squaredNorm() <= reach * reach;
}

bool overlaps(const Obb& first, const Obb& second) { return separating_axis_test(first, second, false).overlap; }

bool overlaps(const Capsule& first, const Capsule& second) {
  const double distance = closest_points_between_segments(first.a, first.b, second.a, second.b).distance;
  return distance <= first.radius + second.radius;
}

bool overlaps(const BoundingSphere& sphere, const Capsule& capsule) {
  const double distance = closest_points_between_segments(sphere.centre, sphere.centre, capsule.a, capsule.b).distance;
  return distance <= sphere.radius + capsule.radius;
}

bool overlaps(const BoundingSphere& sphere, const Obb& box) {
  return (sphere.centre - closest_point_on_obb(box, sphere.centre)).squaredNorm() <= sphere.radius * sphere.radius;
}

// ---- Contacts ----

std::optional<Contact> contact(const BoundingSphere& first, const BoundingSphere& second) {
  const double distance = (first.centre - second.centre).norm();
  if (distance > first.radius + second.radius) return std::nullopt;
  return rounded_contact(first.centre, first.radius, second.centre, second.radius, distance, Vector3d::UnitZ());
}

std::optional<Contact> contact(const BoundingSphere& first, const Capsule& second) {
  const SegmentClosestPoints closest =
      closest_points_between_segments(first.centre, first.centre, second.a, second.b);
  if (closest.distance > first.radius + second.radius) return std::nullopt;
  // The centre on the axis: any direction square to it, pointing away from the capsule's middle.
  const Vector3d axis = second.b - second.a;
  const Vector3d fallback =
      axis.squaredNorm() > kPointLengthSquared
          ? oriented(any_perpendicular(axis), first.centre, 0.5 * (second.a + second.b))
          : Vector3d(Vector3d::UnitZ());
  return rounded_contact(closest.on_first, first.radius, closest.on_second, second.radius, closest.distance, fallback);
}

std::optional<Contact> contact(const Capsule& first, const Capsule& second) {
  const SegmentClosestPoints closest = closest_points_between_segments(first.a, first.b, second.a, second.b);
  if (closest.distance > first.radius + second.radius) return std::nullopt;
  // The axes meet: across both when they cross, else square to whichever has a direction.
  const Vector3d first_axis = first.b - first.a, second_axis = second.b - second.a;
  const Vector3d across = first_axis.cross(second_axis);
  Vector3d fallback = Vector3d::UnitZ();
  if (across.squaredNorm() > kParallelSineSquared * first_axis.squaredNorm() * second_axis.squaredNorm()) {
    fallback = across.normalized();
  } else if (first_axis.squaredNorm() > kPointLengthSquared) {
    fallback = any_perpendicular(first_axis);
  } else if (second_axis.squaredNorm() > kPointLengthSquared) {
    fallback = any_perpendicular(second_axis);
  }
  fallback = oriented(fallback, 0.5 * (first.a + first.b), 0.5 * (second.a + second.b));
  return rounded_contact(closest.on_first, first.radius, closest.on_second, second.radius, closest.distance, fallback);
}

std::optional<Contact> contact(const BoundingSphere& first, const Obb& second) {
  const Vector3d local = second.rotation.transpose() * (first.centre - second.centre);
  const Vector3d clamped = local.cwiseMax(-second.half_extents).cwiseMin(second.half_extents);
  if (clamped != local) {
    // Outside: the closest point of the box is the second's core with radius 0.
    const Vector3d closest = second.centre + second.rotation * clamped;
    const double distance = (first.centre - closest).norm();
    if (distance > first.radius) return std::nullopt;
    return rounded_contact(first.centre, first.radius, closest, 0.0, distance, Vector3d::UnitZ());
  }
  // Inside: leave through the face nearest the centre.
  const Vector3d to_faces = second.half_extents - local.cwiseAbs();
  int face = 0;
  to_faces.minCoeff(&face);
  const Vector3d normal = (local[face] < 0 ? -1.0 : 1.0) * second.rotation.col(face);
  Contact result;
  result.normal = normal;
  result.depth = first.radius + to_faces[face];
  // Midway between the sphere's deepest point and the face it leaves through.
  result.point = 0.5 * ((first.centre - first.radius * normal) + (first.centre + to_faces[face] * normal));
  return result;
}

std::optional<Contact> contact(const Obb& first, const Obb& second) {
  const SeparatingAxisResult sat = separating_axis_test(first, second, true);
  if (!sat.overlap) return std::nullopt;
  const Vector3d& n = sat.normal;
  // Each box's support feature towards the other, reduced to its centre and clamped into the other.
  const Vector3d first_into_second = closest_point_on_obb(second, support_feature_centre(first, -n));
  const Vector3d second_into_first = closest_point_on_obb(first, support_feature_centre(second, n));
  const Vector3d mean = 0.5 * (first_into_second + second_into_first);
  // Along n the overlap is [lowest point of the first, highest point of the second].
  const double overlap_low = first.centre.dot(n) - projected_radius(first, n);
  const double overlap_high = second.centre.dot(n) + projected_radius(second, n);
  Contact result;
  result.normal = n;
  result.depth = std::max(0.0, sat.depth);
  result.point = mean + (0.5 * (overlap_low + overlap_high) - mean.dot(n)) * n;
  return result;
}

SegmentClosestPoints closest_points_between_segments(const Vector3d& p0, const Vector3d& p1, const Vector3d& q0,
                                                     const Vector3d& q1) {
  // Minimise |r + s·d1 − t·d2|², r = p0 − q0. Setting both partial derivatives to zero gives
  //   a s − b t = −c,  b s − e t = −f,  with a = d1·d1, b = d1·d2, c = d1·r, e = d2·d2, f = d2·r,
  // so t = (b s + f)/e for a given s, s = (b t − c)/a for a given t, and the unconstrained
  // s = (b f − c e)/(a e − b²). The function is convex, so clamping s, then t, then (if t was
  // clamped) s again lands on the constrained minimum.
  const Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm();
  const double b = d1.dot(d2), c = d1.dot(r), f = d2.dot(r);
  const auto unit = [](double x) { return std::clamp(x, 0.0, 1.0); };
  double s = 0, t = 0;
  if (a <= kPointLengthSquared && e <= kPointLengthSquared) {
    // Two points.
  } else if (a <= kPointLengthSquared) {
    t = unit(f / e);
  } else if (e <= kPointLengthSquared) {
    s = unit(-c / a);
  } else {
    const double denominator = a * e - b * b;
    if (denominator > kParallelSineSquared * a * e) {
      s = unit((b * f - c * e) / denominator);
    } else {
      // Parallel: the middle of where the second's projection onto the first overlaps [0, 1]
      // (q0 projects to s = −c/a, q1 to (b − c)/a); beyond it, the nearer end.
      const double s_q0 = -c / a, s_q1 = (b - c) / a;
      const double low = std::max(0.0, std::min(s_q0, s_q1)), high = std::min(1.0, std::max(s_q0, s_q1));
      s = unit(0.5 * (low + high));
    }
    t = (b * s + f) / e;
    if (t < 0) {
      t = 0;
      s = unit(-c / a);
    } else if (t > 1) {
      t = 1;
      s = unit((b - c) / a);
    }
  }
  SegmentClosestPoints closest;
  closest.s = s;
  closest.t = t;
  closest.on_first = p0 + s * d1;
  closest.on_second = q0 + t * d2;
  closest.distance = (closest.on_first - closest.on_second).norm();
  return closest;
}

Vector3d closest_point_on_obb(const Obb& box, const Vector3d& point) {
  const Vector3d local = box.rotation.transpose() * (point - box.centre);
  return box.centre + box.rotation * local.cwiseMax(-box.half_extents).cwiseMin(box.half_extents);
}

// ---- Fitting a limb ----

BoundingSphere limb_sphere(const Shape& shape, const Vector3d& position, const Eigen::Quaterniond& /*orientation*/) {
  BoundingSphere sphere;
  sphere.centre = position;
  sphere.radius = bounding_radius(shape);
  return sphere;
}

Aabb limb_aabb(const Shape& shape, const Vector3d& position, const Eigen::Quaterniond& orientation) {
  if (has_half_extents(shape)) {
    // Row i of R·diag(h) is the shape's half-axes' reach along world axis i.
    const Eigen::Matrix3d reach = (orientation * shape.rotation).toRotationMatrix() * shape.half_extents.asDiagonal();
    const Vector3d half_extents = shape.type == ShapeType::box ? Vector3d(reach.cwiseAbs().rowwise().sum()) : Vector3d(reach.rowwise().norm());
    return Aabb{position - half_extents, position + half_extents};
  }
  const Vector3d axis = orientation * Vector3d::UnitZ();
  Vector3d half_extents;
  for (int k = 0; k < 3; ++k) {
    const double lean = std::abs(axis[k]);
    const double rim = shape.type == ShapeType::capsule ? shape.radius
                                                        : shape.radius * std::sqrt(std::max(0.0, 1 - lean * lean));
    half_extents[k] = lean * 0.5 * shape.length + rim;
  }
  return Aabb{position - half_extents, position + half_extents};
}

Obb limb_obb(const Shape& shape, const Vector3d& position, const Eigen::Quaterniond& orientation) {
  const double caps = shape.type == ShapeType::capsule ? shape.radius : 0.0;
  Obb box;
  box.centre = position;
  box.half_extents = Vector3d(shape.radius, shape.radius, 0.5 * shape.length + caps);
  box.rotation = orientation.toRotationMatrix();
  return box;
}

Capsule limb_capsule(const Shape& shape, const Vector3d& position, const Eigen::Quaterniond& orientation) {
  const Vector3d half_axis = orientation * Vector3d(0, 0, 0.5 * shape.length);
  return Capsule{position + half_axis, position - half_axis, shape.radius};
}

// ---- The hierarchical test ----

std::optional<Contact> limb_pair_fine_contact(const PlacedLimb& first, const PlacedLimb& second) {
  if (first.shape.type == ShapeType::capsule && second.shape.type == ShapeType::capsule) {
    return contact(limb_capsule(first.shape, first.position, first.orientation),
                   limb_capsule(second.shape, second.position, second.orientation));
  }
  return contact(limb_obb(first.shape, first.position, first.orientation),
                 limb_obb(second.shape, second.position, second.orientation));
}

std::optional<Contact> limb_pair_contact(const PlacedLimb& first, const PlacedLimb& second,
                                         HierarchicalTestCounts* counts) {
  if (counts != nullptr) ++counts->sphere_tests;
  // Level 1: the bounding spheres reject most pairs with one distance.
  if (!overlaps(limb_sphere(first.shape, first.position, first.orientation),
                limb_sphere(second.shape, second.position, second.orientation))) {
    return std::nullopt;
  }
  // Level 2: the finer volumes.
  if (counts != nullptr) ++counts->fine_tests;
  return limb_pair_fine_contact(first, second);
}

}  // namespace limber
