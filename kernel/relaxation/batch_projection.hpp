// Distance-constraint projection over one block of a colour (ConstraintBatches), written once
// for every lane width and particle layout.
//
// The arithmetic is project_distance_constraint's (distance_projection.hpp), operation for
// operation, with the shares read from the batch: with -ffp-contract=off (CMakeLists.txt) and
// IEEE sqrt and division in every lane, the scalar path (ScalarLanes) and the SIMD path
// (SimdLanes) give the same bits, so the SIMD sweep can be tested bit for bit against scalar code.
//
// Four kernels share the loads and stores (kernel/relaxation/README.md derives them):
// - project_blocks: the pbd projection along the current gradient (thesis eq. 4.7);
// - project_blocks_from_start: the rattle rule's position projection, SHAKE's, along the
//   gradient n₀ stored at the substep's start, with its pbd fallback;
// - project_velocity_blocks: the rattle rule's velocity projection onto the tangent space;
// - store_gradients: writes the unit gradients the two rattle kernels read.
// The Jacobi variants accumulate the same corrections instead of applying them.
#pragma once

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>

#include <xsimd/xsimd.hpp>
#if defined(__AVX512F__)
#include <immintrin.h>
#endif

#include "limber/layouts/constraints/constraint_batches.hpp"
#include "limber/layouts/particles/interleaved_particles.hpp"
#include "limber/layouts/particles/particle_buffer.hpp"

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
  static void scatter_where(bool m, value v, Scalar* base, index offset) {
    if (m) base[offset] = v;
  }
  static void scatter_each_where(bool m, value x, value y, value z, Scalar* base_x, Scalar* base_y, Scalar* base_z, index offset) {
    if (m) base_x[offset] = x, base_y[offset] = y, base_z[offset] = z;
  }
  static value sqrt(value v) { return std::sqrt(v); }
  static value abs(value v) { return std::abs(v); }
  static value max(value a, value b) { return std::max(a, b); }
  static value if_positive(value test, value v) { return test > Scalar(0) ? v : Scalar(0); }
  static Scalar reduce_max(value v) { return v; }
  using mask = bool;
  static value select(mask m, value a, value b) { return m ? a : b; }
  static bool any(mask m) { return m; }
  static std::size_t count(mask m) { return m ? 1 : 0; }
  static void store(value v, Scalar* p) { *p = v; }
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
  // Writes only the lanes where `m` holds: no lane writes a particle it did not move (the null
  // particle, pinned ones), so threads never write the same place.
  static void scatter_where(typename value::batch_bool_type m, value v, Scalar* base, index offset) {
#if defined(__AVX512F__)
    if constexpr (size == 16 && std::is_same_v<Scalar, float>) {
      return _mm512_mask_i32scatter_ps(base, static_cast<__mmask16>(m), offset, v, 4);
    }
    if constexpr (size == 8 && std::is_same_v<Scalar, double>) {
      return _mm512_mask_i64scatter_pd(base, static_cast<__mmask8>(m), offset, v, 8);
    }
#endif
    alignas(64) Scalar values[size];
    alignas(64) Index indices[size];
    bool lanes[size];
    v.store_aligned(values), offset.store_aligned(indices), m.store_unaligned(lanes);
    for (std::size_t lane = 0; lane < size; ++lane) {
      if (lanes[lane]) base[indices[lane]] = values[lane];
    }
  }
  // The three coordinates of the lanes where `m` holds, written lane by lane with scalar stores:
  // where few lanes move (contact rows), faster than three masked scatters, which cost the same
  // whatever the mask (bench/collision.md, "Contact rows").
  static void scatter_each_where(typename value::batch_bool_type m, value x, value y, value z, Scalar* base_x, Scalar* base_y,
                                 Scalar* base_z, index offset) {
    alignas(64) Scalar vx[size], vy[size], vz[size];
    alignas(64) Index at[size];
    x.store_aligned(vx), y.store_aligned(vy), z.store_aligned(vz), offset.store_aligned(at);
    for (std::uint64_t lanes = bits(m); lanes != 0; lanes &= lanes - 1) {
      const auto lane = static_cast<std::size_t>(std::countr_zero(lanes));
      base_x[at[lane]] = vx[lane], base_y[at[lane]] = vy[lane], base_z[at[lane]] = vz[lane];
    }
  }
  // Bit k of the result: lane k of `m`.
  static std::uint64_t bits(typename value::batch_bool_type m) {
#if defined(__AVX512F__)
    if constexpr (size == 16 && std::is_same_v<Scalar, float>) return static_cast<__mmask16>(m);
    if constexpr (size == 8 && std::is_same_v<Scalar, double>) return static_cast<__mmask8>(m);
#endif
    bool lanes[size];
    m.store_unaligned(lanes);
    std::uint64_t result = 0;
    for (std::size_t lane = 0; lane < size; ++lane) result |= std::uint64_t{lanes[lane]} << lane;
    return result;
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
  using mask = typename value::batch_bool_type;
  static value select(mask m, value a, value b) { return xsimd::select(m, a, b); }
  static bool any(mask m) { return xsimd::any(m); }
  static std::size_t count(mask m) {  // xsimd 8.1 has no popcount of a mask
    bool lanes[size];
    m.store_unaligned(lanes);
    return static_cast<std::size_t>(std::count(lanes, lanes + size, true));
  }
  static void store(value v, Scalar* p) { v.store_aligned(p); }
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

/// The two particles of each lane of the block at `slot`: where they are in a layout (vector
/// loads for runs of consecutive particles, else gathers), their values there, and a store back.
template <typename Lanes, typename Positions>
struct BlockEnds {
  const typename Lanes::Index *i, *j;
  bool i_consecutive, j_consecutive;
  LanePositions<Lanes> a, b;  ///< particle i's and j's values in each lane

  template <typename Scalar>
  BlockEnds(const ConstraintBatches<Scalar>& batches, std::size_t slot, const Positions& positions)
      : i(&batches.particle_i[slot]), j(&batches.particle_j[slot]) {
    const std::uint8_t consecutive = consecutive_bits<Lanes>(batches, slot);
    i_consecutive = consecutive & 1, j_consecutive = consecutive & 2;
    a = positions.template load<Lanes>(i, i_consecutive);
    b = positions.template load<Lanes>(j, j_consecutive);
  }
  /// The same lanes' particles in another array triple of the same layout (Jacobi's sums).
  template <typename Other>
  std::pair<LanePositions<Lanes>, LanePositions<Lanes>> load(const Other& other) const {
    return {other.template load<Lanes>(i, i_consecutive), other.template load<Lanes>(j, j_consecutive)};
  }
  template <typename Other>
  void store(const Other& target, const LanePositions<Lanes>& at_i, const LanePositions<Lanes>& at_j) const {
    target.template store<Lanes>(i, i_consecutive, at_i), target.template store<Lanes>(j, j_consecutive, at_j);
  }
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
    BlockEnds<Lanes, Positions> ends(batches, slot, positions);
    LanePositions<Lanes>&a = ends.a, &b = ends.b;
    const V dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
    const V length = Lanes::sqrt(dx * dx + dy * dy + dz * dz);
    const V error = length - Lanes::load(&batches.rest_length[slot]);
    // Coincident ends (and padding slots) have no direction: they move nowhere.
    const V scale = Lanes::if_positive(length, omega * error / length);
    const V s_i = Lanes::load(&batches.share_i[slot]), s_j = Lanes::load(&batches.share_j[slot]);
    const V move_i = s_i * scale, move_j = s_j * scale;
    a.x = a.x - move_i * dx, a.y = a.y - move_i * dy, a.z = a.z - move_i * dz;
    b.x = b.x + move_j * dx, b.y = b.y + move_j * dy, b.z = b.z + move_j * dz;
    ends.store(positions, a, b);
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
    const BlockEnds<Lanes, Positions> ends(batches, slot, positions);
    const LanePositions<Lanes>&a = ends.a, &b = ends.b;
    const V dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
    const V length = Lanes::sqrt(dx * dx + dy * dy + dz * dz);
    const V error = length - Lanes::load(&batches.rest_length[slot]);
    const V scale = Lanes::if_positive(length, error / length);
    const V move_i = Lanes::load(&batches.share_i[slot]) * scale, move_j = Lanes::load(&batches.share_j[slot]) * scale;
    auto [sum_i, sum_j] = ends.load(sums);
    sum_i.x = sum_i.x - move_i * dx, sum_i.y = sum_i.y - move_i * dy, sum_i.z = sum_i.z - move_i * dz;
    sum_j.x = sum_j.x + move_j * dx, sum_j.y = sum_j.y + move_j * dy, sum_j.z = sum_j.z + move_j * dz;
    ends.store(sums, sum_i, sum_j);
  }
}

