// Time integration of rigid bodies (thesis 2.2): the state Y = (x, q, P, L) of eq. 2.29 and its
// derivative Ẏ = (v, ½ ω ⊗ q, F, τ) of eq. 2.30, with v = P/m and ω = R I_body⁻¹ Rᵀ L.
//
// Forces come from a caller's function of the whole state, so coupled systems (springs between
// bodies) are integrated consistently by the multi-stage methods: every stage re-evaluates all
// forces at that stage's state.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build
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
/// the free rigid body's flow split about a symmetric top (Fassò 2003; Dullweber, Leimkuhler &
/// McLachlan 1997). With I_r the middle principal moment, the kinetic energy is
///   ½|L|²/I_r + ½L_j²(1/I_j − 1/I_r) + ½L_k²(1/I_k − 1/I_r),
/// k the axis whose moment is farther from I_r, j the other; each term's flow is exact (a turn
/// about the world L by h|L|/I_r, or about body axis i by h·L_i·(1/I_i − 1/I_r), L_i = (Rᵀ L)_i)
/// and applied as j(h/2) k(h) j(h/2), then the turn about L (it commutes with the others). It is
/// symplectic and second order, keeps |L| exactly and the energy within O(h²) for all time — where
/// advancing q with ω = I_world⁻¹ L (explicitly) makes a thin limb spin up without bound once h·ω
/// is not small. For a symmetric body (I_j = I_r: any limb's shape) it is the exact flow at any h:
/// the spin about the limb's axis, however fast (h·|L_k|/I_k ≫ 1 for a limb of zero radius), does
/// not move the axis, so the momentum about it stays what it was. Splitting about the three
/// principal axes instead (x(h/2) y(h/2) z(h) y(h/2) x(h/2)) turned a zero-radius rod's axis by
/// O(h³·ω_axial) errors, which fed its axial momentum (then ω_axial = L_k/I_k, 10⁶ times it):
/// Lagrange's default step diverged within 0.2 s on 0.1 m rods (kernel/lagrange/README.md).
/// `principal_moments`: the diagonal of the body-frame inertia, which must be diagonal (the body
/// frame on the principal axes), kg·m².
inline void rotate_free_body(Eigen::Quaterniond& orientation, const Eigen::Vector3d& angular_momentum,
                             const Eigen::Vector3d& principal_moments, double h) {
  const Eigen::Vector3d& moment = principal_moments;
  int low = 0, high = 0;
  moment.minCoeff(&low), moment.maxCoeff(&high);
  if (low == high) high = (low + 1) % 3;  // all equal: any order
  const int middle = 3 - low - high;
  const double reference = moment[middle];
  const bool low_is_far = reference - moment[low] > moment[high] - reference;
  const int far = low_is_far ? low : high, near = low_is_far ? high : low;
  const auto turn_about_body_axis = [&](int axis, double fraction) {
    const double body_momentum = (orientation.conjugate() * angular_momentum)[axis];
    const double angle = fraction * h * body_momentum * (1 / moment[axis] - 1 / reference);
    orientation = (orientation * Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::Unit(axis)))).normalized();
  };
  turn_about_body_axis(near, 0.5);
  turn_about_body_axis(far, 1.0);
  turn_about_body_axis(near, 0.5);
  const double norm = angular_momentum.norm();
  if (norm > 0) {
    const Eigen::Quaterniond turn(Eigen::AngleAxisd(h * norm / reference, angular_momentum / norm));
    orientation = (turn * orientation).normalized();
  }
}

/// Scratch for the multi-stage integrators, sized once so stepping allocates nothing.
struct RigidIntegratorScratch {
  RigidBodyState stage;
  RigidForces forces;
  // Stage derivatives k_s of (x, q, P, L): velocities, quaternion rates, forces, torques.
  std::vector<Eigen::Vector3d> velocity[4], force[4], torque[4];
  std::vector<Eigen::Vector4d> orientation_rate[4];
  std::vector<double> axial_torque[4];  ///< d/dt of the momentum about the body's least axis (detail::least_axis)

