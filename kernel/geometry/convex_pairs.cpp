#include "limber/kernel/geometry/convex_pairs.hpp"

#include <ccd/ccd.h>

#include <cmath>
#include <limits>

namespace limber {
namespace {

using Eigen::Vector3d;

// EPA's stopping tolerance, m² (convex_pairs.hpp): exact on polyhedra, µm on curved pairs.
constexpr double kEpaTolerance = 1e-10;
// GJK's and EPA's iterations at most (FCL's setting for libccd); a pair that needs more is left
// at libccd's answer so far.
constexpr unsigned long kIterations = 500;

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
  manifold.points[0] = {Vector3d(position.v[0], position.v[1], position.v[2]), margin - depth, 0};
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
