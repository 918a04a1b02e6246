// The projection of contact rows (kernel/particles/contact_rows.hpp) over a range of slots,
// written once for one lane (ScalarLanes: the overflow and the scalar path) and for xsimd
// registers (SimdLanes), with the same operations in the same order in every lane, so both give
// the same bits. For each lane:
//   C = n·Σ c_k x_k − offset;  where C < 0:  Δλ = −C / Σ w_k c_k²,  λ += Δλ,  x_k += w_k c_k Δλ n;
// then static friction: the contact point's slip since the substep began,
// D = Σ c_k (x_k − x*_k), less its normal part D_t, is undone by a tangential position impulse
// accumulated over the substep's sweeps and clamped to the cone as a whole:
//   P ← clamp(P − D_t / Σ w_k c_k², |P| ≤ μλ),  x_k += w_k c_k ΔP
// (static below the cone; at its edge the slip goes on, resisted by μλ: kinetic friction).
// Rows of one colour share no movable particle, so lanes and threads write disjoint particles;
// a lane writes back only the particles it moves (w·c ≠ 0): never the null particle, and never
// a particle its row names with c = 0 (a limb end another row of the colour moves).
#pragma once

#include <cstddef>

#include "limber/kernel/relaxation/batch_projection.hpp"
#include "limber/layouts/constraints/contact_row_batches.hpp"

namespace limber::contact_projection {

/// The SoA arrays the rows move: positions, the substep's start positions, inverse masses.
template <typename Scalar>
struct ContactFields {
  Scalar *x, *y, *z;
  const Scalar *px, *py, *pz;
  const Scalar* inverse_mass;
};

/// Projects slots [begin, end) (whole blocks of Lanes::size, or any range for one lane).
/// Returns the largest particle displacement, m.
template <typename Lanes, typename Scalar>
Scalar project_contact_rows(ContactRowBatches<Scalar>& batches, std::size_t begin, std::size_t end,
                            const ContactFields<Scalar>& fields) {
  using V = typename Lanes::value;
  constexpr std::size_t kPlaces = kContactRowParticles;
  const V zero = Lanes::broadcast(0), one = Lanes::broadcast(1);
  V largest = zero;
  for (std::size_t slot = begin; slot < end; slot += Lanes::size) {
    typename Lanes::index index[kPlaces];
    V x[kPlaces], y[kPlaces], z[kPlaces], c[kPlaces], w[kPlaces];
    const V nx = Lanes::load(&batches.normal_x[slot]), ny = Lanes::load(&batches.normal_y[slot]),
            nz = Lanes::load(&batches.normal_z[slot]);
    V point_x = zero, point_y = zero, point_z = zero, denominator = zero;
    for (std::size_t k = 0; k < kPlaces; ++k) {
      index[k] = Lanes::load(&batches.particle[k][slot]);
      c[k] = Lanes::load(&batches.coefficient[k][slot]);
      x[k] = Lanes::gather(fields.x, index[k]), y[k] = Lanes::gather(fields.y, index[k]), z[k] = Lanes::gather(fields.z, index[k]);
      w[k] = Lanes::gather(fields.inverse_mass, index[k]);
      point_x = point_x + c[k] * x[k], point_y = point_y + c[k] * y[k], point_z = point_z + c[k] * z[k];
      denominator = denominator + w[k] * c[k] * c[k];
    }
    const auto valid = denominator > zero;
    const V inverse = Lanes::select(valid, one / Lanes::select(valid, denominator, one), zero);
    // The normal push (position impulse, kg·m), only where the surfaces overlap.
    const V separation = nx * point_x + ny * point_y + nz * point_z - Lanes::load(&batches.offset[slot]);
    const V push = Lanes::select(separation < zero, (zero - separation) * inverse, zero);
    const V lambda = Lanes::load(&batches.lambda[slot]) + push;
    Lanes::store(lambda, &batches.lambda[slot]);
    // The slip since the substep began, after the push, and its tangential part.
    V slip_x = zero, slip_y = zero, slip_z = zero;
    for (std::size_t k = 0; k < kPlaces; ++k) {
      const V move = w[k] * c[k] * push;
      x[k] = x[k] + move * nx, y[k] = y[k] + move * ny, z[k] = z[k] + move * nz;
      slip_x = slip_x + c[k] * (x[k] - Lanes::gather(fields.px, index[k]));
      slip_y = slip_y + c[k] * (y[k] - Lanes::gather(fields.py, index[k]));
      slip_z = slip_z + c[k] * (z[k] - Lanes::gather(fields.pz, index[k]));
    }
    const V along = nx * slip_x + ny * slip_y + nz * slip_z;
    slip_x = slip_x - along * nx, slip_y = slip_y - along * ny, slip_z = slip_z - along * nz;
    // The friction impulse that would stop the slip, added to what this substep already took,
    // clamped to the cone as a whole (accumulated, as sequential impulses clamp it).
    const V old_x = Lanes::load(&batches.tangent_x[slot]), old_y = Lanes::load(&batches.tangent_y[slot]),
            old_z = Lanes::load(&batches.tangent_z[slot]);
    V total_x = old_x - slip_x * inverse, total_y = old_y - slip_y * inverse, total_z = old_z - slip_z * inverse;
    const V size = Lanes::sqrt(total_x * total_x + total_y * total_y + total_z * total_z);
    const V grip = Lanes::load(&batches.friction[slot]) * lambda;
    const auto outside = size > grip;
    const V scale = Lanes::select(outside, grip / Lanes::select(outside, size, one), one);
    total_x = scale * total_x, total_y = scale * total_y, total_z = scale * total_z;
    Lanes::store(total_x, &batches.tangent_x[slot]), Lanes::store(total_y, &batches.tangent_y[slot]);
    Lanes::store(total_z, &batches.tangent_z[slot]);
    const V impulse_x = push * nx + (total_x - old_x), impulse_y = push * ny + (total_y - old_y),
            impulse_z = push * nz + (total_z - old_z);
    for (std::size_t k = 0; k < kPlaces; ++k) {
      const V share = w[k] * c[k];
      const V dx = share * impulse_x, dy = share * impulse_y, dz = share * impulse_z;
      x[k] = x[k] + share * (total_x - old_x), y[k] = y[k] + share * (total_y - old_y), z[k] = z[k] + share * (total_z - old_z);
      largest = Lanes::max(largest, Lanes::sqrt(dx * dx + dy * dy + dz * dz));
    }
    for (std::size_t k = 0; k < kPlaces; ++k) {
      const auto moves = (w[k] * c[k]) != zero;  // a place with c = 0 may be another lane's particle
      if (!Lanes::any(moves)) continue;
      Lanes::scatter_where(moves, x[k], fields.x, index[k]);
      Lanes::scatter_where(moves, y[k], fields.y, index[k]);
      Lanes::scatter_where(moves, z[k], fields.z, index[k]);
    }
  }
  return Lanes::reduce_max(largest);
}

}  // namespace limber::contact_projection
