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
#include <type_traits>

#include <xsimd/xsimd.hpp>
#if defined(__AVX512F__)
#include <immintrin.h>
#endif

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
  static value load_unaligned(const Scalar* p) { return *p; }
  static void store_unaligned(value v, Scalar* p) { *p = v; }
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
  static value load_unaligned(const Scalar* p) { return value::load_unaligned(p); }
  static void store_unaligned(value v, Scalar* p) { v.store_unaligned(p); }
  static value broadcast(Scalar v) { return value(v); }
  // xsimd 8.1 resolves gather and scatter on AVX-512 to its element-by-element fallback (a
  // quarter of the sweep's time in perf); the AVX-512 instructions are called directly instead.
  static value gather(const Scalar* base, index offset) {
#if defined(__AVX512F__)
    if constexpr (size == 16 && std::is_same_v<Scalar, float>) return _mm512_i32gather_ps(offset, base, 4);
    if constexpr (size == 8 && std::is_same_v<Scalar, double>) return _mm512_i64gather_pd(offset, base, 8);
#endif
    return value::gather(base, offset);
  }
  static void scatter(value v, Scalar* base, index offset) {
#if defined(__AVX512F__)
    if constexpr (size == 16 && std::is_same_v<Scalar, float>) return _mm512_i32scatter_ps(base, offset, v, 4);
    if constexpr (size == 8 && std::is_same_v<Scalar, double>) return _mm512_i64scatter_pd(base, offset, v, 8);
#endif
    v.scatter(base, offset);
  }
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

/// Three coordinates of one particle per lane (w: the record's fourth field, kept so that an
/// AoS record can be written back whole; unused elsewhere).
template <typename Lanes>
struct LanePositions {
  typename Lanes::value x, y, z, w;
};

/// Particle positions as the sweep sees them: load(index) gives one particle per lane,
/// store(index, positions) writes them back. Structure of arrays: three gathers and scatters.
template <typename Scalar>
struct SoaPositions {
  Scalar *x, *y, *z;
  explicit SoaPositions(ParticleBuffer<Scalar>& particles)
      : x(particles.position_x.data()), y(particles.position_y.data()), z(particles.position_z.data()) {}
  SoaPositions(Scalar* x_array, Scalar* y_array, Scalar* z_array) : x(x_array), y(y_array), z(z_array) {}
  template <typename IndexType>
  static IndexType offset(IndexType p) { return p; }
  // `consecutive`: the lanes' particles are particle[0], particle[0] + 1, … (plain vector loads).
  template <typename Lanes>
  LanePositions<Lanes> load(const typename Lanes::Index* particle, bool consecutive) const {
    if (consecutive) {
      const auto p = particle[0];
      return {Lanes::load_unaligned(x + p), Lanes::load_unaligned(y + p), Lanes::load_unaligned(z + p), Lanes::broadcast(Scalar(0))};
    }
    const auto p = Lanes::load(particle);
    return {Lanes::gather(x, p), Lanes::gather(y, p), Lanes::gather(z, p), Lanes::broadcast(Scalar(0))};
  }
  template <typename Lanes>
  void store(const typename Lanes::Index* particle, bool consecutive, const LanePositions<Lanes>& v) const {
    if (consecutive) {
      const auto p = particle[0];
      Lanes::store_unaligned(v.x, x + p), Lanes::store_unaligned(v.y, y + p), Lanes::store_unaligned(v.z, z + p);
      return;
    }
    const auto p = Lanes::load(particle);
    Lanes::scatter(v.x, x, p), Lanes::scatter(v.y, y, p), Lanes::scatter(v.z, z, p);
  }
};

