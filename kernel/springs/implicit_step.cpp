#include "limber/kernel/springs/implicit_step.hpp"

#include <algorithm>

#include "limber/kernel/rigid/anchor_jacobian.hpp"
#include "limber/kernel/springs/spring_forces.hpp"

namespace limber {
namespace {

using BodyBlock = Eigen::Matrix<double, 6, 6>;

// Offsets, in the column-major value array, of the first stored entry of each of a block's six
// columns: rows 6·row_body … (a diagonal block stores only its lower triangle, from the diagonal).
std::array<std::int64_t, 6> block_offsets(const Eigen::SparseMatrix<double>& matrix, std::int64_t row_body, std::int64_t column_body) {
  std::array<std::int64_t, 6> offsets{};
  for (int c = 0; c < 6; ++c) {
    const std::int64_t column = 6 * column_body + c;
    const std::int64_t first_row = row_body == column_body ? column : 6 * row_body;
    const int* rows = matrix.innerIndexPtr();
    const std::int64_t begin = matrix.outerIndexPtr()[column], end = matrix.outerIndexPtr()[column + 1];
    offsets[c] = std::lower_bound(rows + begin, rows + end, static_cast<int>(first_row)) - rows;
  }
  return offsets;
}

// Adds `block` (or its lower triangle, on the diagonal) at the precomputed offsets.
void add_block(Eigen::SparseMatrix<double>& matrix, const std::array<std::int64_t, 6>& offsets, const BodyBlock& block, bool diagonal) {
  double* values = matrix.valuePtr();
  for (int c = 0; c < 6; ++c) {
    for (int r = diagonal ? c : 0; r < 6; ++r) values[offsets[c] + (r - (diagonal ? c : 0))] += block(r, c);
  }
}

}  // namespace

void prepare_implicit_system(SpringState& state) {
  state.implicit = std::make_unique<ImplicitSystem>();
  ImplicitSystem& system = *state.implicit;
  const std::size_t n = state.bodies.size();
  std::vector<Eigen::Triplet<double>> entries;
  auto add_pattern = [&](std::int64_t row_body, std::int64_t column_body) {
    for (int c = 0; c < 6; ++c) {
      for (int r = row_body == column_body ? c : 0; r < 6; ++r) entries.emplace_back(6 * row_body + r, 6 * column_body + c, 0.0);
    }
  };
  for (std::size_t b = 0; b < n; ++b) add_pattern(static_cast<std::int64_t>(b), static_cast<std::int64_t>(b));
  const SpringBuffer& springs = state.springs;
  for (std::size_t s = 0; s < springs.size(); ++s) {
    if (springs.inboard[s] >= 0) add_pattern(std::max(springs.inboard[s], springs.outboard[s]), std::min(springs.inboard[s], springs.outboard[s]));
  }
  system.matrix.resize(static_cast<Eigen::Index>(6 * n), static_cast<Eigen::Index>(6 * n));
  system.matrix.setFromTriplets(entries.begin(), entries.end());
  system.matrix.makeCompressed();
  system.diagonal_block.resize(n);
  for (std::size_t b = 0; b < n; ++b) system.diagonal_block[b] = block_offsets(system.matrix, b, b);
  system.spring_block.assign(springs.size(), {-1, -1, -1, -1, -1, -1});
  for (std::size_t s = 0; s < springs.size(); ++s) {
    if (springs.inboard[s] < 0) continue;
    system.spring_block[s] = block_offsets(system.matrix, std::max(springs.inboard[s], springs.outboard[s]),
                                           std::min(springs.inboard[s], springs.outboard[s]));
  }
  system.right_hand_side = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(6 * n));
  system.solution = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(6 * n));
  system.correction = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(6 * n));
  if (state.options.linear_solver == SpringLinearSolver::ldlt) system.ldlt.analyzePattern(system.matrix);
  system.conjugate_gradient.setTolerance(state.options.solver_tolerance);
}