// ---- The rattle rule (ProjectionRule::rattle) ----

/// A rattle position projection uses its start gradient n₀ while cos∠(n, n₀) = n·n₀ stays above
/// this, n the current gradient; at or below it, the slot falls back to the pbd projection for
/// the rest of the substep. SHAKE's update divides by n·n₀: as the angle nears 90° the line
/// x + μ·n₀ stops meeting the constraint sphere and the iteration diverges (a link turning more
/// than a radian per substep). 0.5 (60°) keeps the divisor ≥ 1/2, so one projection moves at
/// most twice the pbd one; a substep where a link turns that far is too long to be accurate
/// anyway, and the step report counts the fallbacks.
inline constexpr double kStartGradientMinimumCosine = 0.5;

/// The batches' gradient fields (ConstraintBatches::gradient_*), writable, and the counter of
/// slots that fell back to the pbd projection (summed: the same total for any thread count).
template <typename Scalar>
struct GradientField {
  Scalar *x = nullptr, *y = nullptr, *z = nullptr;
  std::atomic<std::uint64_t>* fallbacks = nullptr;
};

/// Writes the unit gradient n = (x_i − x_j)/|x_i − x_j| of slots [begin, end) at `positions`
/// (the previous positions: the substep's start; or the current ones) into `gradients`; 0 for a
/// zero-length joint (rest length 0: linear, its three rows need no stored direction) and for
/// coincident ends.
template <typename Lanes, typename Positions, typename Scalar>
void store_gradients(const ConstraintBatches<Scalar>& batches, GradientField<Scalar> gradients, std::size_t begin,
                     std::size_t end, Positions positions) {
  using V = typename Lanes::value;
  const V zero = Lanes::broadcast(Scalar(0)), one = Lanes::broadcast(Scalar(1));
  for (std::size_t slot = begin; slot < end; slot += Lanes::size) {
    const BlockEnds<Lanes, Positions> ends(batches, slot, positions);
    const V dx = ends.a.x - ends.b.x, dy = ends.a.y - ends.b.y, dz = ends.a.z - ends.b.z;
    const V length = Lanes::sqrt(dx * dx + dy * dy + dz * dz);
    const typename Lanes::mask valid = (Lanes::load(&batches.rest_length[slot]) > zero) & (length > zero);
    const V inverse = Lanes::select(valid, one / Lanes::select(valid, length, one), zero);
    Lanes::store(dx * inverse, gradients.x + slot), Lanes::store(dy * inverse, gradients.y + slot);
    Lanes::store(dz * inverse, gradients.z + slot);
  }
}

