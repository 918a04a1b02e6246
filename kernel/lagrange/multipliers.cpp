// GCC 12 false positive inside Eigen's AVX-512 code (bug 105593); must precede Eigen's headers.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "kernel/lagrange/multipliers.hpp"

#include <string>
#include <tuple>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "kernel/rigid/anchor_jacobian.hpp"
#include "layouts/graph/compressed_rows.hpp"
#include "layouts/graph/disjoint_sets.hpp"

namespace limber {
namespace {

using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

bool asleep(const LagrangeState& state, std::int32_t body) { return state.islands[state.island_of_body[body]].sleeping; }

// The world levers of joint j's two anchors at y (zero for a world anchor).
std::pair<Eigen::Vector3d, Eigen::Vector3d> levers(const LagrangeState& state, const RigidBodyState& y, std::size_t j) {
  const JointBuffer& joints = state.joints;
  const Eigen::Vector3d outboard = y.orientation[joints.outboard[j]] * joints.outboard_anchor[j];
  const Eigen::Vector3d inboard = joints.inboard[j] >= 0 ? Eigen::Vector3d(y.orientation[joints.inboard[j]] * joints.inboard_anchor[j])
                                                         : Eigen::Vector3d::Zero();
  return {inboard, outboard};
}

// M⁻¹ for body b at y: diag(1/m, I_world⁻¹).
Matrix6 inverse_mass_matrix(const LagrangeState& state, const RigidBodyState& y, std::size_t b) {
  Matrix6 m = Matrix6::Zero();
  m.topLeftCorner<3, 3>().diagonal().setConstant(state.bodies.inverse_mass[b]);
  m.bottomRightCorner<3, 3>() = state.bodies.world_inverse_inertia(y, b);
  return m;
}

// --- Baraff's tree path ---

void solve_tree(LagrangeState& state, const RigidBodyState&, const std::vector<Vector6>& body_rhs,
                const std::vector<Eigen::Vector3d>& joint_rhs, std::vector<Vector6>& accelerations) {
  TreeSolver& tree = state.tree;
  const auto body_count = static_cast<std::int32_t>(state.bodies.size());
  const JointBuffer& joints = state.joints;
  const std::size_t nodes = tree.parent.size();
  // The joint–body block B = J_jb = ±G_b (3×6) of the edge between `node` and its parent.
  auto edge_block = [&](std::int32_t node, std::int32_t parent) {
    const bool node_is_body = node < body_count;
    const std::int32_t body = node_is_body ? node : parent, joint = (node_is_body ? parent : node) - body_count;
    return joints.inboard[joint] == body ? anchor_jacobian(state.inboard_lever[joint])
                                         : AnchorJacobian(-anchor_jacobian(state.outboard_lever[joint]));
  };
  // Diagonal blocks (M_b for bodies, 0 for joints) and right-hand sides.
  std::vector<Matrix6>& diagonal = tree.diagonal;  // D; a joint's is inverted in place when it is eliminated
  for (std::size_t node = 0; node < nodes; ++node) {
    diagonal[node].setZero();
    tree.work[node].setZero();
    if (static_cast<std::int32_t>(node) < body_count) {
      diagonal[node].topLeftCorner<3, 3>().diagonal().setConstant(state.bodies.mass[node]);
      diagonal[node].bottomRightCorner<3, 3>() = state.world_inertia[node];
      tree.work[node] = body_rhs[node];
    } else {
      tree.work[node].head<3>() = joint_rhs[node - body_count];
    }
  }
  // Factor and forward-substitute, children first: L = H_{parent,node}·D⁻¹, then
  // D_parent −= L·H_{node,parent} and y_parent −= L·y_node.
  for (const std::int32_t node : tree.order) {
    const std::int32_t parent = tree.parent[node];
    Matrix6& block_d = diagonal[node];
    Matrix6& to_parent = tree.to_parent[node];
    if (node < body_count) {
      Eigen::LLT<Matrix6>& factor = tree.body_factor[node];  // D_b is symmetric positive definite
      factor.compute(block_d);
      if (parent < 0) continue;
      const AnchorJacobian block = edge_block(node, parent);                       // H_{joint,body}
      const AnchorJacobian l = factor.solve(block.transpose()).transpose();        // 3×6: B·D⁻¹, D symmetric
      to_parent.topLeftCorner<3, 6>() = l;
      diagonal[parent].topLeftCorner<3, 3>() -= l * block.transpose();
      tree.work[parent].head<3>() -= l * tree.work[node];
    } else {
      const Eigen::Matrix3d joint_inverse = block_d.topLeftCorner<3, 3>().inverse();  // negative definite
      block_d.topLeftCorner<3, 3>() = joint_inverse;
      if (parent < 0) continue;
      const AnchorJacobian block = edge_block(node, parent);                       // H_{joint,body}; H_{body,joint} = blockᵀ
      const Eigen::Matrix<double, 6, 3> l = block.transpose() * joint_inverse;     // 6×3
      to_parent.topLeftCorner<6, 3>() = l;
      diagonal[parent] -= l * block;
      tree.work[parent] -= l * tree.work[node].head<3>();
    }
  }
  // Back-substitute, parents first: x_node = D⁻¹·y_node − Lᵀ·x_parent.
  for (auto it = tree.order.rbegin(); it != tree.order.rend(); ++it) {
    const std::int32_t node = *it, parent = tree.parent[node];
    if (node < body_count) {
      Vector6 x = tree.body_factor[node].solve(tree.work[node]);
      if (parent >= 0) x -= tree.to_parent[node].topLeftCorner<3, 6>().transpose() * tree.work[parent].head<3>();
      tree.work[node] = x;
    } else {
      Eigen::Vector3d x = diagonal[node].topLeftCorner<3, 3>() * tree.work[node].head<3>();
      if (parent >= 0) x -= tree.to_parent[node].topLeftCorner<6, 3>().transpose() * tree.work[parent];
      tree.work[node].head<3>() = x;
    }
  }
  for (std::int32_t b = 0; b < body_count; ++b) accelerations[b] = tree.work[b];
  for (std::size_t j = 0; j < joints.size(); ++j) state.multipliers[j] = -tree.work[body_count + j].head<3>();
}

// --- The general sparse path: (J M⁻¹ Jᵀ) λ = c − J M⁻¹ F ---

void solve_sparse(LagrangeState& state, const RigidBodyState& y, const std::vector<Vector6>& body_rhs,
                  const std::vector<Eigen::Vector3d>& joint_rhs, std::vector<Vector6>& accelerations) {
  const std::size_t body_count = state.bodies.size(), joint_count = state.joints.size();
  const JointBuffer& joints = state.joints;
  std::vector<Matrix6> inverse_mass(body_count);
  std::vector<Vector6> free_acceleration(body_count);
  for (std::size_t b = 0; b < body_count; ++b) {
    inverse_mass[b] = inverse_mass_matrix(state, y, b);
    free_acceleration[b] = inverse_mass[b] * body_rhs[b];
  }
  // Each joint's Jacobian blocks: (body, block) pairs.
  std::vector<std::vector<std::pair<std::int32_t, AnchorJacobian>>> blocks(joint_count);
  for (std::size_t j = 0; j < joint_count; ++j) {
    if (joints.inboard[j] >= 0) blocks[j].emplace_back(joints.inboard[j], anchor_jacobian(state.inboard_lever[j]));
    blocks[j].emplace_back(joints.outboard[j], -anchor_jacobian(state.outboard_lever[j]));
  }
  std::vector<std::vector<std::size_t>> joints_of_body(body_count);
  for (std::size_t j = 0; j < joint_count; ++j) {
    for (const auto& [b, block] : blocks[j]) joints_of_body[b].push_back(j);
  }
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd rhs(3 * joint_count);
  for (std::size_t j = 0; j < joint_count; ++j) {
    Eigen::Vector3d c = joint_rhs[j];
    for (const auto& [b, block] : blocks[j]) c -= block * free_acceleration[b];
    rhs.segment<3>(3 * j) = c;
    for (const auto& [b, block] : blocks[j]) {
      for (const std::size_t k : joints_of_body[b]) {
        for (const auto& [b2, block2] : blocks[k]) {
          if (b2 != b) continue;
          const Eigen::Matrix3d a = block * inverse_mass[b] * block2.transpose();
          for (int r = 0; r < 3; ++r)
            for (int c2 = 0; c2 < 3; ++c2) entries.emplace_back(3 * j + r, 3 * k + c2, a(r, c2));
        }
      }
    }
  }
  Eigen::SparseMatrix<double> matrix(3 * joint_count, 3 * joint_count);
  matrix.setFromTriplets(entries.begin(), entries.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(matrix);
  const Eigen::VectorXd lambda = joint_count ? Eigen::VectorXd(ldlt.solve(rhs)) : Eigen::VectorXd();
  std::vector<Vector6> constraint_force(body_count, Vector6::Zero());
  for (std::size_t j = 0; j < joint_count; ++j) {
    state.multipliers[j] = lambda.segment<3>(3 * j);
    for (const auto& [b, block] : blocks[j]) constraint_force[b] += block.transpose() * state.multipliers[j];
  }
  for (std::size_t b = 0; b < body_count; ++b) accelerations[b] = inverse_mass[b] * (body_rhs[b] + constraint_force[b]);
}

}  // namespace

void prepare_multiplier_solver(LagrangeState& state, const Model& model) {
  const auto body_count = static_cast<std::int32_t>(state.bodies.size());
  const JointBuffer& joints = state.joints;
  const std::size_t nodes = static_cast<std::size_t>(body_count) + joints.size();
  // A joint closes a loop when its two bodies are already connected (a world joint never does:
  // each world anchor is its own fixed frame).
  DisjointSets connected(static_cast<std::uint32_t>(body_count));
  std::int64_t loop_joint = -1;
  for (std::size_t j = 0; j < joints.size(); ++j) {
    if (joints.inboard[j] < 0) continue;
    const auto a = static_cast<std::uint32_t>(joints.inboard[j]), b = static_cast<std::uint32_t>(joints.outboard[j]);
    if (connected.find(a) == connected.find(b)) {
      if (loop_joint < 0) loop_joint = static_cast<std::int64_t>(j);
    } else {
      connected.unite(a, b);
    }
  }
  // A joint to the world has no child body of its own to eliminate it with (its diagonal block
  // is zero), so it must be its component's root — which leaves room for one per component. A
  // second one closes a loop through the world.
  std::vector<std::int64_t> world_root(body_count, -1);
  for (std::size_t j = 0; j < joints.size() && loop_joint < 0; ++j) {
    if (joints.inboard[j] >= 0) continue;
    std::int64_t& root = world_root[connected.find(static_cast<std::uint32_t>(joints.outboard[j]))];
    if (root >= 0) loop_joint = static_cast<std::int64_t>(j);
    else root = static_cast<std::int64_t>(j);
  }
  if (loop_joint >= 0 && state.options.solver == MultiplierSolver::tree) {
    throw ModelError("joints[" + std::to_string(loop_joint) + "] '" + model.joints[loop_joint].name +
                     "': closes a loop, which the tree solver cannot order; use the sparse (or automatic) solver");
  }
  state.uses_tree = loop_joint < 0 && state.options.solver != MultiplierSolver::sparse;
  state.multipliers.assign(joints.size(), Eigen::Vector3d::Zero());
  if (!state.uses_tree) return;

  // Breadth-first from each component's root over body–joint edges; parents first in that order,
  // so its reverse eliminates children first, and every joint has a child body.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const auto joint_node = static_cast<std::uint32_t>(body_count + j);
    for (const std::int32_t b : {joints.inboard[j], joints.outboard[j]}) {
      if (b < 0) continue;
      edges.emplace_back(static_cast<std::uint32_t>(b), joint_node);
      edges.emplace_back(joint_node, static_cast<std::uint32_t>(b));
    }
  }
  const CompressedRows<std::uint32_t> neighbours = group_by_row(nodes, edges);
  TreeSolver& tree = state.tree;
  tree.parent.assign(nodes, -1);
  std::vector<bool> visited(nodes, false);
  std::vector<std::int32_t> breadth_first;
  breadth_first.reserve(nodes);
  // Roots: each component's joint to the world where it has one, else its lowest body.
  std::vector<std::size_t> roots;
  for (std::int32_t b = 0; b < body_count; ++b) {
    if (connected.find(static_cast<std::uint32_t>(b)) != static_cast<std::uint32_t>(b)) continue;
    roots.push_back(world_root[b] >= 0 ? static_cast<std::size_t>(body_count + world_root[b]) : static_cast<std::size_t>(b));
  }
  for (const std::size_t root : roots) {
    if (visited[root]) continue;
    visited[root] = true;
    breadth_first.push_back(static_cast<std::int32_t>(root));
    for (std::size_t next = breadth_first.size() - 1; next < breadth_first.size(); ++next) {
      for (const std::uint32_t other : neighbours.row(breadth_first[next])) {
        if (visited[other]) continue;
        visited[other] = true;
        tree.parent[other] = breadth_first[next];
        breadth_first.push_back(static_cast<std::int32_t>(other));
      }
    }
  }
  tree.order.assign(breadth_first.rbegin(), breadth_first.rend());
  tree.diagonal.assign(nodes, Matrix6::Zero());
  tree.to_parent.assign(nodes, Matrix6::Zero());
  tree.work.assign(nodes, Vector6::Zero());
  tree.body_factor.resize(static_cast<std::size_t>(body_count));
}

void update_geometry(LagrangeState& state, const RigidBodyState& y) {
  for (std::size_t j = 0; j < state.joints.size(); ++j) {
    std::tie(state.inboard_lever[j], state.outboard_lever[j]) = levers(state, y, j);
  }
  for (std::size_t b = 0; b < state.bodies.size(); ++b) state.world_inertia[b] = state.bodies.world_inertia(y, b);
}

void solve_constrained(LagrangeState& state, const RigidBodyState& y, const std::vector<Vector6>& body_rhs,
                       const std::vector<Eigen::Vector3d>& joint_rhs, std::vector<Vector6>& accelerations) {
  if (state.uses_tree) solve_tree(state, y, body_rhs, joint_rhs, accelerations);
  else solve_sparse(state, y, body_rhs, joint_rhs, accelerations);
  for (std::size_t b = 0; b < state.bodies.size(); ++b) {
    if (asleep(state, static_cast<std::int32_t>(b))) accelerations[b].setZero();
  }
}


void accumulate_constrained_forces(LagrangeState& state, const RigidBodyState& y, RigidForces& forces) {
  accumulate_applied_forces(state, y, forces);
  const std::size_t body_count = state.bodies.size();
  if (state.joints.size() == 0) return;
  // The right-hand sides: F with the gyroscopic torque; c = −J̇u (− Baumgarte terms).
  update_geometry(state, y);
  std::vector<Vector6>& body_rhs = state.body_rhs;
  for (std::size_t b = 0; b < body_count; ++b) {
    const Eigen::Vector3d& omega = state.angular_velocity[b];
    body_rhs[b].head<3>() = forces.force[b];
    body_rhs[b].tail<3>() = forces.torque[b] - omega.cross(state.world_inertia[b] * omega);
  }
  const double frequency = state.options.stabilization == Stabilization::baumgarte
                               ? (state.options.baumgarte_frequency > 0 ? state.options.baumgarte_frequency : 0.25 / state.time_step)
                               : 0.0;
  const JointBuffer& joints = state.joints;
  std::vector<Eigen::Vector3d>& joint_rhs = state.joint_rhs;
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const Eigen::Vector3d &inboard_lever = state.inboard_lever[j], &outboard_lever = state.outboard_lever[j];
    const std::int32_t i = joints.inboard[j], o = joints.outboard[j];
    const Eigen::Vector3d& w_o = state.angular_velocity[o];
    Eigen::Vector3d bias = -w_o.cross(w_o.cross(outboard_lever));
    Eigen::Vector3d rate = -(state.velocity[o] + w_o.cross(outboard_lever));
    if (i >= 0) {
      const Eigen::Vector3d& w_i = state.angular_velocity[i];
      bias += w_i.cross(w_i.cross(inboard_lever));
      rate += state.velocity[i] + w_i.cross(inboard_lever);
    }
    joint_rhs[j] = -bias;
    if (frequency > 0) {
      const Eigen::Vector3d outboard = y.position[o] + outboard_lever;
      const Eigen::Vector3d inboard = i >= 0 ? Eigen::Vector3d(y.position[i] + inboard_lever) : joints.inboard_anchor[j];
      joint_rhs[j] -= 2 * frequency * rate + frequency * frequency * (inboard - outboard);
    }
  }
  solve_constrained(state, y, body_rhs, joint_rhs, state.accelerations);
  // The constraint forces Jᵀλ: λ on the inboard body at its anchor, −λ on the outboard.
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const Eigen::Vector3d &inboard_lever = state.inboard_lever[j], &outboard_lever = state.outboard_lever[j];
    const std::int32_t i = joints.inboard[j], o = joints.outboard[j];
    if (asleep(state, o)) continue;
    const Eigen::Vector3d& lambda = state.multipliers[j];
    if (i >= 0) {
      forces.force[i] += lambda;
      forces.torque[i] += inboard_lever.cross(lambda);
    }
    forces.force[o] -= lambda;
    forces.torque[o] -= outboard_lever.cross(lambda);
  }
}

}  // namespace limber
