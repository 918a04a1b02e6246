// General convex pairs through libccd's GJK and EPA: the shapes without a closed form of
// limber's own (manifolds.hpp) — ellipsoids, cylinders as themselves, convex hulls of a mesh's
// vertices — against anything convex, as one contact point.
//
// Each shape is its support function s(d), the point of the shape farthest along d. libccd
// (Debian's libccd-dev 2.1, the library MuJoCo and FCL call) runs GJK to find whether the
// Minkowski difference holds the origin and EPA to find the least translation out of it
// (Gilbert, Johnson & Keerthi 1988; van den Bergen 2001). EPA's `epa_tolerance` is in m² — it
// stops when s·w − |w|² < tolerance, w the polytope's nearest point, |w| the depth — so its
// depth is good to tolerance / depth: at 10⁻¹⁰ m² exact on polyhedra and within 9 µm and 2° on
// curved pairs, where FCL's 10⁻⁶ was millimetres off (bench/collision.md, "Convex pairs").
// libccd has no distance query: both shapes are grown by half the margin (their support plus
// margin/2 along d, a Minkowski sum with a ball), so pairs within the margin overlap, and the
// separation is the grown depth less the margin. A grown surface sits margin/2 out along the
// normal on either side, so the midpoint between the surfaces is the grown one's. Grown, a
// polyhedron's edges are rounded: a gap within the margin is good to EPA's curved accuracy.
// Cost: 1.6–3.4 µs a pair on polyhedra, 3.5–7.8 µs on curved pairs, 10–40× limber's closed
// forms; and libccd's EPA allocates its polytope on the heap at every call, which a step that
// never allocates after its first (kernel/PIPELINE.md, `reserve_scratch`) cannot take as it is.
#pragma once

#include <span>

#include <Eigen/Core>

#include "limber/kernel/geometry/bounding_volumes.hpp"
#include "limber/kernel/geometry/manifolds.hpp"

namespace limber {

/// The points centre + rotation·y with Σ_k (y_k / semi_axes_k)² ≤ 1.
struct Ellipsoid {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();       ///< m
  Eigen::Vector3d semi_axes = Eigen::Vector3d::Zero();    ///< m, > 0, along the rotation's columns
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< columns: its axes in world
};

/// A solid cylinder: radius about the rotation's third column, flat ends at ±half_length along it.
struct Cylinder {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();        ///< m, the middle of the axis
  double radius = 0;                                       ///< m, > 0
  double half_length = 0;                                  ///< m, ≥ 0
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< column 2: the axis in world
};

/// The convex hull of `vertices` (in its own frame, m; at least one), placed at centre +
/// rotation·y. The vertices are the caller's and must outlive the hull.
struct ConvexHull {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  std::span<const Eigen::Vector3d> vertices;
};

/// Support functions: the point of the shape farthest along `direction` (world, non-zero).
Eigen::Vector3d support(const Obb& box, const Eigen::Vector3d& direction);
Eigen::Vector3d support(const Capsule& capsule, const Eigen::Vector3d& direction);
Eigen::Vector3d support(const Ellipsoid& ellipsoid, const Eigen::Vector3d& direction);
Eigen::Vector3d support(const Cylinder& cylinder, const Eigen::Vector3d& direction);
Eigen::Vector3d support(const ConvexHull& hull, const Eigen::Vector3d& direction);

/// Two convex shapes within `margin` (m, ≥ 0) as a manifold of one point (id 0), by GJK and EPA;
/// with an ellipsoid, the point is its deepest along the normal, half the separation out (EPA's
/// own point can lie anywhere on a flat support, a capsule's side or a box's face)
/// (above); empty when farther apart. Normal from the second to the first; instantiated for
/// every pair of the shapes above.
template <typename First, typename Second>
Manifold convex_manifold(const First& first, const Second& second, double margin);

}  // namespace limber