/// The rattle rule's position correction of one block: u with Δx_i = −s_i·u, Δx_j = +s_j·u.
/// SHAKE (Ryckaert et al. 1977) moves along the start gradient n₀ by the Newton step of
/// C(μ) = |d + μ(w_i + w_j)n₀| − L, whose slope is (w_i + w_j)·n·n₀:
///   u = ω·C/(n·n₀)·n₀ = ω·C·|d|/(d·n₀)·n₀;
/// the pbd fallback moves along the current gradient, u = ω·C/|d|·d. A slot whose n·n₀ is at or
/// below kStartGradientMinimumCosine falls back, and its n₀ is zeroed so it stays pbd for the
/// rest of the substep (zero-length joints, stored with n₀ = 0, are pbd by construction: their
/// constraint is linear, so both rules move them alike). Returns the largest |u|·max(s_i, s_j).
template <typename Lanes, typename Scalar>
struct StartGradientCorrection {
  using V = typename Lanes::value;
  V x, y, z, magnitude;

  StartGradientCorrection(const ConstraintBatches<Scalar>& batches, GradientField<Scalar> gradients, std::size_t slot,
                          const LanePositions<Lanes>& a, const LanePositions<Lanes>& b, V omega) {
    const V zero = Lanes::broadcast(Scalar(0)), one = Lanes::broadcast(Scalar(1));
    const V dx = a.x - b.x, dy = a.y - b.y, dz = a.z - b.z;
    const V length = Lanes::sqrt(dx * dx + dy * dy + dz * dz);
    const V error = omega * (length - Lanes::load(&batches.rest_length[slot]));
    const V gx = Lanes::load(gradients.x + slot), gy = Lanes::load(gradients.y + slot), gz = Lanes::load(gradients.z + slot);
    const V along = dx * gx + dy * gy + dz * gz;  // |d|·(n·n₀)
    const typename Lanes::mask from_start = along > Lanes::broadcast(Scalar(kStartGradientMinimumCosine)) * length;
    // One division for both scales: q = ω·C/(|d|·a), a = d·n₀ (SHAKE) or 1 (fallback), so that
    // ω·C·|d|/(d·n₀) = q·|d|² and ω·C/|d| = q. Coincident ends (and padding slots) have no
    // current direction: the fallback moves nowhere.
    const V quotient = Lanes::if_positive(length, error / (length * Lanes::select(from_start, along, one)));
    const V start_scale = quotient * length * length, pbd_scale = quotient;
    x = Lanes::select(from_start, start_scale * gx, pbd_scale * dx);
    y = Lanes::select(from_start, start_scale * gy, pbd_scale * dy);
    z = Lanes::select(from_start, start_scale * gz, pbd_scale * dz);
    magnitude = Lanes::if_positive(length, Lanes::abs(Lanes::select(from_start, start_scale, error)));
    const typename Lanes::mask fallback = (!from_start) & (gx * gx + gy * gy + gz * gz > zero);
    if (Lanes::any(fallback)) {
      Lanes::store(Lanes::select(fallback, zero, gx), gradients.x + slot);
      Lanes::store(Lanes::select(fallback, zero, gy), gradients.y + slot);
      Lanes::store(Lanes::select(fallback, zero, gz), gradients.z + slot);
      gradients.fallbacks->fetch_add(Lanes::count(fallback), std::memory_order_relaxed);
    }
  }
};

