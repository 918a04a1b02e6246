// Time integration of rigid bodies (thesis 2.2): the state Y = (x, q, P, L) of eq. 2.29 and its
// derivative Ẏ = (v, ½ ω ⊗ q, F, τ) of eq. 2.30, with v = P/m and ω = R I_body⁻¹ Rᵀ L.
//
// Forces come from a caller's function of the whole state, so coupled systems (springs between
// bodies) are integrated consistently by the multi-stage methods: every stage re-evaluates all
// forces at that stage's state.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/kernel/numerics/integrator.hpp"
#include "limber/layouts/bodies/rigid_body_buffer.hpp"

namespace limber {

/// Per-body force F (N) and torque τ about the centre of mass (N·m), world frame.
struct RigidForces {
  std::vector<Eigen::Vector3d> force, torque;
  void resize(std::size_t count) { force.assign(count, Eigen::Vector3d::Zero()), torque.assign(count, Eigen::Vector3d::Zero()); }
  void clear() {
    for (auto& f : force) f.setZero();
    for (auto& t : torque) t.setZero();
  }
};

/// The rotation by `rotation_vector` (axis · angle, rad) as a unit quaternion.
inline Eigen::Quaterniond rotation_quaternion(const Eigen::Vector3d& rotation_vector) {
  const double angle = rotation_vector.norm();
  if (angle < 1e-12) return Eigen::Quaterniond(1, 0.5 * rotation_vector.x(), 0.5 * rotation_vector.y(), 0.5 * rotation_vector.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, rotation_vector / angle));
}

/// Turns a torque-free body for h seconds, keeping its world angular momentum `angular_momentum`:
/// the free rigid body's flow split into rotations about the principal axes (Strang splitting
/// x(h/2) y(h/2) z(h) y(h/2) x(h/2); each is exact: a turn about body axis i by h·L_i/I_i with
/// L_i = (Rᵀ L)_i). It is symplectic and second order, keeps |L| exactly and the energy within
/// O(h²) for all time — where advancing q with ω = I_world⁻¹ L (explicitly) makes a thin limb
/// spin up without bound once h·ω is not small (McLachlan 1993; Dullweber, Leimkuhler &
/// McLachlan 1997). `principal_moments`: the diagonal of the body-frame inertia, which must be
/// diagonal (the body frame on the principal axes), kg·m².
inline void rotate_free_body(Eigen::Quaterniond& orientation, const Eigen::Vector3d& angular_momentum,
                             const Eigen::Vector3d& principal_moments, double h) {
  constexpr int kAxes[5] = {0, 1, 2, 1, 0};
  constexpr double kFractions[5] = {0.5, 0.5, 1.0, 0.5, 0.5};
  for (int k = 0; k < 5; ++k) {
    const int axis = kAxes[k];
    const double body_momentum = (orientation.conjugate() * angular_momentum)[axis];
    const double angle = kFractions[k] * h * body_momentum / principal_moments[axis];
    orientation = (orientation * Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::Unit(axis)))).normalized();
  }
}

/// Scratch for the multi-stage integrators, sized once so stepping allocates nothing.
struct RigidIntegratorScratch {
  RigidBodyState stage;
  RigidForces forces;
  // Stage derivatives k_s of (x, q, P, L): velocities, quaternion rates, forces, torques.
  std::vector<Eigen::Vector3d> velocity[4], force[4], torque[4];
  std::vector<Eigen::Vector4d> orientation_rate[4];

  void resize(std::size_t count) {
    stage.resize(count);
    forces.resize(count);
    for (int s = 0; s < 4; ++s) {
      velocity[s].assign(count, Eigen::Vector3d::Zero()), force[s].assign(count, Eigen::Vector3d::Zero());
      torque[s].assign(count, Eigen::Vector3d::Zero()), orientation_rate[s].assign(count, Eigen::Vector4d::Zero());
    }
  }
};

