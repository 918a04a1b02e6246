#include "limber/kernel/lagrange/multipliers.hpp"

#include <cmath>
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

// Loads M, the constraints' −A and J into the tree and factors it (the work vectors are not read).
void factor_tree(LagrangeState& state) {
  TreeElimination<double, 6>& tree = state.tree;
  const std::size_t body_count = state.bodies.size();
  const ConstraintSet& constraints = state.constraints;
  for (std::size_t b = 0; b < body_count; ++b) {
    Matrix6& block = tree.diagonal(b);
    block.setZero();
    block.topLeftCorner<3, 3>().diagonal().setConstant(state.bodies.mass[b]);
    block.bottomRightCorner<3, 3>() = state.world_inertia[b];
  }
  for (std::size_t c = 0; c < constraints.size(); ++c) tree.diagonal(body_count + c).setZero();  // rigid: no compliance
  for (const ControlledJoint& controlled : state.controls.joints) {  // −A on the control rows
    for (int r = controlled.row_offset; r < controlled.row_offset + controlled.count; ++r) {
      tree.diagonal(body_count + controlled.joint)(r, r) = -state.compliance[controlled.joint](r);
    }
  }
  const auto edge = [&](std::size_t c, std::int32_t body) -> const ConstraintBlock& {
    return constraints.inboard[c] == body ? state.geometry.inboard_jacobian[c] : state.geometry.outboard_jacobian[c];
  };
  tree.factor(0, static_cast<std::uint32_t>(tree.ordering().order.size()), edge);
}

