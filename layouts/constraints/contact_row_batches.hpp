// Contact rows regrouped by colour into SIMD blocks: what the particle method's contact sweep
// streams over (kernel/relaxation/contact_projection.hpp projects them; kernel/particles/
// contact_rows.hpp says what each field means). Rebuilt every substep, as contacts come and go.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "limber/layouts/aligned_array.hpp"

namespace limber {

/// Particles a contact row may move: a limb's head and tail on each side (a static shape's side
/// has none; the ball's is one particle). Unused places hold the null particle, coefficient 0.
inline constexpr std::size_t kContactRowParticles = 4;
/// Places on each side: 0 and 1 on the first, 2 and 3 on the second.
inline constexpr std::size_t kContactRowSideParticles = 2;

/// The contact rows grouped by colour (no two rows of a colour share a movable particle), each
/// colour a run of blocks of kBlockLanes slots: first the rows whose second side is static (places
/// 2 and 3 unused), then the rest, so that the blocks before pair_begin[colour] are projected
/// over places 0 and 1 alone. Padding slots name the null particle everywhere (zero mass: they
/// move nothing and are never written). Rows the colouring could not place follow as overflow
/// slots [overflow_begin(), slot_count()), projected one at a time.
///
/// What does not change during the sweeps is stored when the rows are packed, so that the sweep
/// gathers positions alone: inverse masses are fixed from compile on (pins are joints to the
/// world; static and kinematic particles have w = 0 from the start), and the start positions x*
/// for the whole substep.
template <typename Scalar>
struct ContactRowBatches {
  using Index = std::conditional_t<sizeof(Scalar) == 4, std::int32_t, std::int64_t>;
  static constexpr std::size_t kBlockLanes = kLanesPerLine<Scalar>;

  std::array<AlignedArray<Index>, kContactRowParticles> particle;
  /// Per place: c_k, and the share w_k c_k (1/kg: how far a unit push moves the particle; 0 for
  /// a place the row does not move).
  std::array<AlignedArray<Scalar>, kContactRowParticles> coefficient, share;
  /// Per slot: the contact normal; the offset that C = n·Σ c_k x_k − offset is measured from
  /// (m); the row's effective mass 1/Σ w_k c_k² (kg; 0 where it moves nothing); its start point
  /// Σ c_k x*_k at the substep's start positions (m); the Coulomb coefficient; the accumulated
  /// normal push λ (kg·m) and friction impulse (kg·m, a tangential vector), both zeroed each
  /// substep.
  AlignedArray<Scalar> normal_x, normal_y, normal_z, offset, effective_mass, start_x, start_y, start_z, friction, lambda,
      tangent_x, tangent_y, tangent_z;
  std::vector<std::uint32_t> colour_begin{0};  ///< slot offsets, colour_count() + 1 entries
  /// Per colour: the first slot of its first block holding a row that moves a second side.
  std::vector<std::uint32_t> pair_begin;
  std::vector<std::uint32_t> row;  ///< the ContactRowSet row of each slot (padding: ~0)

  template <typename Visitor>
  void for_each_field(Visitor&& visit) {
    for (auto& array : particle) visit(array);
    for (auto& array : coefficient) visit(array);
    for (auto& array : share) visit(array);
    for (auto* array : {&normal_x, &normal_y, &normal_z, &offset, &effective_mass, &start_x, &start_y, &start_z, &friction, &lambda,
                        &tangent_x, &tangent_y, &tangent_z}) {
      visit(*array);
    }
  }

  std::size_t colour_count() const { return colour_begin.size() - 1; }
  std::size_t overflow_begin() const { return colour_begin.back(); }
  std::size_t slot_count() const { return lambda.size(); }

  void reserve(std::size_t slots, std::size_t colours) {
    for_each_field([&](auto& array) { array.reserve(slots); });
    colour_begin.reserve(colours + 1);
    pair_begin.reserve(colours);
    row.reserve(slots);
  }
  void clear() {
    for_each_field([&](auto& array) { array.clear(); });
    colour_begin.assign(1, 0);
    pair_begin.clear();
    row.clear();
  }
  /// Appends an empty slot on `null_particle` and returns its index.
  std::size_t push(Index null_particle) {
    for_each_field([&](auto& array) {
      if constexpr (std::is_same_v<typename std::decay_t<decltype(array)>::value_type, Index>) {
        array.push_back(null_particle);
      } else {
        array.push_back(0);
      }
    });
    row.push_back(~std::uint32_t{0});
    return lambda.size() - 1;
  }
  /// Pads the colour just pushed to whole blocks and closes it; its rows that move a second side
  /// begin at slot `pairs` (none if it is the colour's end).
  void close_colour(Index null_particle, std::size_t pairs) {
    const bool has_pairs = pairs < lambda.size();
    while (lambda.size() % kBlockLanes != 0) push(null_particle);
    pair_begin.push_back(static_cast<std::uint32_t>(has_pairs ? pairs / kBlockLanes * kBlockLanes : lambda.size()));
    colour_begin.push_back(static_cast<std::uint32_t>(lambda.size()));
  }
};

}  // namespace limber
