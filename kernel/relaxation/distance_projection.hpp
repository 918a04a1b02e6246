// The projection of one distance constraint: the heart of relaxation (thesis 3.2.2, 4.3).
//
// For C = |x_i − x_j| − d and n = (x_i − x_j)/|x_i − x_j|, a projection moves
//   Δx_i = −s_i · C · n,   Δx_j = +s_j · C · n.
// Weighted (thesis eq. 4.7; the position-based-dynamics projection, Müller et al. 2007):
//   s_i = w_i / (w_i + w_j),  s_j = w_j / (w_i + w_j),   w = 1/m.
// The heavier end moves less: by m_light/(m_i+m_j) of the gap. Because m_i·Δx_i + m_j·Δx_j = 0,
// the pair's centre of mass and (Verlet's implicit) linear momentum are unchanged.
// Unweighted (thesis eq. 4.6, Jakobsen 2001): s_i = s_j = ½ — both ends meet at the midpoint —
// except that a pinned end (w = 0) stays and the free end takes the whole gap, as in the
// thesis's code for an immovable inboard limb.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "limber/kernel/relaxation/batch_projection.hpp"

#include "limber/kernel/particles/verlet_state.hpp"

namespace limber {

/// Share of the correction each end takes. Returns false when neither end can move.
template <typename Scalar>
inline bool correction_shares(RelaxationRule rule, Scalar w_i, Scalar w_j, Scalar& s_i, Scalar& s_j) {
  const Scalar w_sum = w_i + w_j;
  if (w_sum <= Scalar(0)) return false;
  if (rule == RelaxationRule::weighted) {
    s_i = w_i / w_sum;
    s_j = w_j / w_sum;
  } else {
    const Scalar half = (w_i > 0 && w_j > 0) ? Scalar(0.5) : Scalar(1);
    s_i = w_i > 0 ? half : Scalar(0);
    s_j = w_j > 0 ? half : Scalar(0);
  }
  return true;
}

/// Projects constraint `c` of `constraints` on `particles` in place (one Gauss-Seidel update),
/// scaled by the over-relaxation factor ω (1: the plain projection; ω·Δx keeps the centre of
/// mass just as Δx does). Returns the larger of the two particle displacements, m.
template <typename Scalar>
inline Scalar project_distance_constraint(ParticleBuffer<Scalar>& particles,
                                          const DistanceConstraintBuffer<Scalar>& constraints,
                                          std::uint32_t c, RelaxationRule rule,
                                          Scalar over_relaxation = Scalar(1)) {
  const std::uint32_t i = constraints.particle_i[c];
  const std::uint32_t j = constraints.particle_j[c];
  Scalar s_i, s_j;
  if (!correction_shares(rule, particles.inverse_mass[i], particles.inverse_mass[j], s_i, s_j)) {
    return Scalar(0);
  }
  const Scalar dx = particles.position_x[i] - particles.position_x[j];
  const Scalar dy = particles.position_y[i] - particles.position_y[j];
  const Scalar dz = particles.position_z[i] - particles.position_z[j];
  const Scalar length = std::sqrt(dx * dx + dy * dy + dz * dz);
  if (!(length > Scalar(0))) return Scalar(0);  // coincident ends: no direction to push along
  const Scalar error = length - constraints.rest_length[c];  // C
  // C·n = (C / |d|) · d, so no separate normalization.
  const Scalar scale = over_relaxation * error / length;
  const Scalar move_i = s_i * scale, move_j = s_j * scale;
  particles.position_x[i] -= move_i * dx;
  particles.position_y[i] -= move_i * dy;
  particles.position_z[i] -= move_i * dz;
  particles.position_x[j] += move_j * dx;
  particles.position_y[j] += move_j * dy;
  particles.position_z[j] += move_j * dz;
  return std::abs(over_relaxation * error) * std::max(s_i, s_j);
}

/// The unit gradient of constraint `c` at positions x (x_i − x_j normalized), or 0 for a
/// zero-length joint (its constraint is linear: both rules project it alike) and for coincident
/// ends. What the rattle rule stores per constraint at a substep's start.
template <typename Scalar>
inline Eigen::Matrix<Scalar, 3, 1> constraint_gradient(const Eigen::Matrix<Scalar, 3, 1>& x_i, const Eigen::Matrix<Scalar, 3, 1>& x_j,
                                                       Scalar rest_length) {
  const Eigen::Matrix<Scalar, 3, 1> d = x_i - x_j;
  const Scalar length = d.norm();
  if (!(rest_length > Scalar(0)) || !(length > Scalar(0))) return Eigen::Matrix<Scalar, 3, 1>::Zero();
  return d / length;
}

/// The rattle rule's projection of constraint `c` (SHAKE; batch_projection.hpp's
/// StartGradientCorrection, one constraint at a time): moves along its start gradient `start`,
/// Δx_i = −s_i·ω·C/(n·n₀)·n₀, Δx_j = +s_j·ω·C/(n·n₀)·n₀, or, when n·n₀ is at or below
/// kStartGradientMinimumCosine (or n₀ = 0), as project_distance_constraint; a fallback zeroes
/// `start` for the rest of the substep and adds one to `fallbacks`. Returns the larger
/// displacement, m.
template <typename Scalar>
inline Scalar project_distance_constraint_from_start(ParticleBuffer<Scalar>& particles,
                                                     const DistanceConstraintBuffer<Scalar>& constraints, std::uint32_t c,
                                                     RelaxationRule rule, Scalar over_relaxation,
                                                     Eigen::Matrix<Scalar, 3, 1>& start, std::uint64_t& fallbacks) {
  const std::uint32_t i = constraints.particle_i[c], j = constraints.particle_j[c];
  Scalar s_i, s_j;
  if (!correction_shares(rule, particles.inverse_mass[i], particles.inverse_mass[j], s_i, s_j)) return Scalar(0);
  const Eigen::Matrix<Scalar, 3, 1> d = particles.position(i) - particles.position(j);
  const Scalar length = d.norm();
  const Scalar along = d.dot(start);
  if (!(along > Scalar(kStartGradientMinimumCosine) * length)) {
    if (start.squaredNorm() > Scalar(0)) start.setZero(), ++fallbacks;
    return project_distance_constraint(particles, constraints, c, rule, over_relaxation);
  }
  const Scalar scale = over_relaxation * (length - constraints.rest_length[c]) * length / along;
  particles.set_position(i, particles.position(i) - (s_i * scale) * start);
  particles.set_position(j, particles.position(j) + (s_j * scale) * start);
  return std::abs(scale) * std::max(s_i, s_j);
}

/// The rattle rule's velocity projection of constraint `c` (RATTLE's velocity stage;
/// batch_projection.hpp's VelocityCorrection): removes the relative velocity along the current
/// gradient n, u = (n·(v_i − v_j))·n (all of v_i − v_j where there is no gradient: a zero-length
/// joint, or coincident ends), Δv_i = −s_i·u, Δv_j = +s_j·u. Returns the larger velocity change, m/s.
template <typename Scalar>
inline Scalar project_distance_velocity(ParticleBuffer<Scalar>& particles, const DistanceConstraintBuffer<Scalar>& constraints,
                                        std::uint32_t c, RelaxationRule rule) {
  const std::uint32_t i = constraints.particle_i[c], j = constraints.particle_j[c];
  Scalar s_i, s_j;
  if (!correction_shares(rule, particles.inverse_mass[i], particles.inverse_mass[j], s_i, s_j)) return Scalar(0);
  const Eigen::Matrix<Scalar, 3, 1> relative = particles.velocity(i) - particles.velocity(j);
  const Eigen::Matrix<Scalar, 3, 1> n = constraint_gradient(particles.position(i), particles.position(j), constraints.rest_length[c]);
  const Eigen::Matrix<Scalar, 3, 1> u = n.squaredNorm() > Scalar(0) ? Eigen::Matrix<Scalar, 3, 1>(n.dot(relative) * n) : relative;
  particles.set_velocity(i, particles.velocity(i) - s_i * u);
  particles.set_velocity(j, particles.velocity(j) + s_j * u);
  return u.norm() * std::max(s_i, s_j);
}

}  // namespace limber
