#include "limber/kernel/geometry/static_geometry.hpp"

#include <algorithm>
#include <cmath>

#include "limber/kernel/geometry/geometry.hpp"

namespace limber {
namespace {

using Eigen::Vector3d;

Aabb bounds_of(const Vector3d& a, const Vector3d& b) { return {a.cwiseMin(b), a.cwiseMax(b)}; }

Aabb merged(const Aabb& a, const Aabb& b) { return {a.min.cwiseMin(b.min), a.max.cwiseMax(b.max)}; }

StaticPrimitive box_primitive(const StaticCollider& c) {
  StaticPrimitive p;
  p.box.centre = c.position;
  p.box.half_extents = c.half_extents;
  p.box.rotation = c.orientation.normalized().toRotationMatrix();
  // The box's extent along world axis e is Σ_k |R_ek|·h_k.
  const Vector3d reach = p.box.rotation.cwiseAbs() * c.half_extents;
  p.bounds = {c.position - reach, c.position + reach};
  return p;
}

StaticPrimitive capsule_primitive(const StaticCollider& c) {
  StaticPrimitive p;
  const Vector3d half = c.orientation.normalized() * Vector3d(0, 0, 0.5 * c.length);
  p.capsule = {c.position + half, c.position - half, c.radius};
  const Aabb core = bounds_of(p.capsule.a, p.capsule.b);
  p.bounds = {core.min.array() - c.radius, core.max.array() + c.radius};
  return p;
}

StaticPrimitive triangle_primitive(const StaticCollider& c, std::size_t t) {
  StaticPrimitive p;
  const auto& indices = c.mesh.triangles[t];
  for (std::size_t k = 0; k < 3; ++k) p.vertices[k] = c.mesh.vertices[indices[k]];
  p.face_normal = (p.vertices[1] - p.vertices[0]).cross(p.vertices[2] - p.vertices[0]).normalized();
  p.thickness = c.thickness;
  p.triangle = static_cast<std::uint32_t>(t);
  p.bounds = merged(bounds_of(p.vertices[0], p.vertices[1]), bounds_of(p.vertices[2], p.vertices[2]));
  // The volume behind the face within the thickness is the triangle's too: grow the box over it.
  p.bounds = merged(p.bounds, {p.bounds.min - c.thickness * p.face_normal, p.bounds.max - c.thickness * p.face_normal});
  return p;
}

}  // namespace

SurfacePoint box_surface_point(const Obb& box, const Vector3d& p) {
  const Vector3d local = box.rotation.transpose() * (p - box.centre);
  const Vector3d clamped = local.cwiseMax(-box.half_extents).cwiseMin(box.half_extents);
  SurfacePoint result;
  if (clamped != local) {
    result.point = box.centre + box.rotation * clamped;
    const Vector3d out = p - result.point;
    result.distance = out.norm();
    result.normal = out / result.distance;
    return result;
  }
  // Inside (or on the surface): out through the nearest face.
  int axis = 0;
  Eigen::Vector3d room = box.half_extents - local.cwiseAbs();
  for (int k = 1; k < 3; ++k) {
    if (room[k] < room[axis]) axis = k;
  }
  const double side = local[axis] < 0 ? -1.0 : 1.0;
  Vector3d on_face = local;
  on_face[axis] = side * box.half_extents[axis];
  result.point = box.centre + box.rotation * on_face;
  result.normal = side * box.rotation.col(axis);
  result.distance = -room[axis];
  return result;
}

SurfacePoint capsule_surface_point(const Capsule& capsule, const Vector3d& p) {
  const Vector3d axis = capsule.a - capsule.b;
  const double length_squared = axis.squaredNorm();
  const double s = length_squared > 0 ? std::clamp((p - capsule.b).dot(axis) / length_squared, 0.0, 1.0) : 0.0;
  const Vector3d core = capsule.b + s * axis;
  const Vector3d out = p - core;
  const double distance = out.norm();
  SurfacePoint result;
  if (distance > 0) {
    result.normal = out / distance;
  } else if (length_squared > 0) {
    result.normal = axis.unitOrthogonal();
  }  // else a sphere's centre: +z
  result.point = core + capsule.radius * result.normal;
  result.distance = distance - capsule.radius;
  return result;
}

Vector3d closest_point_on_triangle(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& p) {
  // Ericson 5.1.5: which Voronoi region of the triangle holds p.
  const Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denominator = 1.0 / (va + vb + vc);
  return a + ab * (vb * denominator) + ac * (vc * denominator);
}

std::optional<SurfacePoint> triangle_surface_point(const std::array<Vector3d, 3>& t, const Vector3d& n, double thickness,
                                                   const Vector3d& p) {
  const double height = n.dot(p - t[0]);  // m, signed: > 0 in front
  SurfacePoint result;
  if (height <= 0) {
    // Behind: only through the face, and only within the thickness.
    if (height < -thickness || !projects_inside(t, n, p)) return std::nullopt;
    result.point = p - height * n;
    result.normal = n;
    result.distance = height;
    return result;
  }
  result.point = closest_point_on_triangle(t[0], t[1], t[2], p);
  const Vector3d out = p - result.point;
  result.distance = out.norm();
  result.normal = out / result.distance;  // > 0: p is off the plane
  return result;
}

double segment_closest_to_triangle(const Vector3d& p0, const Vector3d& p1, const std::array<Vector3d, 3>& t,
                                   const Vector3d& n) {
  // A segment that crosses the triangle is nearest (distance 0) where it crosses.
  const double h0 = n.dot(p0 - t[0]), h1 = n.dot(p1 - t[0]);
  if ((h0 <= 0 && h1 >= 0) || (h0 >= 0 && h1 <= 0)) {
    const double s = h0 == h1 ? 0.5 : h0 / (h0 - h1);
    if (projects_inside(t, n, p0 + s * (p1 - p0))) return s;
  }
  // Otherwise the nearest pair has an end of the segment or a point of an edge.
  double best_s = 0;
  double best = (p0 - closest_point_on_triangle(t[0], t[1], t[2], p0)).squaredNorm();
  const double at_end = (p1 - closest_point_on_triangle(t[0], t[1], t[2], p1)).squaredNorm();
  if (at_end < best) best = at_end, best_s = 1;
  for (std::size_t k = 0; k < 3; ++k) {
    const SegmentClosestPoints edge = closest_points_between_segments(p0, p1, t[k], t[(k + 1) % 3]);
    if (edge.distance * edge.distance < best) best = edge.distance * edge.distance, best_s = edge.s;
  }
  return best_s;
}

std::optional<SurfacePoint> surface_point(const StaticPrimitive& primitive, const Vector3d& p) {
  switch (primitive.type) {
    case ColliderType::box: return box_surface_point(primitive.box, p);
    case ColliderType::capsule: return capsule_surface_point(primitive.capsule, p);
    case ColliderType::mesh: return triangle_surface_point(primitive.vertices, primitive.face_normal, primitive.thickness, p);
  }
  return std::nullopt;
}

StaticTree::StaticTree(const std::vector<StaticCollider>& colliders) {
  for (std::size_t c = 0; c < colliders.size(); ++c) {
    const StaticCollider& collider = colliders[c];
    const auto add = [&](StaticPrimitive primitive) {
      primitive.type = collider.type;
      primitive.collider = static_cast<std::uint32_t>(c);
      primitive.friction = collider.friction, primitive.restitution = collider.restitution;
      primitive.filter = collider.collision;
      primitive.sphere.centre = 0.5 * (primitive.bounds.min + primitive.bounds.max);
      primitive.sphere.radius = 0.5 * (primitive.bounds.max - primitive.bounds.min).norm();
      primitives_.push_back(primitive);
    };
    switch (collider.type) {
      case ColliderType::box: add(box_primitive(collider)); break;
      case ColliderType::capsule: add(capsule_primitive(collider)); break;
      case ColliderType::mesh:
        for (std::size_t t = 0; t < collider.mesh.triangles.size(); ++t) add(triangle_primitive(collider, t));
        break;
    }
  }
  if (primitives_.empty()) return;
  // A balanced binary tree of n leaves-of-≤4 has fewer than 2n nodes.
  nodes_.reserve(2 * primitives_.size());
  nodes_.emplace_back();
  build(0, 0, static_cast<std::uint32_t>(primitives_.size()));
}

void StaticTree::build(std::uint32_t node, std::uint32_t begin, std::uint32_t end) {
  Aabb bounds = primitives_[begin].bounds;
  Aabb centres{bounds.min + bounds.max, bounds.min + bounds.max};  // 2 × centre: no halving needed to compare
  for (std::uint32_t k = begin + 1; k < end; ++k) {
    const Aabb& b = primitives_[k].bounds;
    bounds = merged(bounds, b);
    centres = merged(centres, bounds_of(b.min + b.max, b.min + b.max));
  }
  nodes_[node].bounds = bounds;
  if (end - begin <= kLeafPrimitives) {
    nodes_[node].first = begin, nodes_[node].count = end - begin;
    return;
  }
  int axis = 0;
  const Vector3d spread = centres.max - centres.min;
  for (int k = 1; k < 3; ++k) {
    if (spread[k] > spread[axis]) axis = k;
  }
  // Median split. The order is strict (ties broken by collider and triangle), so the halves hold the
  // same primitives whatever order the colliders came in.
  const std::uint32_t middle = begin + (end - begin) / 2;
  const auto before = [axis](const StaticPrimitive& a, const StaticPrimitive& b) {
    const double ca = a.bounds.min[axis] + a.bounds.max[axis], cb = b.bounds.min[axis] + b.bounds.max[axis];
    if (ca != cb) return ca < cb;
    return a.collider != b.collider ? a.collider < b.collider : a.triangle < b.triangle;
  };
  std::nth_element(primitives_.begin() + begin, primitives_.begin() + middle, primitives_.begin() + end, before);
  const auto left = static_cast<std::uint32_t>(nodes_.size());
  nodes_.emplace_back();
  nodes_.emplace_back();
  nodes_[node].first = left, nodes_[node].count = 0;
  build(left, begin, middle);
  build(left + 1, middle, end);
}

}  // namespace limber
