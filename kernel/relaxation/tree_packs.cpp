#include "limber/kernel/relaxation/tree_packs.hpp"

#include <algorithm>
#include <map>
#include <span>
#include <utility>

namespace limber {

TreePacksHandle::TreePacksHandle() : packs_(std::make_unique<TreePacks>()) {}
TreePacksHandle::~TreePacksHandle() = default;
TreePacksHandle::TreePacksHandle(const TreePacksHandle& other) : packs_(std::make_unique<TreePacks>(*other.packs_)) {}
TreePacksHandle& TreePacksHandle::operator=(const TreePacksHandle& other) {
  if (this != &other) packs_ = std::make_unique<TreePacks>(*other.packs_);
  return *this;
}
TreePacksHandle::TreePacksHandle(TreePacksHandle&&) noexcept = default;
TreePacksHandle& TreePacksHandle::operator=(TreePacksHandle&&) noexcept = default;

namespace {

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

// A component's elimination shape, node by node in its slice of the order: whether a limb, its
// parent's offset, and for a joint its rows and its limbs' offsets (−1: none, the world).
std::vector<std::int32_t> shape_of(const JointTrees& trees, const TreeOrdering::Component& component, std::vector<std::int32_t>& offset) {
  const TreeOrdering& ordering = trees.elimination.ordering();
  const std::int32_t limbs = trees.elimination.body_count();
  for (std::uint32_t k = component.begin; k < component.end; ++k) offset[static_cast<std::size_t>(ordering.order[k])] = static_cast<std::int32_t>(k - component.begin);
  const auto offset_of = [&](std::int32_t node) { return node < 0 ? -1 : offset[static_cast<std::size_t>(node)]; };
  std::vector<std::int32_t> shape;
  shape.reserve(5 * (component.end - component.begin));
  for (std::uint32_t k = component.begin; k < component.end; ++k) {
    const std::int32_t node = ordering.order[k];
    shape.push_back(node < limbs ? 1 : 0);
    shape.push_back(offset_of(ordering.parent[static_cast<std::size_t>(node)]));
    if (node < limbs) continue;
    const auto j = static_cast<std::size_t>(node - limbs);
    shape.push_back(trees.elimination.rows(j));
    shape.push_back(offset_of(trees.joints[j].limb_a));
    shape.push_back(offset_of(trees.joints[j].limb_b));
  }
  return shape;
}

// A pack's local nodes, ordering and storage, from its first component.
template <typename Number>
TreePack<Number> make_pack(const JointTrees& trees, const std::vector<std::uint32_t>& components) {
  const TreeOrdering& ordering = trees.elimination.ordering();
  const std::int32_t limbs = trees.elimination.body_count();
  const TreeOrdering::Component& first = ordering.components[components.front()];
  const std::uint32_t count = first.end - first.begin;
  TreePack<Number> pack;
  pack.component.fill(-1);
  for (std::size_t lane = 0; lane < components.size(); ++lane) pack.component[lane] = static_cast<std::int32_t>(components[lane]);
  // Local indices: limbs first, then joints, each in the slice's order.
  std::int32_t lane_limbs = 0;
  for (std::uint32_t k = first.begin; k < first.end; ++k) lane_limbs += ordering.order[k] < limbs ? 1 : 0;
  std::vector<std::int32_t> local_of(ordering.parent.size(), -1);  // per global node of the first component
  std::int32_t next_limb = 0, next_joint = lane_limbs;
  pack.position.assign(count, 0);
  for (std::uint32_t k = first.begin; k < first.end; ++k) {
    const std::int32_t node = ordering.order[k];
    const std::int32_t local = node < limbs ? next_limb++ : next_joint++;
    local_of[static_cast<std::size_t>(node)] = local;
    pack.position[static_cast<std::size_t>(local)] = k - first.begin;
  }
  pack.local.assign(count, 0);
  for (std::uint32_t local = 0; local < count; ++local) pack.local[pack.position[local]] = static_cast<std::int32_t>(local);
  TreeOrdering local;
  local.parent.assign(count, -1);
  std::vector<std::uint8_t> rows(count - static_cast<std::uint32_t>(lane_limbs));
  pack.inboard_limb.assign(rows.size(), -1);
  for (std::uint32_t k = first.begin; k < first.end; ++k) {
    const std::int32_t node = ordering.order[k], parent = ordering.parent[static_cast<std::size_t>(node)];
    const auto here = static_cast<std::size_t>(local_of[static_cast<std::size_t>(node)]);
    local.parent[here] = parent < 0 ? -1 : local_of[static_cast<std::size_t>(parent)];
    local.order.push_back(static_cast<std::int32_t>(here));
    if (node < limbs) continue;
    const auto j = static_cast<std::size_t>(node - limbs);
    rows[here - static_cast<std::size_t>(lane_limbs)] = static_cast<std::uint8_t>(trees.elimination.rows(j));
    const std::int32_t inboard = trees.joints[j].limb_a;
    pack.inboard_limb[here - static_cast<std::size_t>(lane_limbs)] = inboard < 0 ? -1 : local_of[static_cast<std::size_t>(inboard)];
  }
  local.components.push_back({0, count, 0});
  using Lanes = TreeLanes<Number>;
  pack.edge.assign(rows.size(), {Block<Lanes, 6, 6>::Zero(), Block<Lanes, 6, 6>::Zero()});
  pack.elimination.assign(std::move(local), static_cast<std::size_t>(lane_limbs), std::move(rows));
  return pack;
}

}  // namespace

template <typename Number>
void build_tree_packs(JointTrees& trees, std::size_t lanes) {
  lanes = std::clamp<std::size_t>(lanes, 1, kTreeLanes<Number>);
  TreePacks& packs = *trees.packs;
  packs.doubles.clear(), packs.floats.clear();
  std::vector<TreePack<Number>>& built = packs.packs<Number>();
  const auto& components = trees.elimination.ordering().components;
  // Components by shape, shapes in the order first met, so the packing is deterministic.
  std::map<std::vector<std::int32_t>, std::size_t> shape_index;
  std::vector<std::vector<std::uint32_t>> by_shape;
  std::vector<std::int32_t> offset(trees.elimination.node_count(), -1);
  for (std::uint32_t c = 0; c < components.size(); ++c) {
    if (components[c].begin == components[c].end) continue;
    const auto [found, fresh] = shape_index.try_emplace(shape_of(trees, components[c], offset), by_shape.size());
    if (fresh) by_shape.emplace_back();
    by_shape[found->second].push_back(c);
  }
  for (const std::vector<std::uint32_t>& group : by_shape) {
    for (std::size_t begin = 0; begin < group.size(); begin += lanes) {
      const std::size_t end = std::min(group.size(), begin + lanes);
      built.push_back(make_pack<Number>(trees, std::vector<std::uint32_t>(group.begin() + static_cast<std::ptrdiff_t>(begin), group.begin() + static_cast<std::ptrdiff_t>(end))));
    }
  }
  packs.offset.assign(trees.elimination.node_count(), 0);
  for (const TreeOrdering::Component& component : components) {
    for (std::uint32_t k = component.begin; k < component.end; ++k) packs.offset[static_cast<std::size_t>(trees.elimination.ordering().order[k])] = k - component.begin;
  }
}

namespace {

// The scalar elimination's node holding local node `local` of lane `lane` (a component's).
template <typename Number>
struct LaneNodes {
  const TreeOrdering& ordering;
  const TreePack<Number>& pack;
  std::array<std::uint32_t, kTreeLanes<Number>> begin{};
  LaneNodes(const JointTrees& trees, const TreePack<Number>& pack, const LaneMask& lanes) : ordering(trees.elimination.ordering()), pack(pack) {
    for (std::size_t lane = 0; lane < kTreeLanes<Number>; ++lane) {
      if (lanes[lane]) begin[lane] = ordering.components[static_cast<std::size_t>(pack.component[lane])].begin;
    }
  }
  std::size_t operator()(std::size_t lane, std::size_t local) const { return static_cast<std::size_t>(ordering.order[begin[lane] + pack.position[local]]); }
};

// Up to 36 entries of a block, lane by lane: every lane's numbers are stored before any entry's
// lanes are loaded (a load right after its lanes' stores waits for them: store-to-load
// forwarding cannot join them into one load).
template <typename Number>
struct LaneEntries {
  alignas(64) Number value[36][kTreeLanes<Number>];
  // entries[k] ← lanes of value[k], k < count.
  template <typename Entry>
  void load(int count, Entry&& entry) const {
    for (int k = 0; k < count; ++k) entry(k) = TreeLanes<Number>::load_aligned(value[k]);
  }
};

// The rows of local node `local`'s block (6 for a limb, its rows for a joint).
template <typename Number>
int node_rows(const TreePack<Number>& pack, std::size_t local) {
  const std::int32_t lane_limbs = pack.elimination.body_count();
  return static_cast<std::int32_t>(local) < lane_limbs ? 6 : pack.elimination.rows(local - static_cast<std::size_t>(lane_limbs));
}

// Each lane's solution (the pack's work, each node's top rows) into its nodes' work().
template <typename Number>
void scatter_solutions(JointTrees& trees, TreePack<Number>& pack, const LaneMask& lanes, const LaneNodes<Number>& node_of) {
  LaneEntries<Number> entries;
  for (std::size_t local = 0; local < pack.position.size(); ++local) {
    const int rows = node_rows(pack, local);
    Block<TreeLanes<Number>, 6, 1>& work = pack.elimination.work(local);
    for (int i = 0; i < rows; ++i) work(i, 0).store_aligned(entries.value[i]);
    for (std::size_t lane = 0; lane < kTreeLanes<Number>; ++lane) {
      if (!lanes[lane]) continue;
      Vector6& out = trees.elimination.work(node_of(lane, local));
      for (int i = 0; i < rows; ++i) out(i) = entries.value[i][lane];
    }
  }
}

// The lanes' right-hand sides (their nodes' work(), top rows; zero in the other lanes) into the pack's.
template <typename Number>
void gather_right_sides(JointTrees& trees, TreePack<Number>& pack, const LaneMask& lanes, const LaneNodes<Number>& node_of) {
  LaneEntries<Number> entries;
  for (std::size_t local = 0; local < pack.position.size(); ++local) {
    const int rows = node_rows(pack, local);
    for (std::size_t lane = 0; lane < kTreeLanes<Number>; ++lane) {
      const Vector6* in = lanes[lane] ? &trees.elimination.work(node_of(lane, local)) : nullptr;
      for (int i = 0; i < rows; ++i) entries.value[i][lane] = in ? static_cast<Number>((*in)(i)) : Number(0);
    }
    Block<TreeLanes<Number>, 6, 1>& work = pack.elimination.work(local);
    entries.load(rows, [&](int i) -> TreeLanes<Number>& { return work(i, 0); });
  }
}

// A limb's block M = diag(m E, I) (an empty lane's: the identity).
template <typename Number>
void gather_limb_block(const JointTrees& trees, TreePack<Number>& pack, const LaneMask& lanes, const LaneNodes<Number>& node_of, std::size_t local) {
  LaneEntries<Number> entries;
  for (std::size_t lane = 0; lane < kTreeLanes<Number>; ++lane) {
    Number* column[7];
    for (int k = 0; k < 7; ++k) column[k] = &entries.value[k][lane];
    if (!lanes[lane]) {
      *column[0] = 1, *column[1] = 1, *column[2] = 0, *column[3] = 1, *column[4] = 0, *column[5] = 0, *column[6] = 1;
      continue;
    }
    const std::size_t limb = node_of(lane, local);
    const Eigen::Matrix3d& inertia = trees.inertia[limb];
    const double entry[7] = {trees.mass[limb], inertia(0, 0), inertia(1, 0), inertia(1, 1), inertia(2, 0), inertia(2, 1), inertia(2, 2)};
    for (int k = 0; k < 7; ++k) *column[k] = static_cast<Number>(entry[k]);
  }
  Block<TreeLanes<Number>, 6, 6>& block = pack.elimination.diagonal(local);
  block = Block<TreeLanes<Number>, 6, 6>::Zero();
  entries.load(7, [&](int k) -> TreeLanes<Number>& {
    static constexpr int kRow[7] = {0, 3, 4, 4, 5, 5, 5}, kColumn[7] = {0, 3, 3, 4, 3, 4, 5};
    return block(kRow[k], kColumn[k]);  // the lower triangle, which is what the factor reads
  });
  block(1, 1) = block(2, 2) = block(0, 0);
}

// A joint's −A (−1 on an idle limit's rows and on every row of an empty lane, else 0) and its
// J blocks' top rows on limb A and limb B.
template <typename Number>
void gather_joint_blocks(const JointTrees& trees, TreePack<Number>& pack, const LaneMask& lanes, const LaneNodes<Number>& node_of, std::size_t local) {
  const std::int32_t limbs = trees.elimination.body_count();
  const std::size_t joint = local - static_cast<std::size_t>(pack.elimination.body_count());
  const int rows = pack.elimination.rows(joint);
  LaneEntries<Number> diagonal, inboard, outboard;
  for (std::size_t lane = 0; lane < kTreeLanes<Number>; ++lane) {
    if (!lanes[lane]) {
      for (int i = 0; i < rows; ++i) {
        diagonal.value[i][lane] = -1;
        for (int c = 0; c < 6; ++c) inboard.value[i * 6 + c][lane] = outboard.value[i * 6 + c][lane] = 0;
      }
      continue;
    }
    const std::size_t j = node_of(lane, local) - static_cast<std::size_t>(limbs);
    for (int i = 0; i < rows; ++i) diagonal.value[i][lane] = 0;
    const JointTrees::Joint& tree_joint = trees.joints[j];
    for (std::size_t l = 0; l < tree_joint.limit.size(); ++l) {
      const int row = tree_joint.limit_row(l);
      if (row >= 0 && !(trees.active_limits[j] & (1u << l))) diagonal.value[row][lane] = -1;  // idle: μ = 0
    }
    for (int i = 0; i < rows; ++i) {
      for (int c = 0; c < 6; ++c) {
        inboard.value[i * 6 + c][lane] = static_cast<Number>(trees.block_a[j](i, c));
        outboard.value[i * 6 + c][lane] = static_cast<Number>(trees.block_b[j](i, c));
      }
    }
  }
  using Lanes = TreeLanes<Number>;
  Block<Lanes, 6, 6>& block = pack.elimination.diagonal(local);
  block = Block<Lanes, 6, 6>::Zero();
  diagonal.load(rows, [&](int i) -> Lanes& { return block(i, i); });
  auto& edge = pack.edge[joint];
  inboard.load(rows * 6, [&](int k) -> Lanes& { return edge[0](k / 6, k % 6); });
  outboard.load(rows * 6, [&](int k) -> Lanes& { return edge[1](k / 6, k % 6); });
}

}  // namespace

template <typename Number>
void eliminate_pack(JointTrees& trees, TreePack<Number>& pack, const LaneMask& lanes, bool mobility) {
  const std::int32_t lane_limbs = pack.elimination.body_count();
  const auto count = static_cast<std::uint32_t>(pack.position.size());
  const LaneNodes<Number> node_of(trees, pack, lanes);
  for (std::size_t local = 0; local < count; ++local) {
    if (static_cast<std::int32_t>(local) < lane_limbs) {
      gather_limb_block(trees, pack, lanes, node_of, local);
    } else {
      gather_joint_blocks(trees, pack, lanes, node_of, local);
    }
  }
  gather_right_sides(trees, pack, lanes, node_of);
  ++pack.factors;
  pack.elimination.eliminate(0, count, [&](std::size_t joint, std::int32_t limb) -> const Block<TreeLanes<Number>, 6, 6>& {
    return pack.edge[joint][pack.inboard_limb[joint] == limb ? 0 : 1];
  });
  scatter_solutions(trees, pack, lanes, node_of);
  if (!mobility) return;
  pack.elimination.inverse_diagonal(0, count);
  Matrix6 sink;
  std::array<Matrix6*, kTreeLanes<Number>> blocks{};
  for (std::size_t local = 0; local < static_cast<std::size_t>(lane_limbs); ++local) {
    for (std::size_t lane = 0; lane < kTreeLanes<Number>; ++lane) blocks[lane] = lanes[lane] ? &trees.mobility[node_of(lane, local)] : &sink;
    unpack_lanes(pack.elimination.mobility(local), blocks);
  }
}

template <typename Number>
void solve_pack(JointTrees& trees, TreePack<Number>& pack, const LaneMask& lanes) {
  const LaneNodes<Number> node_of(trees, pack, lanes);
  gather_right_sides(trees, pack, lanes, node_of);
  pack.elimination.solve(0, static_cast<std::uint32_t>(pack.position.size()));
  scatter_solutions(trees, pack, lanes, node_of);
}

template <typename Number>
void solve_pack_paths(JointTrees& trees, TreePack<Number>& pack, std::span<PathLoad, kTreeLanes<Number>> paths) {
  using Lanes = TreeLanes<Number>;
  constexpr std::size_t kLanes = kTreeLanes<Number>;
  const TreePacks& packs = *trees.packs;
  // Each loaded lane's two limbs as the pack's local nodes; the sources of the union of paths.
  std::array<std::array<std::int32_t, 2>, kLanes> local{};
  std::array<std::int32_t, 2 * kLanes> sources{};
  std::size_t source_count = 0, first = kLanes;
  for (std::size_t lane = 0; lane < kLanes; ++lane) {
    if (paths[lane].limbs[0] < 0) continue;
    first = std::min(first, lane);
    for (std::size_t s = 0; s < 2; ++s) {
      local[lane][s] = pack.local[packs.offset[static_cast<std::size_t>(paths[lane].limbs[s])]];
      sources[source_count++] = local[lane][s];
    }
  }
  if (first == kLanes) return;
  // A component's slice of the scratch (the first loaded lane's: the pack's task owns it) holds
  // the union, which has at most a component's nodes.
  const TreeOrdering::Component& nodes = trees.elimination.ordering().components[static_cast<std::size_t>(pack.component[first])];
  const std::span<std::int32_t> room(trees.path_scratch.data() + nodes.begin, nodes.end - nodes.begin);
  const std::span<const std::int32_t> path = room.first(pack.elimination.path_to_root(std::span(sources.data(), source_count), room));
  for (const std::int32_t node : path) pack.elimination.work(static_cast<std::size_t>(node)) = Block<Lanes, 6, 1>::Zero();
  // Each lane's loads in its lane alone, 0 in the others (a select, not a store into one lane of
  // a stored batch, which the next load would wait on); adding an exact 0 changes no lane's bits.
  alignas(64) Number lane_index[kLanes];
  for (std::size_t k = 0; k < kLanes; ++k) lane_index[k] = static_cast<Number>(k);
  const Lanes index = Lanes::load_aligned(lane_index);
  for (std::size_t lane = first; lane < kLanes; ++lane) {
    if (paths[lane].limbs[0] < 0) continue;
    const auto this_lane = index == Lanes(static_cast<Number>(lane));
    for (std::size_t s = 0; s < 2; ++s) {
      Block<Lanes, 6, 1>& work = pack.elimination.work(static_cast<std::size_t>(local[lane][s]));
      for (int i = 0; i < 6; ++i) work(i, 0) += xsimd::select(this_lane, Lanes(static_cast<Number>(paths[lane].load[s](i))), Lanes(Number(0)));
    }
  }
  pack.elimination.solve_nodes(path);
  for (std::size_t lane = first; lane < kLanes; ++lane) {
    if (paths[lane].limbs[0] < 0) continue;
    for (std::size_t s = 0; s < 2; ++s) {
      const Block<Lanes, 6, 1>& work = pack.elimination.work(static_cast<std::size_t>(local[lane][s]));
      for (int i = 0; i < 6; ++i) paths[lane].motion[s](i) = get_lane(work(i, 0), lane);  // a store, then one of its lanes: forwarded
    }
  }
}

#define LIMBER_INSTANTIATE(Number)                                                                                         \
  template void build_tree_packs<Number>(JointTrees&, std::size_t);                                                       \
  template void eliminate_pack<Number>(JointTrees&, TreePack<Number>&, const LaneMask&, bool);                           \
  template void solve_pack<Number>(JointTrees&, TreePack<Number>&, const LaneMask&);                                     \
  template void solve_pack_paths<Number>(JointTrees&, TreePack<Number>&, std::span<PathLoad, kTreeLanes<Number>>);
LIMBER_INSTANTIATE(float)
LIMBER_INSTANTIATE(double)
#undef LIMBER_INSTANTIATE

}  // namespace limber
