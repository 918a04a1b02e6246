// Bounding volumes, their overlap tests and the hierarchical test (thesis 2.3 "bounding volumes",
// 2.4 "hierarchical test").
//
// A limb is tested against another in two levels (2.4): first their bounding spheres, which cost
// one distance and reject most pairs; only when the spheres overlap, the finer test — the
// separating-axis test of two oriented boxes for cylinders, closest points of two segments for
// capsules. The volumes (2.3), from loosest to tightest around a limb:
// - BoundingSphere: rotation invariant, one comparison; loose around a long thin limb.
// - UprightCylinder: a sphere stretched along world z (a standing figure); axis fixed to z.
// - Aabb: what the broadphase sorts (kernel/geometry/broadphase.hpp); refitted every step.
// - Obb: the limb's own box; tight around a cylinder up to its four long edges.
// - Capsule: exact for a capsule limb, and bounds a cylinder limb with its caps.
//
// Conventions: world frame, metres, double precision. Touching counts as overlapping (every test
// uses ≤), so a resting contact is never dropped by a bound that is exactly tight. A Contact's
// normal points from the second volume towards the first (move the first along +normal by depth
// to separate them), matching SphereLimbContact in kernel/geometry/geometry.hpp.
// Volumes are assumed valid: finite numbers, radii and extents ≥ 0, min ≤ max, rotation a rotation.
#pragma once

#include <cstdint>
#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/kernel/model/model.hpp"

