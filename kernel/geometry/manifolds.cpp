#include "limber/kernel/geometry/manifolds.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "limber/kernel/geometry/separating_axis.hpp"

namespace limber {
namespace {

using Eigen::Vector3d;

// A segment within this sine (3°) of a face's plane lies along it: it touches along its length.
constexpr double kAlongFaceSine = 0.0523;
// Below this (m), the capsule's core meets the box: the overlap is found by axes, not distance.
constexpr double kCoreTouches = 1e-12;

// Which feature made a point, for ManifoldPoint::id: the kind of contact in bits 16–17, then its
// own fields.
enum class Feature : std::uint32_t { vertex = 0, face = 1, edges = 2 };
std::uint32_t feature_id(Feature kind, std::uint32_t fields) { return static_cast<std::uint32_t>(kind) << 16 | fields; }

// A box's face as an index 0–5: its axis and whether it is the + side.
std::uint32_t face_index(int axis, double sign) { return static_cast<std::uint32_t>(2 * axis + (sign > 0 ? 1 : 0)); }

// --- Clipping (Sutherland–Hodgman) ---------------------------------------------------------------

// A vertex of the incident face as it is clipped. `code`: an incident vertex 0–3; an incident
// edge e cut by side s, 4 + 4e + s; two sides q and s meeting (a corner of the reference face),
// 20 + 4q + s. `edge_out`: what the polygon's edge leaving it lies on, an incident edge 0–3 or a
// side 4 + s.
struct ClipVertex {
  Vector3d x = Vector3d::Zero();
  int code = 0;
  int edge_out = 0;
};
struct ClipPolygon {
  std::array<ClipVertex, 8> vertices{};  // a quadrilateral cut by four sides has at most 8
  int count = 0;
};

int cut_code(int edge_out, int side) { return edge_out < 4 ? 4 + 4 * edge_out + side : 20 + 4 * (edge_out - 4) + side; }

// The part of `in` with direction·x ≤ limit.
ClipPolygon clip(const ClipPolygon& in, const Vector3d& direction, double limit, int side) {
  ClipPolygon out;
  for (int i = 0; i < in.count; ++i) {
    const ClipVertex& a = in.vertices[static_cast<std::size_t>(i)];
    const ClipVertex& b = in.vertices[static_cast<std::size_t>((i + 1) % in.count)];
    const double da = direction.dot(a.x) - limit, db = direction.dot(b.x) - limit;
    if (da <= 0) out.vertices[static_cast<std::size_t>(out.count++)] = a;
    if ((da <= 0) == (db <= 0)) continue;
    ClipVertex cut;
    cut.x = a.x + (da / (da - db)) * (b.x - a.x);
    cut.code = cut_code(a.edge_out, side);
    cut.edge_out = da <= 0 ? 4 + side : a.edge_out;  // leaving: along the side; entering: along a's edge
    out.vertices[static_cast<std::size_t>(out.count++)] = cut;
  }
  return out;
}

// --- Reduction -----------------------------------------------------------------------------------

struct PointCandidate {
  Vector3d x = Vector3d::Zero();  // on the incident surface
  double separation = 0;
  std::uint32_t id = 0;
};

// Up to four of `candidates` that span them most (plane normal `normal`): the deepest, the one
// farthest from it, then the two on either side of that line that make the widest triangles.
int reduce(std::array<PointCandidate, 8>& candidates, int count, const Vector3d& normal) {
  if (count <= Manifold::kMaxPoints) return count;
  const auto index = [&](auto score) {  // the remaining candidate of the highest score
    int best = -1;
    double best_score = -std::numeric_limits<double>::infinity();
    for (int i = 0; i < count; ++i) {
      const double value = score(candidates[static_cast<std::size_t>(i)]);
      if (value > best_score) best_score = value, best = i;
    }
    return best;
  };
  std::array<PointCandidate, 4> kept;
  const auto take = [&](int k, int i) {
    kept[static_cast<std::size_t>(k)] = candidates[static_cast<std::size_t>(i)];
    candidates[static_cast<std::size_t>(i)] = candidates[static_cast<std::size_t>(--count)];
  };
  take(0, index([](const PointCandidate& c) { return -c.separation; }));
  const Vector3d a = kept[0].x;
  take(1, index([&](const PointCandidate& c) { return (c.x - a).squaredNorm(); }));
  const Vector3d b = kept[1].x;
  const auto area = [&](const PointCandidate& c) { return (b - a).cross(c.x - a).dot(normal); };
  take(2, index(area));
  take(3, index([&](const PointCandidate& c) { return -area(c); }));
  std::copy(kept.begin(), kept.end(), candidates.begin());
  return Manifold::kMaxPoints;
}

// --- Box pairs -----------------------------------------------------------------------------------

// The face case of box_box_manifold: the reference face is the face of the box whose face normal
// the test chose that looks at the other box; the incident face the other box's face most against it.
void face_points(const Obb& first, const Obb& second, const SeparatingAxisResult& sat, double margin, Manifold& manifold) {
  const bool first_is_reference = sat.axis.kind == BoxAxis::Kind::first_face;
  const Obb& reference = first_is_reference ? first : second;
  const Obb& incident = first_is_reference ? second : first;
  const int k = first_is_reference ? sat.axis.first : sat.axis.second;
  const Vector3d towards = first_is_reference ? Vector3d(-sat.normal) : sat.normal;  // reference → incident
  const double reference_sign = reference.rotation.col(k).dot(towards) >= 0 ? 1.0 : -1.0;
  const Vector3d face_normal = reference_sign * reference.rotation.col(k);
  const Vector3d face_centre = reference.centre + reference_sign * reference.half_extents[k] * reference.rotation.col(k);

  int m = 0;
  (incident.rotation.transpose() * face_normal).cwiseAbs().maxCoeff(&m);
  const double incident_sign = incident.rotation.col(m).dot(face_normal) > 0 ? -1.0 : 1.0;
  const int u = (m + 1) % 3, v = (m + 2) % 3;
  const Vector3d centre = incident.centre + incident_sign * incident.half_extents[m] * incident.rotation.col(m);
  const Vector3d du = incident.half_extents[u] * incident.rotation.col(u), dv = incident.half_extents[v] * incident.rotation.col(v);
  ClipPolygon polygon;
  polygon.count = 4;
  polygon.vertices = {{{centre + du + dv, 0, 0}, {centre - du + dv, 1, 1}, {centre - du - dv, 2, 2}, {centre + du - dv, 3, 3}}};

  // The reference face's four sides: ±its other two axes, at their half-extents.
  for (int side = 0; side < 4; ++side) {
    const int axis = (k + 1 + side / 2) % 3;
    const Vector3d direction = (side % 2 == 0 ? 1.0 : -1.0) * reference.rotation.col(axis);
    polygon = clip(polygon, direction, direction.dot(reference.centre) + reference.half_extents[axis], side);
  }

  const std::uint32_t faces = (first_is_reference ? 1U : 0U) << 14 | face_index(k, reference_sign) << 11 | face_index(m, incident_sign) << 8;
  std::array<PointCandidate, 8> candidates;
  int count = 0;
  for (int i = 0; i < polygon.count; ++i) {
    const ClipVertex& vertex = polygon.vertices[static_cast<std::size_t>(i)];
    const double separation = face_normal.dot(vertex.x - face_centre);
    if (separation > margin) continue;
    candidates[static_cast<std::size_t>(count++)] = {vertex.x, separation, feature_id(Feature::face, faces | static_cast<std::uint32_t>(vertex.code))};
  }
  count = reduce(candidates, count, face_normal);
  for (int i = 0; i < count; ++i) {
    const PointCandidate& c = candidates[static_cast<std::size_t>(i)];
    // Midway between the incident point and its foot on the reference face.
    manifold.points[static_cast<std::size_t>(i)] = {c.x - 0.5 * c.separation * face_normal, c.separation, c.id};
  }
  manifold.count = count;
}

// A box's edge along its axis `axis` that reaches farthest along `direction`, as its two ends,
// and an index of it (its axis and the signs of the other two half-extents: 0–11).
struct BoxEdge {
  Vector3d a, b;
  std::uint32_t index = 0;
};
BoxEdge supporting_edge(const Obb& box, int axis, const Vector3d& direction) {
  Vector3d middle = box.centre;
  std::uint32_t signs = 0;
  for (int step = 1; step <= 2; ++step) {
    const int other = (axis + step) % 3;
    const bool positive = box.rotation.col(other).dot(direction) >= 0;
    middle += (positive ? 1.0 : -1.0) * box.half_extents[other] * box.rotation.col(other);
    signs |= (positive ? 1U : 0U) << (step - 1);
  }
  const Vector3d half = box.half_extents[axis] * box.rotation.col(axis);
  return {middle - half, middle + half, static_cast<std::uint32_t>(4 * axis) + signs};
}

// --- Capsule and box -----------------------------------------------------------------------------

// The segment p(s) = p0 + s·d, s ∈ [0, 1], against the box |x_k| ≤ h_k, in the box's frame: the s
// nearest the box. The squared distance Σ_k max(|p_k(s)| − h_k, 0)² is convex and quadratic
// between the s where a coordinate crosses ±h_k, so each piece's minimum is exact.
double nearest_parameter(const Vector3d& p0, const Vector3d& d, const Vector3d& h) {
  std::array<double, 8> breaks{0.0, 1.0};
  int count = 2;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0) continue;
    for (const double limit : {-h[k], h[k]}) {
      const double s = (limit - p0[k]) / d[k];
      if (s > 0 && s < 1) breaks[static_cast<std::size_t>(count++)] = s;
    }
  }
  std::sort(breaks.begin(), breaks.begin() + count);
  const auto distance_squared = [&](double s) {
    const Vector3d p = p0 + s * d;
    return (p.cwiseAbs() - h).cwiseMax(0.0).squaredNorm();
  };
  double best_s = 0, best = distance_squared(0);
  for (int i = 0; i + 1 < count; ++i) {
    const double lo = breaks[static_cast<std::size_t>(i)], hi = breaks[static_cast<std::size_t>(i + 1)];
    const Vector3d middle = p0 + 0.5 * (lo + hi) * d;
    double slope = 0, curvature = 0;  // of ½Σ(p_k(s) − σ_k h_k)² over the coordinates outside
    for (int k = 0; k < 3; ++k) {
      if (std::abs(middle[k]) <= h[k]) continue;
      const double bound = middle[k] > 0 ? h[k] : -h[k];
      slope += (p0[k] - bound) * d[k], curvature += d[k] * d[k];
    }
    const double s = curvature > 0 ? std::clamp(-slope / curvature, lo, hi) : 0.5 * (lo + hi);
    const double value = distance_squared(s);
    if (value < best) best = value, best_s = s;
  }
  if (distance_squared(1) < best) best_s = 1;
  return best_s;
}