  void resize(std::size_t count) {
    stage.resize(count);
    forces.resize(count);
    for (int s = 0; s < 4; ++s) {
      velocity[s].assign(count, Eigen::Vector3d::Zero()), force[s].assign(count, Eigen::Vector3d::Zero());
      torque[s].assign(count, Eigen::Vector3d::Zero()), orientation_rate[s].assign(count, Eigen::Vector4d::Zero());
      axial_torque[s].assign(count, 0.0);
    }
  }
};

namespace detail {

// q̇ = ½ (0, ω) ⊗ q as coefficients (x, y, z, w).
inline Eigen::Vector4d orientation_rate(const Eigen::Quaterniond& q, const Eigen::Vector3d& omega) {
  const Eigen::Quaterniond w(0, omega.x(), omega.y(), omega.z());
  return 0.5 * (w * q).coeffs();
}

// The principal axis of body b's least moment (a limb's own axis).
inline int least_axis(const RigidBodyBuffer& bodies, std::size_t b) {
  int axis = 0;
  bodies.body_inertia[b].diagonal().minCoeff(&axis);
  return axis;
}

// Evaluates Ẏ(y) into stage slot s. `accumulate` adds forces and torques for state y. Also the
// rate of the momentum about the least axis k in the body frame, Euler's equation
// L̇_k = τ_k + L_i·L_j·(1/I_j − 1/I_i) ((i, j, k) cyclic): 0 for a symmetric limb without torque
// about its axis, exactly, however the world L and q are being advanced.
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
    const int k = least_axis(bodies, b), i = (k + 1) % 3, j = (k + 2) % 3;
    const Eigen::Vector3d moment = bodies.body_inertia[b].diagonal();
    const Eigen::Vector3d momentum = y.orientation[b].conjugate() * y.angular_momentum[b];
    scratch.axial_torque[s][b] = (y.orientation[b].conjugate() * scratch.forces.torque[b])[k] +
                                 momentum[i] * momentum[j] * (1 / moment[j] - 1 / moment[i]);
  }
}

// Turns `orientation` about the axis ⊥ to both the body's least axis a and the world L so that
// L·a = `axial` (clamped to ±|L|): the momentum about a as the body-frame equation gave it.
inline void align_axial_momentum(Eigen::Quaterniond& orientation, const Eigen::Vector3d& angular_momentum, int axis,
                                 double axial) {
  const double norm = angular_momentum.norm();
  const Eigen::Vector3d a = orientation * Eigen::Vector3d::Unit(axis);
  const Eigen::Vector3d normal = a.cross(angular_momentum);
  if (normal.norm() <= 1e-12 * norm) return;  // L along the axis: turning cannot change L·a
  // The angles between a and L now and wanted, by atan2 (acos loses half the digits near 0 and π).
  const double now = std::atan2(normal.norm(), a.dot(angular_momentum));
  const double s = std::clamp(axial, -norm, norm);
  const double wanted = std::atan2(std::sqrt((norm - s) * (norm + s)), s);
  orientation = (Eigen::Quaterniond(Eigen::AngleAxisd(now - wanted, normal.normalized())) * orientation).normalized();
}

// What advance() writes: a Runge-Kutta stage (a state only derivative() reads) or the step's end.
enum class Advance : std::uint8_t { stage, step_end };