namespace limber {

struct BoundingSphere {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< m
  double radius = 0;                                 ///< m, ≥ 0
};

/// A solid cylinder whose axis is world z (+z is up, kernel/model/model.hpp): the points x with
/// |x.z − centre.z| ≤ half_height and |(x − centre).xy| ≤ radius. Centred rather than based at its
/// foot so that the vertical test reads like the horizontal one (two intervals about centres).
struct UprightCylinder {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< m, the middle of the axis
  double radius = 0;                                 ///< m, ≥ 0
  double half_height = 0;                            ///< m, ≥ 0 (total height 2·half_height)
};

/// Axis-aligned box: the points with min ≤ x ≤ max component-wise.
struct Aabb {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();  ///< m
  Eigen::Vector3d max = Eigen::Vector3d::Zero();  ///< m, ≥ min on every axis
};

/// Oriented box: the points centre + rotation·y with |y_k| ≤ half_extents_k.
struct Obb {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();          ///< m
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();    ///< m, ≥ 0, along the box's own axes
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();    ///< columns: the box's axes in world, orthonormal
};

/// The points within `radius` of the segment a–b (a sphere when a == b).
struct Capsule {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();  ///< m, one end of the core segment
  Eigen::Vector3d b = Eigen::Vector3d::Zero();  ///< m, the other end
  double radius = 0;                            ///< m, ≥ 0
};

/// Where two overlapping volumes touch, as one point.
struct Contact {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit, from the second volume towards the first
  Eigen::Vector3d point = Eigen::Vector3d::Zero();    ///< m, world: midway through the overlap along the normal
  double depth = 0;                                   ///< m, ≥ 0: how far the first must move along normal to separate
};

// ---- Overlap tests (boolean) ----

bool overlaps(const BoundingSphere& first, const BoundingSphere& second);
/// By the squared distance from the centre to the box (its closest point: clamp the centre).
bool overlaps(const BoundingSphere& sphere, const Aabb& box);
bool overlaps(const Aabb& first, const Aabb& second);
/// Upright cylinders overlap iff their vertical intervals overlap and their horizontal circles do.
bool overlaps(const UprightCylinder& first, const UprightCylinder& second);
/// By the separating-axis test (separating_axis.hpp).
bool overlaps(const Obb& first, const Obb& second);
bool overlaps(const Capsule& first, const Capsule& second);
bool overlaps(const BoundingSphere& sphere, const Capsule& capsule);
bool overlaps(const BoundingSphere& sphere, const Obb& box);

// ---- Contacts (std::nullopt when apart; normal from second to first) ----

/// Along the line of centres; coincident centres take +z.
std::optional<Contact> contact(const BoundingSphere& first, const BoundingSphere& second);
/// Between the sphere's centre and its closest point on the capsule's segment.
std::optional<Contact> contact(const BoundingSphere& first, const Capsule& second);
/// Between the closest points of the two segments. Axes that cross take the normal across both
/// (a × b), and parallel axes at zero distance any normal perpendicular to them; in both cases
/// its sign is chosen to point from the second segment's midpoint towards the first's.
std::optional<Contact> contact(const Capsule& first, const Capsule& second);
/// From the box's closest point to the sphere's centre; a centre inside the box leaves through
/// the nearest face.
std::optional<Contact> contact(const BoundingSphere& first, const Obb& second);
/// The separating-axis test's axis of least penetration (projections overlap least) is the normal
/// and that overlap the depth. Edge–edge axes are normalized first, skipped when their edges are
/// near parallel (the axis is undefined), and chosen over the best face axis only when their
/// depth is below 0.95 of it — face normals give steadier contacts, as in Box2D and ODE.
/// The point: each box's support feature along the normal (its vertex, edge or face deepest into
/// the other; ties taken at the feature's centre) is reduced to that centre and clamped into the
/// other box; the point is the mean of the two clamped points, moved along the normal to the
/// middle of the overlap interval. For a face on a face it lies in the overlap of the faces when
/// either face's centre is over the other; it is one point, not a contact manifold.
std::optional<Contact> contact(const Obb& first, const Obb& second);

/// Closest points of the segments p(s) = p0 + s(p1 − p0) and q(t) = q0 + t(q1 − q0), s, t ∈ [0, 1]
/// (Ericson 5.1.9: minimise |p(s) − q(t)|², then clamp s and t in turn). A zero-length segment is
/// a point. Parallel segments (sin² of the angle below 1e-12) have a whole interval of closest
/// pairs; the one in the middle of the interval where their projections overlap is taken (or the
/// nearest ends when they do not overlap), so a contact lies midway along the shared length.
struct SegmentClosestPoints {
  Eigen::Vector3d on_first = Eigen::Vector3d::Zero();   ///< p(s), m
  Eigen::Vector3d on_second = Eigen::Vector3d::Zero();  ///< q(t), m
  double s = 0;                                         ///< in [0, 1]
  double t = 0;                                         ///< in [0, 1]
  double distance = 0;                                  ///< |p(s) − q(t)|, m
};
SegmentClosestPoints closest_points_between_segments(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                                     const Eigen::Vector3d& q0, const Eigen::Vector3d& q1);

/// The point of the box nearest `point` (the point itself when inside).
Eigen::Vector3d closest_point_on_obb(const Obb& box, const Eigen::Vector3d& point);

// ---- Fitting a limb (kernel/model/model.hpp: its Shape in its body frame, axis local +z,
// ---- placed with its centre at `position` and rotated by `orientation` from body to world) ----

/// The smallest sphere about the centre, of radius bounding_radius(shape) (model.hpp):
/// √((L/2)² + r²) for a cylinder (its rim), L/2 + r for a capsule, |half_extents| for a box, the
/// longest semi-axis for an ellipsoid. (It needs no orientation; the argument keeps the four
/// fitters alike.)
BoundingSphere limb_sphere(const Shape& shape, const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation);
/// The tight box. With u the world axis, a cylinder's half-extent along world axis e is
/// |u·e|·L/2 + r·√(1 − (u·e)²) (the end disk's rim reaches r·√(1 − (u·e)²) along e beyond its
/// centre); a capsule's is |u·e|·L/2 + r (a cap's sphere reaches r along every axis). With R the
/// shape frame's turn to world (orientation × shape.rotation) and h the half-extents, a box's is
/// Σ_j |R_ij| h_j (its farthest corner) and an ellipsoid's √(Σ_j (R_ij h_j)²) (its support).
Aabb limb_aabb(const Shape& shape, const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation);
/// The body-frame box, half-extents (r, r, L/2) for a cylinder and (r, r, L/2 + r) for a capsule.
Obb limb_obb(const Shape& shape, const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation);
/// The capsule on the limb's axis from head to tail: exact for a capsule; for a cylinder it adds
/// hemispherical caps over the flat ends.
Capsule limb_capsule(const Shape& shape, const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation);

// ---- The hierarchical test (thesis 2.4) ----

/// A limb placed in the world: its shape, the world position of its centre, body → world rotation
/// (for a Body: {body.shape, body.position, body.orientation()}).
struct PlacedLimb {
  Shape shape;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

/// How many pairs reached each level; add up over calls.
struct HierarchicalTestCounts {
  std::uint64_t sphere_tests = 0;  ///< pairs tested by bounding spheres
  std::uint64_t fine_tests = 0;    ///< pairs whose spheres overlapped and so reached the fine test
};

/// The fine level alone: capsule–capsule when both limbs are capsules (exact), else OBB–OBB by
/// the separating-axis test on limb_obb (conservative: a cylinder's box holds more than it).
std::optional<Contact> limb_pair_fine_contact(const PlacedLimb& first, const PlacedLimb& second);
/// The hierarchical test: limb_sphere against limb_sphere, and only when they overlap
/// limb_pair_fine_contact. Both levels bound the limbs, so whenever the limbs touch both report
/// it; the result equals the fine level alone for two capsules (the sphere bounds the capsule)
/// and can only be tighter when a box is used (a box's corners poke out of the limb's sphere).
/// `counts`, when given, is incremented per level reached.
std::optional<Contact> limb_pair_contact(const PlacedLimb& first, const PlacedLimb& second,
                                         HierarchicalTestCounts* counts = nullptr);

}  // namespace limber
