// Spatial vector algebra (Featherstone, "Rigid Body Dynamics Algorithms", 2008, chapter 2): the
// 6-D vectors, transforms and inertias every algorithm in kernel/featherstone/ is written in.
//
// Conventions (Featherstone's, throughout this folder):
// - A motion vector (velocity, acceleration, joint axis) is m = (ω, v): angular part first, then
//   the linear velocity of the body point that is at the frame's origin (not the centre of mass),
//   both in the frame's coordinates. rad/s and m/s (or their rates).
// - A force vector is f = (n, f): the moment about the frame's origin first, then the force.
//   N·m and N. Power is the dot product m·f, the same in every frame.
// - A Plücker transform ᴮX_A maps motion vectors in A coordinates to B coordinates. It is stored
//   as (E, r), not 6×6: E = the 3×3 rotation taking A coordinates to B coordinates, r = the
//   position of B's origin relative to A's origin in A coordinates:
//       ᴮX_A = [ E  0 ; −E r×  E ],   ᴮX_A* = [ E  −E r× ; 0  E ]   (force transform).
//   The five operations of Table 2.5 (apply to motion, to force, inverse, compose,
//   transpose-apply) then cost a few 3×3 products instead of a 6×6 one.
// - Cross products: m × m' = crm(m)·m', m ×* f = crf(m)·f with crf(m) = −crm(m)ᵀ.
// - A rigid body's spatial inertia (eq. 2.63) about a frame whose origin is not at the centre
//   of mass c:  I = [ I_c + m c× c×ᵀ   m c× ; m c×ᵀ   m 1 ].  Stored compactly (Table 2.5's
//   "rbi"): the mass m, the first moment h = m c, and the rotational inertia about the frame's
//   origin Ī = I_c + m c× c×ᵀ, 10 numbers. Multiplying it by a motion vector then takes two
//   3×3 products. An articulated-body inertia (chapter 7) is a general symmetric 6×6 and is
//   stored as one (SpatialMatrix).
#pragma once

#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// A motion or force vector: (angular, linear), 6×1 (see the conventions above).
using SpatialVector = Eigen::Matrix<double, 6, 1>;
/// A 6×6 spatial operator: an articulated-body inertia, a cross-product matrix, a transform.
using SpatialMatrix = Eigen::Matrix<double, 6, 6>;

/// [u]×, the 3×3 matrix with [u]× x = u × x.
inline Eigen::Matrix3d skew(const Eigen::Vector3d& u) {
  Eigen::Matrix3d m;
  m << 0, -u.z(), u.y(), u.z(), 0, -u.x(), -u.y(), u.x(), 0;
  return m;
}

/// m × m' for motion vectors (crm): (ω × ω', ω × v' + v × ω').
inline SpatialVector cross_motion(const SpatialVector& m, const SpatialVector& other) {
  SpatialVector out;
  const Eigen::Vector3d w = m.head<3>(), v = m.tail<3>();
  out.head<3>() = w.cross(other.head<3>());
  out.tail<3>() = w.cross(other.tail<3>()) + v.cross(other.head<3>());
  return out;
}

/// m ×* f for a motion vector m and a force vector f (crf): (ω × n + v × f, ω × f).
inline SpatialVector cross_force(const SpatialVector& m, const SpatialVector& f) {
  SpatialVector out;
  const Eigen::Vector3d w = m.head<3>(), v = m.tail<3>();
  out.head<3>() = w.cross(f.head<3>()) + v.cross(f.tail<3>());
  out.tail<3>() = w.cross(f.tail<3>());
  return out;
}

/// crm(m) = [ ω×  0 ; v×  ω× ] (6×6), the matrix of m × (·).
inline SpatialMatrix motion_cross_matrix(const SpatialVector& m) {
  SpatialMatrix out = SpatialMatrix::Zero();
  const Eigen::Matrix3d w = skew(m.head<3>());
  out.topLeftCorner<3, 3>() = w;
  out.bottomRightCorner<3, 3>() = w;
  out.bottomLeftCorner<3, 3>() = skew(m.tail<3>());
  return out;
}

/// crf(m) = −crm(m)ᵀ = [ ω×  v× ; 0  ω× ] (6×6), the matrix of m ×* (·).
inline SpatialMatrix force_cross_matrix(const SpatialVector& m) { return -motion_cross_matrix(m).transpose(); }

/// A Plücker transform ᴮX_A from frame A to frame B, stored as (E, r) (conventions above).
struct PluckerTransform {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< E: A coordinates → B coordinates
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();   ///< r: B's origin from A's, in A coordinates, m

  static PluckerTransform identity() { return {}; }

  /// The transform to a frame B whose axes are `orientation` in A (B-to-A rotation matrix R, so
  /// E = Rᵀ) and whose origin is at `position` in A.
  static PluckerTransform from_pose(const Eigen::Matrix3d& orientation, const Eigen::Vector3d& position) {
    return {orientation.transpose(), position};
  }