// out = y + h · Σ weight_k · k_k over the listed stages, q renormalized, for the state extended by
// the momentum about each body's least axis a in the body frame, L_a (derivative(): Euler's
// equation). The world L and q, advanced apart, keep L·a only to the method's order, and
// ω_axial = L·a/I_axial magnifies that error by I_transverse/I_axial (10⁶ for a limb of zero
// radius): RK4 spun thin rods up until they diverged, at any Δt (kernel/lagrange/README.md). So
// - a stage's L gets the component L_a along a (L += (L_a − L·a)·a): only ω's part about a
//   changes, to L_a/I_axial, and linearly, so the method is Runge-Kutta on the extended state and
//   keeps its order. Turning q in the stages instead moved the axis itself, the joints' geometry,
//   by (L·a − L_a)/|L × a|: an O(h²) difference over a transverse momentum that passes through 0
//   whenever a limb's swing reverses, which cost RK4 its order (kernel/lagrange/README.md);
// - the step's end turns q so that L·a = L_a (align_axial_momentum), by O(h^(order+1)): L stays as
//   integrated, exactly kept for a torque-free body. Without this turn the stored L·a drifts from
//   L_a by the method's error every step, and thin rods spun up and diverged again.
inline void advance(const RigidBodyBuffer& bodies, const RigidBodyState& y, double h,
                    std::initializer_list<std::pair<int, double>> stages, const RigidIntegratorScratch& scratch,
                    Advance what, RigidBodyState& out) {
  for (std::size_t b = 0; b < y.size(); ++b) {
    const int k = least_axis(bodies, b);
    double axial = (y.orientation[b].conjugate() * y.angular_momentum[b])[k];
    Eigen::Vector3d x = y.position[b], p = y.linear_momentum[b], l = y.angular_momentum[b];
    Eigen::Vector4d q = y.orientation[b].coeffs();
    for (const auto& [s, weight] : stages) {
      x += h * weight * scratch.velocity[s][b];
      q += h * weight * scratch.orientation_rate[s][b];
      p += h * weight * scratch.force[s][b];
      l += h * weight * scratch.torque[s][b];
      axial += h * weight * scratch.axial_torque[s][b];
    }
    out.position[b] = x, out.linear_momentum[b] = p;
    out.orientation[b].coeffs() = q.normalized();
    if (what == Advance::stage) {
      const Eigen::Vector3d a = out.orientation[b] * Eigen::Vector3d::Unit(k);
      out.angular_momentum[b] = l + (axial - l.dot(a)) * a;
    } else {
      out.angular_momentum[b] = l;
      align_axial_momentum(out.orientation[b], l, k, axial);
    }
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
/// euler, rk2 and rk4 also advance each body's momentum about its least principal axis in the body
/// frame, as part of the state: the stages take ω about that axis from it, and the step's end
/// turns q to agree with it (detail::advance: a limb of zero radius spun up otherwise).
/// Every integrator needs diagonal body inertias (the body frame on the principal axes).
/// backward_euler is the spring method's own (kernel/springs/implicit_step.hpp): compile refuses
/// it elsewhere, and here it does nothing.
template <typename AccumulateForces>
void integrate_rigid_bodies(RigidBodyBuffer& bodies, double h, Integrator integrator, RigidIntegratorScratch& scratch,
                            AccumulateForces&& accumulate) {
  RigidBodyState& y = bodies.state;
  switch (integrator) {
    case Integrator::euler:
      detail::derivative(bodies, y, accumulate, scratch, 0);
      detail::advance(bodies, y, h, {{0, 1.0}}, scratch, detail::Advance::step_end, y);
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
      detail::advance(bodies, y, h, {{0, 0.5}}, scratch, detail::Advance::stage, scratch.stage);
      detail::derivative(bodies, scratch.stage, accumulate, scratch, 1);
      detail::advance(bodies, y, h, {{1, 1.0}}, scratch, detail::Advance::step_end, y);
      return;
    case Integrator::rk4:
      detail::derivative(bodies, y, accumulate, scratch, 0);
      detail::advance(bodies, y, h, {{0, 0.5}}, scratch, detail::Advance::stage, scratch.stage);
      detail::derivative(bodies, scratch.stage, accumulate, scratch, 1);
      detail::advance(bodies, y, h, {{1, 0.5}}, scratch, detail::Advance::stage, scratch.stage);
      detail::derivative(bodies, scratch.stage, accumulate, scratch, 2);
      detail::advance(bodies, y, h, {{2, 1.0}}, scratch, detail::Advance::stage, scratch.stage);
      detail::derivative(bodies, scratch.stage, accumulate, scratch, 3);
      detail::advance(bodies, y, h, {{0, 1.0 / 6}, {1, 2.0 / 6}, {2, 2.0 / 6}, {3, 1.0 / 6}}, scratch,
                       detail::Advance::step_end, y);
      return;
    case Integrator::backward_euler: return;
  }
}

}  // namespace limber
