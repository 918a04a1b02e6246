// Continuous collision of a sphere moving in a straight line: when, along its path over a step,
// it first touches a limb or a static collider (the time of impact). What a method that finds
// contacts only where bodies overlap at the end of a step needs against tunnelling: a ball at
// 100 m/s moves 1.7 m in a 1/60 s step, across a 4 cm limb or a thin box with no step ending
// inside it.
//
// The sphere's centre moves from `from` (t = 0) to `to` (t = 1); the time of impact is the first
// t ∈ [0, 1] at which its surface touches the shape, that is the first t at which the centre
// enters the shape grown by the sphere's radius (the Minkowski sum). Each grown shape is cut into
// pieces the path can be tested against in closed form (Ericson, "Real-Time Collision Detection",
// 2005: 5.3.2 ray–sphere, 5.3.7 ray–cylinder, 5.5.7 moving sphere against a box):
// - a capsule grown by r is a capsule of radius r_capsule + r: its side (an infinite cylinder,
//   where the crossing's axial parameter lies on the segment) and its two end spheres;
// - a box grown by r is the union of the box grown by r along one of its axes only (three boxes,
//   by slabs) and the capsules of radius r on its twelve edges (its corners are their ends);
// - a one-sided triangle (static_geometry.hpp) grown by r, from its front: its face raised by r
//   along its normal where the path's point projects inside it, and the capsules on its edges;
// - a cylinder limb (solid, flat ends; geometry.hpp's sphere_limb_contact) grown by r has rounded
//   rims (tori, quartic), so it is found by search: the capsule around it (which holds it) gives
//   a time no later than the true one, conservative advancement (Mirtich 1996) steps on from
//   there by the separation over the path's length, which never passes the touch, and where that
//   is slow (a glancing path), golden-section search finds the path's closest approach (the
//   separation is convex along a line) and bisection the first touch before it.
// All are exact up to round-off (the cylinder to 1e-9 m of separation). Shapes hold still over the
// step: a method sweeps a moving sphere against a limb at one pose of the limb.
#pragma once

#include <array>

#include <Eigen/Core>

#include "limber/kernel/geometry/bounding_volumes.hpp"
#include "limber/kernel/geometry/shape_pairs.hpp"
#include "limber/kernel/geometry/static_geometry.hpp"
#include "limber/kernel/model/model.hpp"

namespace limber {

/// When a sphere moving from `from` (t = 0) to `to` (t = 1) first touches a shape.
struct TimeOfImpact {
  bool hit = false;  ///< it touches (or overlaps) the shape at some t ∈ [0, 1]
  double time = 1;   ///< the first such t; 0 when it already touches or overlaps at the start
};

/// Against the capsule of core segment a–b (a point when a == b) and `capsule_radius` (m):
/// exact.
TimeOfImpact sphere_capsule_time_of_impact(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double radius,
                                           const Eigen::Vector3d& a, const Eigen::Vector3d& b, double capsule_radius);

/// Against a limb (axis head → tail, `shape` of radius `limb_radius`, m) as sphere_limb_contact
/// sees it: a capsule exactly; a cylinder, solid with flat ends, by search to 1e-9 m of
/// separation, never later than the touch.
TimeOfImpact sphere_limb_time_of_impact(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double radius,
                                        const Eigen::Vector3d& head, const Eigen::Vector3d& tail, ShapeType shape,
                                        double limb_radius);

/// Against a solid box: exact.
TimeOfImpact sphere_box_time_of_impact(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double radius, const Obb& box);

/// Against the one-sided triangle a, b, c (`face_normal` unit, out of its front): exact, for a
/// sphere whose centre starts in front of the triangle's plane or on it (a centre behind it is
/// the triangle's thickness rule's, triangle_surface_point: no hit); touches on an edge count
/// only where the centre is not behind the plane, as triangle_surface_point answers only those.
TimeOfImpact sphere_triangle_time_of_impact(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double radius,
                                            const std::array<Eigen::Vector3d, 3>& triangle,
                                            const Eigen::Vector3d& face_normal);

/// Against a limb's convex shape (shape_pairs.hpp): a capsule's and a box's exact, as above; any
/// other's (an ellipsoid) by conservative advancement on the shape-pair table's separation, from
/// the touch of its bounding sphere, to 1e-9 m of separation, never later than the touch.
TimeOfImpact sphere_shape_time_of_impact(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double radius,
                                         const PlacedShape& shape);

/// Against a static primitive (a box, a capsule or a mesh triangle), as the functions above.
TimeOfImpact sphere_static_time_of_impact(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double radius,
                                          const StaticPrimitive& primitive);

/// The ball's continuous collision, every method alike (answer_at_touch): kSweptDepth ball
/// radii is how deep the ball may end a step in a shape for a test of overlap at the step's end
/// to answer the touch; kSweptSlop radii is how far a shape may be overlapped at the path's start
/// (deeper is the push-out's) and how far the rest of the path must approach a surface for its
/// touch to count (less is a sphere sliding along it).
inline constexpr double kSweptDepth = 0.5, kSweptSlop = 0.01;

/// Whether a sphere of `radius` (m) whose path (to − from, m) touches a shape at `time` with
/// `normal` (unit, towards the sphere) there needs that touch answered where it happens: the
/// rest of the path approaches the surface by more than kSweptSlop radii, and a test of overlap
/// at the path's end will not answer it — the sphere does not end overlapping the shape by at
/// most kSweptDepth radii with that contact's normal against the path (`end_separation`, m, and
/// `end_normal` there; +∞ where the shape does not answer the end point). So a ball that passes
/// through a shape, grazes it between two steps, ends deep in it or beyond its middle is
/// answered at its touch; one that ends just inside, on the side it came from, as before.
inline bool answer_at_touch(const Eigen::Vector3d& path, double time, const Eigen::Vector3d& normal, double radius,
                            double end_separation, const Eigen::Vector3d& end_normal) {
  if (!(-normal.dot(path) * (1 - time) > kSweptSlop * radius)) return false;
  const bool end_answers = end_separation < 0 && end_separation >= -kSweptDepth * radius && end_normal.dot(path) < 0;
  return !end_answers;
}

/// The earliest touch on a sphere's path that needs answering there (answer_at_touch).
struct SweptTouch {
  double time = 2;  ///< ∈ [0, 1] along the path; > 1: none
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit, from the shape towards the centre, at the touch
  double separation = 0;  ///< m, at the touch: ≈ 0 (< 0 when the sphere started overlapping)

  bool found() const { return time <= 1; }
  /// Keeps a touch at `touch_time` with `touch_normal` and `touch_separation` there if it is
  /// earlier than the one held.
  void keep_if_earlier(double touch_time, const Eigen::Vector3d& touch_normal, double touch_separation) {
    if (!(touch_time < time)) return;
    time = touch_time, normal = touch_normal, separation = touch_separation;
  }
};

}  // namespace limber