// The capsule's core p0 + t·d (box frame) clipped to face k's rectangle (σ its side): two points,
// each with its separation from the face less the radius. False when nothing of it is over the face.
bool along_face(const Capsule& capsule, const Obb& box, const Vector3d& p0, const Vector3d& d, int k, double sigma, double margin,
                Manifold& manifold) {
  const Vector3d& h = box.half_extents;
  double lo = 0, hi = 1;
  for (int step = 1; step <= 2; ++step) {
    const int axis = (k + step) % 3;
    if (d[axis] == 0) {
      if (std::abs(p0[axis]) > h[axis]) return false;
      continue;
    }
    const double a = (-h[axis] - p0[axis]) / d[axis], b = (h[axis] - p0[axis]) / d[axis];
    lo = std::max(lo, std::min(a, b)), hi = std::min(hi, std::max(a, b));
  }
  if (lo > hi) return false;
  manifold.normal = sigma * box.rotation.col(k);
  manifold.count = 0;
  for (const double t : {lo, hi}) {
    const Vector3d local = p0 + t * d;
    const double separation = sigma * local[k] - h[k] - capsule.radius;
    if (separation > margin) continue;
    const Vector3d core = box.centre + box.rotation * local;
    const Vector3d surface = core - capsule.radius * manifold.normal;
    manifold.points[static_cast<std::size_t>(manifold.count++)] = {surface - 0.5 * separation * manifold.normal, separation,
                                                                   feature_id(Feature::face, t == lo ? 0U : 1U)};
  }
  return true;
}