#if defined(__AVX512F__)
// AoS records (x, y, z, w) of 16 particles (float) or 8 (double), loaded with one 128-/256-bit
// load each and transposed into coordinate registers with two-source permutes — 16 loads and 8
// permutes instead of three 16-element gathers, and 16 stores instead of three scatters. (Box2D
// v3 gathers its body states the same way, by loading records and transposing.)
inline void load_records(const float* base, const std::int32_t* particle, bool consecutive, __m512& x, __m512& y,
                         __m512& z, __m512& w) {
  const auto o = [&](int k) { return 4 * static_cast<std::ptrdiff_t>(particle[k]); };
  __m512 r[4];
  for (int k = 0; k < 4; ++k) {  // r[k] holds records 4k … 4k+3
    if (consecutive) {
      r[k] = _mm512_loadu_ps(base + o(0) + 16 * k);
      continue;
    }
    r[k] = _mm512_castps128_ps512(_mm_load_ps(base + o(4 * k)));
    r[k] = _mm512_insertf32x4(r[k], _mm_load_ps(base + o(4 * k + 1)), 1);
    r[k] = _mm512_insertf32x4(r[k], _mm_load_ps(base + o(4 * k + 2)), 2);
    r[k] = _mm512_insertf32x4(r[k], _mm_load_ps(base + o(4 * k + 3)), 3);
  }
  const __m512i xy = _mm512_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28, 1, 5, 9, 13, 17, 21, 25, 29);
  const __m512i zw = _mm512_setr_epi32(2, 6, 10, 14, 18, 22, 26, 30, 3, 7, 11, 15, 19, 23, 27, 31);
  const __m512i low = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 16, 17, 18, 19, 20, 21, 22, 23);
  const __m512i high = _mm512_setr_epi32(8, 9, 10, 11, 12, 13, 14, 15, 24, 25, 26, 27, 28, 29, 30, 31);
  const __m512 xy_first = _mm512_permutex2var_ps(r[0], xy, r[1]), xy_second = _mm512_permutex2var_ps(r[2], xy, r[3]);
  const __m512 zw_first = _mm512_permutex2var_ps(r[0], zw, r[1]), zw_second = _mm512_permutex2var_ps(r[2], zw, r[3]);
  x = _mm512_permutex2var_ps(xy_first, low, xy_second), y = _mm512_permutex2var_ps(xy_first, high, xy_second);
  z = _mm512_permutex2var_ps(zw_first, low, zw_second), w = _mm512_permutex2var_ps(zw_first, high, zw_second);
}
inline void store_records(float* base, const std::int32_t* particle, bool consecutive, __m512 x, __m512 y, __m512 z,
                          __m512 w) {
  const auto o = [&](int k) { return 4 * static_cast<std::ptrdiff_t>(particle[k]); };
  const __m512i first = _mm512_setr_epi32(0, 16, 1, 17, 2, 18, 3, 19, 4, 20, 5, 21, 6, 22, 7, 23);
  const __m512i second = _mm512_setr_epi32(8, 24, 9, 25, 10, 26, 11, 27, 12, 28, 13, 29, 14, 30, 15, 31);
  const __m512i even = _mm512_setr_epi32(0, 1, 16, 17, 2, 3, 18, 19, 4, 5, 20, 21, 6, 7, 22, 23);
  const __m512i odd = _mm512_setr_epi32(8, 9, 24, 25, 10, 11, 26, 27, 12, 13, 28, 29, 14, 15, 30, 31);
  const __m512 xy_first = _mm512_permutex2var_ps(x, first, y), xy_second = _mm512_permutex2var_ps(x, second, y);
  const __m512 zw_first = _mm512_permutex2var_ps(z, first, w), zw_second = _mm512_permutex2var_ps(z, second, w);
  const __m512 r[4] = {_mm512_permutex2var_ps(xy_first, even, zw_first), _mm512_permutex2var_ps(xy_first, odd, zw_first),
                       _mm512_permutex2var_ps(xy_second, even, zw_second), _mm512_permutex2var_ps(xy_second, odd, zw_second)};
  for (int k = 0; k < 4; ++k) {
    if (consecutive) {
      _mm512_storeu_ps(base + o(0) + 16 * k, r[k]);
      continue;
    }
    _mm_store_ps(base + o(4 * k), _mm512_castps512_ps128(r[k]));
    _mm_store_ps(base + o(4 * k + 1), _mm512_extractf32x4_ps(r[k], 1));
    _mm_store_ps(base + o(4 * k + 2), _mm512_extractf32x4_ps(r[k], 2));
    _mm_store_ps(base + o(4 * k + 3), _mm512_extractf32x4_ps(r[k], 3));
  }
}
inline void load_records(const double* base, const std::int64_t* particle, bool consecutive, __m512d& x, __m512d& y,
                         __m512d& z, __m512d& w) {
  const auto o = [&](int k) { return 4 * static_cast<std::ptrdiff_t>(particle[k]); };
  __m512d r[4];
  for (int k = 0; k < 4; ++k) {  // r[k] holds records 2k, 2k+1
    r[k] = consecutive ? _mm512_loadu_pd(base + o(0) + 8 * k) : _mm512_insertf64x4(_mm512_castpd256_pd512(_mm256_load_pd(base + o(2 * k))), _mm256_load_pd(base + o(2 * k + 1)), 1);
  }
  const __m512i xy = _mm512_setr_epi64(0, 4, 8, 12, 1, 5, 9, 13), zw = _mm512_setr_epi64(2, 6, 10, 14, 3, 7, 11, 15);
  const __m512i low = _mm512_setr_epi64(0, 1, 2, 3, 8, 9, 10, 11), high = _mm512_setr_epi64(4, 5, 6, 7, 12, 13, 14, 15);
  const __m512d xy_first = _mm512_permutex2var_pd(r[0], xy, r[1]), xy_second = _mm512_permutex2var_pd(r[2], xy, r[3]);
  const __m512d zw_first = _mm512_permutex2var_pd(r[0], zw, r[1]), zw_second = _mm512_permutex2var_pd(r[2], zw, r[3]);
  x = _mm512_permutex2var_pd(xy_first, low, xy_second), y = _mm512_permutex2var_pd(xy_first, high, xy_second);
  z = _mm512_permutex2var_pd(zw_first, low, zw_second), w = _mm512_permutex2var_pd(zw_first, high, zw_second);
}
inline void store_records(double* base, const std::int64_t* particle, bool consecutive, __m512d x, __m512d y, __m512d z,
                          __m512d w) {
  const auto o = [&](int k) { return 4 * static_cast<std::ptrdiff_t>(particle[k]); };
  const __m512i first = _mm512_setr_epi64(0, 8, 1, 9, 2, 10, 3, 11), second = _mm512_setr_epi64(4, 12, 5, 13, 6, 14, 7, 15);
  const __m512i even = _mm512_setr_epi64(0, 1, 8, 9, 2, 3, 10, 11), odd = _mm512_setr_epi64(4, 5, 12, 13, 6, 7, 14, 15);
  const __m512d xy_first = _mm512_permutex2var_pd(x, first, y), xy_second = _mm512_permutex2var_pd(x, second, y);
  const __m512d zw_first = _mm512_permutex2var_pd(z, first, w), zw_second = _mm512_permutex2var_pd(z, second, w);
  const __m512d r[4] = {_mm512_permutex2var_pd(xy_first, even, zw_first), _mm512_permutex2var_pd(xy_first, odd, zw_first),
                        _mm512_permutex2var_pd(xy_second, even, zw_second), _mm512_permutex2var_pd(xy_second, odd, zw_second)};
  for (int k = 0; k < 4; ++k) {
    if (consecutive) {
      _mm512_storeu_pd(base + o(0) + 8 * k, r[k]);
      continue;
    }
    _mm256_store_pd(base + o(2 * k), _mm512_castpd512_pd256(r[k]));
    _mm256_store_pd(base + o(2 * k + 1), _mm512_extractf64x4_pd(r[k], 1));
  }
}
#endif

