// Constraints regrouped by colour into SIMD blocks: what a coloured sweep streams over.
#pragma once

#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "limber/layouts/aligned_array.hpp"

namespace limber {

/// The awake distance constraints between two movable particles, grouped by colour. Colour k
/// occupies slots [colour_begin[k], colour_begin[k + 1]), a whole number of blocks of
/// kBlockLanes slots (16 floats or 8 doubles: one cache line per field, one AVX-512 register);
/// no two constraints of a colour share a particle, so a block is projected in SIMD lanes with
/// gather/scatter and blocks of a colour run on any thread in any order.
///
/// Padding slots join the null particle to itself with rest length 0 and shares 0, so a block
/// needs no masks. Each slot carries its two particles' shares of the correction (the
/// relaxation rule, thesis eq. 4.6 or 4.7, evaluated once when the batches are built), so the
/// sweep reads no inverse masses.
///
/// Constraints with a pinned end, and those the colouring could not place (hubs), follow the
/// colours as overflow slots [overflow_begin(), slot_count()), unpadded, projected one at a
/// time by scalar code in that order.
template <typename Scalar>
struct ConstraintBatches {
  /// Particle index type of the SIMD gathers: as wide as Scalar, so index and value registers
  /// have the same lane count.
  using Index = std::conditional_t<sizeof(Scalar) == 4, std::int32_t, std::int64_t>;
  static constexpr std::size_t kBlockLanes = kLanesPerLine<Scalar>;

  AlignedArray<Index> particle_i, particle_j;
  AlignedArray<Scalar> rest_length;        ///< m
  AlignedArray<Scalar> share_i, share_j;   ///< fraction of the correction each end takes
  /// The unit constraint gradient n = (x_i − x_j)/|x_i − x_j| where the projection rule needs it
  /// stored (rattle: at the substep's start for the position sweeps, at its end for the velocity
  /// sweeps); 0 for a zero-length joint, whose three-row constraint is linear, and for a slot
  /// that falls back to the pbd projection. Unused (0) under pbd.
  AlignedArray<Scalar> gradient_x, gradient_y, gradient_z;
  std::vector<std::uint32_t> colour_begin{0};  ///< slot offsets, colour_count() + 1 entries
  /// Per block of the colours: bit 0 set when its particle_i are consecutive (p, p + 1, …),
  /// bit 1 the same for particle_j — then the sweep loads positions with vector loads instead
  /// of gathers. Overflow slots have no entry.
  std::vector<std::uint8_t> consecutive;

  template <typename Visitor>
  void for_each_field(Visitor&& visit) {
    visit("particle_i", particle_i), visit("particle_j", particle_j), visit("rest_length", rest_length);
    visit("share_i", share_i), visit("share_j", share_j);
    visit("gradient_x", gradient_x), visit("gradient_y", gradient_y), visit("gradient_z", gradient_z);
  }

  std::size_t colour_count() const { return colour_begin.size() - 1; }
  std::size_t overflow_begin() const { return colour_begin.back(); }
  std::size_t slot_count() const { return particle_i.size(); }
  std::size_t block_count(std::size_t colour) const {
    return (colour_begin[colour + 1] - colour_begin[colour]) / kBlockLanes;
  }

  /// Capacity for `slots` slots (padding included) in `colours` colours, so rebuilding after
  /// islands sleep or wake does not allocate.
  void reserve(std::size_t slots, std::size_t colours) {
    for_each_field([&](const char*, auto& array) { array.reserve(slots); });
    colour_begin.reserve(colours + 1);
    consecutive.reserve(slots / kBlockLanes + colours);
  }

  /// Empties every colour and the overflow, keeping the capacity.
  void clear() {
    for_each_field([&](const char*, auto& array) { array.clear(); });
    colour_begin.assign(1, 0);
    consecutive.clear();
  }

  /// Appends one slot: to the colour being filled, or to the overflow once the colours are closed.
  void push(Index i, Index j, Scalar rest, Scalar s_i, Scalar s_j) {
    particle_i.push_back(i), particle_j.push_back(j), rest_length.push_back(rest);
    share_i.push_back(s_i), share_j.push_back(s_j);
    gradient_x.push_back(0), gradient_y.push_back(0), gradient_z.push_back(0);
  }

  /// Pads the colour being filled to a whole number of blocks with no-op slots on
  /// `null_particle` and closes it.
  void close_colour(Index null_particle) {
    while (particle_i.size() % kBlockLanes != 0) push(null_particle, null_particle, 0, 0, 0);
    for (std::size_t slot = colour_begin.back(); slot < particle_i.size(); slot += kBlockLanes) {
      const auto runs = [&](const AlignedArray<Index>& particle) {
        for (std::size_t lane = 1; lane < kBlockLanes; ++lane) {
          if (particle[slot + lane] != particle[slot] + static_cast<Index>(lane)) return false;
        }
        return true;
      };
      consecutive.push_back(static_cast<std::uint8_t>((runs(particle_i) ? 1 : 0) | (runs(particle_j) ? 2 : 0)));
    }
    colour_begin.push_back(static_cast<std::uint32_t>(particle_i.size()));
  }
};

}  // namespace limber