// Where the core meets the box: the axis of least overlap among the box's faces and the core's
// crosses with the box's edges (the separating-axis test of a segment and a box), as a unit axis
// in the box's frame pointing from the box to the core, the overlap, and a face index or −1.
struct CoreAxis {
  Vector3d axis = Vector3d::UnitZ();
  double overlap = std::numeric_limits<double>::infinity();
  int face = -1;
};
CoreAxis least_overlap(const Vector3d& p0, const Vector3d& d, const Vector3d& h) {
  CoreAxis face, edge;
  const auto consider = [&](CoreAxis& best, const Vector3d& axis, int index) {
    const double a = axis.dot(p0), b = axis.dot(p0 + d);
    const double radius = h.dot(axis.cwiseAbs());
    const double up = radius - std::min(a, b), down = std::max(a, b) + radius;  // moves that clear it along ±axis
    const double overlap = std::min(up, down);
    if (overlap < best.overlap) best = {up <= down ? axis : Vector3d(-axis), overlap, index};
  };
  for (int k = 0; k < 3; ++k) consider(face, Vector3d::Unit(k), k);
  for (int k = 0; k < 3; ++k) {
    const Vector3d across = d.cross(Vector3d::Unit(k));
    if (across.norm() > 1e-6 * d.norm()) consider(edge, across.normalized(), -1);
  }
  return edge.overlap < kEdgeAxisPreference * face.overlap ? edge : face;
}

}  // namespace

