#include "limber/kernel/geometry/time_of_impact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "limber/kernel/geometry/geometry.hpp"
#include "limber/kernel/geometry/golden_section.hpp"

namespace limber {
namespace {

using Eigen::Vector3d;

constexpr double kNever = std::numeric_limits<double>::infinity();

// The cylinder's search: separation within which the sphere touches, m, and the steps of each stage.
constexpr double kTouchTolerance = 1e-9;
constexpr int kAdvanceSteps = 16, kGoldenSteps = 60, kBisectionSteps = 60;

TimeOfImpact at(double time) { return time <= 1 ? TimeOfImpact{true, std::max(time, 0.0)} : TimeOfImpact{}; }

// The smaller root of A·t² + 2B·t + C = 0 for a point outside (C > 0) approaching (B < 0), in the
// form without cancellation (the roots' product is C/A); kNever when it does not reach the surface.
double entry_root(double a, double b, double c) {
  if (!(b < 0)) return kNever;
  const double discriminant = b * b - a * c;
  if (discriminant < 0) return kNever;
  return c / (-b + std::sqrt(discriminant));
}

// First t ≥ 0 at which o + t·d is within `radius` of `centre` (Ericson 5.3.2); 0 when it starts inside.
double sphere_entry(const Vector3d& o, const Vector3d& d, const Vector3d& centre, double radius) {
  const Vector3d m = o - centre;
  const double c = m.squaredNorm() - radius * radius;
  if (c <= 0) return 0;
  return entry_root(d.squaredNorm(), m.dot(d), c);
}

// First t ≥ 0 at which o + t·d is within `radius` of segment a–b; 0 when it starts inside. The
// side: the infinite cylinder about the axis, where the crossing's axial parameter is on the
// segment (Ericson 5.3.7); a path that enters the infinite cylinder beyond an end is then within
// `radius` of that end before it reaches the segment's span, so the end spheres hold the rest.
double segment_entry(const Vector3d& o, const Vector3d& d, const Vector3d& a, const Vector3d& b, double radius) {
  const Vector3d u = b - a;
  const double uu = u.squaredNorm();
  const Vector3d m = o - a;
  const double s0 = uu > 0 ? std::clamp(m.dot(u) / uu, 0.0, 1.0) : 0.0;
  if ((m - s0 * u).squaredNorm() <= radius * radius) return 0;
  double first = std::min(sphere_entry(o, d, a, radius), sphere_entry(o, d, b, radius));
  if (uu > 0) {
    const Vector3d m_across = m - (m.dot(u) / uu) * u, d_across = d - (d.dot(u) / uu) * u;
    const double t = entry_root(d_across.squaredNorm(), m_across.dot(d_across), m_across.squaredNorm() - radius * radius);
    if (t < first) {
      const double s = (m + t * d).dot(u) / uu;
      if (s >= 0 && s <= 1) first = t;
    }
  }
  return first;
}

// First t ≥ 0 at which o + t·d is inside the axis-aligned box |x_k| ≤ half_k (slabs, Ericson 5.3.3).
double slab_entry(const Vector3d& o, const Vector3d& d, const Vector3d& half) {
  double enter = 0, leave = kNever;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) {
      if (std::abs(o[k]) > half[k]) return kNever;
      continue;
    }
    double near = (-half[k] - o[k]) / d[k], far = (half[k] - o[k]) / d[k];
    if (near > far) std::swap(near, far);
    enter = std::max(enter, near), leave = std::min(leave, far);
    if (enter > leave) return kNever;
  }
  return enter;
}

// The first t ∈ [t0, 1] at which separation(t) ≤ 0, for a separation that is convex in t and
// changes by at most `speed` per unit t (a distance along a straight path), and t0 no later than
// the touch: conservative advancement, then golden section for the minimum and bisection.
template <typename Separation>
double first_touch(Separation&& separation, double t0, double speed) {
  double t = t0, gap = separation(t);
  for (int k = 0; k < kAdvanceSteps && gap > kTouchTolerance; ++k) {
    t += gap / speed;
    if (t > 1) return kNever;
    gap = separation(t);
  }
  if (gap <= kTouchTolerance) return t;
  // Glancing: the closest approach on [t, 1] (convex, so unimodal), then the touch before it.
  const GoldenBracket closest =
      golden_section(separation, t, 1.0, kGoldenSteps, [](double f_left, double f_right) { return !(f_left > 0 && f_right > 0); });
  double inside = closest.f_left <= 0 ? closest.left : closest.f_right <= 0 ? closest.right : 1.0;
  if (inside == 1.0 && separation(1.0) > 0) return kNever;
  double outside = t;
  for (int k = 0; k < kBisectionSteps && separation(outside) > kTouchTolerance; ++k) {
    const double middle = 0.5 * (outside + inside);
    (separation(middle) <= 0 ? inside : outside) = middle;
  }
  return outside;
}

}  // namespace

TimeOfImpact sphere_capsule_time_of_impact(const Vector3d& from, const Vector3d& to, double radius, const Vector3d& a,
                                           const Vector3d& b, double capsule_radius) {
  return at(segment_entry(from, to - from, a, b, capsule_radius + radius));
}