/// Interleaved storage (AoS, AoSoA). Where a whole record is one aligned vector (AoS) and the
/// lanes fill a register (AVX-512), records are loaded and transposed; otherwise gathered.
template <typename Scalar, std::size_t Width>
struct InterleavedPositions {
  using Store = InterleavedParticles<Scalar, Width>;
  Scalar *x, *y, *z;
  explicit InterleavedPositions(Store& store)
      : x(store.data.data() + Store::x * Width), y(store.data.data() + Store::y * Width),
        z(store.data.data() + Store::z * Width) {}
  template <typename IndexType>
  static IndexType offset(IndexType p) { return Store::offset(p); }

  template <typename Lanes>
  static constexpr bool transposes() {
#if defined(__AVX512F__)
    return Width == 1 && Lanes::size * sizeof(Scalar) == 64;
#else
    return false;
#endif
  }
  template <typename Lanes>
  LanePositions<Lanes> load(const typename Lanes::Index* particle, [[maybe_unused]] bool consecutive) const {
    if constexpr (transposes<Lanes>()) {
      LanePositions<Lanes> v;
      typename Lanes::value::register_type rx, ry, rz, rw;
      load_records(x, particle, consecutive, rx, ry, rz, rw);
      v.x = rx, v.y = ry, v.z = rz, v.w = rw;
      return v;
    } else {
      const auto o = offset(Lanes::load(particle));
      return {Lanes::gather(x, o), Lanes::gather(y, o), Lanes::gather(z, o), Lanes::broadcast(Scalar(0))};
    }
  }
  template <typename Lanes>
  void store(const typename Lanes::Index* particle, [[maybe_unused]] bool consecutive, const LanePositions<Lanes>& v) const {
    if constexpr (transposes<Lanes>()) {
      store_records(x, particle, consecutive, v.x, v.y, v.z, v.w);
    } else {
      const auto o = offset(Lanes::load(particle));
      Lanes::scatter(v.x, x, o), Lanes::scatter(v.y, y, o), Lanes::scatter(v.z, z, o);
    }
  }
};

