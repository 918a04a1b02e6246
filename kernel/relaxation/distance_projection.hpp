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

#include "kernel/verlet/verlet_state.hpp"

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

}  // namespace limber