Manifold box_plane_manifold(const Obb& box, const Plane& plane, double margin) {
  Manifold manifold;
  manifold.normal = plane.normal;
  std::array<PointCandidate, 8> found;
  int count = 0;
  for (std::uint32_t corner = 0; corner < 8; ++corner) {
    const Vector3d local((corner & 1U) ? box.half_extents.x() : -box.half_extents.x(), (corner & 2U) ? box.half_extents.y() : -box.half_extents.y(),
                         (corner & 4U) ? box.half_extents.z() : -box.half_extents.z());
    const Vector3d x = box.centre + box.rotation * local;
    const double separation = plane.normal.dot(x) - plane.offset;
    if (separation <= margin) found[static_cast<std::size_t>(count++)] = {x, separation, feature_id(Feature::vertex, corner)};
  }
  // The deepest four: a box within the margin of a plane with more than four corners is thinner
  // than the margin, and its lower face's corners are what touch.
  std::stable_sort(found.begin(), found.begin() + count, [](const PointCandidate& a, const PointCandidate& b) { return a.separation < b.separation; });
  manifold.count = std::min(count, Manifold::kMaxPoints);
  for (int i = 0; i < manifold.count; ++i) {
    const PointCandidate& c = found[static_cast<std::size_t>(i)];
    manifold.points[static_cast<std::size_t>(i)] = {c.x - 0.5 * c.separation * plane.normal, c.separation, c.id};
  }
  return manifold;
}

Manifold box_box_manifold(const Obb& first, const Obb& second, double margin) {
  Manifold manifold;
  const SeparatingAxisResult sat = separating_axis_test(first, second, true, margin);
  if (!sat.overlap) return manifold;
  manifold.normal = sat.normal;
  if (sat.axis.kind != BoxAxis::Kind::edges) {
    face_points(first, second, sat, margin, manifold);
    return manifold;
  }
  // The two edges that cross: each box's edge along its axis reaching farthest towards the other.
  const BoxEdge a = supporting_edge(first, sat.axis.first, -sat.normal);
  const BoxEdge b = supporting_edge(second, sat.axis.second, sat.normal);
  const SegmentClosestPoints closest = closest_points_between_segments(a.a, a.b, b.a, b.b);
  manifold.count = 1;
  manifold.points[0] = {0.5 * (closest.on_first + closest.on_second), -sat.depth, feature_id(Feature::edges, a.index << 4 | b.index)};
  return manifold;
}

Manifold capsule_box_manifold(const Capsule& capsule, const Obb& box, double margin) {
  Manifold manifold;
  const Vector3d p0 = box.rotation.transpose() * (capsule.a - box.centre);
  const Vector3d d = box.rotation.transpose() * (capsule.b - capsule.a);
  const Vector3d& h = box.half_extents;
  const double length = d.norm();
  const auto along = [&](int k) { return length > 0 && std::abs(d[k]) < kAlongFaceSine * length; };
  // One point: the core's point at t, the normal (box frame, from the box to the core), its separation.
  const auto one_point = [&](double t, const Vector3d& normal, double separation) {
    manifold.normal = box.rotation * normal;
    const Vector3d surface = box.centre + box.rotation * (p0 + t * d) - capsule.radius * manifold.normal;
    manifold.points[0] = {surface - 0.5 * separation * manifold.normal, separation, feature_id(Feature::face, 2U)};
    manifold.count = 1;
    return manifold;
  };

  const double s = nearest_parameter(p0, d, h);
  const Vector3d p = p0 + s * d;
  const Vector3d nearest = p.cwiseMax(-h).cwiseMin(h);
  const double distance = (p - nearest).norm();
  if (distance > kCoreTouches) {
    if (distance - capsule.radius > margin) return manifold;
    // Over one face (one coordinate outside), along it: the core clipped to the face.
    int outside = 0, face = 0;
    for (int k = 0; k < 3; ++k) {
      if (std::abs(p[k]) > h[k]) ++outside, face = k;
    }
    if (outside == 1 && along(face) && along_face(capsule, box, p0, d, face, p[face] > 0 ? 1.0 : -1.0, margin, manifold)) return manifold;
    return one_point(s, (p - nearest) / distance, distance - capsule.radius);
  }
  const CoreAxis axis = least_overlap(p0, d, h);
  // The core's point deepest against the normal: an end, or the middle of a core square to it.
  const double lean = axis.axis.dot(d);
  const double t = std::abs(lean) <= 1e-12 * length ? 0.5 : (lean > 0 ? 0.0 : 1.0);
  const Vector3d deepest = p0 + t * d;
  // Along the face with its deepest point over it: the face's clip keeps that depth.
  if (axis.face >= 0 && along(axis.face)) {
    const int u = (axis.face + 1) % 3, v = (axis.face + 2) % 3;
    if (std::abs(deepest[u]) <= h[u] && std::abs(deepest[v]) <= h[v] &&
        along_face(capsule, box, p0, d, axis.face, axis.axis[axis.face] > 0 ? 1.0 : -1.0, margin, manifold)) {
      return manifold;
    }
  }
  return one_point(t, axis.axis, axis.axis.dot(deepest) - h.dot(axis.axis.cwiseAbs()) - capsule.radius);
}

}  // namespace limber