/// Per-particle accumulators of Jacobi corrections (structure of arrays, by particle index).
template <typename Scalar>
using CorrectionSums = SoaPositions<Scalar>;

/// The ConstraintBatches::consecutive bits of the block holding `slot` (0 for one lane, which
/// also serves the overflow slots, which have no block).
template <typename Lanes, typename Scalar>
std::uint8_t consecutive_bits(const ConstraintBatches<Scalar>& batches, std::size_t slot) {
  if constexpr (Lanes::size == 1) {
    return 0;
  } else {
    return batches.consecutive[slot / ConstraintBatches<Scalar>::kBlockLanes];
  }
}

/// Projects slots [begin, end) of `batches` (whole blocks of one colour) in place, Gauss-Seidel
/// style, with over-relaxation ω. Returns the largest particle displacement, m.
template <typename Lanes, typename Positions, typename Scalar>
Scalar project_blocks(const ConstraintBatches<Scalar>& batches, std::size_t begin, std::size_t end,
                      Positions positions, Scalar over_relaxation) {
  using V = typename Lanes::value;
  const V omega = Lanes::broadcast(over_relaxation);
  V largest = Lanes::broadcast(Scalar(0));
  for (std::size_t slot = begin; slot < end; slot += Lanes::size) {
    const auto* i = &batches.particle_i[slot];
    const auto* j = &batches.particle_j[slot];
    const std::uint8_t consecutive = consecutive_bits<Lanes>(batches, slot);
    const bool i_consecutive = consecutive & 1, j_consecutive = consecutive & 2;
    LanePositions<Lanes> a = positions.template load<Lanes>(i, i_consecutive);
    LanePositions<Lanes> b = positions.template load<Lanes>(j, j_consecutive);
    const V dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
    const V length = Lanes::sqrt(dx * dx + dy * dy + dz * dz);
    const V error = length - Lanes::load(&batches.rest_length[slot]);
    // Coincident ends (and padding slots) have no direction: they move nowhere.
    const V scale = Lanes::if_positive(length, omega * error / length);
    const V s_i = Lanes::load(&batches.share_i[slot]), s_j = Lanes::load(&batches.share_j[slot]);
    const V move_i = s_i * scale, move_j = s_j * scale;
    a.x = a.x - move_i * dx, a.y = a.y - move_i * dy, a.z = a.z - move_i * dz;
    b.x = b.x + move_j * dx, b.y = b.y + move_j * dy, b.z = b.z + move_j * dz;
    positions.template store<Lanes>(i, i_consecutive, a), positions.template store<Lanes>(j, j_consecutive, b);
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
    const auto* i = &batches.particle_i[slot];
    const auto* j = &batches.particle_j[slot];
    const std::uint8_t consecutive = consecutive_bits<Lanes>(batches, slot);
    const bool i_consecutive = consecutive & 1, j_consecutive = consecutive & 2;
    const LanePositions<Lanes> a = positions.template load<Lanes>(i, i_consecutive);
    const LanePositions<Lanes> b = positions.template load<Lanes>(j, j_consecutive);
    const V dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
    const V length = Lanes::sqrt(dx * dx + dy * dy + dz * dz);
    const V error = length - Lanes::load(&batches.rest_length[slot]);
    const V scale = Lanes::if_positive(length, error / length);
    const V move_i = Lanes::load(&batches.share_i[slot]) * scale, move_j = Lanes::load(&batches.share_j[slot]) * scale;
    LanePositions<Lanes> sum_i = sums.template load<Lanes>(i, i_consecutive);
    LanePositions<Lanes> sum_j = sums.template load<Lanes>(j, j_consecutive);
    sum_i.x = sum_i.x - move_i * dx, sum_i.y = sum_i.y - move_i * dy, sum_i.z = sum_i.z - move_i * dz;
    sum_j.x = sum_j.x + move_j * dx, sum_j.y = sum_j.y + move_j * dy, sum_j.z = sum_j.z + move_j * dz;
    sums.template store<Lanes>(i, i_consecutive, sum_i), sums.template store<Lanes>(j, j_consecutive, sum_j);
  }
}

}  // namespace limber
