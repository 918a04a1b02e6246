// Joint rows regrouped by colour into SIMD blocks: what the particle method's joint sweep streams
// over (kernel/relaxation/joint_projection.hpp projects them; kernel/particles/joint_rows.hpp
// says what each field means).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "limber/layouts/aligned_array.hpp"

namespace limber {

/// Particles a joint row may touch: five on each of its two sides (a limb's head, tail, its two
/// frame particles and its centre; unused places hold the null particle).
inline constexpr std::size_t kJointRowSideParticles = 5;
inline constexpr std::size_t kJointRowParticles = 2 * kJointRowSideParticles;
/// Numbers a row's kind reads as directions or coefficients (joint_rows.hpp).
inline constexpr std::size_t kJointRowDirections = 12;

/// The awake joint rows grouped by colour (no two rows of a colour share a movable particle),
/// each colour a run of blocks of kBlockLanes slots, and inside a colour, blocks grouped by row
/// kind so a block is one kind: the kernel branches once per block, not per lane. Padding slots
/// name the null particle everywhere (zero mass, so they move nothing). Rows the colouring
/// could not place follow as overflow slots [overflow_begin(), slot_count()), unpadded, one
/// at a time by scalar code.
template <typename Scalar>
struct JointRowBatches {
  using Index = std::conditional_t<sizeof(Scalar) == 4, std::int32_t, std::int64_t>;
  static constexpr std::size_t kBlockLanes = kLanesPerLine<Scalar>;

  std::array<AlignedArray<Index>, kJointRowParticles> particle;
  std::array<AlignedArray<Scalar>, kJointRowDirections> direction;
  /// Per slot (kernel/particles/joint_rows.hpp's JointRow): side kinds (A and B), the bounds
  /// the row's coordinate is held in, the target and target velocity, the weight of the
  /// start-of-substep term of a rigid row, a drive's stiffness and damping, the friction bound,
  /// and the accumulated multiplier (zeroed at each substep's start).
  AlignedArray<Scalar> side_a, side_b, lower, upper, target, target_velocity, blend, stiffness, damping, friction, lambda;
  std::vector<std::uint32_t> colour_begin{0};  ///< slot offsets, colour_count() + 1 entries
  std::vector<std::uint8_t> block_kind;         ///< per block of the colours
  std::vector<std::uint32_t> overflow_row;      ///< the JointRowSet row of each overflow slot
  std::vector<std::uint8_t> overflow_kind;      ///< and its kind

  template <typename Visitor>
  void for_each_field(Visitor&& visit) {
    for (auto& array : particle) visit(array);
    for (auto& array : direction) visit(array);
    for (auto* array : {&side_a, &side_b, &lower, &upper, &target, &target_velocity, &blend, &stiffness, &damping, &friction, &lambda}) {
      visit(*array);
    }
  }

  std::size_t colour_count() const { return colour_begin.size() - 1; }
  std::size_t overflow_begin() const { return colour_begin.back(); }
  std::size_t slot_count() const { return lambda.size(); }

  void reserve(std::size_t slots, std::size_t colours) {
    for_each_field([&](auto& array) { array.reserve(slots); });
    colour_begin.reserve(colours + 1);
    block_kind.reserve(slots / kBlockLanes + 1);
    overflow_row.reserve(slots);
    overflow_kind.reserve(slots);
  }
  void clear() {
    for_each_field([&](auto& array) { array.clear(); });
    colour_begin.assign(1, 0);
    block_kind.clear();
    overflow_row.clear();
    overflow_kind.clear();
  }
  /// Appends an empty slot on `null_particle` and returns its index.
  std::size_t push(Index null_particle) {
    for (auto& array : particle) array.push_back(null_particle);
    for (auto& array : direction) array.push_back(0);
    for (auto* array : {&side_a, &side_b, &lower, &upper, &target, &target_velocity, &blend, &stiffness, &damping, &friction, &lambda}) {
      array->push_back(0);
    }
    return lambda.size() - 1;
  }
  /// Pads the run of `kind` just pushed to whole blocks and records the kind of its blocks.
  void close_kind(Index null_particle, std::uint8_t kind, std::size_t run_begin) {
    if (lambda.size() == run_begin) return;
    while (lambda.size() % kBlockLanes != 0) push(null_particle);
    for (std::size_t slot = run_begin; slot < lambda.size(); slot += kBlockLanes) block_kind.push_back(kind);
  }
  void close_colour() { colour_begin.push_back(static_cast<std::uint32_t>(lambda.size())); }
};

}  // namespace limber