TimeOfImpact sphere_limb_time_of_impact(const Vector3d& from, const Vector3d& to, double radius, const Vector3d& head,
                                        const Vector3d& tail, ShapeType shape, double limb_radius) {
  const TimeOfImpact around = sphere_capsule_time_of_impact(from, to, radius, head, tail, limb_radius);
  if (shape == ShapeType::capsule || limb_radius == 0 || !around.hit) return around;
  // The cylinder is inside the capsule around it: the capsule's touch comes no later.
  const Vector3d path = to - from;
  const auto separation = [&](double t) {
    return sphere_limb_contact(from + t * path, radius, head, tail, ShapeType::cylinder, limb_radius).separation;
  };
  if (separation(0) <= 0) return {true, 0};
  return at(first_touch(separation, around.time, path.norm()));
}

TimeOfImpact sphere_shape_time_of_impact(const Vector3d& from, const Vector3d& to, double radius, const PlacedShape& shape) {
  if (const auto* capsule = std::get_if<Capsule>(&shape)) return sphere_capsule_time_of_impact(from, to, radius, capsule->a, capsule->b, capsule->radius);
  if (const auto* box = std::get_if<Obb>(&shape)) return sphere_box_time_of_impact(from, to, radius, *box);
  // The bounding sphere about the shape's own centre (the support's midpoint along three axes).
  Vector3d centre;
  double bound = 0;
  for (int k = 0; k < 3; ++k) {
    const Vector3d axis = Vector3d::Unit(k);
    const auto extent = [&](const Vector3d& d) { return std::visit([&](const auto& s) { return support(s, d); }, shape); };
    const Vector3d high = extent(axis), low = extent(-axis);
    centre[k] = 0.5 * (high[k] + low[k]);
    bound = std::max(bound, 0.5 * (high[k] - low[k]));
  }
  bound *= std::sqrt(3.0);  // the box of the supports holds the shape, its half-diagonal bounds it
  const TimeOfImpact around = sphere_capsule_time_of_impact(from, to, radius, centre, centre, bound);
  if (!around.hit) return around;
  const Vector3d path = to - from;
  // Gaps past `margin` are not measured (GJK grows both shapes by it): taken as the margin,
  // which keeps the advancement conservative.
  const double margin = bound + radius;
  const auto separation = [&](double t) {
    const Vector3d p = from + t * path;
    const Manifold manifold = collide(Capsule{p, p, radius}, shape, margin);
    return manifold.count > 0 ? std::min(manifold.points[0].separation, margin) : margin;
  };
  if (separation(0) <= 0) return {true, 0};
  return at(first_touch(separation, around.time, path.norm()));
}

TimeOfImpact sphere_box_time_of_impact(const Vector3d& from, const Vector3d& to, double radius, const Obb& box) {
  if (box_surface_point(box, from).distance <= radius) return {true, 0};
  // In the box's frame: three boxes each grown along one axis, and the twelve edge capsules.
  const Vector3d o = box.rotation.transpose() * (from - box.centre), d = box.rotation.transpose() * (to - from);
  const Vector3d& h = box.half_extents;
  double first = kNever;
  for (int k = 0; k < 3; ++k) {
    Vector3d grown = h;
    grown[k] += radius;
    first = std::min(first, slab_entry(o, d, grown));
  }
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3, j = (k + 2) % 3;
    for (const double si : {-1.0, 1.0}) {
      for (const double sj : {-1.0, 1.0}) {
        Vector3d a = Vector3d::Zero();
        a[i] = si * h[i], a[j] = sj * h[j], a[k] = -h[k];
        Vector3d b = a;
        b[k] = h[k];
        first = std::min(first, segment_entry(o, d, a, b, radius));
      }
    }
  }
  return at(first);
}

TimeOfImpact sphere_triangle_time_of_impact(const Vector3d& from, const Vector3d& to, double radius,
                                            const std::array<Vector3d, 3>& triangle, const Vector3d& face_normal) {
  const double height = face_normal.dot(from - triangle[0]);  // m, > 0 in front
  if (height < 0) return {};
  if ((from - closest_point_on_triangle(triangle[0], triangle[1], triangle[2], from)).norm() <= radius) return {true, 0};
  const Vector3d path = to - from;
  double first = kNever;
  // The face, raised by the radius: reached while approaching, where the point projects inside.
  const double approach = -face_normal.dot(path);
  if (approach > 0 && height > radius) {
    const double t = (height - radius) / approach;
    if (t <= 1 && projects_inside(triangle, face_normal, from + t * path)) first = t;
  }
  for (std::size_t k = 0; k < 3; ++k) {
    const double t = segment_entry(from, path, triangle[k], triangle[(k + 1) % 3], radius);
    if (t < first && face_normal.dot(from + t * path - triangle[0]) >= 0) first = t;
  }
  return at(first);
}

TimeOfImpact sphere_static_time_of_impact(const Vector3d& from, const Vector3d& to, double radius,
                                          const StaticPrimitive& primitive) {
  switch (primitive.type) {
    case ColliderType::box: return sphere_box_time_of_impact(from, to, radius, primitive.box);
    case ColliderType::capsule:
      return sphere_capsule_time_of_impact(from, to, radius, primitive.capsule.a, primitive.capsule.b, primitive.capsule.radius);
    case ColliderType::mesh: return sphere_triangle_time_of_impact(from, to, radius, primitive.vertices, primitive.face_normal);
  }
  return {};
}

}  // namespace limber
