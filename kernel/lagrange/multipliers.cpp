// GCC 12 false positive inside Eigen's AVX-512 code (bug 105593); must precede Eigen's headers.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "kernel/lagrange/multipliers.hpp"

#include <string>
#include <type_traits>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "layouts/graph/compressed_rows.hpp"
#include "layouts/graph/disjoint_sets.hpp"

namespace limber {
namespace {

using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

bool asleep(const LagrangeState& state, std::int32_t body) { return state.islands[state.island_of_body[body]].sleeping; }

// M⁻¹ for body b at y: diag(1/m, I_world⁻¹).
Matrix6 inverse_mass_matrix(const LagrangeState& state, const RigidBodyState& y, std::size_t b) {
  Matrix6 m = Matrix6::Zero();
  m.topLeftCorner<3, 3>().diagonal().setConstant(state.bodies.inverse_mass[b]);
  m.bottomRightCorner<3, 3>() = state.bodies.world_inverse_inertia(y, b);
  return m;
}

// Calls function(std::integral_constant<int, rows>{}) for rows in 1…6, so each constraint's
// blocks get fixed-size (unrolled, vectorized) arithmetic.
template <typename Function>
void with_rows(int rows, Function&& function) {
  switch (rows) {
    case 1: return function(std::integral_constant<int, 1>{});
    case 2: return function(std::integral_constant<int, 2>{});
    case 3: return function(std::integral_constant<int, 3>{});
    case 4: return function(std::integral_constant<int, 4>{});
    case 5: return function(std::integral_constant<int, 5>{});
    default: return function(std::integral_constant<int, 6>{});
  }
}

// A square block of at most 6×6, stored without heap allocation.
using SmallMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;

// --- Baraff's tree path ---

void solve_tree(LagrangeState& state, const std::vector<Vector6>& body_rhs, const std::vector<ConstraintVector>& constraint_rhs,
                std::vector<Vector6>& accelerations) {
  TreeSolver& tree = state.tree;
  const auto body_count = static_cast<std::int32_t>(state.bodies.size());
  const ConstraintSet& constraints = state.constraints;
  const std::size_t nodes = tree.parent.size();
  const auto rows_of = [&](std::int32_t node) {
    return node < body_count ? 6 : constraints.row_offset[node - body_count + 1] - constraints.row_offset[node - body_count];
  };
  // The constraint–body block H_{constraint,body} = J_cb (rows × 6) of the edge between `node` and its parent.
  auto edge_block = [&](std::int32_t node, std::int32_t parent) -> const ConstraintBlock& {
    const bool node_is_body = node < body_count;
    const std::int32_t body = node_is_body ? node : parent, c = (node_is_body ? parent : node) - body_count;
    return constraints.inboard[c] == body ? state.geometry.inboard_jacobian[c] : state.geometry.outboard_jacobian[c];
  };
  // Diagonal blocks (M_b for bodies, 0 for constraints) and right-hand sides.
  std::vector<Matrix6>& diagonal = tree.diagonal;  // D; a constraint's is inverted in place when it is eliminated
  for (std::size_t node = 0; node < nodes; ++node) {
    diagonal[node].setZero();
    tree.work[node].setZero();
    if (static_cast<std::int32_t>(node) < body_count) {
      diagonal[node].topLeftCorner<3, 3>().diagonal().setConstant(state.bodies.mass[node]);
      diagonal[node].bottomRightCorner<3, 3>() = state.world_inertia[node];
      tree.work[node] = body_rhs[node];
    } else {
      const ConstraintVector& rhs = constraint_rhs[node - body_count];
      tree.work[node].head(rhs.size()) = rhs;
    }
  }
  // Factor and forward-substitute, children first: L = H_{parent,node}·D⁻¹, then
  // D_parent −= L·H_{node,parent} and y_parent −= L·y_node. Blocks are fixed-size per row count.
  for (const std::int32_t node : tree.order) {
    const std::int32_t parent = tree.parent[node];
    Matrix6& block_d = diagonal[node];
    Matrix6& to_parent = tree.to_parent[node];
    if (node < body_count) {
      SmallCholesky<6>& factor = tree.body_factor[node];  // D_b is symmetric positive definite
      factor.compute(block_d);
      if (parent < 0) continue;
      const ConstraintBlock& edge = edge_block(node, parent);  // H_{constraint,body}
      with_rows(rows_of(parent), [&](auto rows) {
        constexpr int m = decltype(rows)::value;
        const Eigen::Matrix<double, m, 6> block = edge.template topRows<m>();
        const Eigen::Matrix<double, m, 6> l = factor.solve(Eigen::Matrix<double, 6, m>(block.transpose())).transpose();  // B·D⁻¹, D symmetric
        to_parent.template topRows<m>() = l;
        diagonal[parent].template topLeftCorner<m, m>().noalias() -= l * block.transpose();
        tree.work[parent].template head<m>().noalias() -= l * tree.work[node];
      });
    } else {
      with_rows(rows_of(node), [&](auto rows) {
        constexpr int m = decltype(rows)::value;
        // D is negative definite (the Schur complement −J M⁻¹ Jᵀ of its children): Eigen's
        // closed form inverts up to 4×4, and −D has a Cholesky factor for larger blocks.
        using Square = Eigen::Matrix<double, m, m>;
        Square inverse;
        if constexpr (m <= 4) {
          inverse = block_d.template topLeftCorner<m, m>().inverse();
        } else {
          inverse = -Eigen::LLT<Square>(-block_d.template topLeftCorner<m, m>()).solve(Square::Identity());
        }
        block_d.template topLeftCorner<m, m>() = inverse;
        if (parent < 0) return;
        const Eigen::Matrix<double, m, 6> block = edge_block(node, parent).template topRows<m>();  // H_{constraint,body}
        const Eigen::Matrix<double, 6, m> l = block.transpose() * inverse;
        to_parent.template leftCols<m>() = l;
        diagonal[parent].noalias() -= l * block;
        tree.work[parent].noalias() -= l * tree.work[node].template head<m>();
      });
    }
  }
  // Back-substitute, parents first: x_node = D⁻¹·y_node − Lᵀ·x_parent.
  for (auto it = tree.order.rbegin(); it != tree.order.rend(); ++it) {
    const std::int32_t node = *it, parent = tree.parent[node];
    if (node < body_count) {
      Vector6 x = tree.body_factor[node].solve(Vector6(tree.work[node]));
      if (parent >= 0) {
        with_rows(rows_of(parent), [&](auto rows) {
          constexpr int m = decltype(rows)::value;
          x.noalias() -= tree.to_parent[node].template topRows<m>().transpose() * tree.work[parent].template head<m>();
        });
      }
      tree.work[node] = x;
    } else {
      with_rows(rows_of(node), [&](auto rows) {
        constexpr int m = decltype(rows)::value;
        Eigen::Matrix<double, m, 1> x = diagonal[node].template topLeftCorner<m, m>() * tree.work[node].template head<m>();
        if (parent >= 0) x.noalias() -= tree.to_parent[node].template leftCols<m>().transpose() * tree.work[parent];
        tree.work[node].template head<m>() = x;
      });
    }
  }
  for (std::int32_t b = 0; b < body_count; ++b) accelerations[b] = tree.work[b];
  for (std::size_t c = 0; c < constraints.size(); ++c) {
    state.multipliers[c] = -tree.work[body_count + c].head(rows_of(body_count + static_cast<std::int32_t>(c)));
  }
}

// --- The general sparse path: (J M⁻¹ Jᵀ) λ = c − J M⁻¹ F ---

void solve_sparse(LagrangeState& state, const RigidBodyState& y, const std::vector<Vector6>& body_rhs,
                  const std::vector<ConstraintVector>& constraint_rhs, std::vector<Vector6>& accelerations) {
  const std::size_t body_count = state.bodies.size();
  const ConstraintSet& constraints = state.constraints;
  const ConstraintGeometry& geometry = state.geometry;
  std::vector<Matrix6> inverse_mass(body_count);
  std::vector<Vector6> free_acceleration(body_count);
  for (std::size_t b = 0; b < body_count; ++b) {
    inverse_mass[b] = inverse_mass_matrix(state, y, b);
    free_acceleration[b] = inverse_mass[b] * body_rhs[b];
  }
  // Each constraint's Jacobian blocks: (body, block) pairs.
  const auto blocks = [&](std::size_t c) {
    std::vector<std::pair<std::int32_t, const ConstraintBlock*>> pairs;
    if (constraints.inboard[c] >= 0) pairs.emplace_back(constraints.inboard[c], &geometry.inboard_jacobian[c]);
    pairs.emplace_back(constraints.outboard[c], &geometry.outboard_jacobian[c]);
    return pairs;
  };
  std::vector<std::vector<std::size_t>> constraints_of_body(body_count);
  for (std::size_t c = 0; c < constraints.size(); ++c) {
    for (const auto& [b, block] : blocks(c)) constraints_of_body[b].push_back(c);
  }
  const auto total_rows = static_cast<Eigen::Index>(constraints.total_rows());
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::VectorXd rhs(total_rows);
  for (std::size_t c = 0; c < constraints.size(); ++c) {
    const std::int32_t offset = constraints.row_offset[c];
    ConstraintVector right = constraint_rhs[c];
    for (const auto& [b, block] : blocks(c)) right.noalias() -= *block * free_acceleration[b];
    rhs.segment(offset, right.size()) = right;
    for (const auto& [b, block] : blocks(c)) {
      for (const std::size_t k : constraints_of_body[b]) {
        for (const auto& [b2, block2] : blocks(k)) {
          if (b2 != b) continue;
          const SmallMatrix a = *block * inverse_mass[b] * block2->transpose();
          for (Eigen::Index r = 0; r < a.rows(); ++r)
            for (Eigen::Index col = 0; col < a.cols(); ++col) entries.emplace_back(offset + r, constraints.row_offset[k] + col, a(r, col));
        }
      }
    }
  }
  Eigen::SparseMatrix<double> matrix(total_rows, total_rows);
  matrix.setFromTriplets(entries.begin(), entries.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(matrix);
  const Eigen::VectorXd lambda = total_rows ? Eigen::VectorXd(ldlt.solve(rhs)) : Eigen::VectorXd();
  std::vector<Vector6> constraint_force(body_count, Vector6::Zero());
  for (std::size_t c = 0; c < constraints.size(); ++c) {
    state.multipliers[c] = lambda.segment(constraints.row_offset[c], constraints.rows[c].rows());
    for (const auto& [b, block] : blocks(c)) constraint_force[b].noalias() += block->transpose() * state.multipliers[c];
  }
  for (std::size_t b = 0; b < body_count; ++b) accelerations[b] = inverse_mass[b] * (body_rhs[b] + constraint_force[b]);
}

}  // namespace

void prepare_multiplier_solver(LagrangeState& state, const Model& model) {
  const auto body_count = static_cast<std::int32_t>(state.bodies.size());
  const ConstraintSet& joints = state.constraints;  // joints and gears alike
  const std::size_t nodes = static_cast<std::size_t>(body_count) + joints.size();
  // A constraint closes a loop when its two bodies are already connected (a world joint never
  // does: each world anchor is its own fixed frame).
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
    const auto index = static_cast<std::size_t>(loop_joint);
    const bool gear = index >= joints.joint_count;
    const std::size_t model_index = gear ? index - joints.joint_count : index;
    throw ModelError(std::string(gear ? "gears[" : "joints[") + std::to_string(model_index) + "] '" +
                     (gear ? model.gears[model_index].name : model.joints[model_index].name) + "': closes a loop, which the tree solver cannot order; use the sparse (or automatic) solver");
  }
  state.uses_tree = loop_joint < 0 && state.options.solver != MultiplierSolver::sparse;
  state.multipliers.resize(joints.size());
  for (std::size_t c = 0; c < joints.size(); ++c) state.multipliers[c].setZero(joints.rows[c].rows());
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
  update_constraint_geometry(state.constraints, state.joints, y, state.geometry);
  for (std::size_t b = 0; b < state.bodies.size(); ++b) state.world_inertia[b] = state.bodies.world_inertia(y, b);
}

void solve_constrained(LagrangeState& state, const RigidBodyState& y, const std::vector<Vector6>& body_rhs,
                       const std::vector<ConstraintVector>& constraint_rhs, std::vector<Vector6>& accelerations) {
  if (state.uses_tree) solve_tree(state, body_rhs, constraint_rhs, accelerations);
  else solve_sparse(state, y, body_rhs, constraint_rhs, accelerations);
  for (std::size_t b = 0; b < state.bodies.size(); ++b) {
    if (asleep(state, static_cast<std::int32_t>(b))) accelerations[b].setZero();
  }
}

double baumgarte_frequency(const LagrangeState& state, double dt) {
  if (state.options.stabilization != Stabilization::baumgarte) return 0;
  return state.options.baumgarte_frequency > 0 ? state.options.baumgarte_frequency : 0.25 / dt;
}

void add_constraint_forces(LagrangeState& state, RigidForces& forces, double scale) {
  const ConstraintSet& constraints = state.constraints;
  for (std::size_t c = 0; c < constraints.size(); ++c) {
    const std::int32_t i = constraints.inboard[c], o = constraints.outboard[c];
    if (asleep(state, o)) continue;
    const ConstraintVector& lambda = state.multipliers[c];
    const Vector6 outboard = scale * (state.geometry.outboard_jacobian[c].transpose() * lambda);
    forces.force[o] += outboard.head<3>();
    forces.torque[o] += outboard.tail<3>();
    if (i < 0) continue;
    const Vector6 inboard = scale * (state.geometry.inboard_jacobian[c].transpose() * lambda);
    forces.force[i] += inboard.head<3>();
    forces.torque[i] += inboard.tail<3>();
  }
}

void accumulate_constrained_forces(LagrangeState& state, const RigidBodyState& y, RigidForces& forces) {
  accumulate_applied_forces(state, y, forces);
  const std::size_t body_count = state.bodies.size();
  const ConstraintSet& constraints = state.constraints;
  if (constraints.size() == 0) return;
  // The right-hand sides: F with the gyroscopic torque; c = −J̇u (− Baumgarte terms).
  update_geometry(state, y);
  std::vector<Vector6>& body_rhs = state.body_rhs;
  for (std::size_t b = 0; b < body_count; ++b) {
    const Eigen::Vector3d& omega = state.angular_velocity[b];
    body_rhs[b].head<3>() = forces.force[b];
    body_rhs[b].tail<3>() = forces.torque[b] - omega.cross(state.world_inertia[b] * omega);
  }
  const double frequency = baumgarte_frequency(state, state.time_step);
  for (std::size_t c = 0; c < constraints.size(); ++c) {
    state.constraint_rhs[c] =
        -velocity_product(constraints, state.joints, state.geometry, y, state.velocity, state.angular_velocity, c);
    if (frequency > 0) {
      state.constraint_rhs[c] -= 2 * frequency * constraint_rate(constraints, state.geometry, state.velocity, state.angular_velocity, c) +
                                 frequency * frequency * constraint_error(constraints, state.joints, y, c);
    }
  }
  solve_constrained(state, y, body_rhs, state.constraint_rhs, state.accelerations);
  add_constraint_forces(state, forces, 1.0);
}

}  // namespace limber
