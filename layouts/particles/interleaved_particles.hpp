// Particle storage in interleaved layouts, for cache studies against the structure-of-arrays
// default (ParticleBuffer): array of structures (AoS) and arrays of structures of arrays (AoSoA).
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>

#include "layouts/aligned_array.hpp"
#include "layouts/particles/particle_buffer.hpp"

namespace limber {

/// How particle fields are laid out in memory.
enum class ParticleLayout : std::uint8_t {
  soa,    ///< one array per field (ParticleBuffer): a SIMD load takes consecutive particles
  aos,    ///< one record per particle: x y z x* y* z* w (pad)
  aosoa,  ///< blocks of kLanesPerLine particles, one line per field inside a block
};

/// Particles interleaved in blocks of `Width` particles: a block holds, for each of the 8 record
/// fields (x, y, z, previous x, y, z, inverse mass, padding), Width consecutive values. Width 1
/// is the array of structures (a 32-byte float or 64-byte double record per particle); Width =
/// kLanesPerLine is AoSoA (one cache line per field per block). The record carries the fields
/// relaxation does not touch too, so the cache footprint is that of a real particle record.
///
/// Field f of particle p sits at data[(p / Width)·8·Width + f·Width + p mod Width].
/// Shapes: capacity for the source buffer's capacity() particles, null particle included.
template <typename Scalar, std::size_t Width>
struct InterleavedParticles {
  static_assert(std::has_single_bit(Width), "Width must be a power of two");
  static constexpr std::size_t kFields = 8;
  static constexpr unsigned kWidthShift = static_cast<unsigned>(std::countr_zero(Width));
  enum Field : std::size_t { x, y, z, previous_x, previous_y, previous_z, inverse_mass };

  AlignedArray<Scalar> data;

  /// Offset of field 0 of particle p; field f is at offset(p) + f·Width. Works on scalar and
  /// SIMD integer types alike.
  template <typename IndexType>
  static IndexType offset(IndexType p) {
    return ((p >> kWidthShift) << (kWidthShift + 3)) + (p & IndexType(Width - 1));
  }
  static constexpr std::size_t field_stride = Width;

  /// Copies every field of particles [begin, end) from `source`, sizing the storage to match it.
  void copy_from(const ParticleBuffer<Scalar>& source, std::size_t begin, std::size_t end) {
    data.resize(padded_size(source.capacity(), Width) * kFields);
    for (std::size_t p = begin; p < end; ++p) {
      Scalar* record = data.data() + offset(p);
      record[x * Width] = source.position_x[p], record[y * Width] = source.position_y[p];
      record[z * Width] = source.position_z[p];
      record[previous_x * Width] = source.previous_x[p], record[previous_y * Width] = source.previous_y[p];
      record[previous_z * Width] = source.previous_z[p];
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
