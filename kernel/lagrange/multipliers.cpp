// GCC 12 false positive inside Eigen's AVX-512 code (bug 105593); must precede Eigen's headers.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "limber/kernel/lagrange/multipliers.hpp"

#include <string>

#include <Eigen/Cholesky>
#include <Eigen/LU>


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

// A square block of at most 6×6, stored without heap allocation.
using SmallMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;

// --- Baraff's tree path ---

void solve_tree(LagrangeState& state, const std::vector<Vector6>& body_rhs, const std::vector<ConstraintVector>& constraint_rhs,
                std::vector<Vector6>& accelerations) {
  TreeElimination<double, 6>& tree = state.tree;
  const std::size_t body_count = state.bodies.size();
  const ConstraintSet& constraints = state.constraints;
  for (std::size_t b = 0; b < body_count; ++b) {
    Matrix6& block = tree.diagonal(b);
    block.setZero();
    block.topLeftCorner<3, 3>().diagonal().setConstant(state.bodies.mass[b]);
    block.bottomRightCorner<3, 3>() = state.world_inertia[b];
    tree.work(b) = body_rhs[b];
  }
  for (std::size_t c = 0; c < constraints.size(); ++c) {
    tree.diagonal(body_count + c).setZero();  // rigid: no compliance
    tree.work(body_count + c).setZero();
    tree.work(body_count + c).head(constraint_rhs[c].size()) = constraint_rhs[c];
  }
  const auto edge = [&](std::size_t c, std::int32_t body) -> const ConstraintBlock& {
    return constraints.inboard[c] == body ? state.geometry.inboard_jacobian[c] : state.geometry.outboard_jacobian[c];
  };
  tree.eliminate(0, static_cast<std::uint32_t>(tree.ordering().order.size()), edge);
  for (std::size_t b = 0; b < body_count; ++b) accelerations[b] = tree.work(b);
  for (std::size_t c = 0; c < constraints.size(); ++c) {
    state.multipliers[c] = -tree.work(body_count + c).head(tree.rows(c));
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
  const std::size_t body_count = state.bodies.size();
  const ConstraintSet& constraints = state.constraints;  // joints and gears alike
  TreeOrdering ordering = order_tree(body_count, constraints.inboard, constraints.outboard);
  if (!ordering.loop_constraints.empty() && state.options.solver == MultiplierSolver::tree) {
    const std::size_t index = ordering.loop_constraints.front();
    const bool gear = index >= constraints.joint_count;
    const std::size_t model_index = gear ? index - constraints.joint_count : index;
    throw ModelError(std::string(gear ? "gears[" : "joints[") + std::to_string(model_index) + "] '" +
                     (gear ? model.gears[model_index].name : model.joints[model_index].name) + "': closes a loop, which the tree solver cannot order; use the sparse (or automatic) solver");
  }
  state.uses_tree = ordering.loop_constraints.empty() && state.options.solver != MultiplierSolver::sparse;
  state.multipliers.resize(constraints.size());
  for (std::size_t c = 0; c < constraints.size(); ++c) state.multipliers[c].setZero(constraints.rows[c].rows());
  if (!state.uses_tree) return;
  std::vector<std::uint8_t> rows(constraints.size());
  for (std::size_t c = 0; c < constraints.size(); ++c) rows[c] = static_cast<std::uint8_t>(constraints.rows[c].rows());
  state.tree.assign(std::move(ordering), body_count, std::move(rows));
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
