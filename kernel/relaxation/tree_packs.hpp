// Components of one shape solved side by side in SIMD lanes (kernel/relaxation/README.md, "Lanes
// across ragdolls").
//
// The joint trees' components (a ragdoll each, usually) are grouped by the shape of their
// elimination: the same nodes in the same order relative to the component's first, the same
// parents, the same rows per joint (fixed: an idle limit keeps a decoupled row,
// JointTrees::Joint::fixed_rows) and the same sides. kTreeLanes components of one shape make a
// pack, whose TreeElimination holds one component a lane; a shape met once is a pack of one
// lane, through the same code. Each lane's bits are those its component gets alone
// (lane_blocks.hpp), so a ragdoll steps to the same bits whatever its neighbours in the pack.
// A pack works in the state's precision: a state in float factors in float lanes, twice as many
// to a batch as doubles (the staging stays in double, and the inputs are rounded to float as
// they are gathered).
//
// A solve stages each component one at a time as before: its limbs' mass and inertia
// (JointTrees::mass, inertia), its joints' J blocks and active limits (block_a, block_b,
// active_limits) and each node's right-hand side (the scalar elimination's work()). Then
// eliminate_pack() gathers a pack's lanes from there, factors and solves them side by side, and
// writes each lane's solution back into its nodes' work(). Of the scalar elimination
// (JointTrees::elimination) only the ordering and work() are used.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

#include <xsimd/xsimd.hpp>

#include "limber/kernel/numerics/lane_blocks.hpp"
#include "limber/kernel/numerics/tree_elimination.hpp"
#include "limber/kernel/particles/relaxation_plan.hpp"

namespace limber {

/// The lanes of a pack in precision Number (the state's: double or float): xsimd's widest batch
/// of Number for this build — doubles 4 with AVX2, 8 with AVX-512; floats twice as many.
template <typename Number>
using TreeLanes = xsimd::batch<Number>;
template <typename Number>
inline constexpr std::size_t kTreeLanes = TreeLanes<Number>::size;
/// Which lanes of a pack a stage works on (those past the pack's width are never set).
using LaneMask = std::array<bool, kTreeLanes<float>>;

/// Up to kTreeLanes<Number> components of one shape. A node's local index: the pack's limbs
/// 0…L−1 and joints L…, each numbered in the order the components' slices of the elimination
/// order list them.
template <typename Number>
struct TreePack {
  static constexpr std::size_t kLanes = kTreeLanes<Number>;
  using Lanes = TreeLanes<Number>;
  std::array<std::int32_t, kLanes> component{};  ///< per lane (−1: an empty lane)
  std::vector<std::uint32_t> position;          ///< per local node: its offset in a lane's slice
  std::vector<std::int32_t> local;              ///< per offset in a slice: its local node
  std::vector<std::int32_t> inboard_limb;       ///< per local joint: its limb A's local index (−1: the world)
  TreeElimination<Lanes, 6> elimination;        ///< over the local nodes, one component a lane
  std::vector<std::array<Block<Lanes, 6, 6>, 2>> edge;  ///< per local joint: J on limb A, on limb B
  int factors = 0;           ///< since the substep began (begin_joint_trees)
  TreeStageSeconds seconds;  ///< the same (profiled steps only)
};

/// The packs of a state in double or in float (the other list empty), and where each node is in
/// its component.
struct TreePacks {
  std::vector<TreePack<double>> doubles;
  std::vector<TreePack<float>> floats;
  /// Per node of the scalar elimination: its offset in its component's slice of the order.
  std::vector<std::uint32_t> offset;

  template <typename Number>
  std::vector<TreePack<Number>>& packs() {
    if constexpr (std::is_same_v<Number, float>) {
      return floats;
    } else {
      return doubles;
    }
  }
};

/// Groups trees' components by shape into packs of up to `lanes` (1…kTreeLanes<Number>)
/// components, in Number's lanes (prepare_joint_trees, after the elimination is assigned; fewer
/// lanes: for tests and studies of lane occupancy). O(nodes).
template <typename Number>
void build_tree_packs(JointTrees& trees, std::size_t lanes = kTreeLanes<Number>);

/// Factors and solves the lanes of `pack` where `lanes` holds, each from its component's staged
/// inputs (trees.mass, inertia, block_a, block_b, active_limits and its nodes' work()), and
/// writes each one's solution into its nodes' work(); with `mobility`, each one's limbs' blocks
/// of the inverse too (TreeElimination::inverse_diagonal) into trees.mobility. The other lanes
/// solve an identity system and write nothing. The pack keeps the factor for solve_pack() and
/// solve_pack_paths() until its next eliminate_pack(). In float the inputs are rounded to float
/// and the answers widened back.
template <typename Number>
void eliminate_pack(JointTrees& trees, TreePack<Number>& pack, const LaneMask& lanes, bool mobility = false);

/// Solves the lanes where `lanes` holds again with the pack's factor, for the right-hand sides
/// in their components' work(), written back there.
template <typename Number>
void solve_pack(JointTrees& trees, TreePack<Number>& pack, const LaneMask& lanes);

/// One lane's loads for solve_pack_paths: 6-vectors (force, torque) at two limbs of its
/// component, and the motion of those two limbs they make.
struct PathLoad {
  std::array<std::int32_t, 2> limbs{-1, -1};  ///< the limbs (scalar elimination's nodes); −1: no load in this lane
  std::array<Eigen::Matrix<double, 6, 1>, 2> load{}, motion{};
};

/// The responses of the components of `pack`'s lanes (its factor) to their loads paths[lane]
/// alone, solved together on the union of the paths from the loaded limbs to the root
/// (TreeElimination::solve_nodes): each lane's motion is the bits it gets solved alone (the other
/// lanes' nodes carry exact zeros in it). O(the union's nodes), once for the whole pack.
template <typename Number>
void solve_pack_paths(JointTrees& trees, TreePack<Number>& pack, std::span<PathLoad, kTreeLanes<Number>> paths);

}  // namespace limber