// Solves the factored tree for one right-hand side.
void substitute_tree(LagrangeState& state, const std::vector<Vector6>& body_rhs, const std::vector<ConstraintVector>& constraint_rhs,
                     std::vector<Vector6>& accelerations) {
  TreeElimination<double, 6>& tree = state.tree;
  const std::size_t body_count = state.bodies.size();
  const ConstraintSet& constraints = state.constraints;
  for (std::size_t b = 0; b < body_count; ++b) tree.work(b) = body_rhs[b];
  for (std::size_t c = 0; c < constraints.size(); ++c) {
    tree.work(body_count + c).setZero();
    tree.work(body_count + c).head(constraint_rhs[c].size()) = constraint_rhs[c];
  }
  tree.solve(0, static_cast<std::uint32_t>(tree.ordering().order.size()));
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
  for (const ControlledJoint& controlled : state.controls.joints) {
    for (int r = controlled.row_offset; r < controlled.row_offset + controlled.count; ++r) {
      const std::int32_t row = constraints.row_offset[controlled.joint] + r;
      entries.emplace_back(row, row, state.compliance[controlled.joint](r));
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

namespace {

// Every control row off: zero Jacobian row, compliance 1.
void switch_off_controls(LagrangeState& state) {
  for (const ControlledJoint& controlled : state.controls.joints) {
    for (int r = controlled.row_offset; r < controlled.row_offset + controlled.count; ++r) {
      state.geometry.inboard_jacobian[controlled.joint].row(r).setZero();
      state.geometry.outboard_jacobian[controlled.joint].row(r).setZero();
      state.compliance[controlled.joint](r) = 1;
    }
  }
}

}  // namespace

void update_geometry(LagrangeState& state, const RigidBodyState& y) {
  update_constraint_geometry(state.constraints, state.joints, y, state.geometry);
  for (std::size_t b = 0; b < state.bodies.size(); ++b) state.world_inertia[b] = state.bodies.world_inertia(y, b);
  if (state.controls.empty()) return;
  measure_joint_controls(state, state.joints, state.joint_controls, y, state.velocity, state.angular_velocity, state.controls);
  switch_off_controls(state);
}


// --- Joint controls: the problem at each level and the active-set loop ---

namespace {

// The mode a row falls back to when its limit is not engaged: friction's (stick, or sliding with
// or without the drive), the drive's, or none.
ControlMode free_mode(const ControlledJoint& joint, const ControlRow& row) {
  if (joint.friction_bound > 0) {
    if (!joint.sliding) return ControlMode::stick;
    return row.compliance > 0 ? ControlMode::soft : ControlMode::slide;
  }
  return row.compliance > 0 ? ControlMode::soft : ControlMode::off;
}

// The drive's part of a row's multiplier at rate w (0 without a drive at this level).
double drive_part(const ControlRow& row, double rate) {
  return row.compliance > 0 ? (row.drive_rhs - rate) / row.compliance : 0;
}

// Writes the control rows of the current modes into the Jacobian blocks, compliances and
// right-hand sides, and sliding friction's known multipliers into `body_rhs` (as Jᵀ·slip).
void write_control_rows(LagrangeState& state, std::vector<Vector6>& body_rhs) {
  for (const ControlledJoint& controlled : state.controls.joints) {
    const std::size_t c = controlled.joint;
    const std::int32_t i = state.constraints.inboard[c], o = state.constraints.outboard[c];
    for (int k = 0; k < controlled.count; ++k) {
      ControlRow& row = state.controls.rows[controlled.first_row + k];
      const int r = controlled.row_offset + k;
      auto inboard = state.geometry.inboard_jacobian[c].row(r);
      auto outboard = state.geometry.outboard_jacobian[c].row(r);
      double& compliance = state.compliance[c](r);
      double& rhs = state.constraint_rhs[c](r);
      const bool present = row.mode != ControlMode::off && row.mode != ControlMode::slide;
      if (present) inboard = row.inboard_jacobian, outboard = row.outboard_jacobian;
      else inboard.setZero(), outboard.setZero();
      switch (row.mode) {
        case ControlMode::off: compliance = 1, rhs = 0; break;
        case ControlMode::limit: compliance = 0, rhs = row.limit * row.bound; break;
        case ControlMode::stick: compliance = 0, rhs = row.stick_rate; break;
        case ControlMode::soft: compliance = row.compliance, rhs = row.drive_rhs + row.compliance * row.slip; break;
        case ControlMode::slide:
          compliance = 1, rhs = 0;
          body_rhs[o] += row.slip * row.outboard_jacobian.transpose();
          if (i >= 0) body_rhs[i] += row.slip * row.inboard_jacobian.transpose();
          break;
      }
    }
  }
}

// MuJoCo's armature a on a revolute or prismatic row (rate w exactly the coordinate's): the joint
// force −a·ẇ, which is M + a·JᵀJ in place of M, or M with one more row of compliance 1/a
// (Sherman–Morrison). Its row is J·x + λ/a = rhs: at the velocity level (x = u after the step)
// λ = a·(w₀ − J·x), rhs = w₀ the rate before it; on a change of velocities (x = Δu) λ = −a·J·x,
// rhs = 0; at the acceleration level (x = u̇) λ = −a·(J·x + J̇u), rhs = −J̇u. A drive on the same
// row is a compliance too: the two add as conductances (1/A).
void add_armature(ControlRow& row, double armature, double rhs) {
  const double drive = row.compliance > 0 ? 1 / row.compliance : 0;
  row.drive_rhs = (drive * row.drive_rhs + armature * rhs) / (drive + armature);
  row.compliance = 1 / (drive + armature);
}

}  // namespace

void set_control_problem(LagrangeState& state, ControlLevel level, double dt, double frequency) {
  constexpr double kAtLimit = 1e-9;  // rad or m: a limit this close counts as reached
  // The velocity-level step's rows, on the velocities or on a change of them.
  const bool step_rows = level == ControlLevel::velocity || level == ControlLevel::velocity_change;
  const bool change = level == ControlLevel::velocity_change || level == ControlLevel::velocity_stop;
  const bool stage = level == ControlLevel::stage_change || level == ControlLevel::acceleration;
  for (ControlledJoint& controlled : state.controls.joints) {
    const Joint& joint = state.joint_controls.joints[controlled.joint];
    const bool friction = joint.friction > 0 && (step_rows || (stage && controlled.stuck));
    controlled.friction_bound = !friction ? 0 : level == ControlLevel::acceleration ? joint.friction : joint.friction * dt;
    controlled.sliding = false;
    const JointDrive* drive = joint.drive && step_rows ? &*joint.drive : nullptr;
    // A servo on the joint's one row (revolute, prismatic) adds to its drive: stiffness K, damping
    // C and the force F − K·q at the coordinate q (JointServos).
    const JointServos& servos = state.servos;
    const bool servo = servos.any && step_rows && (servos.stiffness[controlled.joint] != 0 || servos.damping[controlled.joint] != 0);
    const double servo_gain = servo ? servos.stiffness[controlled.joint] * dt + servos.damping[controlled.joint] : 0;  // K·h + C
    const double drive_gain = (drive ? drive->stiffness * dt + drive->damping : 0) + servo_gain;  // k·h + c
    for (int k = 0; k < controlled.count; ++k) {
      ControlRow& row = state.controls.rows[controlled.first_row + k];
      const double offset = change ? row.rate : 0;  // the rate before a velocity change
      row.limit = 0, row.bound = 0, row.compliance = 0, row.drive_rhs = 0, row.slip = 0;
      row.stick_rate = level == ControlLevel::acceleration ? -row.velocity_product : -offset;  // stop, or keep the rate
      if (drive_gain > 0) {
        // τ = k·(e₀ − h·w) + c·(w* − w), implicit in the rate w after the step; its impulse
        // h·τ = (drive_rhs − w)/A.
        double force = drive ? drive->stiffness * row.drive_error + drive->damping * row.target_rate : 0;
        if (servo) force += servos.force[controlled.joint] - servos.stiffness[controlled.joint] * row.coordinate;
        row.compliance = 1 / (dt * drive_gain);
        row.drive_rhs = force / drive_gain - offset;
      }
      if (joint.armature > 0 && level != ControlLevel::position) {
        // The unknown: u after the step (velocity), a change of u (the other impulse levels), u̇.
        const double armature_rhs = level == ControlLevel::acceleration ? -row.velocity_product : level == ControlLevel::velocity ? row.rate : 0.0;
        add_armature(row, joint.armature, armature_rhs);
      }
      if (row.side == 0) continue;
      // At or past the limit; the stages also keep a row the impulse pass engaged (it reaches
      // the limit within the step) until it releases.
      const bool reached = row.gap <= kAtLimit || (stage && row.previous == ControlMode::limit);
      switch (level) {
        case ControlLevel::velocity:
        case ControlLevel::velocity_change:  // speculative: reach the limit, do not cross it, within the step
          row.limit = row.side;
          row.bound = (row.gap >= 0 ? -row.gap / dt : -frequency * row.gap) - row.side * offset;
          break;
        case ControlLevel::stage_change:
          if (reached) row.limit = row.side, row.bound = 0;
          break;
        case ControlLevel::acceleration:
          if (!reached) break;
          row.limit = row.side;
          row.bound = -2 * frequency * row.side * row.rate - frequency * frequency * row.gap - row.side * row.velocity_product;
          break;
        case ControlLevel::velocity_stop:
          if (row.gap <= kAtLimit) row.limit = row.side, row.bound = -row.side * offset;
          break;
        case ControlLevel::position:  // every row: the correction of one joint must not push another past
          row.limit = row.side, row.bound = -row.gap;
          break;
      }
    }
  }
}

void solve_with_controls(LagrangeState& state, const RigidBodyState& y, const std::vector<Vector6>& body_rhs,
                         std::vector<Vector6>& x) {
  JointControlSet& controls = state.controls;
  for (ControlledJoint& controlled : controls.joints) {
    for (int k = 0; k < controlled.count; ++k) {
      ControlRow& row = controls.rows[controlled.first_row + k];
      const bool engaged = row.limit != 0 && (row.previous == ControlMode::limit || row.gap < 0);
      row.mode = engaged ? ControlMode::limit : free_mode(controlled, row);
    }
  }
  for (int iteration = 0; iteration < kMaxControlIterations; ++iteration) {
    std::vector<Vector6>& rhs = state.control_body_rhs;
    for (std::size_t b = 0; b < rhs.size(); ++b) rhs[b] = body_rhs[b];
    write_control_rows(state, rhs);
    solve_constrained(state, y, rhs, state.constraint_rhs, x);
    bool changed = false;
    for (ControlledJoint& controlled : controls.joints) {
      const std::size_t c = controlled.joint;
      const std::int32_t i = state.constraints.inboard[c], o = state.constraints.outboard[c];
      double holding_squared = 0;  // |λ − λ_drive|² over the sticking rows: what friction must hold
      for (int k = 0; k < controlled.count; ++k) {
        ControlRow& row = controls.rows[controlled.first_row + k];
        row.solved_rate = row.outboard_jacobian.dot(x[o]) + (i >= 0 ? row.inboard_jacobian.dot(x[i]) : 0.0);
        row.multiplier = row.mode == ControlMode::slide ? row.slip
                         : row.mode == ControlMode::off  ? 0.0
                                                         : state.multipliers[c](controlled.row_offset + k);
        const double held = row.multiplier - drive_part(row, row.solved_rate);
        if (row.mode == ControlMode::stick) holding_squared += held * held;
        if (row.limit == 0) continue;
        if (row.mode == ControlMode::limit) {
          // The limit's own part pulls (beyond what friction could hold): release it.
          const double tolerance = 1e-10 * (std::abs(row.multiplier) + controlled.friction_bound) + 1e-300;
          if (row.limit * held + controlled.friction_bound < -tolerance) row.mode = free_mode(controlled, row), changed = true;
        } else if (row.limit * row.solved_rate < row.bound - 1e-10 * (1 + std::abs(row.bound))) {
          row.mode = ControlMode::limit, changed = true;
        }
      }
      const double bound = controlled.friction_bound;
      if (bound > 0 && !controlled.sliding && holding_squared > bound * bound * (1 + 1e-9)) {
        // Friction cannot hold: it slides at its bound, along the multipliers it would need.
        const double scale = bound / std::sqrt(holding_squared);
        controlled.sliding = true;
        for (int k = 0; k < controlled.count; ++k) {
          ControlRow& row = controls.rows[controlled.first_row + k];
          if (row.mode != ControlMode::stick) continue;
          row.slip = scale * (row.multiplier - drive_part(row, row.solved_rate));
          row.mode = free_mode(controlled, row);
        }
        changed = true;
      }
    }
    if (!changed) break;
  }
  for (const ControlledJoint& controlled : controls.joints) {
    for (int k = 0; k < controlled.count; ++k) {
      ControlRow& row = controls.rows[controlled.first_row + k];
      row.previous = row.mode;
      state.multipliers[controlled.joint](controlled.row_offset + k) = row.multiplier;
    }
  }
}

void solve_constrained(LagrangeState& state, const RigidBodyState& y, const std::vector<Vector6>& body_rhs,
                       const std::vector<ConstraintVector>& constraint_rhs, std::vector<Vector6>& accelerations) {
  factor_constrained(state);
  solve_factored(state, y, body_rhs, constraint_rhs, accelerations);
}

void factor_constrained(LagrangeState& state) {
  if (state.uses_tree) factor_tree(state);
}

void solve_factored(LagrangeState& state, const RigidBodyState& y, const std::vector<Vector6>& body_rhs,
                    const std::vector<ConstraintVector>& constraint_rhs, std::vector<Vector6>& accelerations) {
  if (state.uses_tree) substitute_tree(state, body_rhs, constraint_rhs, accelerations);
  else solve_sparse(state, y, body_rhs, constraint_rhs, accelerations);
  for (std::size_t b = 0; b < state.bodies.size(); ++b) {
    if (asleep(state, static_cast<std::int32_t>(b))) accelerations[b].setZero();
  }
}

double baumgarte_frequency(const LagrangeState& state, double dt) {
  if (state.options.stabilization != Stabilization::baumgarte) return 0;
  if (state.options.baumgarte_frequency > 0) return state.options.baumgarte_frequency;
  // A step shorter than the Model's keeps the Model's rate: 1/(4Δt) would turn the error a longer
  // step left into a velocity C/(4Δt) (a 10⁻⁸ s step after steps of 1/240 s: 10⁸ J on a chain).
  return 0.25 / std::max(dt, state.settings.time_step);
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
  const bool controlled = !state.controls.empty();
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
  if (controlled) {
    set_control_problem(state, ControlLevel::acceleration, state.time_step, frequency);
    solve_with_controls(state, y, body_rhs, state.accelerations);
  } else {
    solve_constrained(state, y, body_rhs, state.constraint_rhs, state.accelerations);
  }
  add_constraint_forces(state, forces, 1.0);
  if (!controlled) return;
  for (const ControlledJoint& joint : state.controls.joints) {  // sliding friction: a known force, not a row
    const std::int32_t i = constraints.inboard[joint.joint], o = constraints.outboard[joint.joint];
    for (int k = 0; k < joint.count; ++k) {
      const ControlRow& row = state.controls.rows[joint.first_row + k];
      if (row.mode != ControlMode::slide || asleep(state, o)) continue;
      forces.force[o] += row.slip * row.outboard_jacobian.head<3>().transpose();
      forces.torque[o] += row.slip * row.outboard_jacobian.tail<3>().transpose();
      if (i < 0) continue;
      forces.force[i] += row.slip * row.inboard_jacobian.head<3>().transpose();
      forces.torque[i] += row.slip * row.inboard_jacobian.tail<3>().transpose();
    }
  }
}

}  // namespace limber
