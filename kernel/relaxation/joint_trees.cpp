#include "limber/kernel/relaxation/joint_trees.hpp"

#include <algorithm>
#include <map>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "limber/kernel/relaxation/joint_tree_limbs.hpp"
#include "limber/kernel/relaxation/tree_packs.hpp"

// Building the joint trees at compile: which limbs are rigid, which joints and limits the trees
// hold, their elimination order, and the scratch the solve (joint_tree_solve.cpp) uses.
namespace limber {
namespace {

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;
using joint_tree_limbs::kSide;
using joint_tree_limbs::limb_particles;
using joint_tree_limbs::limb_pose;
using joint_tree_limbs::LimbPose;

// Where each tree joint's parts came from, to mark them held once the tree is known.
struct JointSources {
  std::int32_t constraint = -1, point_row = -1, align_row = -1;
  std::array<std::int32_t, 2> limit_row{-1, -1};
};

// The limb each particle belongs to (−1: none, or more than one: shared), and per limb whether
// it can move as a rigid cluster (every particle its own and movable).
template <typename Scalar>
std::vector<std::int32_t> limb_of_particles(const VerletState<Scalar>& state, JointTrees& trees, std::vector<bool>& rigid) {
  const std::uint32_t null_particle = state.particles.null_particle();
  const std::size_t limb_count = state.limbs.head.size();
  std::vector<std::int32_t> limb_of(state.particles.size(), -1);
  trees.limb_particles.assign(limb_count, {});
  trees.limb_framed.assign(limb_count, 0);
  rigid.assign(limb_count, true);
  std::vector<std::int32_t> body_of_limb(limb_count, -1);
  for (std::size_t b = 0; b < state.body_limb.size(); ++b) body_of_limb[state.body_limb[b]] = static_cast<std::int32_t>(b);
  const JointRowSet& rows = state.joint_rows;
  for (std::size_t l = 0; l < limb_count; ++l) {
    auto& particles = trees.limb_particles[l];
    particles.fill(null_particle);
    std::size_t n = 0;
    particles[n++] = state.limbs.head[l], particles[n++] = state.limbs.tail[l];
    const std::int32_t body = body_of_limb[l];
    if (body >= 0 && !rows.frame_plus.empty() && rows.frame_plus[static_cast<std::size_t>(body)] != null_particle) {
      particles[n++] = rows.frame_plus[static_cast<std::size_t>(body)], particles[n++] = rows.frame_minus[static_cast<std::size_t>(body)];
      trees.limb_framed[l] = 1;
    }
    if (state.limbs.centre[l] != kNoCentre) particles[n++] = state.limbs.centre[l];
    for (std::size_t k = 0; k < n; ++k) {
      const std::uint32_t p = particles[k];
      if (!(state.particles.inverse_mass[p] > 0)) rigid[l] = false;
      if (limb_of[p] >= 0) rigid[l] = rigid[static_cast<std::size_t>(limb_of[p])] = false;
      limb_of[p] = static_cast<std::int32_t>(l);
    }
  }
  return limb_of;
}

// The side of a joint a particle names: its limb, −1 for a pin (the world), or −2 for a particle
// a rigid limb does not own (the joint stays rows).
std::int32_t side_of(const std::vector<std::int32_t>& limb_of, const std::vector<bool>& rigid, bool movable, std::uint32_t p) {
  const std::int32_t limb = limb_of[p];
  if (limb < 0) return movable ? -2 : -1;
  return rigid[static_cast<std::size_t>(limb)] ? limb : -2;
}

using JointPairs = std::map<std::tuple<std::int32_t, std::int32_t, std::uint32_t>, std::size_t>;

// The limits of the tree joints found (rigid: no drive, no friction), limb to limb, into
// trees.limits; `side(p)` is side_of a particle.
template <typename Scalar, typename Side>
void attach_limits(const VerletState<Scalar>& state, JointTrees& trees, Side&& side, const JointPairs& joint_of_pair,
                   std::vector<JointSources>& sources) {
  const JointRowSet& rows = state.joint_rows;
  const std::uint32_t null_particle = state.particles.null_particle();
  for (std::size_t r = 0; r < rows.rows.size(); ++r) {
    const JointRow& row = rows.rows[r];
    const bool limit = row.kind == JointRowKind::swing || row.kind == JointRowKind::twist || row.kind == JointRowKind::hinge;
    if (row.joint < 0 || !limit || row.drive || row.friction != 0 || row.stiffness != 0 || row.damping != 0 || row.blend != 0) continue;
    if (row.side_a == JointSide::world) continue;
    const std::int32_t a = side(row.particle[0]), b = side(row.particle[kJointRowSideParticles]);
    const auto found = joint_of_pair.find(std::make_tuple(std::min(a, b), std::max(a, b), 0u));
    if (a < 0 || b < 0 || found == joint_of_pair.end()) continue;
    JointTrees::Joint& joint = trees.joints[found->second];
    const auto free = std::find(joint.limit.begin(), joint.limit.end(), -1);
    if (joint.limb_a != a || free == joint.limit.end()) continue;
    const std::size_t slot = trees.limits.push(static_cast<JointRowBatches<double>::Index>(null_particle));
    for (std::size_t k = 0; k < kJointRowDirections; ++k) trees.limits.direction[k][slot] = row.direction[k];
    trees.limits.lower[slot] = row.lower, trees.limits.upper[slot] = row.upper;
    trees.limit_kind.push_back(row.kind);
    *free = static_cast<std::int32_t>(slot);
    JointSources& source = sources[found->second];
    source.limit_row[static_cast<std::size_t>(free - joint.limit.begin())] = static_cast<std::int32_t>(r);
  }

}

// The maps the contacts with the trees read (tree_contacts.hpp): each particle's tree limb
// (own(p): a limb of a tree component), each limb's component, each component's island.
template <typename Own>
void map_tree_limbs(JointTrees& trees, const TreeOrdering& ordering, const std::vector<std::pair<std::uint32_t, std::uint32_t>>& island_components,
                    const std::vector<std::int32_t>& limb_of, Own&& own) {
  const auto limb_count = static_cast<std::int32_t>(trees.limb_particles.size());
  trees.limb_of_particle.assign(limb_of.size(), -1);
  for (std::size_t p = 0; p < limb_of.size(); ++p) {
    if (own(static_cast<std::uint32_t>(p))) trees.limb_of_particle[p] = limb_of[p];
  }
  trees.component_of_limb.assign(static_cast<std::size_t>(limb_count), -1);
  trees.component_island.assign(ordering.components.size(), 0);
  for (const auto& [island, k] : island_components) {
    trees.component_island[k] = island;
    const TreeOrdering::Component& component = ordering.components[k];
    for (std::uint32_t n = component.begin; n < component.end; ++n) {
      const std::int32_t node = ordering.order[n];
      if (node < limb_count) trees.component_of_limb[static_cast<std::size_t>(node)] = static_cast<std::int32_t>(k);
    }
  }
}

// Orders the tree joints into trees (the loops left to the sweeps), marks what the trees hold,
// finds each island's components and the rest shapes of their limbs, and sizes the scratch.
template <typename Scalar>
void order_trees(const VerletState<Scalar>& state, JointTrees& trees, const std::vector<std::int32_t>& limb_of,
                 const std::vector<JointSources>& sources) {
  const JointRowSet& rows = state.joint_rows;
  const std::size_t limb_count = trees.limb_particles.size();
  std::vector<std::int32_t> inboard(trees.joints.size()), outboard(trees.joints.size());
  std::vector<std::uint8_t> joint_rows(trees.joints.size());
  for (std::size_t j = 0; j < trees.joints.size(); ++j) {
    inboard[j] = trees.joints[j].limb_a, outboard[j] = trees.joints[j].limb_b;
    joint_rows[j] = static_cast<std::uint8_t>(trees.joints[j].fixed_rows());
  }
  TreeOrdering ordering = order_tree(limb_count, inboard, outboard);
  std::vector<bool> in_tree(trees.joints.size(), true);
  for (const std::uint32_t loop : ordering.loop_constraints) in_tree[loop] = false;
  trees.tree_constraint.assign(state.constraints.size(), 0);
  trees.tree_row.assign(rows.rows.size(), 0);
  for (std::size_t j = 0; j < trees.joints.size(); ++j) {
    if (!in_tree[j]) continue;
    if (sources[j].constraint >= 0) trees.tree_constraint[static_cast<std::size_t>(sources[j].constraint)] = 1;
    if (sources[j].point_row >= 0) trees.tree_row[static_cast<std::size_t>(sources[j].point_row)] = 1;
    if (sources[j].align_row >= 0) trees.tree_row[static_cast<std::size_t>(sources[j].align_row)] = 1;
    for (const std::int32_t r : sources[j].limit_row) {
      if (r >= 0) trees.tree_row[static_cast<std::size_t>(r)] = 1;
    }
  }
  // Components of more than one limb, by island (a limb's island from the islands' limb ranges).
  std::vector<std::uint32_t> island_of_limb(limb_count, 0);
  for (std::size_t i = 0; i < state.islands.size(); ++i) {
    std::fill(island_of_limb.begin() + state.islands[i].limb_begin, island_of_limb.begin() + state.islands[i].limb_end,
              static_cast<std::uint32_t>(i));
  }
  std::vector<std::pair<std::uint32_t, std::uint32_t>> island_components;
  for (std::size_t k = 0; k < ordering.components.size(); ++k) {
    const TreeOrdering::Component& component = ordering.components[k];
    if (component.end - component.begin < 2) continue;
    island_components.emplace_back(island_of_limb[static_cast<std::size_t>(component.body)], static_cast<std::uint32_t>(k));
  }
  trees.island_components = group_by_row(state.islands.size(), island_components);
  // The limbs of those components are rigid bodies: their rest shapes, and their own
  // constraints (link, centre, frame) held by the tree (load_limb) rather than the sweeps.
  std::vector<bool> tree_limb(limb_count, false);
  for (const auto& [island, k] : island_components) {
    const TreeOrdering::Component& component = ordering.components[k];
    for (std::uint32_t n = component.begin; n < component.end; ++n) {
      if (ordering.order[n] < static_cast<std::int32_t>(limb_count)) tree_limb[static_cast<std::size_t>(ordering.order[n])] = true;
    }
  }
  trees.rest_offset.assign(limb_count, {});
  for (std::size_t l = 0; l < limb_count; ++l) {
    Eigen::Vector3d x[kSide];
    double mass[kSide];
    const int n = limb_particles(state, trees, l, x, mass);
    const LimbPose pose = limb_pose(x, mass, n, trees.limb_framed[l]);
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3d r = x[k] - pose.centre;
      trees.rest_offset[l][static_cast<std::size_t>(k)] =
          trees.limb_framed[l] ? Eigen::Vector3d(pose.frame.transpose() * r) : Eigen::Vector3d(0, 0, r.dot(pose.frame.col(2)));
    }
  }
  const auto own = [&](std::uint32_t p) { return limb_of[p] >= 0 && tree_limb[static_cast<std::size_t>(limb_of[p])]; };
  for (std::size_t c = 0; c < state.constraints.size(); ++c) {
    const std::uint32_t i = state.constraints.particle_i[c], j = state.constraints.particle_j[c];
    if (own(i) && limb_of[i] == limb_of[j]) trees.tree_constraint[c] = 1;
  }
  for (std::size_t r = 0; r < rows.rows.size(); ++r) {
    const JointRow& row = rows.rows[r];
    if (row.joint < 0 && row.kind == JointRowKind::point && own(row.particle[0])) trees.tree_row[r] = 1;  // a frame's row
  }
  map_tree_limbs(trees, ordering, island_components, limb_of, own);
  trees.elimination.assign(std::move(ordering), limb_count, std::move(joint_rows));
  trees.centre.assign(limb_count, Eigen::Vector3d::Zero());
  trees.frame.assign(limb_count, Eigen::Matrix3d::Identity());
  trees.mobility.assign(limb_count, Matrix6::Zero());
  trees.block_a.assign(trees.joints.size(), Matrix6::Zero());
  trees.block_b.assign(trees.joints.size(), Matrix6::Zero());
  trees.rate.assign(limb_count, Vector6::Zero());
  trees.mass.assign(limb_count, 0.0);
  trees.inertia.assign(limb_count, Eigen::Matrix3d::Zero());
  trees.active_limits.assign(trees.joints.size(), 0);
  trees.limit_upper.assign(trees.joints.size(), 0);
  trees.limit_held.assign(trees.joints.size(), 0);
  const std::size_t component_count = trees.elimination.ordering().components.size();
  trees.counts.assign(component_count, {});
  trees.load_scale.assign(component_count, 1.0);
  trees.settled.assign(component_count, 0);
  trees.path_scratch.assign(trees.elimination.ordering().order.size(), -1);
  trees.component_awake.assign(component_count, 0);
  build_tree_packs<Scalar>(trees);
  trees.joint_motion.assign(limb_count, Vector6::Zero());
  trees.load_motion.assign(limb_count, Vector6::Zero());
}

// Throws std::invalid_argument for the options the trees cannot run with.
void refuse_unsupported(const VerletOptions& options) {
  const auto refuse = [](const char* what) { throw std::invalid_argument(std::string("options: joint_solve tree needs ") + what); };
  if (options.rule != RelaxationRule::weighted) refuse("the weighted rule (limbs keep their masses)");
  if (options.solver != RelaxationSolver::gauss_seidel || options.order != SweepOrder::coloured) {
    refuse("the coloured Gauss-Seidel sweep (not Jacobi, the sequential sweep or the direct solver)");
  }
  if (options.layout == ParticleLayout::aos || options.layout == ParticleLayout::aosoa) refuse("the SoA layout");
}

}  // namespace

