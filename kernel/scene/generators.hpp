// Model generators for scalability workloads: chains, trees, cloth-like grids and piles of
// humanoids of any size, built in C++ (a scene file of a million bodies would be mostly names);
// copies of a model side by side or stacked in layers; and level geometry (stairs).
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
//
// Generated links belong to collision group kLinkCollisionGroup and do not collide with each
// other (a workload measures relaxation; a rope or cloth that folds onto itself is not what they
// model), only with static colliders, the ground, the bounds and the balls.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "limber/kernel/model/model.hpp"

namespace limber {

/// CollisionFilter::group of every generated link; their mask leaves it out.
inline constexpr std::uint32_t kLinkCollisionGroup = 2;

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

/// A flight of stairs as a static mesh (StaticCollider::mesh): `steps` risers of `rise`, the
/// treads between them `run` deep, and a landing `landing` deep at the top. `position` is the
/// foot of the first riser's front edge, at the middle of its width; `direction` (horizontal)
/// points uphill. The solid is closed: risers (facing down the stairs, −direction), treads and
/// the landing (up), the back (+direction), both sides and the bottom (down), every triangle
/// counter-clockwise seen from outside, each face a quad of two triangles on its own 4 vertices.
struct StairsSpec {
  std::size_t steps = 6;            ///< ≥ 1: risers
  double rise = 0.15;               ///< m, > 0: each riser's height
  double run = 0.3;                 ///< m, > 0: each tread's depth
  double width = 2;                 ///< m, > 0
  double landing = 0.3;             ///< m, > 0: the top's depth beyond the last riser
  Vector3 position{0, 0, 0};        ///< m: the first riser's foot, mid-width
  Vector3 direction{1, 0, 0};       ///< horizontal, non-zero (normalized): uphill
};

/// The stairs' mesh: 4·steps + 2 quads, 8·steps + 4 triangles, world coordinates. Its top is
/// steps · rise above `position`, its length (steps − 1) · run + landing. Throws ModelError
/// "stairs.<field>: ..." on a bad spec.
TriangleMesh make_stairs_mesh(const StairsSpec& spec);
/// How many triangles make_stairs_mesh(spec) makes: 8·steps + 4.
inline std::size_t stairs_triangles(const StairsSpec& spec) { return 8 * spec.steps + 4; }

/// The larger of the bodies' extents in x and y (capsule axes ± radius; boxes and ellipsoids
/// their bounding spheres, model.hpp's bounding_radius), m; 0 for no bodies.
double footprint(const Model& model);

/// The bodies' extent in z (as footprint's), m; 0 for no bodies.
double vertical_extent(const Model& model);

/// `count` ≥ 1 copies of `model`'s bodies, joints and gears on square lattices, names led by
/// "<prefix><k>.". With `layers` = 1 (the default): one lattice, copy k shifted by
/// spacing · (k mod n, k div n, 0), n = ⌈√count⌉ copies per row. With `layers` = L > 1 (a pile
/// to drop): the copies fill L lattices of m = ⌈count / L⌉ copies each, lattice l (from the
/// bottom) `layer_height` · l higher, copy k in lattice k div m at place i = k mod m; odd
/// lattices are shifted by half a spacing in x and y, so a copy falls between the copies below
/// it rather than onto one. Everything else (settings, ground, bounds, balls, colliders) is the
/// model's, once. `spacing` (m) must be at least footprint(model) and, with layers,
/// `layer_height` (m) at least vertical_extent(model), so copies do not overlap; 1 ≤ layers ≤ count.
/// Errors name `path`.count, `path`.spacing, `path`.layers and `path`.layer_height.
Model copies_of(const Model& model, std::size_t count, double spacing, std::string_view prefix, std::string_view path,
                std::size_t layers = 1, double layer_height = 0);

/// `count` ≥ 1 copies of `model` in layers of `per_layer` ≥ 1 copies each, as many layers as the
/// count needs (a crowd that grows upward with its count, as a rain of bodies does): the lattices,
/// offsets, names and staggering of copies_of with m = `per_layer`. `layer_height` (m) must be at
/// least vertical_extent(model) when count > per_layer. Errors name `path`.count, `path`.spacing,
/// `path`.per_layer and `path`.layer_height.
Model copies_in_layers_of(const Model& model, std::size_t count, double spacing, std::string_view prefix, std::string_view path,
                          std::size_t per_layer, double layer_height);

/// copies_of the embedded humanoid scene (scene_file.hpp) with prefix "h", its ball and bounds
/// left out; `spacing` must be at least the humanoid's footprint (≈ 0.2 m). Its ground and
/// settings are kept — including sleep.start_asleep: with no ball, the copies start asleep and
/// stay so until a force wakes them (turn sleeping off to measure stepping them).
/// 160 copies are the size of Jolt's ragdoll performance test.
Model make_humanoid_pile(std::size_t count, double spacing = 1.0);

}  // namespace limber