  /// ᴮX_A m (Table 2.5): (E ω, E (v − r × ω)).
  SpatialVector apply_motion(const SpatialVector& m) const {
    SpatialVector out;
    out.head<3>() = rotation * m.head<3>();
    out.tail<3>() = rotation * (m.tail<3>() - translation.cross(m.head<3>()));
    return out;
  }

  /// ᴮX_A* f (Table 2.5): (E (n − r × f), E f).
  SpatialVector apply_force(const SpatialVector& f) const {
    SpatialVector out;
    out.head<3>() = rotation * (f.head<3>() - translation.cross(f.tail<3>()));
    out.tail<3>() = rotation * f.tail<3>();
    return out;
  }

  /// ᴮX_Aᵀ f = ᴬX_B* f: a force in B coordinates expressed in A (Table 2.5):
  /// (Eᵀ n + r × Eᵀ f, Eᵀ f).
  SpatialVector transpose_apply_force(const SpatialVector& f) const {
    SpatialVector out;
    const Eigen::Vector3d force = rotation.transpose() * f.tail<3>();
    out.head<3>() = rotation.transpose() * f.head<3>() + translation.cross(force);
    out.tail<3>() = force;
    return out;
  }

  /// ᴮX_A⁻¹ m = ᴬX_B m: a motion in B coordinates expressed in A: (Eᵀ ω, Eᵀ v + r × Eᵀ ω).
  SpatialVector inverse_apply_motion(const SpatialVector& m) const {
    SpatialVector out;
    const Eigen::Vector3d w = rotation.transpose() * m.head<3>();
    out.head<3>() = w;
    out.tail<3>() = rotation.transpose() * m.tail<3>() + translation.cross(w);
    return out;
  }

  /// ᴮX_Aᵀ M ᴮX_A: an inertia M (6×6 symmetric, B coordinates) expressed in A, i.e.
  /// ᴬX_B* M ᴮX_A (the step IA_λ += λX_i* I^a_i ⁱX_λ of Tables 6.2 and 7.1). With M's blocks
  /// [A B; Bᵀ C] first rotated, A' = Eᵀ A E etc., the result is
  ///   [ A' − B' r× + r× B'ᵀ − r× C' r×    B' + r× C' ; (B' + r× C')ᵀ    C' ].
  SpatialMatrix transpose_apply_inertia(const SpatialMatrix& inertia) const {
    const Eigen::Matrix3d& e = rotation;
    const Eigen::Matrix3d a = e.transpose() * inertia.topLeftCorner<3, 3>() * e;
    const Eigen::Matrix3d b = e.transpose() * inertia.topRightCorner<3, 3>() * e;
    const Eigen::Matrix3d c = e.transpose() * inertia.bottomRightCorner<3, 3>() * e;
    const Eigen::Matrix3d rx = skew(translation);
    const Eigen::Matrix3d upper_right = b + rx * c;
    // The middle pair is W + Wᵀ with W = −B' r×, so the block is symmetric in exact arithmetic;
    // it is symmetrized so that it stays exactly symmetric under round-off too.
    const Eigen::Matrix3d w = -b * rx;
    const Eigen::Matrix3d upper_left = a + w + w.transpose() - rx * c * rx;
    SpatialMatrix out;
    out.topLeftCorner<3, 3>() = 0.5 * (upper_left + upper_left.transpose());
    out.topRightCorner<3, 3>() = upper_right;
    out.bottomLeftCorner<3, 3>() = upper_right.transpose();
    out.bottomRightCorner<3, 3>() = 0.5 * (c + c.transpose());
    return out;
  }

  /// ᴬX_B = ᴮX_A⁻¹ = (Eᵀ, −E r) (Table 2.5).
  PluckerTransform inverse() const { return {rotation.transpose(), -(rotation * translation)}; }

  /// ᶜX_A = ᶜX_B ᴮX_A with *this = ᶜX_B (Table 2.5): (E₁ E₂, r₂ + E₂ᵀ r₁).
  PluckerTransform operator*(const PluckerTransform& b_from_a) const {
    return {rotation * b_from_a.rotation, b_from_a.translation + b_from_a.rotation.transpose() * translation};
  }

  /// The 6×6 motion transform [ E 0 ; −E r× E ], for tests and cross-checks.
  SpatialMatrix motion_matrix() const {
    SpatialMatrix out = SpatialMatrix::Zero();
    out.topLeftCorner<3, 3>() = rotation;
    out.bottomRightCorner<3, 3>() = rotation;
    out.bottomLeftCorner<3, 3>() = -rotation * skew(translation);
    return out;
  }