void implicit_step(SpringState& state, double h, StepReport& report) {
  ImplicitSystem& system = *state.implicit;
  RigidBodyBuffer& bodies = state.bodies;
  RigidBodyState& y = bodies.state;
  const std::size_t n = bodies.size();

  // f₀ at the current state (also fills state.velocity / angular_velocity).
  RigidForces& forces = state.scratch.forces;
  forces.clear();
  accumulate_forces(state, y, forces);

  // M and the explicit part of b, per awake body; the gyroscopic torque −ω × I ω.
  std::fill(system.matrix.valuePtr(), system.matrix.valuePtr() + system.matrix.nonZeros(), 0.0);
  system.right_hand_side.setZero();
  std::vector<Eigen::Matrix3d>& world_inertia = state.scratch_world_inertia;
  for (std::size_t b = 0; b < n; ++b) {
    world_inertia[b] = bodies.world_inertia(y, b);
    BodyBlock mass = BodyBlock::Zero();
    mass.topLeftCorner<3, 3>().diagonal().setConstant(bodies.mass[b]);
    mass.bottomRightCorner<3, 3>() = world_inertia[b];
    add_block(system.matrix, system.diagonal_block[b], mass, true);
    if (state.islands[state.island_of_body[b]].sleeping) continue;
    const Eigen::Vector3d& omega = state.angular_velocity[b];
    system.right_hand_side.segment<3>(6 * b) = h * forces.force[b];
    system.right_hand_side.segment<3>(6 * b + 3) = h * (forces.torque[b] - omega.cross(world_inertia[b] * omega));
  }

  // Each spring's implicit terms: (h·c + h²·k) JᵀJ into A, −h²·k Jᵀḋ₀ into b (a hinge's two
  // springs each with their own levers, into the same blocks).
  const SpringBuffer& springs = state.springs;
  for (std::size_t s = 0; s < springs.size(); ++s) {
    const std::int32_t i = springs.inboard[s], j = springs.outboard[s];
    if (state.islands[state.island_of_body[j]].sleeping) continue;
    for (int e = 0; e < springs.count[s]; ++e) {
      const SpringEnds ends = spring_ends(state, y, s, spring_side(springs, s, e));
      const double k = springs.stiffness[s], c = springs.damping[s];
      const double weight = h * c + h * h * k;
      const Eigen::Vector3d implicit_force = -h * h * k * ends.separation_rate;  // acts like f: + on i, − on j
      const AnchorJacobian g_j = anchor_jacobian(ends.outboard_lever);
      add_block(system.matrix, system.diagonal_block[j], weight * g_j.transpose() * g_j, true);
      system.right_hand_side.segment<6>(6 * j) -= g_j.transpose() * implicit_force;
      if (i < 0) continue;
      const AnchorJacobian g_i = anchor_jacobian(ends.inboard_lever);
      add_block(system.matrix, system.diagonal_block[i], weight * g_i.transpose() * g_i, true);
      system.right_hand_side.segment<6>(6 * i) += g_i.transpose() * implicit_force;
      const BodyBlock coupling = i > j ? BodyBlock(-weight * g_i.transpose() * g_j) : BodyBlock(-weight * g_j.transpose() * g_i);
      add_block(system.matrix, system.spring_block[s], coupling, false);
    }
  }

  // The drives' and engaged limits' angular springs, implicit the same way on the relative
  // rotation (J = [0, E] on the outboard body, [0, −E] on the inboard; a limit's, and a hinge's
  // drive, along d dᵀ); friction stays explicit (regularized: spring_forces.hpp).
  for (const std::uint32_t s : state.controlled_joints) {
    const std::int32_t i = springs.inboard[s], j = springs.outboard[s];
    if (state.islands[state.island_of_body[j]].sleeping) continue;
    const JointControlTorques torques = joint_control_torques(state, y, s);
    const Eigen::Vector3d relative = state.angular_velocity[j] - (i >= 0 ? state.angular_velocity[i] : Eigen::Vector3d::Zero());
    Eigen::Matrix3d weight = (h * torques.drive_damping + h * h * torques.drive_stiffness) * Eigen::Matrix3d::Identity();
    Eigen::Vector3d implicit_torque = -h * h * torques.drive_stiffness * relative;  // on the outboard body
    if (!torques.drive_axis.isZero(0)) {  // a hinge's drive, about its axis alone
      const Eigen::Vector3d& d = torques.drive_axis;
      weight = (h * torques.drive_damping + h * h * torques.drive_stiffness) * d * d.transpose();
      implicit_torque = -h * h * torques.drive_stiffness * d.dot(relative) * d;
    }
    for (int l = 0; l < torques.limit_count; ++l) {
      const Eigen::Vector3d& d = torques.limit_direction[l];
      weight += (h * torques.limit_damping[l] + h * h * torques.limit_stiffness[l]) * d * d.transpose();
      implicit_torque -= h * h * torques.limit_stiffness[l] * d.dot(relative) * d;
    }
    BodyBlock block = BodyBlock::Zero();
    block.bottomRightCorner<3, 3>() = weight;
    add_block(system.matrix, system.diagonal_block[j], block, true);
    system.right_hand_side.segment<3>(6 * j + 3) += implicit_torque;
    if (i < 0) continue;
    add_block(system.matrix, system.diagonal_block[i], block, true);
    system.right_hand_side.segment<3>(6 * i + 3) -= implicit_torque;
    add_block(system.matrix, system.spring_block[s], BodyBlock(-block), false);
  }

  auto solve = [&](const Eigen::VectorXd& right_hand_side, Eigen::VectorXd& out, bool factorize) {
    // A right-hand side below ~1e-100 N·s (a spring settled to rounding) needs no solve, and
    // conjugate gradients would divide by its underflowed |b|².
    if (right_hand_side.squaredNorm() < 1e-200) {
      out.setZero();
    } else if (state.options.linear_solver == SpringLinearSolver::ldlt) {
      if (factorize) system.ldlt.factorize(system.matrix);
      out = system.ldlt.solve(right_hand_side);
    } else {
      if (factorize) system.conjugate_gradient.compute(system.matrix);
      out = system.conjugate_gradient.solveWithGuess(right_hand_side, out);
      report.linear_solver_iterations += static_cast<int>(system.conjugate_gradient.iterations());
      report.linear_solver_error = std::max(report.linear_solver_error, system.conjugate_gradient.error());
    }
  };
  solve(system.right_hand_side, system.solution, true);

  // The state the velocity change Δu leads to: v = v₀ + Δv, x = x₀ + h·v, L = L₀ + h·τ (with
  // I₀Δω = h·(τ − ω₀ × I₀ω₀)), q turned by the free rotation with L.
  RigidBodyState& start = state.scratch.stage;
  std::vector<Eigen::Vector3d>& start_velocity = state.scratch.velocity[0];
  std::vector<Eigen::Vector3d>& start_angular_velocity = state.scratch.velocity[1];
  for (std::size_t b = 0; b < n; ++b) {
    start.position[b] = y.position[b], start.orientation[b] = y.orientation[b];
    start.linear_momentum[b] = y.linear_momentum[b], start.angular_momentum[b] = y.angular_momentum[b];
    start_velocity[b] = state.velocity[b], start_angular_velocity[b] = state.angular_velocity[b];
  }
  auto advance = [&](const Eigen::VectorXd& change) {
    for (std::size_t b = 0; b < n; ++b) {
      if (state.islands[state.island_of_body[b]].sleeping) continue;
      const Eigen::Vector3d velocity = start_velocity[b] + change.segment<3>(6 * b);
      const Eigen::Vector3d& omega = start_angular_velocity[b];
      y.linear_momentum[b] = bodies.mass[b] * velocity;
      y.angular_momentum[b] = start.angular_momentum[b] + world_inertia[b] * change.segment<3>(6 * b + 3) +
                              h * omega.cross(world_inertia[b] * omega);
      y.position[b] = start.position[b] + h * velocity;
      y.orientation[b] = start.orientation[b];
      rotate_free_body(y.orientation[b], y.angular_momentum[b], bodies.body_inertia[b].diagonal(), h);
    }
  };
  advance(system.solution);

  // Further Newton iterations on the nonlinear backward-Euler equations
  //   M₀Δu − h·(f(y(Δu)) − ω₀ × I₀ω₀) = 0,
  // with the same matrix (a modified Newton method): each costs one force evaluation and one
  // back-substitution, and removes what the linearization of the anchors' rotation leaves.
  for (int iteration = 1; iteration < state.options.newton_iterations; ++iteration) {
    forces.clear();
    accumulate_forces(state, y, forces);
    Eigen::VectorXd& residual = system.right_hand_side;
    for (std::size_t b = 0; b < n; ++b) {
      residual.segment<6>(6 * b).setZero();
      if (state.islands[state.island_of_body[b]].sleeping) continue;
      const Eigen::Vector3d& omega = start_angular_velocity[b];
      residual.segment<3>(6 * b) = h * forces.force[b] - bodies.mass[b] * system.solution.segment<3>(6 * b);
      residual.segment<3>(6 * b + 3) = h * (forces.torque[b] - omega.cross(world_inertia[b] * omega)) -
                                       world_inertia[b] * system.solution.segment<3>(6 * b + 3);
    }
    solve(residual, system.correction, false);
    system.solution += system.correction;
    advance(system.solution);
  }
}

}  // namespace limber
