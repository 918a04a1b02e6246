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
// One axis alone leaves k large when the boxes spread over a plane or a volume: on a square
// lattice of n ragdolls or balls each box overlaps a whole column of √n on the sweep axis, and
// the sweep costs n^1.5. So the sweep runs in the cells of a coarse grid over the other two
// axes (as PhysX's multi box pruning and Bullet's multi-SAP do): a box enters every cell it
// reaches, the boxes are sorted by (cell, lower bound) and each cell is swept alone, and a pair
// is reported only in the first cell the two boxes share. The cells are twice the boxes' mean
// extent along their axes — wider when that would put more than four entries per box in all,
// so a few large boxes cannot multiply the work — and anchored at the world origin, so they stay
// put while the boxes move. A row of limbs is one row of cells; a lattice, a cell or two per
// box: k stays the boxes' true neighbours.
//
// Frame coherence: limbs move little between steps, so last step's order is nearly sorted, and
// insertion sort — O(n + number of swaps) on a nearly sorted list, in place, no allocation — is
// the classic choice (I-COLLIDE). The entries are laid out again in last call's order, a box's
// entries where its first one was, so a box that crossed into another cell costs only the
// entries of the cells it left and entered. When the box count, the axes or the cells' size
// change, the old order says nothing, and the order is rebuilt with std::sort (also in place).
//
// Two sets (find_pairs_between: the balls' paths against the limbs, BallCandidates) are swept
// as two sorted lists side by side, cell by cell: each pair overlapping on the axis is found
// from the box that starts first, so the sweep never walks the pairs inside one set — a ball
// beside a million limbs costs the limbs' sort and its own neighbours, not the limbs' pairs
// among themselves.
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

  /// The pairs (i, j), i indexing `first` and j `second`, whose boxes overlap, sorted
  /// lexicographically: brute_force_pairs_between's list, without comparing two boxes of one
  /// set. Same conditions and lifetime as find_pairs (whose list this call replaces).
  const std::vector<CandidatePair>& find_pairs_between(std::span<const Aabb> first, std::span<const Aabb> second);

  /// The axis of the last sweep: 0 (x), 1 (y) or 2 (z).
  int axis() const { return grid_.axis < 0 ? 0 : grid_.axis; }
  /// Box pairs the sweeps compared on all three axes, over every call so far: the sweep's
  /// work (n·k above), for tests and benchmarks that count work instead of timing it.
  std::uint64_t comparisons() const { return comparisons_; }
  /// Room for `boxes` boxes (for find_pairs_between: `boxes` in the first set and
  /// `second_boxes` in the second) and `pairs` pairs, so calls needing no more allocate nothing.
  void reserve(std::size_t boxes, std::size_t second_boxes, std::size_t pairs);
  /// Bytes held by the sort and pair buffers (their capacities); for checking that a call
  /// allocated nothing.
  std::size_t reserved_bytes() const;

 private:
  // One box in one grid cell: its interval on the sweep axis, the cell and the box's index.
  struct Entry {
    std::uint64_t cell = 0;
    double min = 0;
    double max = 0;
    std::uint32_t box = 0;
  };
  // The cells a box reaches: indices low..high along each of the two cell axes.
  struct CellRange {
    std::int64_t low[2] = {0, 0};
    std::int64_t high[2] = {0, 0};
    bool operator==(const CellRange&) const = default;
  };
  // One set of boxes as the sweep holds it.
  struct Sorted {
    std::vector<Entry> entries;            // by (cell, min, box) after a call
    std::vector<CellRange> cells;          // per box, this call's
    std::vector<CellRange> previous_cells; // per box, last call's
    std::vector<Entry> added;              // scratch: entries in cells the boxes newly reach
  };
  // The grid: the sweep axis, the two cell axes, the cells' width along each (m; ∞: one cell)
  // and the width the boxes' extents asked for when it was chosen.
  struct Grid {
    int axis = -1;
    int cell_axes[2] = {1, 2};
    double width[2] = {0, 0};
    double basis[2] = {0, 0};
  };
  // Chooses the grid for `sets`, keeping the last one's cells when still fitting.
  bool choose_grid(std::initializer_list<std::span<const Aabb>> sets);
  void sort_entries(Sorted& sorted, std::span<const Aabb> boxes, bool coherent) const;
  std::uint64_t cell_key(std::int64_t a, std::int64_t b) const;
  // The first cell two boxes both reach: where their pair is reported.
  std::uint64_t first_shared_cell(const CellRange& a, const CellRange& b) const;
  std::int64_t cell_index(double coordinate, int k) const;

  Sorted first_, second_;  // the boxes (find_pairs), or the first and second sets
  std::vector<CandidatePair> pairs_;
  Grid grid_;
  std::uint64_t comparisons_ = 0;
};

