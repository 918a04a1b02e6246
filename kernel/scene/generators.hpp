// Model generators for scalability workloads: chains, trees, cloth-like grids and piles of
// humanoids of any size, built in C++ (a scene file of a million bodies would be mostly names).
//
// Units are SI (m, kg); z is up. Limbs are joined head to tail at their axis end points, the
// only places the particle (Verlet) method has particles (compile.hpp). Every generator returns
// a Model that passes validate() and throws ModelError, one line "<spec>.<field>: <problem>",
// on a spec that describes no model (no links, a non-positive length or mass, ...).
//
// Chains, trees and grids turn sleeping off: a workload measures the cost of simulating, which
// sleeping bodies skip. The particle method joins their links with zero-length constraints
// unless told VerletSettings::joints = shared_particle (VerletOptions::verlet), which makes each
// joint one particle: the workloads' usual form.
#pragma once

#include <cstddef>
#include <string_view>

#include "limber/kernel/model/model.hpp"

namespace limber {

/// A straight chain of capsule links laid head to tail from `anchor` along `direction`.
struct ChainSpec {
  std::size_t links = 0;            ///< ≥ 1
  double link_length = 0.1;         ///< m, > 0; capsule radius 0.01 · link_length
  double link_mass = 1;             ///< kg, > 0
  double end_mass_ratio = 1;        ///< > 0: the last link's mass / link_mass (a heavy end)
  Vector3 anchor{0, 0, 0};          ///< world point of link_0's head, m
  Vector3 direction{1, 0, 0};       ///< non-zero (normalized): from each link's head to its tail;
                                    ///< horizontal releases the chain to swing down
  bool pinned = true;               ///< joint "pin" holds link_0's head at the anchor
};

/// Bodies "link_0" … "link_{N−1}"; joints "pin" (if pinned) and "joint_k" (k ≥ 1) from
/// link_{k−1}'s tail to link_k's head, as the scene file's "chain" generator lays them (which
/// names the pin "joint_0").
Model make_chain_model(const ChainSpec& spec);

/// A complete `branching`-ary tree of links, filled breadth first.
struct TreeSpec {
  std::size_t links = 0;      ///< ≥ 1: bodies in the tree
  std::size_t branching = 2;  ///< ≥ 1: children per link (1 gives a chain)
  double link_length = 0.1;   ///< m, > 0; capsule radius 0.01 · link_length
  double link_mass = 1;       ///< kg, > 0
  bool pinned = true;         ///< joint "pin" holds the root's head at the origin
};

/// Body "link_k" hangs from the tail of its parent "link_{(k−1)/branching}" by joint "joint_k"
/// (head to tail); "link_0" is the root, pointing straight down from the origin. Children fan
/// out below their parent in the x-z plane, ±45° about −z, so siblings do not coincide (other
/// subtrees may cross: positions are consistent, not pretty). A parent's tail joins 1 + branching
/// links: a hub, the worst case for relaxation's colouring when branching is large.
Model make_tree_model(const TreeSpec& spec);

/// A cloth-like grid of particles: `rows` × `columns` nodes `spacing` apart, every horizontal and
/// vertical edge a capsule link.
struct GridSpec {
  std::size_t columns = 100;    ///< ≥ 2
  std::size_t rows = 100;       ///< ≥ 2
  double spacing = 0.1;         ///< m, > 0: the link length; capsule radius 0.01 · spacing
  double link_mass = 0.1;       ///< kg, > 0, per edge
  bool pin_top_corners = true;  ///< joints "pin_top_left", "pin_top_right"
};

/// rows·(columns−1) + columns·(rows−1) bodies: "h_<r>_<c>" from node (r, c) to (r, c+1) and
/// "v_<r>_<c>" from (r, c) down to (r+1, c), head at (r, c). Node (r, c) is at
/// (c·spacing, 0, −r·spacing): a vertical sheet hanging from its top corners, row 0 at z = 0.
/// At a node meeting d link ends, joints "node_<r>_<c>_<k>" (k = 1 … d−1) join the first end to
/// each other one — a star, so zero-length constraints would not be redundant either.
/// Compiled with shared-particle joints, each node is one particle and each edge one distance
/// constraint (rows·columns particles; the pins add neither).
Model make_grid_model(const GridSpec& spec);

/// The larger of the bodies' extents in x and y (capsule axes ± radius), m; 0 for no bodies.
double footprint(const Model& model);

/// `count` ≥ 1 copies of `model`'s bodies, joints and gears on a square lattice: copy k shifted
/// by spacing · (k mod n, k div n, 0), n = ⌈√count⌉ copies per row, names led by
/// "<prefix><k>.". Everything else (settings, ground, bounds, ball) is the model's, once.
/// `spacing` (m) must be at least footprint(model) so copies do not overlap. Errors name
/// `path`.count and `path`.spacing.
Model copies_of(const Model& model, std::size_t count, double spacing, std::string_view prefix, std::string_view path);

/// copies_of the embedded humanoid scene (scene_file.hpp) with prefix "h", its ball and bounds
/// left out; `spacing` must be at least the humanoid's footprint (≈ 0.2 m). Its ground and
/// settings are kept — including sleep.start_asleep: with no ball, the copies start asleep and
/// stay so until a force wakes them (turn sleeping off to measure stepping them).
/// 160 copies are the size of Jolt's ragdoll performance test.
Model make_humanoid_pile(std::size_t count, double spacing = 1.0);

}  // namespace limber
