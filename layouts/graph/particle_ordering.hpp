// Particle orderings for locality studies: which index each particle gets inside its island.
//
// A sweep gathers the two particles of each constraint; when constraints that follow each other
// touch particles with nearby indices, those gathers hit cache lines already loaded. compile()
// numbers particles breadth-first from the island's root, which on chains and trees is already
// such an order. These alternatives let the cache study (tools/cachegrind_layouts.sh) compare:
// - reverse Cuthill-McKee (Cuthill & McKee 1969; George 1971): breadth-first from a
//   minimum-degree particle, neighbours by increasing degree, the whole order reversed — the
//   classic bandwidth-reducing order for sparse matrices (grids, meshes);
// - depth parity (red-black): the particles at even breadth-first depth, then those at odd
//   depth, each in breadth-first order. On a chain, a colour's constraints then join runs of
//   consecutive particles — lane k of a block touches particles p + k and q + k — so the sweep
//   loads and stores whole vectors instead of gathering (ConstraintBatches::consecutive). It is
//   the ordering of red-black Gauss-Seidel on grids;
// - shuffled: a fixed pseudo-random permutation, the no-locality baseline.
#pragma once

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <random>
#include <vector>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build
#include "limber/layouts/graph/compressed_rows.hpp"
#include "limber/layouts/layout_choices.hpp"

namespace limber {

/// Reverse Cuthill-McKee order of particles [begin, end), whose neighbours (all inside the
/// range) are `adjacency.row(p)`. Returns the particles in their new order (a permutation of
/// the range). Deterministic: ties go to the lower index.
inline std::vector<std::uint32_t> reverse_cuthill_mckee(const CompressedRows<std::uint32_t>& adjacency,
                                                        std::uint32_t begin, std::uint32_t end) {
  const auto degree = [&](std::uint32_t p) { return adjacency.offsets[p + 1] - adjacency.offsets[p]; };
  std::vector<std::uint32_t> order;
  order.reserve(end - begin);
  std::vector<bool> placed(end - begin, false);
  std::vector<std::uint32_t> by_degree(end - begin);
  std::iota(by_degree.begin(), by_degree.end(), begin);
  std::stable_sort(by_degree.begin(), by_degree.end(), [&](std::uint32_t a, std::uint32_t b) { return degree(a) < degree(b); });
  std::vector<std::uint32_t> neighbours;
  for (const std::uint32_t start : by_degree) {  // one search per connected part
    if (placed[start - begin]) continue;
    placed[start - begin] = true;
    order.push_back(start);
    for (std::size_t next = order.size() - 1; next < order.size(); ++next) {
      neighbours.clear();
      for (const std::uint32_t q : adjacency.row(order[next])) {
        if (!placed[q - begin]) placed[q - begin] = true, neighbours.push_back(q);
      }
      std::stable_sort(neighbours.begin(), neighbours.end(), [&](std::uint32_t a, std::uint32_t b) { return degree(a) < degree(b); });
      order.insert(order.end(), neighbours.begin(), neighbours.end());
    }
  }
  std::reverse(order.begin(), order.end());
  return order;
}

/// Depth-parity order of particles [begin, end) (neighbours inside the range): breadth-first from
/// `begin` (and from the lowest unreached particle, for any part not connected to it), even
/// depths first. Returns the particles in their new order.
inline std::vector<std::uint32_t> depth_parity_order(const CompressedRows<std::uint32_t>& adjacency, std::uint32_t begin,
                                                     std::uint32_t end) {
  std::vector<std::uint32_t> visit;
  visit.reserve(end - begin);
  std::vector<std::uint32_t> depth(end - begin, ~0u);
  for (std::uint32_t root = begin; root < end; ++root) {
    if (depth[root - begin] != ~0u) continue;
    depth[root - begin] = 0;
    visit.push_back(root);
    for (std::size_t next = visit.size() - 1; next < visit.size(); ++next) {
      const std::uint32_t p = visit[next];
      for (const std::uint32_t q : adjacency.row(p)) {
        if (depth[q - begin] == ~0u) depth[q - begin] = depth[p - begin] + 1, visit.push_back(q);
      }
    }
  }
  std::stable_partition(visit.begin(), visit.end(), [&](std::uint32_t p) { return depth[p - begin] % 2 == 0; });
  return visit;
}

/// A fixed pseudo-random order of [begin, end) (the same for the same range and seed).
inline std::vector<std::uint32_t> shuffled_order(std::uint32_t begin, std::uint32_t end, std::uint32_t seed = 1) {
  std::vector<std::uint32_t> order(end - begin);
  std::iota(order.begin(), order.end(), begin);
  std::mt19937 random(seed);
  // Fisher-Yates written out: std::shuffle's sequence is not specified across standard libraries.
  for (std::size_t k = order.size(); k > 1; --k) {
    std::swap(order[k - 1], order[random() % k]);
  }
  return order;
}

}  // namespace limber
