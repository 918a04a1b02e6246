#include "limber/kernel/numerics/tree_elimination.hpp"

#include "limber/layouts/graph/compressed_rows.hpp"
#include "limber/layouts/graph/disjoint_sets.hpp"

namespace limber {

TreeOrdering order_tree(std::size_t body_count, std::span<const std::int32_t> inboard, std::span<const std::int32_t> outboard) {
  const std::size_t constraint_count = outboard.size();
  const std::size_t nodes = body_count + constraint_count;
  TreeOrdering ordering;
  std::vector<bool> in_tree(constraint_count, true);
  // A constraint between bodies closes a loop when they are already connected.
  DisjointSets connected(body_count);
  for (std::size_t c = 0; c < constraint_count; ++c) {
    if (inboard[c] < 0 || outboard[c] < 0) continue;
    const auto a = static_cast<std::uint32_t>(inboard[c]), b = static_cast<std::uint32_t>(outboard[c]);
    if (connected.find(a) == connected.find(b)) {
      in_tree[c] = false;
      ordering.loop_constraints.push_back(static_cast<std::uint32_t>(c));
    } else {
      connected.unite(a, b);
    }
  }
  // Each world anchor is its own fixed frame, so one constraint to the world per component is a
  // root; a second closes a loop through the world.
  std::vector<std::int64_t> world_root(body_count, -1);
  for (std::size_t c = 0; c < constraint_count; ++c) {
    if (inboard[c] >= 0 || outboard[c] < 0) continue;
    std::int64_t& root = world_root[connected.find(static_cast<std::uint32_t>(outboard[c]))];
    if (root >= 0) {
      in_tree[c] = false;
      ordering.loop_constraints.push_back(static_cast<std::uint32_t>(c));
    } else {
      root = static_cast<std::int64_t>(c);
    }
  }

  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  edges.reserve(4 * constraint_count);
  for (std::size_t c = 0; c < constraint_count; ++c) {
    if (!in_tree[c] || outboard[c] < 0) continue;
    const auto constraint_node = static_cast<std::uint32_t>(body_count + c);
    for (const std::int32_t b : {inboard[c], outboard[c]}) {
      if (b < 0) continue;
      edges.emplace_back(static_cast<std::uint32_t>(b), constraint_node);
      edges.emplace_back(constraint_node, static_cast<std::uint32_t>(b));
    }
  }
  const CompressedRows<std::uint32_t> neighbours = group_by_row(nodes, edges);
  ordering.parent.assign(nodes, -1);
  std::vector<bool> visited(nodes, false);
  std::vector<std::int32_t> breadth_first;
  breadth_first.reserve(nodes);
  std::vector<std::pair<std::size_t, std::int32_t>> component_starts;  // (index in breadth_first, a body)
  for (std::size_t b = 0; b < body_count; ++b) {
    if (connected.find(static_cast<std::uint32_t>(b)) != b) continue;
    const std::size_t root = world_root[b] >= 0 ? body_count + static_cast<std::size_t>(world_root[b]) : b;
    component_starts.emplace_back(breadth_first.size(), static_cast<std::int32_t>(b));
    visited[root] = true;
    breadth_first.push_back(static_cast<std::int32_t>(root));
    for (std::size_t next = breadth_first.size() - 1; next < breadth_first.size(); ++next) {
      for (const std::uint32_t other : neighbours.row(static_cast<std::size_t>(breadth_first[next]))) {
        if (visited[other]) continue;
        visited[other] = true;
        ordering.parent[other] = breadth_first[next];
        breadth_first.push_back(static_cast<std::int32_t>(other));
      }
    }
  }
  const auto total = static_cast<std::uint32_t>(breadth_first.size());
  ordering.order.assign(breadth_first.rbegin(), breadth_first.rend());
  for (std::size_t k = 0; k < component_starts.size(); ++k) {
    const auto start = static_cast<std::uint32_t>(component_starts[k].first);
    const auto stop = static_cast<std::uint32_t>(k + 1 < component_starts.size() ? component_starts[k + 1].first : total);
    ordering.components.push_back({total - stop, total - start, component_starts[k].second});
  }
  return ordering;
}

}  // namespace limber
