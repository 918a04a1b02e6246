// The separating-axis test of two oriented boxes, with the axis it decided on: what the boxes'
// overlap tests, their one-point contact (bounding_volumes.hpp) and their contact manifold
// (manifolds.hpp) share.
//
// Two boxes are disjoint iff their projections are disjoint on one of 15 axes: the 3 face
// normals of each and the 9 cross products of an edge of one with an edge of the other
// (Gottschalk, Lin & Manocha 1996; Ericson, "Real-Time Collision Detection", 4.4.1). Near-parallel
// edges make a cross product nearly zero, and rounding could then make that degenerate axis look
// separating; as Ericson does, a small ε is added to every |R_ij| so such an axis can never
// separate (the face normals decide those cases): the boxes are grown by about 1e-12 of their size.
#pragma once

#include <Eigen/Core>

#include "limber/kernel/geometry/bounding_volumes.hpp"

namespace limber {

/// An edge–edge axis becomes the contact normal only when its depth is below this fraction of the
/// best face axis's (face contacts are steadier; Box2D and ODE bias the same way); the capsule–box
/// manifold's axes take the same preference (manifolds.cpp).
inline constexpr double kEdgeAxisPreference = 0.95;

/// Which of the 15 axes: a face normal of the first box (`first` its axis 0–2), of the second
/// (`second` its axis 0–2), or the cross product of the first's edges along its axis `first` and
/// the second's along its axis `second`.
struct BoxAxis {
  enum class Kind { first_face, second_face, edges };
  Kind kind = Kind::first_face;
  int first = 0;
  int second = 0;
};

/// What the test found. With `margin` > 0, boxes apart by at most `margin` along every axis count
/// as touching, with a negative depth (speculative contacts: a gap the step may close).
struct SeparatingAxisResult {
  bool overlap = false;                        ///< no axis separates the boxes by more than the margin
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit, world, from the second box towards the first
  double depth = 0;                            ///< m: the projections' overlap along `normal`; < 0 a gap
  BoxAxis axis;                                ///< the axis `normal` lies along
};

/// The test (Ericson 4.4.1). With `find_contact` false it returns at the first separating axis
/// and fills only `overlap`. Otherwise the axis of least overlap (or widest gap) is the normal:
/// edge–edge axes are normalized first, skipped when their edges are near parallel (the axis is
/// undefined), and chosen over the best face axis only when their depth is below 0.95 of it (a
/// gap 1.05 times wider) — face normals give steadier contacts, as in Box2D and ODE. Between the
/// two boxes' best face axes, the first box's wins when they are within 1° of parallel (a box on
/// a box: the same reference face step after step, so the manifold's ids hold; Box2D v3 prefers
/// its first polygon the same way); otherwise the shallower. `margin`: m, ≥ 0.
SeparatingAxisResult separating_axis_test(const Obb& first, const Obb& second, bool find_contact, double margin = 0);

}  // namespace limber
