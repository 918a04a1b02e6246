// Particle storage in interleaved layouts, for cache studies against the structure-of-arrays
// default (ParticleBuffer): array of structures (AoS) and arrays of structures of arrays (AoSoA).
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>

#include "limber/layouts/aligned_array.hpp"
#include "limber/layouts/layout_choices.hpp"
#include "limber/layouts/particles/particle_buffer.hpp"

namespace limber {

/// Particles interleaved in blocks of `Width` particles: a block holds, for each of the 4 record
/// fields (position x, y, z and inverse mass w — what relaxation reads; the previous positions
/// stay in the ParticleBuffer), Width consecutive values. Width 1 is the array of structures
/// (the "float4" particle: one aligned 16-byte record in float, 32 in double); Width =
/// kLanesPerLine is AoSoA (one cache line per field per block).
///
/// Field f of particle p sits at data[(p / Width)·4·Width + f·Width + p mod Width].
/// Shapes: capacity for the source buffer's capacity() particles, null particle included.
template <typename Scalar, std::size_t Width>
struct InterleavedParticles {
  static_assert(std::has_single_bit(Width), "Width must be a power of two");
  static constexpr std::size_t kFields = 4;
  static constexpr unsigned kWidthShift = static_cast<unsigned>(std::countr_zero(Width));
  enum Field : std::size_t { x, y, z, inverse_mass };

  AlignedArray<Scalar> data;

  /// Offset of field 0 of particle p; field f is at offset(p) + f·Width. Works on scalar and
  /// SIMD integer types alike.
  template <typename IndexType>
  static IndexType offset(IndexType p) {
    return ((p >> kWidthShift) << (kWidthShift + 2)) + (p & IndexType(Width - 1));
  }
  static constexpr std::size_t field_stride = Width;

  /// Sizes the storage for `source`'s capacity (null particle and padding included), zeroed.
  void resize_for(const ParticleBuffer<Scalar>& source) { data.assign(padded_size(source.capacity(), Width) * kFields, 0); }

  /// Copies every field of particles [begin, end) from `source` (storage sized by resize_for).
  void copy_from(const ParticleBuffer<Scalar>& source, std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p) {
      Scalar* record = data.data() + offset(p);
      record[x * Width] = source.position_x[p], record[y * Width] = source.position_y[p];
      record[z * Width] = source.position_z[p];
      record[inverse_mass * Width] = source.inverse_mass[p];
    }
  }
  /// Copies the positions of particles [begin, end) into `target` (relaxation moves nothing else).
  void copy_positions_to(ParticleBuffer<Scalar>& target, std::size_t begin, std::size_t end) const {
    for (std::size_t p = begin; p < end; ++p) copy_position_to(target, p);
  }
  void copy_position_to(ParticleBuffer<Scalar>& target, std::size_t p) const {
    const Scalar* record = data.data() + offset(p);
    target.position_x[p] = record[x * Width], target.position_y[p] = record[y * Width];
    target.position_z[p] = record[z * Width];
  }
  void copy_position_from(const ParticleBuffer<Scalar>& source, std::size_t p) {
    Scalar* record = data.data() + offset(p);
    record[x * Width] = source.position_x[p], record[y * Width] = source.position_y[p];
    record[z * Width] = source.position_z[p];
  }
};

}  // namespace limber