/// The balls' candidate search (kernel/collision/contacts.hpp, rigid_contacts.hpp: a ball meets
/// the limbs through its own path, swept over the step): the caller fills a box per shape (a
/// limb) and one per ball, each holding what its bounding-sphere test can accept; find() then
/// gives every ball the shapes — and, when asked, the other balls — whose boxes overlap its own,
/// by the sweep and prune (find_pairs_between, find_pairs), instead of every ball against every
/// body. Fewer than kSearchFromBalls balls are not worth sorting the shapes for (one ball against
/// 10⁵ limbs: the sort and sweep cost several times the limbs' sphere tests): each gets every
/// shape, and boxes() asks for no boxes. Keeps its buffers: once it has seen a count of boxes and
/// of candidates, calls needing no more allocate nothing.
class BallCandidates {
 public:
  static constexpr std::size_t kSearchFromBalls = 8;

  /// The boxes to fill, `shapes` shapes' then `balls` balls' (m); valid until the next call.
  /// Empty when every ball will get every shape (fewer than kSearchFromBalls balls, or the
  /// reference): then there is nothing to fill.
  std::span<Aabb> boxes(std::size_t shapes, std::size_t balls);
  /// Finds each ball's candidates among the boxes just filled; with `other_balls`, the other
  /// balls as well as the shapes. A box not finite makes every ball get every body this call.
  void find(bool other_balls);
  /// Ball `ball`'s candidates in increasing order: a shape's index, or (shapes + b) for ball b.
  /// When every ball gets every body, the list holds the ball itself too: skip it.
  std::span<const std::uint32_t> of(std::size_t ball) const {
    if (list_every_) return std::span<const std::uint32_t>(every_).first(listed_count_);
    return std::span<const std::uint32_t>(candidates_).subspan(begin_[ball], begin_[ball + 1] - begin_[ball]);
  }
  /// Box pairs the sweeps compared, over every call: the search's work (when listing every
  /// body, the pairs listed).
  std::uint64_t comparisons() const { return across_.comparisons() + among_.comparisons() + listed_; }
  /// The brute-force reference for tests: with `on`, every ball gets every shape (and every
  /// ball) whatever their number, as a search that misses nothing must answer the same.
  void use_reference(bool on) { reference_ = on; }
  /// Room for `candidates` candidates in all without allocating.
  void reserve(std::size_t shapes, std::size_t balls, std::size_t candidates);
  /// Bytes held by its buffers (capacities).
  std::size_t reserved_bytes() const;

 private:
  SweepAndPrune across_;  // shapes against balls
  SweepAndPrune among_;   // balls against balls
  std::vector<Aabb> boxes_;
  std::size_t shapes_ = 0, balls_ = 0;
  std::vector<std::uint32_t> begin_{0};  // per ball, then the end: where its candidates start
  std::vector<std::uint32_t> candidates_;
  bool reference_ = false;
  bool list_every_ = false;              // this call lists every body for every ball
  std::vector<std::uint32_t> every_;     // 0, 1, 2, ...: the list every ball shares then
  std::size_t listed_count_ = 0;
  std::uint64_t listed_ = 0;             // pairs listed so
};

/// Every pair (i, j), i < j, whose boxes overlap, by testing all n(n − 1)/2: the reference the
/// sweep must match.
std::vector<CandidatePair> brute_force_pairs(std::span<const Aabb> boxes);

/// Every pair (i, j) of a box i of `first` and a box j of `second` that overlap, by testing all
/// of them, sorted: the reference for find_pairs_between.
std::vector<CandidatePair> brute_force_pairs_between(std::span<const Aabb> first, std::span<const Aabb> second);

}  // namespace limber
