#include "limber/kernel/geometry/convex_pairs.hpp"

#include <ccd/ccd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <type_traits>

namespace limber {
namespace {

using Eigen::Vector3d;

// EPA's stopping tolerance, m² (convex_pairs.hpp): exact on polyhedra, µm on curved pairs.
constexpr double kEpaTolerance = 1e-10;
// GJK's and EPA's iterations at most (FCL's setting for libccd); a pair that needs more is left
// at libccd's answer so far.
constexpr unsigned long kIterations = 500;
// How much wider a simple axis's gap must be than EPA's to replace its normal, m: above EPA's
// error on curved pairs (9 µm), so a right answer is never traded for round-off.
constexpr double kAxisTolerance = 1e-5;

// A shape grown by `grow` (m) along every direction, as libccd's callbacks see it.
template <typename Shape>
struct Grown {
  const Shape& shape;
  double grow;
};

template <typename Shape>
void ccd_support(const void* object, const ccd_vec3_t* direction, ccd_vec3_t* out) {
  const auto& grown = *static_cast<const Grown<Shape>*>(object);
  const Vector3d d(direction->v[0], direction->v[1], direction->v[2]);
  const Vector3d p = support(grown.shape, d) + grown.grow * d.normalized();
  out->v[0] = p.x(), out->v[1] = p.y(), out->v[2] = p.z();
}


// A shape's centre (its frame's origin; a capsule's middle).
Vector3d centre_of(const Obb& box) { return box.centre; }
Vector3d centre_of(const Capsule& capsule) { return 0.5 * (capsule.a + capsule.b); }
Vector3d centre_of(const Ellipsoid& ellipsoid) { return ellipsoid.centre; }
Vector3d centre_of(const Cylinder& cylinder) { return cylinder.centre; }
Vector3d centre_of(const ConvexHull& hull) { return hull.centre; }

// Directions from the shape out towards `point` that a contact normal with a shape there is likely
// to take: its face normals (a box), from the nearest point of its core (a capsule), or from its
// centre. Unit; `count` of them.
struct Axes {
  std::array<Vector3d, 3> axis;
  int count = 0;
  void add(const Vector3d& direction) {
    if (direction.squaredNorm() > 1e-24) axis[static_cast<std::size_t>(count++)] = direction.normalized();
  }
};
Axes axes_toward(const Obb& box, const Vector3d& point) {
  Axes axes;
  for (int k = 0; k < 3; ++k) {
    const Vector3d normal = box.rotation.col(k);
    axes.add(normal.dot(point - box.centre) >= 0 ? normal : Vector3d(-normal));
  }
  return axes;
}
Axes axes_toward(const Capsule& capsule, const Vector3d& point) {
  const Vector3d core = capsule.b - capsule.a;
  const double length2 = core.squaredNorm();
  const double t = length2 > 0 ? std::clamp((point - capsule.a).dot(core) / length2, 0.0, 1.0) : 0.0;
  Axes axes;
  axes.add(point - (capsule.a + t * core));
  return axes;
}
template <typename Shape>
Axes axes_toward(const Shape& shape, const Vector3d& point) {
  Axes axes;
  axes.add(point - centre_of(shape));
  return axes;
}

// The gap between the two shapes' projections on `normal` (unit, from the second towards the
// first): ≤ their distance apart, ≥ −(their depth) overlapping, equal on the axis of contact.
template <typename First, typename Second>
double projected_separation(const First& first, const Second& second, const Vector3d& normal) {
  return normal.dot(support(first, -normal)) - normal.dot(support(second, normal));
}

}  // namespace

Vector3d support(const Obb& box, const Vector3d& direction) {
  const Vector3d local = box.rotation.transpose() * direction;
  return box.centre + box.rotation * Vector3d(local.x() >= 0 ? box.half_extents.x() : -box.half_extents.x(),
                                              local.y() >= 0 ? box.half_extents.y() : -box.half_extents.y(),
                                              local.z() >= 0 ? box.half_extents.z() : -box.half_extents.z());
}

Vector3d support(const Capsule& capsule, const Vector3d& direction) {
  const Vector3d end = direction.dot(capsule.b - capsule.a) >= 0 ? capsule.b : capsule.a;
  return end + capsule.radius * direction.normalized();
}

Vector3d support(const Ellipsoid& ellipsoid, const Vector3d& direction) {
  // The farthest point of the unit sphere along A d is A d / |A d|, A = diag(semi-axes): mapped
  // back, A² d / |A d|.
  const Vector3d scaled = ellipsoid.semi_axes.cwiseProduct(ellipsoid.rotation.transpose() * direction);
  return ellipsoid.centre + ellipsoid.rotation * (ellipsoid.semi_axes.cwiseProduct(scaled) / scaled.norm());
}

Vector3d support(const Cylinder& cylinder, const Vector3d& direction) {
  const Vector3d local = cylinder.rotation.transpose() * direction;
  const double across = std::hypot(local.x(), local.y());
  Vector3d point(0, 0, local.z() >= 0 ? cylinder.half_length : -cylinder.half_length);
  if (across > 0) point.head<2>() = cylinder.radius * local.head<2>() / across;  // the rim; along the axis, the end's centre
  return cylinder.centre + cylinder.rotation * point;
}

Vector3d support(const ConvexHull& hull, const Vector3d& direction) {
  const Vector3d local = hull.rotation.transpose() * direction;
  const Vector3d* best = &hull.vertices.front();
  double reach = -std::numeric_limits<double>::infinity();
  for (const Vector3d& vertex : hull.vertices) {
    const double value = vertex.dot(local);
    if (value > reach) reach = value, best = &vertex;
  }
  return hull.centre + hull.rotation * *best;
}

template <typename First, typename Second>
Manifold convex_manifold(const First& first, const Second& second, double margin) {
  const Grown<First> a{first, 0.5 * margin};
  const Grown<Second> b{second, 0.5 * margin};
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = ccd_support<First>, ccd.support2 = ccd_support<Second>;
  ccd.max_iterations = kIterations, ccd.epa_tolerance = kEpaTolerance;
  ccd_real_t depth = 0;
  ccd_vec3_t direction, position;
  Manifold manifold;
  if (ccdGJKPenetration(&a, &b, &ccd, &depth, &direction, &position) != 0) return manifold;
  // libccd's direction moves the second out of the first: the normal from the second is against it.
  const Vector3d along(direction.v[0], direction.v[1], direction.v[2]);
  if (!(along.squaredNorm() > 0)) return manifold;  // touching at a point of the grown surfaces: no normal
  manifold.normal = -along.normalized();
  // libccd's EPA can end on a wrong face of its polytope (measured: an ellipsoid 2 cm into a wall's
  // capsule given 1 m deep, its normal through the wall). Its normal is kept only when no simple
  // axis — a box's face normals, from a capsule's core, between the centres — shows a wider gap
  // between the shapes' projections: each such gap is at most the true separation, and equal to
  // it on the axis of contact, so the widest is the best estimate and never pushes too far.
  double separation = projected_separation(first, second, manifold.normal);
  const auto consider = [&](const Vector3d& normal) {
    const double gap = projected_separation(first, second, normal);
    if (gap > separation + kAxisTolerance) separation = gap, manifold.normal = normal;
  };
  const Axes from_second = axes_toward(second, centre_of(first)), from_first = axes_toward(first, centre_of(second));
  for (int k = 0; k < from_second.count; ++k) consider(from_second.axis[static_cast<std::size_t>(k)]);
  for (int k = 0; k < from_first.count; ++k) consider(-from_first.axis[static_cast<std::size_t>(k)]);
  if (!(separation <= margin)) return manifold;
  // EPA's position is only as good as the supports it came from: where a shape's support is a
  // segment or a face (a capsule's side, a box's face), libccd's point may lie anywhere on it —
  // a metre off along a wall's capsule, measured. A strictly convex shape's deepest point along
  // the normal is unique: the contact is there, half the depth out.
  Vector3d point(position.v[0], position.v[1], position.v[2]);
  if constexpr (std::is_same_v<First, Ellipsoid>) {
    point = support(first, -manifold.normal) - 0.5 * separation * manifold.normal;
  } else if constexpr (std::is_same_v<Second, Ellipsoid>) {
    point = support(second, manifold.normal) + 0.5 * separation * manifold.normal;
  }
  manifold.points[0] = {point, separation, 0};
  manifold.count = 1;
  return manifold;
}

template Manifold convex_manifold(const Obb&, const Obb&, double);
template Manifold convex_manifold(const Obb&, const Capsule&, double);
template Manifold convex_manifold(const Obb&, const Ellipsoid&, double);
template Manifold convex_manifold(const Obb&, const Cylinder&, double);
template Manifold convex_manifold(const Obb&, const ConvexHull&, double);
template Manifold convex_manifold(const Capsule&, const Obb&, double);
template Manifold convex_manifold(const Capsule&, const Capsule&, double);
template Manifold convex_manifold(const Capsule&, const Ellipsoid&, double);
template Manifold convex_manifold(const Capsule&, const Cylinder&, double);
template Manifold convex_manifold(const Capsule&, const ConvexHull&, double);
template Manifold convex_manifold(const Ellipsoid&, const Obb&, double);
template Manifold convex_manifold(const Ellipsoid&, const Capsule&, double);
template Manifold convex_manifold(const Ellipsoid&, const Ellipsoid&, double);
template Manifold convex_manifold(const Ellipsoid&, const Cylinder&, double);
template Manifold convex_manifold(const Ellipsoid&, const ConvexHull&, double);
template Manifold convex_manifold(const Cylinder&, const Obb&, double);
template Manifold convex_manifold(const Cylinder&, const Capsule&, double);
template Manifold convex_manifold(const Cylinder&, const Ellipsoid&, double);
template Manifold convex_manifold(const Cylinder&, const Cylinder&, double);
template Manifold convex_manifold(const Cylinder&, const ConvexHull&, double);
template Manifold convex_manifold(const ConvexHull&, const Obb&, double);
template Manifold convex_manifold(const ConvexHull&, const Capsule&, double);
template Manifold convex_manifold(const ConvexHull&, const Ellipsoid&, double);
template Manifold convex_manifold(const ConvexHull&, const Cylinder&, double);
template Manifold convex_manifold(const ConvexHull&, const ConvexHull&, double);

}  // namespace limber
