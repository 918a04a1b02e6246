// Contact manifolds: where two shapes touch as up to four points sharing one normal, so a box
// rests on a face without rocking and a solver can warm start each point from the last step's.
//
// A single closest point (bounding_volumes.hpp's `contact`) serves rounded shapes, which touch at
// a point; a box lying on a face or an edge touches along a face or a segment, and one point
// there lets it rock about that point. The manifold keeps the corners of the touching region
// (Box2D v3's `b2Manifold`, Jolt's contact manifolds, ODE's `dBoxBox`): the incident face clipped
// against the reference face's sides (Sutherland–Hodgman), reduced to the four that span it most.
//
// Conventions (those of bounding_volumes.hpp): world frame, metres. The normal points from the
// second shape towards the first (move the first along +normal to separate them). Each point
// carries its separation along the normal — negative overlapping, positive a gap — and points
// apart by up to `margin` are kept (speculative contacts: a gap the step may close). A point lies
// midway between the two surfaces: the first's surface point is point + ½·separation·normal, the
// second's point − ½·separation·normal. Each point's `id` names the features that made it (a
// vertex, or an edge clipped by a side of the reference face, with the faces' and boxes' roles):
// the same while the same features touch, different between the points of one manifold.
#pragma once

#include <array>
#include <cstdint>

#include <Eigen/Core>

#include "limber/kernel/geometry/bounding_volumes.hpp"
#include "limber/kernel/geometry/geometry.hpp"

namespace limber {

struct ManifoldPoint {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< m, world: midway between the surfaces
  double separation = 0;                            ///< m, along the normal: < 0 overlapping, > 0 a gap
  std::uint32_t id = 0;                             ///< the features that made it (above)
};

/// Up to four points; `count` 0 when the shapes are farther apart than the margin.
struct Manifold {
  static constexpr int kMaxPoints = 4;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit, world, from the second shape towards the first
  std::array<ManifoldPoint, kMaxPoints> points{};
  int count = 0;
};

/// A box against the half-space n·x ≥ offset (the box first, the plane second: normal = n): its
/// vertices within `margin` of the plane, the four deepest when more are (a box on a face: the
/// face's corners; on an edge: the edge's ends). ids: the vertex, 0–7. `margin`: m, ≥ 0.
Manifold box_plane_manifold(const Obb& box, const Plane& plane, double margin);

/// Two boxes, by the separating-axis test (separating_axis.hpp) with `margin`: on a face axis the
/// incident box's face most against the reference face, clipped to the reference face's four
/// sides and kept where within `margin` of it, reduced to four (the deepest, the farthest from it,
/// then the two that widen the quadrilateral most); on an edge–edge axis one point, between the
/// two edges' closest points. Exact depth on every axis; the points of a face pair are the
/// corners of the faces' overlap.
Manifold box_box_manifold(const Obb& first, const Obb& second, double margin);

/// A capsule (first; a sphere when its ends coincide) against a box (second): the closest points of its core segment and the solid
/// box (exact: the squared distance is piecewise quadratic along the segment); where the segment
/// enters the box, the axis of least overlap among the box's faces and the segment's crosses with
/// its edges. Two points when the segment lies along the face it touches (within 3°), clipped
/// to the face, so a capsule lies still on a box; one point otherwise. ids: 0 and 1 the
/// segment's ends (clipped or not), 2 a single point. (Two capsules' manifold is the collision
/// world's, `add_limb_pair_contacts` in limb_collisions.cpp; its capsule against a static box
/// finds the deepest point by a search, which this exact pair can replace.)
Manifold capsule_box_manifold(const Capsule& capsule, const Obb& box, double margin);

}  // namespace limber
