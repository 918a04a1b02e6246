// Rigid-body storage: one array per field, like the particles (layouts/particles/).
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// The integration state Y = (x, q, P, L) of n rigid bodies (thesis eq. 2.29), one array per
/// field, each of length n, world frame:
/// - position          x, centre of mass, m
/// - orientation       q, unit quaternion, body frame → world (R(q) replaces the thesis's R)
/// - linear_momentum   P = m v, kg·m/s
/// - angular_momentum  L = I ω about the centre of mass, kg·m²/s
/// Keeping L rather than ω makes the gyroscopic term exact: a free body's L never changes, and
/// ω = R I_body⁻¹ Rᵀ L follows the orientation (eq. 2.30).
struct RigidBodyState {
  std::vector<Eigen::Vector3d> position;
  std::vector<Eigen::Quaterniond> orientation;
  std::vector<Eigen::Vector3d> linear_momentum;
  std::vector<Eigen::Vector3d> angular_momentum;

  /// The field list: every per-body array, once, with its name.
  template <typename Visitor>
  void for_each_field(Visitor&& visit) {
    visit("position", position), visit("orientation", orientation);
    visit("linear_momentum", linear_momentum), visit("angular_momentum", angular_momentum);
  }

  void resize(std::size_t count) {
    position.assign(count, Eigen::Vector3d::Zero());
    orientation.assign(count, Eigen::Quaterniond::Identity());
    linear_momentum.assign(count, Eigen::Vector3d::Zero());
    angular_momentum.assign(count, Eigen::Vector3d::Zero());
  }
  std::size_t size() const { return position.size(); }
};

/// Rigid bodies: the state Y plus the constant mass properties, per body:
/// - mass, inverse_mass                 kg, 1/kg (inverse 0: immovable)
/// - body_inertia, body_inverse_inertia  about the centre of mass, body frame, kg·m² and its
///                                       inverse (symmetric positive definite; diagonal when the
///                                       body frame is on the principal axes, as the methods set it)
struct RigidBodyBuffer {
  RigidBodyState state;
  std::vector<double> mass, inverse_mass;
  std::vector<Eigen::Matrix3d> body_inertia, body_inverse_inertia;

  void resize(std::size_t count) {
    state.resize(count);
    mass.assign(count, 0.0), inverse_mass.assign(count, 0.0);
    body_inertia.assign(count, Eigen::Matrix3d::Zero()), body_inverse_inertia.assign(count, Eigen::Matrix3d::Zero());
  }
  std::size_t size() const { return state.size(); }

  /// R I_body⁻¹ Rᵀ for body `b` in state `y` (1/(kg·m²)).
  Eigen::Matrix3d world_inverse_inertia(const RigidBodyState& y, std::size_t b) const {
    const Eigen::Matrix3d rotation = y.orientation[b].toRotationMatrix();
    return rotation * body_inverse_inertia[b] * rotation.transpose();
  }
  /// R I_body Rᵀ (kg·m²).
  Eigen::Matrix3d world_inertia(const RigidBodyState& y, std::size_t b) const {
    const Eigen::Matrix3d rotation = y.orientation[b].toRotationMatrix();
    return rotation * body_inertia[b] * rotation.transpose();
  }
  Eigen::Vector3d linear_velocity(const RigidBodyState& y, std::size_t b) const { return inverse_mass[b] * y.linear_momentum[b]; }
  /// ω = I_world⁻¹ L, rad/s.
  Eigen::Vector3d angular_velocity(const RigidBodyState& y, std::size_t b) const {
    return world_inverse_inertia(y, b) * y.angular_momentum[b];
  }
};

}  // namespace limber
