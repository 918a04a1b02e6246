// Broadphase: which pairs of limbs are close enough to be worth the hierarchical test
// (kernel/geometry/bounding_volumes.hpp, thesis 2.4).
//
// Sweep and prune (Baraff 1992; Cohen et al., I-COLLIDE, 1995): sort the boxes by their lower
// bound on one axis, then sweep — each box is compared only with the boxes after it whose lower
// bound does not pass its upper bound, and those are checked on all three axes. Cost
// O(n log n + n·k) for k boxes overlapping on the sweep axis, instead of the O(n²) of testing
// every pair.
//
// The axis is the one along which the box centres spread most (largest variance), recomputed
// each call: sweeping along the long direction of a scene (a figure lying down, a row of limbs)
// keeps k small. Ties keep x before y before z.
//
// Frame coherence: limbs move little between steps, so last step's order is nearly sorted, and
// insertion sort — O(n + number of swaps) on a nearly sorted list, in place, no allocation — is
// the classic choice (I-COLLIDE). When the box count or the axis changes the old order says
// nothing, and the order is rebuilt with std::sort (also in place).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "limber/kernel/geometry/bounding_volumes.hpp"

namespace limber {

/// Two box indices, first < second.
using CandidatePair = std::pair<std::uint32_t, std::uint32_t>;

/// Sweep and prune that keeps its buffers between calls: once it has seen a box count and a
/// number of pairs, calls needing no more allocate nothing.
class SweepAndPrune {
 public:
  /// The pairs (i, j), i < j, of `boxes` that overlap (touching counts, as in overlaps(Aabb,
  /// Aabb)), sorted lexicographically — the same list as brute_force_pairs, whatever the order
  /// of the sweep. Boxes must be finite with min ≤ max. The reference stays valid until the
  /// next call.
  const std::vector<CandidatePair>& find_pairs(std::span<const Aabb> boxes);

  /// The axis of the last sweep: 0 (x), 1 (y) or 2 (z).
  int axis() const { return axis_; }
  /// Bytes held by the sort and pair buffers (their capacities); for checking that a call
  /// allocated nothing.
  std::size_t reserved_bytes() const;

 private:
  // One box on the sweep axis: its interval there and its index.
  struct Interval {
    double min = 0;
    double max = 0;
    std::uint32_t box = 0;
  };
  std::vector<Interval> sorted_;       // by (min, box) after a call
  std::vector<CandidatePair> pairs_;
  int axis_ = 0;
};

/// Every pair (i, j), i < j, whose boxes overlap, by testing all n(n − 1)/2: the reference the
/// sweep must match.
std::vector<CandidatePair> brute_force_pairs(std::span<const Aabb> boxes);

}  // namespace limber
