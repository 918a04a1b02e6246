// Graph colouring of constraints: validity on chains, trees and random graphs; optimal colour
// counts where theory gives them; hubs go to the overflow; fixed particles never conflict.
#include <algorithm>
#include <numeric>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "limber/layouts/graph/constraint_colouring.hpp"

namespace limber {
namespace {

struct Graph {
  std::vector<std::uint32_t> i, j;
  std::vector<bool> movable;
  std::vector<std::uint32_t> all() const {
    std::vector<std::uint32_t> order(i.size());
    std::iota(order.begin(), order.end(), 0u);
    return order;
  }
  void add(std::uint32_t a, std::uint32_t b) { i.push_back(a), j.push_back(b); }
};

ConstraintColouring colour(const Graph& graph, std::uint32_t max_colours = 64) {
  return colour_constraints(graph.i, graph.j, graph.all(), graph.movable, max_colours);
}

// No two constraints of a colour share a movable particle; every constraint with a movable end
// is in exactly one colour or in the overflow; batch sizes add up.
void expect_valid(const Graph& graph, const ConstraintColouring& result) {
  ASSERT_EQ(result.colour.size(), graph.i.size());
  std::vector<std::vector<int>> owner(result.colour_count(), std::vector<int>(graph.movable.size(), -1));
  std::vector<std::uint32_t> sizes(result.colour_count(), 0);
  std::vector<int> in_overflow(graph.i.size(), 0);
  for (std::uint32_t c : result.overflow) ++in_overflow[c];
  for (std::uint32_t c = 0; c < graph.i.size(); ++c) {
    const bool movable = graph.movable[graph.i[c]] || graph.movable[graph.j[c]];
    if (result.colour[c] == kNoColour) {
      EXPECT_EQ(in_overflow[c], movable ? 1 : 0) << "constraint " << c;
      continue;
    }
    EXPECT_EQ(in_overflow[c], 0);
    const std::uint8_t k = result.colour[c];
    ASSERT_LT(k, result.colour_count());
    ++sizes[k];
    for (std::uint32_t p : {graph.i[c], graph.j[c]}) {
      if (!graph.movable[p]) continue;
      EXPECT_EQ(owner[k][p], -1) << "colour " << int(k) << " meets particle " << p << " twice";
      owner[k][p] = static_cast<int>(c);
    }
  }
  EXPECT_EQ(sizes, result.batch_size);
}

Graph chain(std::uint32_t links, bool pinned) {
  Graph graph;
  graph.movable.assign(links + 1, true);
  graph.movable[0] = !pinned;
  for (std::uint32_t k = 0; k < links; ++k) graph.add(k, k + 1);
  return graph;
}

// A random tree in breadth-first order: particle p > 0 hangs from a random earlier particle,
// edges listed in order of the child (as compile.cpp stores them).
Graph random_tree(std::uint32_t particles, std::uint32_t seed, std::uint32_t& max_degree) {
  std::mt19937 random(seed);
  Graph graph;
  graph.movable.assign(particles, true);
  std::vector<std::uint32_t> degree(particles, 0);
  for (std::uint32_t p = 1; p < particles; ++p) {
    // Parents chosen among recent particles keep the order breadth-first-like and make hubs.
    std::uniform_int_distribution<std::uint32_t> pick(p > 8 ? p - 8 : 0, p - 1);
    const std::uint32_t parent = pick(random);
    graph.add(parent, p);
    ++degree[parent], ++degree[p];
  }
  max_degree = *std::max_element(degree.begin(), degree.end());
  return graph;
}

TEST(ConstraintColouring, ChainNeedsTwoColours) {
  const Graph graph = chain(1001, false);
  const ConstraintColouring result = colour(graph);
  expect_valid(graph, result);
  EXPECT_EQ(result.colour_count(), 2u);
  EXPECT_EQ(result.batch_size[0] + result.batch_size[1], 1001u);
  EXPECT_TRUE(result.overflow.empty());
}

TEST(ConstraintColouring, BreadthFirstTreeUsesAsManyColoursAsItsBusiestParticle) {
  for (std::uint32_t seed = 1; seed <= 20; ++seed) {
    std::uint32_t max_degree = 0;
    const Graph graph = random_tree(2000, seed, max_degree);
    const ConstraintColouring result = colour(graph);
    expect_valid(graph, result);
    // At least that many (the busiest particle's constraints are pairwise in conflict) and, in
    // breadth-first order, no more.
    EXPECT_EQ(result.colour_count(), max_degree) << "seed " << seed;
  }
}

TEST(ConstraintColouring, RandomGraphsAreColouredValidly) {
  std::mt19937 random(7);
  for (int trial = 0; trial < 20; ++trial) {
    Graph graph;
    const std::uint32_t particles = 300;
    graph.movable.assign(particles, true);
    std::uniform_int_distribution<std::uint32_t> pick(0, particles - 1);
    for (int k = 0; k < 900; ++k) {
      const std::uint32_t a = pick(random), b = pick(random);
      if (a != b) graph.add(a, b);
    }
    for (std::uint32_t p = 0; p < particles; p += 37) graph.movable[p] = false;
    expect_valid(graph, colour(graph, 8));
  }
}

TEST(ConstraintColouring, HubBeyondTheColourLimitGoesToTheOverflow) {
  // A star: 20 spokes on particle 0. With 8 colours, 8 spokes are coloured and 12 overflow.
  Graph graph;
  graph.movable.assign(21, true);
  for (std::uint32_t k = 1; k <= 20; ++k) graph.add(0, k);
  const ConstraintColouring result = colour(graph, 8);
  expect_valid(graph, result);
  EXPECT_EQ(result.colour_count(), 8u);
  EXPECT_EQ(result.overflow.size(), 12u);
}

TEST(ConstraintColouring, FixedParticlesNeverConflict) {
  // 10 pendulums hanging from one pinned particle share no movable particle: one colour.
  Graph graph;
  graph.movable.assign(11, true);
  graph.movable[0] = false;
  for (std::uint32_t k = 1; k <= 10; ++k) graph.add(0, k);
  graph.add(0, 0);  // both ends fixed: never projected, in no colour and not in the overflow
  const ConstraintColouring result = colour(graph);
  expect_valid(graph, result);
  EXPECT_EQ(result.colour_count(), 1u);
  EXPECT_EQ(result.colour.back(), kNoColour);
}

TEST(ConstraintColouring, IsDeterministicAndRejectsBadInput) {
  std::uint32_t max_degree = 0;
  const Graph graph = random_tree(500, 3, max_degree);
  EXPECT_EQ(colour(graph).colour, colour(graph).colour);
  EXPECT_THROW(colour(graph, 0), std::invalid_argument);
  EXPECT_THROW(colour(graph, 65), std::invalid_argument);
  Graph bad = graph;
  bad.i[3] = 10000;
  EXPECT_THROW(colour(bad), std::invalid_argument);
}

}  // namespace
}  // namespace limber