template <typename Scalar>
void prepare_joint_trees(VerletState<Scalar>& state) {
  JointTrees& trees = state.plan.joint_trees;
  JointTrees empty;  // (g++ 12 fails on `trees = JointTrees{}`: an internal compiler error)
  trees = std::move(empty);
  if (state.options.verlet.joint_solve != JointSolve::tree) return;
  refuse_unsupported(state.options);

  std::vector<bool> rigid;
  const std::vector<std::int32_t> limb_of = limb_of_particles(state, trees, rigid);
  const auto movable = [&](std::uint32_t p) { return state.particles.inverse_mass[p] > 0; };
  const auto side = [&](std::uint32_t p) { return side_of(limb_of, rigid, movable(p), p); };
  // One tree joint per pair of limbs (or limb and world pin): its point part and its hinge axis.
  std::vector<JointSources> sources;
  JointPairs joint_of_pair;
  const std::uint32_t null_particle = state.particles.null_particle();
  const auto joint_for = [&](std::int32_t a, std::int32_t b, std::uint32_t pin, bool point) -> JointTrees::Joint* {
    if (a == -2 || b == -2 || a == b || b < 0) return nullptr;
    const auto key = std::make_tuple(std::min(a, b), std::max(a, b), a < 0 ? pin : 0u);
    auto found = joint_of_pair.find(key);
    if (found == joint_of_pair.end() || (point ? trees.joints[found->second].point : trees.joints[found->second].align_row >= 0)) {
      // A second part of one kind between one pair closes a loop: its own node, which order_tree reports.
      found = joint_of_pair.insert_or_assign(key, trees.joints.size()).first;
      JointTrees::Joint joint;
      joint.limb_a = a, joint.limb_b = b;
      joint.particle.fill(null_particle);
      trees.joints.push_back(joint);
      sources.emplace_back();
    }
    return &trees.joints[found->second];
  };
  for (const auto& [c, reference] : state.joint_constraints) {
    const std::uint32_t i = state.constraints.particle_i[c], j = state.constraints.particle_j[c];
    std::int32_t a = side(i), b = side(j);
    std::uint32_t p_a = i, p_b = j;
    if (b == -1) std::swap(a, b), std::swap(p_a, p_b);  // the world is side A
    JointTrees::Joint* joint = joint_for(a, b, p_a, true);
    if (joint == nullptr) continue;
    const bool a_first = joint->limb_a == a;
    joint->point = true;
    joint->particle[0] = a_first ? p_a : p_b, joint->coefficient[0] = -1;
    joint->particle[kSide] = a_first ? p_b : p_a, joint->coefficient[kSide] = 1;
    sources[static_cast<std::size_t>(joint - trees.joints.data())].constraint = static_cast<std::int32_t>(c);
  }
  const JointRowSet& rows = state.joint_rows;
  for (std::size_t r = 0; r < rows.rows.size(); ++r) {
    const JointRow& row = rows.rows[r];
    if (row.joint < 0) continue;  // a frame's own row
    const bool rigid_equality = row.lower == 0 && row.upper == 0 && row.stiffness == 0 && row.damping == 0 && row.friction == 0 && !row.drive;
    if (row.kind == JointRowKind::point) {
      const std::int32_t a = side(row.particle[0]), b = side(row.particle[kJointRowSideParticles]);
      JointTrees::Joint* joint = joint_for(a, b, row.particle[0], true);
      if (joint == nullptr) continue;
      const bool a_first = joint->limb_a == a;
      joint->point = true;
      for (int s = 0; s < 2; ++s) {
        const std::size_t from = static_cast<std::size_t>((s == 0) == a_first ? 0 : kJointRowSideParticles);
        for (int k = 0, n = 0; k < 4; ++k) {
          const std::uint32_t p = row.particle[from + k];
          if (p == null_particle || row.direction[from + k] == 0) continue;
          joint->particle[s * kSide + n] = p, joint->coefficient[s * kSide + n] = row.direction[from + k], ++n;
        }
      }
      sources[static_cast<std::size_t>(joint - trees.joints.data())].point_row = static_cast<std::int32_t>(r);
    } else if (row.kind == JointRowKind::align && rigid_equality) {
      const std::int32_t a = row.side_a == JointSide::world ? -1 : side(row.particle[0]);
      const std::int32_t b = side(row.particle[kJointRowSideParticles]);
      if (b < 0 || (a >= 0 && !trees.limb_framed[a]) || !trees.limb_framed[b]) continue;
      JointTrees::Joint* joint = joint_for(a, b, null_particle, false);
      if (joint == nullptr || joint->limb_a != a) continue;  // a tree keeps A inboard
      const Eigen::Vector3d d(row.direction[0], row.direction[1], row.direction[2]);
      const Eigen::Vector3d helper = std::abs(d.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
      joint->align_row = static_cast<std::int32_t>(r);
      joint->t1 = d.cross(helper).normalized(), joint->t2 = d.normalized().cross(joint->t1);
      joint->e = Eigen::Vector3d(row.direction[3], row.direction[4], row.direction[5]).normalized();
      sources[static_cast<std::size_t>(joint - trees.joints.data())].align_row = static_cast<std::int32_t>(r);
    }
  }
  attach_limits(state, trees, side, joint_of_pair, sources);
  order_trees(state, trees, limb_of, sources);
  if (trees.island_components.entries.empty()) trees.joints.clear();  // nothing to solve: inactive
  // The rattle rule's contacts are inequalities of its velocity stage too: they stay rows there.
  trees.with_contacts = trees.active() && !uses_rattle(state);
}

#define LIMBER_INSTANTIATE(Scalar) template void prepare_joint_trees<Scalar>(VerletState<Scalar>&);
LIMBER_INSTANTIATE(float)
LIMBER_INSTANTIATE(double)
#undef LIMBER_INSTANTIATE

}  // namespace limber
