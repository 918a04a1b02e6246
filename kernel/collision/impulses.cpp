#include "limber/kernel/collision/impulses.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>

#include "limber/kernel/rigid/anchor_jacobian.hpp"

namespace limber {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

// [r]×: the matrix with [r]× x = r × x.
// A tangential velocity or impulse this small relative to the whole vector is rounding, not a
// direction (the tangential part is computed as v − (v·n) n, exact only to ~1e-16·|v|).
constexpr double kNegligible = 1e-12;

}  // namespace

Matrix3d world_inverse_inertia(const Matrix3d& body_inertia, const Eigen::Quaterniond& orientation) {
  const Eigen::LLT<Matrix3d> factor(0.5 * (body_inertia + body_inertia.transpose()));
  if (factor.info() != Eigen::Success || !body_inertia.allFinite()) {
    throw std::invalid_argument("body_inertia: must be symmetric positive definite");
  }
  const Matrix3d body_inverse = factor.solve(Matrix3d::Identity());
  const Matrix3d rotation = orientation.normalized().toRotationMatrix();
  const Matrix3d world = rotation * body_inverse * rotation.transpose();
  return 0.5 * (world + world.transpose());  // symmetric to the last bit, like the tensor it inverts
}

Vector3d velocity_at(const ImpulseBody& body, const Vector3d& point) {
  return body.linear_velocity + body.angular_velocity.cross(point - body.centre_of_mass);
}

Matrix3d collision_matrix(const ImpulseBody& a, const ImpulseBody& b, const Vector3d& point) {
  // Each body's point velocity changes by (w E − [r]× I⁻¹ [r]×) j for an impulse j on it:
  // Δv = w j and Δω × r = (I⁻¹ (r × j)) × r = −[r]× I⁻¹ [r]× j. b receives −j and enters
  // v_rel with a minus sign, so its term adds.
  const Matrix3d ra = cross_matrix(point - a.centre_of_mass);
  const Matrix3d rb = cross_matrix(point - b.centre_of_mass);
  return (a.inverse_mass + b.inverse_mass) * Matrix3d::Identity() - ra * a.inverse_inertia * ra -
         rb * b.inverse_inertia * rb;
}

Vector3d linear_collision_impulse(const ImpulseBody& a, const ImpulseBody& b, const Vector3d& normal,
                                  double restitution) {
  const double approach = (a.linear_velocity - b.linear_velocity).dot(normal);  // (v1 − v2)·n, eq. 2.33
  const double denominator = a.inverse_mass + b.inverse_mass;                  // 1/m1 + 1/m2, eq. 2.34
  if (approach >= 0 || denominator <= 0) return Vector3d::Zero();
  return (-(1 + restitution) * approach / denominator) * normal;
}