namespace detail {

// q̇ = ½ (0, ω) ⊗ q as coefficients (x, y, z, w).
inline Eigen::Vector4d orientation_rate(const Eigen::Quaterniond& q, const Eigen::Vector3d& omega) {
  const Eigen::Quaterniond w(0, omega.x(), omega.y(), omega.z());
  return 0.5 * (w * q).coeffs();
}

// Evaluates Ẏ(y) into stage slot s. `accumulate` adds forces and torques for state y.
template <typename AccumulateForces>
void derivative(const RigidBodyBuffer& bodies, const RigidBodyState& y, AccumulateForces& accumulate,
                RigidIntegratorScratch& scratch, int s) {
  scratch.forces.clear();
  accumulate(y, scratch.forces);
  for (std::size_t b = 0; b < y.size(); ++b) {
    scratch.velocity[s][b] = bodies.linear_velocity(y, b);
    scratch.orientation_rate[s][b] = orientation_rate(y.orientation[b], bodies.angular_velocity(y, b));
    scratch.force[s][b] = scratch.forces.force[b];
    scratch.torque[s][b] = scratch.forces.torque[b];
  }
}

// out = y + h · Σ weight_k · k_k over the listed stages; q renormalized.
inline void advance(const RigidBodyState& y, double h, std::initializer_list<std::pair<int, double>> stages,
                    const RigidIntegratorScratch& scratch, RigidBodyState& out) {
  for (std::size_t b = 0; b < y.size(); ++b) {
    Eigen::Vector3d x = y.position[b], p = y.linear_momentum[b], l = y.angular_momentum[b];
    Eigen::Vector4d q = y.orientation[b].coeffs();
    for (const auto& [s, weight] : stages) {
      x += h * weight * scratch.velocity[s][b];
      q += h * weight * scratch.orientation_rate[s][b];
      p += h * weight * scratch.force[s][b];
      l += h * weight * scratch.torque[s][b];
    }
    out.position[b] = x, out.linear_momentum[b] = p, out.angular_momentum[b] = l;
    out.orientation[b].coeffs() = q.normalized();
  }
}

}  // namespace detail

/// Advances `bodies.state` by h seconds with `integrator`. `accumulate(const RigidBodyState& y,
/// RigidForces& forces)` must *add* every force and torque acting at state y (the forces
/// arrive zeroed); it is called 1, 1, 2 or 4 times. `scratch` must be resized to the body
/// count. Allocates nothing. Orders are for the state; every integrator renormalizes q:
/// - euler: Y' = Y + h·Ẏ(Y), the thesis's (order 1); q advanced additively;
/// - semi_implicit_euler: P, L first, then x with the new v and q by the free rotation with the
///   new L (rotate_free_body; order 1 with forces, 2 without); needs diagonal body inertias;
/// - rk2 (midpoint, order 2) and rk4 (classical, order 4).
/// backward_euler is the spring method's own (kernel/springs/implicit_step.hpp): compile refuses
/// it elsewhere, and here it does nothing.
template <typename AccumulateForces>
void integrate_rigid_bodies(RigidBodyBuffer& bodies, double h, Integrator integrator, RigidIntegratorScratch& scratch,
                            AccumulateForces&& accumulate) {
  RigidBodyState& y = bodies.state;
  switch (integrator) {
    case Integrator::euler:
      detail::derivative(bodies, y, accumulate, scratch, 0);
      detail::advance(y, h, {{0, 1.0}}, scratch, y);
      return;
    case Integrator::semi_implicit_euler:
      scratch.forces.clear();
      accumulate(y, scratch.forces);
      for (std::size_t b = 0; b < y.size(); ++b) {
        y.linear_momentum[b] += h * scratch.forces.force[b];
        y.angular_momentum[b] += h * scratch.forces.torque[b];
        y.position[b] += h * bodies.linear_velocity(y, b);
        rotate_free_body(y.orientation[b], y.angular_momentum[b], bodies.body_inertia[b].diagonal(), h);
      }
      return;
    case Integrator::rk2:
      detail::derivative(bodies, y, accumulate, scratch, 0);
      detail::advance(y, h, {{0, 0.5}}, scratch, scratch.stage);
      detail::derivative(bodies, scratch.stage, accumulate, scratch, 1);
      detail::advance(y, h, {{1, 1.0}}, scratch, y);
      return;
    case Integrator::rk4:
      detail::derivative(bodies, y, accumulate, scratch, 0);
      detail::advance(y, h, {{0, 0.5}}, scratch, scratch.stage);
      detail::derivative(bodies, scratch.stage, accumulate, scratch, 1);
      detail::advance(y, h, {{1, 0.5}}, scratch, scratch.stage);
      detail::derivative(bodies, scratch.stage, accumulate, scratch, 2);
      detail::advance(y, h, {{2, 1.0}}, scratch, scratch.stage);
      detail::derivative(bodies, scratch.stage, accumulate, scratch, 3);
      detail::advance(y, h, {{0, 1.0 / 6}, {1, 2.0 / 6}, {2, 2.0 / 6}, {3, 1.0 / 6}}, scratch, y);
      return;
    case Integrator::backward_euler: return;
  }
}

}  // namespace limber
