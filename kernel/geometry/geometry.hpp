// Closest-point geometry between the ball, limbs and planes (double precision; few contacts).
#pragma once

#include <algorithm>
#include <array>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/model/model.hpp"

namespace limber {

/// A half-space n·x ≥ offset (ground, a wall of the bounds), solid where n·x < offset.
struct Plane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset = 0;
  double restitution = 0;
  double friction = 0;
};

/// The ground and the six walls of the bounds as planes, ground first, each with its
/// restitution and friction (what every method collides against).
std::vector<Plane> scene_planes(const Model& model);

/// Any unit vector perpendicular to `u` (u non-zero, not necessarily unit).
Eigen::Vector3d any_perpendicular(const Eigen::Vector3d& u);

/// Whether p, on or off the plane of the triangle t with normal n, projects inside it along n
/// (edges included).
bool projects_inside(const std::array<Eigen::Vector3d, 3>& t, const Eigen::Vector3d& n, const Eigen::Vector3d& p);

/// A sphere against a limb: where they are closest, and how far apart.
struct SphereLimbContact {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitX();  ///< unit, from the limb's surface towards the sphere
  double separation = 0;  ///< m; < 0 when they overlap (penetration depth = −separation)
  double axial = 0;       ///< where on the axis the contact is: 0 at the head, 1 at the tail
};

/// Sphere (centre, radius) against the limb whose axis runs head → tail with `shape`'s radius:
/// a capsule is the segment swept by a sphere; a cylinder is solid with flat ends (a centre
/// inside it is pushed out through the nearest face). Exact for both.
SphereLimbContact sphere_limb_contact(const Eigen::Vector3d& centre, double sphere_radius,
                                      const Eigen::Vector3d& head, const Eigen::Vector3d& tail,
                                      ShapeType shape, double limb_radius);

/// A limb end's support against a plane of normal n (unit): its lowest point relative to the
/// end's centre, and how far below the centre that is. A capsule's end sphere (or the ball)
/// reaches `radius` along −n; a cylinder's end disk with unit axis u reaches its rim point along
/// −(n − c·u), c = n·u, radius·√(1 − c²) below — a disk lying flat (√(1 − c²) ≤ 1e-9) touches
/// with its whole face, represented by its centre. One rule for the particle and rigid methods.
struct EndSupport {
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  ///< lowest point − centre, m
  double reach = 0;                                  ///< −n·offset, m, ≥ 0
  double cosine = 0, sine = 0;                       ///< disk: n·u and √(1 − (n·u)²)
};
EndSupport end_support(const Eigen::Vector3d& normal, const Eigen::Vector3d& axis, double radius, bool is_disk);

/// The separation (m, ≤ 0) a contact may be left at after a step: 0 for an overlap the step
/// made, and an overlap there at the start (`start_separation` < 0) reduced by at most
/// `recovery` (Settings::contact_recovery_speed·Δt, m), so an initial overlap is not flung out
/// (Box2D's push-out limit). One rule for every method's push-out.
inline double allowed_separation(double start_separation, double recovery) {
  return start_separation < 0 ? std::min(0.0, start_separation + recovery) : 0.0;
}

/// The contact of a feature with the half-space n·x ≥ offset (n unit, solid below), as a
/// constraint on two particles for position-based projection. The feature is a sphere of
/// `radius` about `point`, or (`is_disk`) the end disk of a cylinder of `radius` centred at
/// `point` with axis u = (point − partner)/|point − partner|, whose lowest rim point sits
/// r·√(1 − (n·u)²) below its centre. C is the signed distance of the lowest point (< 0
/// inside). For a sphere (or a disk with coincident particles) ∇_point C = n and ∇_partner C = 0.
/// For a disk, with c = n·u and f = √(1 − c²), tilting the axis moves the rim:
///   ∇_point C = n + (r·c / (f·L))·(n − c·u),   ∇_partner C = −(r·c / (f·L))·(n − c·u),
/// L = |point − partner|; |n − c·u| = f, so the rim term has magnitude r|c|/L and stays finite
/// (taken as 0 where the disk lies flat, f → 0, and the rim has no single lowest point).
/// `at_midpoint`: a sphere of `radius` about (point + partner)/2 (a sphere limb's, whose two
/// particles straddle its centre): ∇_point C = ∇_partner C = n/2.
struct PlaneFeatureConstraint {
  double separation = 0;  ///< C, m
  Eigen::Vector3d gradient_point = Eigen::Vector3d::Zero();
  Eigen::Vector3d gradient_partner = Eigen::Vector3d::Zero();
};
PlaneFeatureConstraint plane_feature_constraint(const Eigen::Vector3d& normal, double offset,
                                                const Eigen::Vector3d& point, const Eigen::Vector3d& partner,
                                                double radius, bool is_disk, bool at_midpoint = false);

}  // namespace limber