  /// The 6×6 force transform [ E −E r× ; 0 E ] = motion_matrix()⁻ᵀ.
  SpatialMatrix force_matrix() const {
    SpatialMatrix out = SpatialMatrix::Zero();
    out.topLeftCorner<3, 3>() = rotation;
    out.bottomRightCorner<3, 3>() = rotation;
    out.topRightCorner<3, 3>() = -rotation * skew(translation);
    return out;
  }
};

/// A rigid body's spatial inertia in some frame (eq. 2.63), stored compactly as (m, h, Ī).
struct SpatialInertia {
  double mass = 0;                                                       ///< m, kg
  Eigen::Vector3d first_moment = Eigen::Vector3d::Zero();                ///< h = m c, kg·m
  Eigen::Matrix3d rotational_inertia = Eigen::Matrix3d::Zero();          ///< Ī about the origin, kg·m²

  /// From the mass (kg), the centre of mass c in the frame (m) and the rotational inertia about
  /// the centre of mass in the frame's axes I_c (kg·m², symmetric): eq. 2.63,
  /// Ī = I_c + m c× c×ᵀ.
  static SpatialInertia from_mass_properties(double mass, const Eigen::Vector3d& centre_of_mass,
                                             const Eigen::Matrix3d& inertia_about_centre_of_mass) {
    const Eigen::Matrix3d cx = skew(centre_of_mass);
    return {mass, mass * centre_of_mass, inertia_about_centre_of_mass + mass * cx * cx.transpose()};
  }

  /// c = h / m, m.
  Eigen::Vector3d centre_of_mass() const { return first_moment / mass; }

  /// I_c = Ī − m c× c×ᵀ, kg·m².
  Eigen::Matrix3d inertia_about_centre_of_mass() const {
    const Eigen::Matrix3d cx = skew(centre_of_mass());
    return rotational_inertia - mass * cx * cx.transpose();
  }

  /// I m: the momentum of the body moving with motion m, (Ī ω + h × v, m v − h × ω).
  SpatialVector operator*(const SpatialVector& m) const {
    SpatialVector out;
    out.head<3>() = rotational_inertia * m.head<3>() + first_moment.cross(m.tail<3>());
    out.tail<3>() = mass * m.tail<3>() - first_moment.cross(m.head<3>());
    return out;
  }

  /// The sum of two bodies' inertias in one frame: a rigid body's again (the composite of a subtree).
  SpatialInertia& operator+=(const SpatialInertia& other) {
    mass += other.mass, first_moment += other.first_moment, rotational_inertia += other.rotational_inertia;
    return *this;
  }

  /// ᴮX_Aᵀ I ᴮX_A for this inertia I in B coordinates, b_from_a = ᴮX_A = (E, r): the same body's
  /// inertia in A (Table 2.5), m, h' = Eᵀh + m r, Ī' = EᵀĪE − r×(Eᵀh)× − h'× r× — what
  /// PluckerTransform::transpose_apply_inertia gives for matrix(), without its 6×6 blocks. With
  /// y = Eᵀh and a×b× + b×a× = b aᵀ + a bᵀ − 2(a·b)1, r×r× = r rᵀ − |r|²1, the correction is
  /// (2 r·y + m|r|²)1 − y rᵀ − r yᵀ − m r rᵀ: symmetric as written, EᵀĪE symmetrized.
  SpatialInertia transformed_by(const PluckerTransform& b_from_a) const {
    const Eigen::Matrix3d& e = b_from_a.rotation;
    const Eigen::Vector3d& r = b_from_a.translation;
    const Eigen::Vector3d rotated_moment = e.transpose() * first_moment;
    const Eigen::Matrix3d turned = e.transpose() * rotational_inertia * e;
    const Eigen::Vector3d lever = rotated_moment + 0.5 * mass * r;  // y r + r y + m r r = lever rᵀ + r leverᵀ
    const double trace = 2 * r.dot(rotated_moment) + mass * r.squaredNorm();
    Eigen::Matrix3d out;
    for (int a = 0; a < 3; ++a) {
      for (int b = a; b < 3; ++b) {
        out(a, b) = out(b, a) = 0.5 * (turned(a, b) + turned(b, a)) - lever[a] * r[b] - r[a] * lever[b] + (a == b ? trace : 0.0);
      }
    }
    return {mass, rotated_moment + mass * r, out};
  }

  /// The 6×6 form [ Ī  h× ; h×ᵀ  m 1 ].
  SpatialMatrix matrix() const {
    SpatialMatrix out;
    const Eigen::Matrix3d hx = skew(first_moment);
    out.topLeftCorner<3, 3>() = rotational_inertia;
    out.topRightCorner<3, 3>() = hx;
    out.bottomLeftCorner<3, 3>() = hx.transpose();
    out.bottomRightCorner<3, 3>() = mass * Eigen::Matrix3d::Identity();
    return out;
  }
};

}  // namespace limber