/// The rattle rule's velocity correction of one block (the velocity stage of RATTLE, Andersen
/// 1983): u with Δv_i = −s_i·u, Δv_j = +s_j·u removes the relative velocity along the stored
/// end-of-substep gradient n, u = (n·(v_i − v_j))·n, so that d/dt |x_i − x_j| = 0; where no
/// gradient is stored (n = 0: a zero-length joint, or coincident ends) all three rows,
/// u = v_i − v_j. The weights are the position stage's, so momentum is kept. magnitude: |u|, m/s.
template <typename Lanes, typename Scalar>
struct VelocityCorrection {
  using V = typename Lanes::value;
  V x, y, z, magnitude;

  VelocityCorrection(const ConstraintBatches<Scalar>& batches, std::size_t slot, const LanePositions<Lanes>& a,
                     const LanePositions<Lanes>& b) {
    const V rx = a.x - b.x, ry = a.y - b.y, rz = a.z - b.z;
    const V gx = Lanes::load(&batches.gradient_x[slot]), gy = Lanes::load(&batches.gradient_y[slot]),
            gz = Lanes::load(&batches.gradient_z[slot]);
    const V normal = gx * rx + gy * ry + gz * rz;
    const typename Lanes::mask point = !(gx * gx + gy * gy + gz * gz > Lanes::broadcast(Scalar(0)));
    x = Lanes::select(point, rx, normal * gx), y = Lanes::select(point, ry, normal * gy), z = Lanes::select(point, rz, normal * gz);
    magnitude = Lanes::sqrt(x * x + y * y + z * z);
  }
};

/// Gauss-Seidel over slots [begin, end) (whole blocks of one colour) with a correction kernel
/// (StartGradientCorrection on positions, VelocityCorrection on velocities); `make(slot, a, b)`
/// builds it. Returns the largest particle displacement (m) or velocity change (m/s).
template <typename Lanes, typename Positions, typename Scalar, typename Make>
Scalar project_blocks_with(const ConstraintBatches<Scalar>& batches, std::size_t begin, std::size_t end,
                           Positions positions, Make&& make) {
  using V = typename Lanes::value;
  V largest = Lanes::broadcast(Scalar(0));
  for (std::size_t slot = begin; slot < end; slot += Lanes::size) {
    BlockEnds<Lanes, Positions> ends(batches, slot, positions);
    LanePositions<Lanes>&a = ends.a, &b = ends.b;
    const auto u = make(slot, a, b);
    const V s_i = Lanes::load(&batches.share_i[slot]), s_j = Lanes::broadcast(Scalar(1)) - s_i;  // one field less to stream
    a.x = a.x - s_i * u.x, a.y = a.y - s_i * u.y, a.z = a.z - s_i * u.z;
    b.x = b.x + s_j * u.x, b.y = b.y + s_j * u.y, b.z = b.z + s_j * u.z;
    ends.store(positions, a, b);
    largest = Lanes::max(largest, u.magnitude * Lanes::max(s_i, s_j));
  }
  return Lanes::reduce_max(largest);
}

/// Jacobi with a correction kernel: adds the corrections of slots [begin, end), computed from
/// the unchanged positions (or velocities), to the per-particle sums (as accumulate_blocks).
template <typename Lanes, typename Positions, typename Scalar, typename Make>
void accumulate_blocks_with(const ConstraintBatches<Scalar>& batches, std::size_t begin, std::size_t end,
                            Positions positions, CorrectionSums<Scalar> sums, Make&& make) {
  using V = typename Lanes::value;
  for (std::size_t slot = begin; slot < end; slot += Lanes::size) {
    const BlockEnds<Lanes, Positions> ends(batches, slot, positions);
    const auto u = make(slot, ends.a, ends.b);
    const V s_i = Lanes::load(&batches.share_i[slot]), s_j = Lanes::broadcast(Scalar(1)) - s_i;
    auto [sum_i, sum_j] = ends.load(sums);
    sum_i.x = sum_i.x - s_i * u.x, sum_i.y = sum_i.y - s_i * u.y, sum_i.z = sum_i.z - s_i * u.z;
    sum_j.x = sum_j.x + s_j * u.x, sum_j.y = sum_j.y + s_j * u.y, sum_j.z = sum_j.z + s_j * u.z;
    ends.store(sums, sum_i, sum_j);
  }
}

}  // namespace limber
