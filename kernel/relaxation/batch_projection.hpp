// Distance-constraint projection over one block of a colour (ConstraintBatches), written once
// for every lane width and particle layout.
//
// The arithmetic is project_distance_constraint's (distance_projection.hpp), operation for
// operation, with the shares read from the batch: with -ffp-contract=off (CMakeLists.txt) and
// IEEE sqrt and division in every lane, the scalar path (ScalarLanes) and the SIMD path
// (SimdLanes) give the same bits, so the SIMD sweep can be tested bit for bit against scalar code.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>

#include <xsimd/xsimd.hpp>

#include "layouts/constraints/constraint_batches.hpp"
#include "layouts/particles/interleaved_particles.hpp"
#include "layouts/particles/particle_buffer.hpp"

namespace limber {

/// One lane at a time: the reference path, and the code that runs the overflow constraints.
template <typename Scalar>
struct ScalarLanes {
  using Index = typename ConstraintBatches<Scalar>::Index;
  using value = Scalar;
  using index = Index;
  static constexpr std::size_t size = 1;
  static value load(const Scalar* p) { return *p; }
  static index load(const Index* p) { return *p; }
  static value broadcast(Scalar v) { return v; }
  static value gather(const Scalar* base, index offset) { return base[offset]; }
  static void scatter(value v, Scalar* base, index offset) { base[offset] = v; }
  static value sqrt(value v) { return std::sqrt(v); }
  static value abs(value v) { return std::abs(v); }
  static value max(value a, value b) { return std::max(a, b); }
  static value if_positive(value test, value v) { return test > Scalar(0) ? v : Scalar(0); }
  static Scalar reduce_max(value v) { return v; }
};

/// xsimd batches of the build's widest instruction set (16 floats / 8 doubles on AVX-512).
template <typename Scalar>
struct SimdLanes {
  using Index = typename ConstraintBatches<Scalar>::Index;
  using value = xsimd::batch<Scalar>;
  using index = xsimd::batch<Index>;
  static_assert(value::size == index::size, "index and value registers must have the same lane count");
  static constexpr std::size_t size = value::size;
  static value load(const Scalar* p) { return value::load_aligned(p); }
  static index load(const Index* p) { return index::load_aligned(p); }
  static value broadcast(Scalar v) { return value(v); }
  static value gather(const Scalar* base, index offset) { return value::gather(base, offset); }
  static void scatter(value v, Scalar* base, index offset) { v.scatter(base, offset); }
  static value sqrt(value v) { return xsimd::sqrt(v); }
  static value abs(value v) { return xsimd::abs(v); }
  static value max(value a, value b) { return xsimd::max(a, b); }
  static value if_positive(value test, value v) { return xsimd::select(test > value(Scalar(0)), v, value(Scalar(0))); }
  static Scalar reduce_max(value v) {  // xsimd 8.1 has no horizontal max
    alignas(64) Scalar lanes[size];
    v.store_aligned(lanes);
    return *std::max_element(lanes, lanes + size);
  }
};

/// Particle positions as the sweep sees them: three base pointers and the offset of a particle
/// from them. Structure of arrays: offset = index.
template <typename Scalar>
struct SoaPositions {
  Scalar *x, *y, *z;
  explicit SoaPositions(ParticleBuffer<Scalar>& particles)
      : x(particles.position_x.data()), y(particles.position_y.data()), z(particles.position_z.data()) {}
  template <typename IndexType>
  static IndexType offset(IndexType p) { return p; }
};

/// Interleaved storage (AoS, AoSoA): the three position fields of one record.
template <typename Scalar, std::size_t Width>
struct InterleavedPositions {
  using Store = InterleavedParticles<Scalar, Width>;
  Scalar *x, *y, *z;
  explicit InterleavedPositions(Store& store)
      : x(store.data.data() + Store::x * Width), y(store.data.data() + Store::y * Width),
        z(store.data.data() + Store::z * Width) {}
  template <typename IndexType>
  static IndexType offset(IndexType p) { return Store::offset(p); }
};

/// Per-particle accumulators of Jacobi corrections (structure of arrays, by particle index).
template <typename Scalar>
struct CorrectionSums {
  Scalar *x, *y, *z;
};

/// Projects slots [begin, end) of `batches` (whole blocks of one colour) in place, Gauss-Seidel
/// style, with over-relaxation ω. Returns the largest particle displacement, m.
template <typename Lanes, typename Positions, typename Scalar>
Scalar project_blocks(const ConstraintBatches<Scalar>& batches, std::size_t begin, std::size_t end,
                      Positions positions, Scalar over_relaxation) {
  using V = typename Lanes::value;
  const V omega = Lanes::broadcast(over_relaxation);
  V largest = Lanes::broadcast(Scalar(0));
  for (std::size_t slot = begin; slot < end; slot += Lanes::size) {
    const auto i = Positions::offset(Lanes::load(&batches.particle_i[slot]));
    const auto j = Positions::offset(Lanes::load(&batches.particle_j[slot]));
    const V xi = Lanes::gather(positions.x, i), yi = Lanes::gather(positions.y, i), zi = Lanes::gather(positions.z, i);
    const V xj = Lanes::gather(positions.x, j), yj = Lanes::gather(positions.y, j), zj = Lanes::gather(positions.z, j);
    const V dx = xi - xj, dy = yi - yj, dz = zi - zj;
    const V length = Lanes::sqrt(dx * dx + dy * dy + dz * dz);
    const V error = length - Lanes::load(&batches.rest_length[slot]);
    // Coincident ends (and padding slots) have no direction: they move nowhere.
    const V scale = Lanes::if_positive(length, omega * error / length);
    const V s_i = Lanes::load(&batches.share_i[slot]), s_j = Lanes::load(&batches.share_j[slot]);
    const V move_i = s_i * scale, move_j = s_j * scale;
    Lanes::scatter(xi - move_i * dx, positions.x, i), Lanes::scatter(yi - move_i * dy, positions.y, i);
    Lanes::scatter(zi - move_i * dz, positions.z, i);
    Lanes::scatter(xj + move_j * dx, positions.x, j), Lanes::scatter(yj + move_j * dy, positions.y, j);
    Lanes::scatter(zj + move_j * dz, positions.z, j);
    largest = Lanes::max(largest, Lanes::if_positive(length, Lanes::abs(omega * error) * Lanes::max(s_i, s_j)));
  }
  return Lanes::reduce_max(largest);
}

/// Jacobi: adds the corrections of slots [begin, end) (whole blocks of one colour), computed
/// from the unchanged positions, to the per-particle sums. One colour at a time, so no two
/// lanes or threads add to the same particle and the sums are race-free and deterministic.
template <typename Lanes, typename Positions, typename Scalar>
void accumulate_blocks(const ConstraintBatches<Scalar>& batches, std::size_t begin, std::size_t end,
                       Positions positions, CorrectionSums<Scalar> sums) {
  using V = typename Lanes::value;
  for (std::size_t slot = begin; slot < end; slot += Lanes::size) {
    const auto i = Lanes::load(&batches.particle_i[slot]), j = Lanes::load(&batches.particle_j[slot]);
    const auto oi = Positions::offset(i), oj = Positions::offset(j);
    const V dx = Lanes::gather(positions.x, oi) - Lanes::gather(positions.x, oj);
    const V dy = Lanes::gather(positions.y, oi) - Lanes::gather(positions.y, oj);
    const V dz = Lanes::gather(positions.z, oi) - Lanes::gather(positions.z, oj);
    const V length = Lanes::sqrt(dx * dx + dy * dy + dz * dz);
    const V error = length - Lanes::load(&batches.rest_length[slot]);
    const V scale = Lanes::if_positive(length, error / length);
    const V move_i = Lanes::load(&batches.share_i[slot]) * scale, move_j = Lanes::load(&batches.share_j[slot]) * scale;
    Lanes::scatter(Lanes::gather(sums.x, i) - move_i * dx, sums.x, i);
    Lanes::scatter(Lanes::gather(sums.y, i) - move_i * dy, sums.y, i);
    Lanes::scatter(Lanes::gather(sums.z, i) - move_i * dz, sums.z, i);
    Lanes::scatter(Lanes::gather(sums.x, j) + move_j * dx, sums.x, j);
    Lanes::scatter(Lanes::gather(sums.y, j) + move_j * dy, sums.y, j);
    Lanes::scatter(Lanes::gather(sums.z, j) + move_j * dz, sums.z, j);
  }
}

}  // namespace limber
