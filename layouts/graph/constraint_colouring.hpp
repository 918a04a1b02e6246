// Graph colouring of distance constraints into independent batches (colours).
//
// Two constraints conflict when they share a particle that can move. Within one colour no two
// constraints conflict, so a colour can be projected in SIMD lanes and split across threads
// with no races and no atomics, and the result does not depend on the order inside the colour.
// Particles that cannot move (pinned, inverse mass 0) never conflict: projecting a constraint
// never writes them (Box2D v3 treats static bodies the same way).
//
// Greedy colouring in the given order, one 64-bit used-colour mask per particle: O(constraints).
// Given a tree's constraints in breadth-first order (compile.cpp's storage order), every edge
// (parent p, child c) meets only p's already coloured edges, so greedy uses exactly as many
// colours as the busiest particle has constraints — the optimum for a tree (trees are
// bipartite, so that many suffice). On other graphs greedy may use more.
//
// A constraint that finds all `max_colours` colours taken at one of its particles (a hub: a
// torso with many joints, a star) goes to the overflow list, projected by scalar code after
// (or before) the colours, rather than growing the colour count (Box2D v3's overflow constraints).
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// Colour of a constraint that is in no colour (overflow, or never projected).
inline constexpr std::uint8_t kNoColour = 0xFF;

/// The greatest number of colours the per-particle masks can track.
inline constexpr std::uint32_t kMaxColours = 64;

struct ConstraintColouring {
  /// colour[c] for every constraint c of the input: 0 … colour_count − 1, or kNoColour.
  std::vector<std::uint8_t> colour;
  /// Number of constraints in each colour (the batch sizes), colour_count() entries.
  std::vector<std::uint32_t> batch_size;
  /// Constraints between movable particles that found no free colour, in input order.
  std::vector<std::uint32_t> overflow;

  std::uint32_t colour_count() const { return static_cast<std::uint32_t>(batch_size.size()); }
};

/// Colours the constraints listed in `order` (indices into particle_i / particle_j), greedily in
/// that order. `movable[p]` is false for particles that never move; a constraint with a fixed
/// end is coloured by its movable end alone, and one with two fixed ends gets kNoColour and
/// is not listed anywhere. Constraints not in `order` get kNoColour.
///
/// Shapes: particle_i and particle_j have one entry per constraint; movable has one per
/// particle and every index is < movable.size(). max_colours in [1, kMaxColours].
/// Throws std::invalid_argument on a bad max_colours or an out-of-range particle index.
inline ConstraintColouring colour_constraints(std::span<const std::uint32_t> particle_i,
                                              std::span<const std::uint32_t> particle_j,
                                              std::span<const std::uint32_t> order, const std::vector<bool>& movable,
                                              std::uint32_t max_colours) {
  if (max_colours < 1 || max_colours > kMaxColours) {
    throw std::invalid_argument("colour_constraints: max_colours must be in [1, 64]");
  }
  if (particle_i.size() != particle_j.size()) {
    throw std::invalid_argument("colour_constraints: particle_i and particle_j differ in length");
  }
  ConstraintColouring result;
  result.colour.assign(particle_i.size(), kNoColour);
  std::vector<std::uint64_t> used(movable.size(), 0);  // bit k: the particle has a colour-k constraint
  const std::uint64_t allowed = max_colours == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << max_colours) - 1;
  for (const std::uint32_t c : order) {
    const std::uint32_t i = particle_i[c], j = particle_j[c];
    if (i >= movable.size() || j >= movable.size()) {
      throw std::invalid_argument("colour_constraints: constraint " + std::to_string(c) + " names particle " +
                                  std::to_string(std::max(i, j)) + " of " + std::to_string(movable.size()));
    }
    if (!movable[i] && !movable[j]) continue;
    const std::uint64_t taken = (movable[i] ? used[i] : 0) | (movable[j] ? used[j] : 0);
    const std::uint64_t free = ~taken & allowed;
    if (free == 0) {
      result.overflow.push_back(c);
      continue;
    }
    const auto k = static_cast<std::uint32_t>(std::countr_zero(free));
    result.colour[c] = static_cast<std::uint8_t>(k);
    if (movable[i]) used[i] |= std::uint64_t{1} << k;
    if (movable[j]) used[j] |= std::uint64_t{1} << k;
    if (k >= result.batch_size.size()) result.batch_size.resize(k + 1, 0);
    ++result.batch_size[k];
  }
  return result;
}

/// The same greedy colouring for rows that touch any number of particles (the particle method's
/// joint rows): row r touches particles_of(r) (a range of indices; fixed particles and repeats
/// allowed). Rows with no movable particle get kNoColour and are not listed.
template <typename ParticlesOf>
ConstraintColouring colour_rows(std::size_t row_count, ParticlesOf&& particles_of, const std::vector<bool>& movable,
                                std::uint32_t max_colours) {
  if (max_colours < 1 || max_colours > kMaxColours) throw std::invalid_argument("colour_rows: max_colours must be in [1, 64]");
  ConstraintColouring result;
  result.colour.assign(row_count, kNoColour);
  std::vector<std::uint64_t> used(movable.size(), 0);
  const std::uint64_t allowed = max_colours == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << max_colours) - 1;
  for (std::size_t r = 0; r < row_count; ++r) {
    std::uint64_t taken = 0;
    bool moves = false;
    for (const std::uint32_t p : particles_of(r)) {
      if (p >= movable.size()) throw std::invalid_argument("colour_rows: row " + std::to_string(r) + " names particle " + std::to_string(p));
      if (movable[p]) taken |= used[p], moves = true;
    }
    if (!moves) continue;
    const std::uint64_t free = ~taken & allowed;
    if (free == 0) {
      result.overflow.push_back(static_cast<std::uint32_t>(r));
      continue;
    }
    const auto k = static_cast<std::uint32_t>(std::countr_zero(free));
    result.colour[r] = static_cast<std::uint8_t>(k);
    for (const std::uint32_t p : particles_of(r)) {
      if (movable[p]) used[p] |= std::uint64_t{1} << k;
    }
    if (k >= result.batch_size.size()) result.batch_size.resize(k + 1, 0);
    ++result.batch_size[k];
  }
  return result;
}

}  // namespace limber
