// The projection of contact rows (kernel/particles/contact_rows.hpp) over a range of slots,
// written once for one lane (ScalarLanes: the overflow and the scalar path) and for xsimd
// registers (SimdLanes), with the same operations in the same order in every lane, so both give
// the same bits. For each lane, with the shares s_k = w_k c_k, the effective mass
// m = 1/Σ w_k c_k² and the start point p* = Σ c_k x*_k stored when the rows were packed:
//   C = n·Σ c_k x_k − offset;  where C < 0:  Δλ = −C·m,  λ += Δλ,  x_k += s_k Δλ n;
// then static friction: the contact point's slip since the substep began,
// D = Σ c_k x_k − p*, less its normal part D_t, is undone by a tangential position impulse
// accumulated over the substep's sweeps and clamped to the cone as a whole:
//   P ← clamp(P − D_t·m, |P| ≤ μλ),  x_k += s_k ΔP
// (static below the cone; at its edge the slip goes on, resisted by μλ: kinetic friction). The
// push moves the point along n alone (by Σ s_k c_k Δλ n = Δλ/m n), so D_t is taken before it.
// Rows of one colour share no movable particle, so lanes and threads write disjoint particles;
// a lane writes back only the particles it moves (s ≠ 0, and only if its row pushed): never the
// null particle, and never a particle its row names with c = 0 (a limb end another row of the
// colour moves).
#pragma once

#include <cstddef>

#include "limber/kernel/relaxation/batch_projection.hpp"
#include "limber/layouts/constraints/contact_row_batches.hpp"

namespace limber::contact_projection {

/// The SoA position arrays the rows move.
template <typename Scalar>
struct ContactFields {
  Scalar *x, *y, *z;
};

/// Projects slots [begin, end) (whole blocks of Lanes::size, or any range for one lane) over
/// their first kPlaces places: 2 for rows whose places 2 and 3 are unused (c = 0: their terms
/// would add ±0 to every sum, so both widths give the same bits), else kContactRowParticles.
/// Returns the largest particle displacement, m.
template <typename Lanes, std::size_t kPlaces, typename Scalar>
Scalar project_contact_rows(ContactRowBatches<Scalar>& batches, std::size_t begin, std::size_t end,
                            const ContactFields<Scalar>& fields) {
  static_assert(kPlaces == kContactRowSideParticles || kPlaces == kContactRowParticles);
  using V = typename Lanes::value;
  const V zero = Lanes::broadcast(0), one = Lanes::broadcast(1);
  V largest = zero;
  for (std::size_t slot = begin; slot < end; slot += Lanes::size) {
    typename Lanes::index index[kPlaces];
    V x[kPlaces], y[kPlaces], z[kPlaces];
    V point_x = zero, point_y = zero, point_z = zero;
    for (std::size_t k = 0; k < kPlaces; ++k) {
      index[k] = Lanes::load(&batches.particle[k][slot]);
      const V c = Lanes::load(&batches.coefficient[k][slot]);
      x[k] = Lanes::gather(fields.x, index[k]), y[k] = Lanes::gather(fields.y, index[k]), z[k] = Lanes::gather(fields.z, index[k]);
      point_x = point_x + c * x[k], point_y = point_y + c * y[k], point_z = point_z + c * z[k];
    }
    const V nx = Lanes::load(&batches.normal_x[slot]), ny = Lanes::load(&batches.normal_y[slot]),
            nz = Lanes::load(&batches.normal_z[slot]);
    const V mass = Lanes::load(&batches.effective_mass[slot]);
    // The normal push (position impulse, kg·m), only where the surfaces overlap.
    const V separation = nx * point_x + ny * point_y + nz * point_z - Lanes::load(&batches.offset[slot]);
    const V push = Lanes::select(separation < zero, (zero - separation) * mass, zero);
    const V lambda = Lanes::load(&batches.lambda[slot]) + push;
    Lanes::store(lambda, &batches.lambda[slot]);
    // The slip since the substep began, and its tangential part.
    V slip_x = point_x - Lanes::load(&batches.start_x[slot]), slip_y = point_y - Lanes::load(&batches.start_y[slot]),
      slip_z = point_z - Lanes::load(&batches.start_z[slot]);
    const V along = nx * slip_x + ny * slip_y + nz * slip_z;
    slip_x = slip_x - along * nx, slip_y = slip_y - along * ny, slip_z = slip_z - along * nz;
    // The friction impulse that would stop the slip, added to what this substep already took,
    // clamped to the cone as a whole (accumulated, as sequential impulses clamp it).
    const V old_x = Lanes::load(&batches.tangent_x[slot]), old_y = Lanes::load(&batches.tangent_y[slot]),
            old_z = Lanes::load(&batches.tangent_z[slot]);
    V total_x = old_x - slip_x * mass, total_y = old_y - slip_y * mass, total_z = old_z - slip_z * mass;
    const V size = Lanes::sqrt(total_x * total_x + total_y * total_y + total_z * total_z);
    const V grip = Lanes::load(&batches.friction[slot]) * lambda;
    const auto outside = size > grip;
    const V scale = Lanes::select(outside, grip / Lanes::select(outside, size, one), one);
    total_x = scale * total_x, total_y = scale * total_y, total_z = scale * total_z;
    Lanes::store(total_x, &batches.tangent_x[slot]), Lanes::store(total_y, &batches.tangent_y[slot]);
    Lanes::store(total_z, &batches.tangent_z[slot]);
    const V impulse_x = push * nx + (total_x - old_x), impulse_y = push * ny + (total_y - old_y),
            impulse_z = push * nz + (total_z - old_z);
    // Each place moves by s_k times the impulse: the largest move is max |s_k| times its size.
    const V size_squared = impulse_x * impulse_x + impulse_y * impulse_y + impulse_z * impulse_z;
    const auto pushed = size_squared > zero;
    V reach = zero;
    for (std::size_t k = 0; k < kPlaces; ++k) {
      const V share = Lanes::load(&batches.share[k][slot]);
      reach = Lanes::max(reach, Lanes::abs(share));
      x[k] = x[k] + share * impulse_x, y[k] = y[k] + share * impulse_y, z[k] = z[k] + share * impulse_z;
      // A place with c = 0 may be another lane's particle; one not pushed is not written.
      const auto moves = (share != zero) & pushed;
      if (Lanes::any(moves)) Lanes::scatter_each_where(moves, x[k], y[k], z[k], fields.x, fields.y, fields.z, index[k]);
    }
    largest = Lanes::max(largest, reach * Lanes::sqrt(size_squared));
  }
  return Lanes::reduce_max(largest);
}

}  // namespace limber::contact_projection