CollisionImpulse collision_impulse(const ImpulseBody& a, const ImpulseBody& b, const Vector3d& point,
                                   const Vector3d& normal, double restitution, double friction) {
  if (!(restitution >= 0 && restitution <= 1)) {
    throw std::invalid_argument("restitution: must be in [0, 1], got " + std::to_string(restitution));
  }
  if (!(friction >= 0) || !std::isfinite(friction)) {
    throw std::invalid_argument("friction: must be a finite number >= 0, got " + std::to_string(friction));
  }
  CollisionImpulse result;

  // Approach speed along the normal; nothing to do when the points separate.
  const Vector3d relative = velocity_at(a, point) - velocity_at(b, point);
  const double normal_speed = relative.dot(normal);
  if (!(normal_speed < 0)) return result;

  // No impulse can change the normal velocity: both immovable, or pinned against it.
  const Matrix3d k = collision_matrix(a, b, point);
  const double normal_response = normal.dot(k * normal);
  if (!(normal_response > kNegligible * k.norm())) return result;

  // Sticking: the impulse that leaves relative velocity −e·v_n·n. K is positive definite when
  // either body has mass; otherwise (two pinned bodies) it may be singular, the pivoted LDLᵀ
  // drops its zero pivots, and the result counts only if it reaches the target.
  const Vector3d target_change = -relative - restitution * normal_speed * normal;
  const Vector3d sticking = k.ldlt().solve(target_change);
  const bool sticking_reaches = a.inverse_mass + b.inverse_mass > 0 ||
                                (k * sticking - target_change).norm() <= 1e-9 * target_change.norm();
  const double sticking_normal = sticking.dot(normal);
  const Vector3d sticking_tangential = sticking - sticking_normal * normal;
  if (sticking_reaches && sticking_tangential.norm() <= friction * sticking_normal) {
    result.impulse = sticking;
    result.normal_impulse = sticking_normal;
    return result;
  }

  // Sliding: friction at the cone's edge, against the pre-impact sliding direction t (or along
  // the sticking impulse's tangential part when the points were not sliding), scaled so the
  // normal velocity still ends at −e·v_n.
  const Vector3d tangential_velocity = relative - normal_speed * normal;
  Vector3d slide = Vector3d::Zero();
  if (tangential_velocity.norm() > kNegligible * relative.norm()) {
    slide = tangential_velocity.normalized();
  } else if (sticking_tangential.norm() > kNegligible * sticking.norm()) {
    slide = -sticking_tangential.normalized();
  }
  const Vector3d direction = normal - friction * slide;
  const double sliding_response = normal.dot(k * direction);
  if (!(sliding_response > kNegligible * normal_response)) {
    // nᵀK(n − μt) ≤ 0: a sliding impulse would pull the bodies together (Painlevé). Sticking is
    // the one answer that still meets the restitution law; without it, fall back to no friction.
    if (sticking_reaches && sticking_normal > 0) {
      result.impulse = sticking;
      result.normal_impulse = sticking_normal;
    } else {
      result.normal_impulse = -(1 + restitution) * normal_speed / normal_response;
      result.impulse = result.normal_impulse * normal;
      result.sliding = true;
    }
    return result;
  }
  result.normal_impulse = -(1 + restitution) * normal_speed / sliding_response;
  result.impulse = result.normal_impulse * direction;
  result.sliding = true;
  return result;
}

void apply_impulse(ImpulseBody& body, const Vector3d& point, const Vector3d& impulse) {
  body.linear_velocity += body.inverse_mass * impulse;
  body.angular_velocity += body.inverse_inertia * (point - body.centre_of_mass).cross(impulse);
}

CollisionImpulse sequential_collision_impulse(const ImpulseBody& a, const ImpulseBody& b, const Vector3d& point,
                                              const Vector3d& normal, double restitution, double friction) {
  CollisionImpulse result;
  const Vector3d relative = velocity_at(a, point) - velocity_at(b, point);
  const double normal_speed = relative.dot(normal);
  const Eigen::Matrix3d k = collision_matrix(a, b, point);
  const double normal_inverse_mass = normal.dot(k * normal);
  if (normal_speed >= 0 || !(normal_inverse_mass > 0)) return result;
  result.normal_impulse = -(1 + restitution) * normal_speed / normal_inverse_mass;
  result.impulse = result.normal_impulse * normal;
  const Vector3d after = relative + k * result.impulse;
  const Vector3d sliding = after - after.dot(normal) * normal;
  const double sliding_speed = sliding.norm();
  if (friction <= 0 || sliding_speed <= 1e-12 * relative.norm()) return result;
  const Vector3d tangent = sliding / sliding_speed;
  const double tangent_inverse_mass = tangent.dot(k * tangent);
  if (!(tangent_inverse_mass > 0)) return result;
  const double stopping = sliding_speed / tangent_inverse_mass, limit = friction * result.normal_impulse;
  result.sliding = stopping > limit;
  result.impulse -= std::min(stopping, limit) * tangent;
  return result;
}

}  // namespace limber
