#include "limber/kernel/geometry/shape_pairs.hpp"

#include <stdexcept>

namespace limber {
namespace {

// The closed forms (shape_pairs.hpp's table); every other pair goes to GJK/EPA.
Manifold pair_manifold(const Obb& first, const Obb& second, double margin) { return box_box_manifold(first, second, margin); }
Manifold pair_manifold(const Capsule& first, const Obb& second, double margin) { return capsule_box_manifold(first, second, margin); }
Manifold pair_manifold(const Obb& first, const Capsule& second, double margin) {
  return swapped(capsule_box_manifold(second, first, margin));
}
[[noreturn]] Manifold pair_manifold(const Capsule&, const Capsule&, double) {
  throw std::invalid_argument("collide: two capsules are the collision world's pair (limb_collisions.cpp), not the shape-pair table's");
}
template <typename First, typename Second>
Manifold pair_manifold(const First& first, const Second& second, double margin) {
  return convex_manifold(first, second, margin);
}

// The deepest point of a shape below a plane, as a one-point manifold.
template <typename Shape>
Manifold deepest_point_manifold(const Shape& shape, const Plane& plane, double margin) {
  Manifold manifold;
  manifold.normal = plane.normal;
  const Eigen::Vector3d lowest = support(shape, -plane.normal);
  const double separation = plane.normal.dot(lowest) - plane.offset;
  if (!(separation <= margin)) return manifold;
  manifold.points[0] = {lowest - 0.5 * separation * plane.normal, separation, 0};
  manifold.count = 1;
  return manifold;
}

Manifold plane_manifold(const Obb& box, const Plane& plane, double margin) { return box_plane_manifold(box, plane, margin); }
template <typename Shape>
Manifold plane_manifold(const Shape& shape, const Plane& plane, double margin) {
  return deepest_point_manifold(shape, plane, margin);
}

}  // namespace

Manifold collide(const PlacedShape& first, const PlacedShape& second, double margin) {
  return std::visit([margin](const auto& a, const auto& b) { return pair_manifold(a, b, margin); }, first, second);
}

Manifold collide(const PlacedShape& shape, const Plane& plane, double margin) {
  return std::visit([&](const auto& s) { return plane_manifold(s, plane, margin); }, shape);
}

}  // namespace limber
