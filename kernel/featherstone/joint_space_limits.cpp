#include "limber/kernel/featherstone/joint_space_limits.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "limber/kernel/featherstone/joint_space_contacts.hpp"
#include "limber/kernel/featherstone/joint_space_response.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/model/joint_coordinates.hpp"
#include "limber/kernel/rigid/rigid_integration.hpp"

namespace limber {
namespace joint_space {

// --- Joint limits (joint_space_contacts.hpp, "Joint limits") -------------------------------------

// Rows closer than this to their limit (rad or m), or closer than two steps of their approach, are
// solved; the others cannot reach it within the step (nor be pushed there by the contacts'
// push-out of an ordinary step).
constexpr double kLimitMargin = 0.02;

MeasuredJoint measure_joint(const FeatherstoneState& state, std::size_t k) {
  const Joint& joint = state.joint_controls.joints[k];
  const TreeJoint& held = state.tree_joint[k];
  MeasuredJoint out;
  if (joint.inboard != kWorld) out.inboard = model_frame_pose(state, static_cast<std::size_t>(joint.inboard));
  out.outboard = model_frame_pose(state, static_cast<std::size_t>(joint.outboard));
  out.coordinates = joint_coordinates(joint, state.joint_controls.frames[k], out.inboard, out.outboard);
  out.inboard_to_velocity =
      held.sign * (state.kinematics.world_to_body[static_cast<std::size_t>(held.body)].rotation * out.inboard.orientation.toRotationMatrix());
  return out;
}

double tree_coordinate(const FeatherstoneState& state, const TreeJoint& held) {
  return held.sign * state.q[state.tree.position_offset(held.body)];
}

// Whether joint k's island is awake.
bool awake(const FeatherstoneState& state, const TreeJoint& held) { return !state.islands[island_of(state, held)].sleeping; }

// The slots of a joint's limits (JointLimitRow::key).
constexpr std::int32_t kLimitsPerJoint = 5;

// What find_limit_rows does with the rows it finds.
struct LimitRowSearch {
  const Eigen::VectorXd* also = nullptr;  // a second velocity a row may act within the step at
  bool count_only = false;                // count them, keep state.controls.rows
  int count = 0;
};

// Adds `row` with C = gap ≥ 0 and ∂C/∂v = direction when it may act within the step (at v, or at
// search.also).
void add_limit_row(FeatherstoneState& state, JointLimitRow row, double gap, const Eigen::Vector3d& direction, double dt,
                   LimitRowSearch& search) {
  const auto reaches = [&](const Eigen::VectorXd& v) {
    const double rate = joint_dot(direction, v, row.offset, row.dofs);
    return gap < kLimitMargin + 2 * dt * std::max(-rate, 0.0);  // false for a NaN
  };
  if (!reaches(state.v) && !(search.also && reaches(*search.also))) return;
  ++search.count;
  if (search.count_only) return;
  row.gap = gap, row.direction = direction;
  state.controls.rows.push_back(row);
}

// A serial joint's axis ranges: each axis's coordinate is its tree body's q (0 at rest).
void find_serial_limit_rows(FeatherstoneState& state, double dt, LimitRowSearch& search) {
  // Their keys follow every joint's slots: a lower and an upper side an axis.
  const std::int32_t first_key = kLimitsPerJoint * static_cast<std::int32_t>(state.joint_controls.joints.size());
  for (const std::int32_t limited : state.limited_axes) {
    const TreeSerialAxis& node = state.serial_axes[static_cast<std::size_t>(limited)];
    const SerialAxis& axis = state.joint_controls.joints[static_cast<std::size_t>(node.joint)].serial_axes[static_cast<std::size_t>(node.axis)];
    const TreeJoint& held = state.tree_joint[static_cast<std::size_t>(node.joint)];
    if (!awake(state, held)) continue;
    JointLimitRow row;
    row.island = static_cast<std::int32_t>(island_of(state, held)), row.body = node.body, row.offset = node.offset, row.dofs = 1;
    const double x = state.q[state.tree.position_offset(node.body)];
    row.key = first_key + 2 * limited;
    add_limit_row(state, row, x - axis.range->min, Eigen::Vector3d::UnitX(), dt, search);
    row.key = first_key + 2 * limited + 1;
    add_limit_row(state, row, axis.range->max - x, -Eigen::Vector3d::UnitX(), dt, search);
  }
}

// The rows of every limit that is violated or may be within the step, at the current (q, v) (or
// at `also`): gaps and directions (their inverse masses come with their half rows, prepare_group).
// Returns how many; `count_only` leaves state.controls.rows as they are.
int find_limit_rows(FeatherstoneState& state, double dt, const Eigen::VectorXd* also, bool count_only) {
  LimitRowSearch search{also, count_only};
  if (!count_only) state.controls.rows.clear();
  const JointControls& controls = state.joint_controls;
  for (const std::int32_t limited : state.limited_joints) {
    const auto k = static_cast<std::size_t>(limited);
    const Joint& joint = controls.joints[k];
    const TreeJoint& held = state.tree_joint[k];
    if (!awake(state, held)) continue;
    JointLimitRow row;
    row.island = static_cast<std::int32_t>(island_of(state, held));
    row.body = held.body, row.offset = held.offset, row.dofs = held.dofs;
    // Each of the joint's limits has its slot: the range's or twist's lower and upper side, the swing.
    enum Slot : std::int32_t { lower, upper, swing, twist_lower, twist_upper };
    const auto add = [&](Slot slot, double gap, const Eigen::Vector3d& direction) {
      row.key = kLimitsPerJoint * static_cast<std::int32_t>(k) + slot;
      add_limit_row(state, row, gap, direction, dt, search);
    };
    if (joint.type == JointType::revolute || joint.type == JointType::prismatic) {
      if (!joint.limits.range) continue;
      const double x = tree_coordinate(state, held);
      add(lower, x - joint.limits.range->min, Eigen::Vector3d(held.sign, 0, 0));
      add(upper, joint.limits.range->max - x, Eigen::Vector3d(-held.sign, 0, 0));
      continue;
    }
    const JointFrame& frame = controls.frames[k];
    const MeasuredJoint measured = measure_joint(state, k);
    const JointCoordinates& q = measured.coordinates;
    // Spherical: rates of the swing and twist as rows on the relative angular velocity ω
    // (inboard frame), carried onto v.
    const Eigen::Vector3d axis = (rotation_quaternion(q.rotation) * frame.rest_axis).normalized();  // a = D·a₀
    const Eigen::Vector3d& cone = frame.cone_axis;                                           // c
    if (joint.limits.swing) {
      // θ = acos(c·a), θ̇ = ω·(c × a)/|c × a|: the axis that turns the cone's axis to the outboard's.
      const Eigen::Vector3d normal = cone.cross(axis);
      const double length = normal.norm();
      if (length > 1e-9) add(swing, *joint.limits.swing - q.swing, -(measured.inboard_to_velocity * (normal / length)));
    }
    if (joint.limits.twist && 1 + cone.dot(axis) > 1e-6) {
      // ψ = 2·atan2((D·Q).vec·c, (D·Q).w) has ψ̇ = ω·(c + a)/(1 + c·a): the outboard's axis a plus
      // the swing's own turn about it (= a where a = c).
      const Eigen::Vector3d gradient = measured.inboard_to_velocity * twist_gradient(axis, cone);
      add(twist_lower, q.twist - joint.limits.twist->min, gradient);
      add(twist_upper, joint.limits.twist->max - q.twist, -gradient);
    }
  }
  find_serial_limit_rows(state, dt, search);
  return search.count;
}

// --- Holding rows: an island's limit rows solved together -----------------------------------------
//
// Sequential impulses converge slowly on limit rows of neighbouring joints (a light spine between
// a torso and a pelvis both at their limits: each row's impulse undoes the other's), so an
// island's rows are solved together, exactly, in constraint space: their Delassus matrix
// A = Y D⁻¹ Yᵀ through the factor (formed once a step, form_limit_delassus) and an active-set
// solve of their complementarity problem (kernel/numerics/active_set.hpp): the rows held reach
// their targets, rows that would pull are released, rows left past their targets are held, at
// most kActiveSetIterations rounds.

// The Delassus matrix of each of the group's islands with limit rows (their blocks' half rows on
// their paths: A_ij = Σ_k Y_i,k Y_j,k / D_k over the coordinates the paths share).
void form_limit_delassus(FeatherstoneState& state, const ConstraintGroup& group) {
  JointSpaceContactScratch& s = state.contact;
  for (int t = group.first_limit; t < group.last_limit; ++t) {
    const LimitIsland& limit = s.limit_islands[static_cast<std::size_t>(t)];
    const auto m = static_cast<std::size_t>(limit.rows);
    s.island_scratch[static_cast<std::size_t>(limit.island)].active_set.forget();
    // s.response: D⁻¹ Y_j on its path, zero elsewhere on the island.
    const auto [first, last] = island_velocities(state, static_cast<std::size_t>(limit.island));
    s.response.segment(first, last - first).setZero();
    for (std::size_t j = 0; j < m; ++j) {
      const std::size_t g = static_cast<std::size_t>(limit.first_block) + j;
      for (int e = s.row_begin[g]; e < s.half_end[g]; ++e) {
        const int k = s.half_coordinate[static_cast<std::size_t>(e)];
        s.response[k] = s.half_value[static_cast<std::size_t>(e)][0] * s.factor.inverse_pivot(k);
      }
      for (std::size_t i = 0; i < m; ++i) {
        const std::size_t h = static_cast<std::size_t>(limit.first_block) + i;
        double entry = 0;
        for (int e = s.row_begin[h]; e < s.half_end[h]; ++e) {
          entry += s.half_value[static_cast<std::size_t>(e)][0] * s.response[s.half_coordinate[static_cast<std::size_t>(e)]];
        }
        s.limit_matrix[limit.matrix + j * m + i] = entry;
      }
      for (int e = s.row_begin[g]; e < s.half_end[g]; ++e) s.response[s.half_coordinate[static_cast<std::size_t>(e)]] = 0;
    }
  }
}

namespace {

// An island's limit rows into its solve's scratch (values J_l x + Y_lᵀ y, targets, impulses so
// far, held flags); returns how many, 0 when none needs a change.
int gather_island_rows(FeatherstoneState& state, const LimitIsland& limit, IslandSolveScratch& scratch, double dt, bool position,
                       const Eigen::VectorXd& x, double tolerance) {
  const JointSpaceContactScratch& s = state.contact;
  const bool before_move = constraints_before_move(state);
  const int m = limit.rows;
  scratch.reserve_limit_rows(m);  // past what compile reserved (an island of more than 256 rows) it allocates
  bool needed = false;
  for (int i = 0; i < m; ++i) {
    const auto g = static_cast<std::size_t>(limit.first_block + i);
    const JointLimitRow& row = state.controls.rows[static_cast<std::size_t>(s.block_source[g])];
    const double value = joint_dot(row.direction, x, row.offset, row.dofs) + lagging_motion(s, g)[0];
    const double accumulated = position ? row.push : row.impulse;
    // Position: a violation in full (it is never the Model's, always the solver's), and a row
    // inside its limit not pushed past it. Velocity: a limit not yet reached lets the joint arrive
    // at it by the step's end.
    // Before the move (constraints_before_move), the positions move by h·v as well: the push-out
    // keeps what is left of the gap after that motion, C + h·(row·v) (not pushed past it twice).
    const double gap = position && before_move ? row.gap + state.last_substep[static_cast<std::size_t>(row.island)] * joint_dot(row.direction, state.v, row.offset, row.dofs)
                                               : row.gap;
    const double target = position ? -gap : (gap > 0 ? -gap / dt : 0.0);
    const bool active = row.inverse_mass > 0 && (value < target - tolerance || accumulated > 0);
    needed = needed || (active && std::abs(target - value) > tolerance + (position ? 1e-5 * std::abs(target) : 0.0));
    scratch.limit_value[i] = value, scratch.limit_target[i] = target, scratch.limit_accumulated[i] = accumulated;
    scratch.limit_active[static_cast<std::size_t>(i)] = active;
  }
  return needed ? m : 0;
}

}  // namespace

bool solve_limit_rows(FeatherstoneState& state, const ConstraintGroup& group, double dt, bool position, const Eigen::VectorXd& x) {
  JointSpaceContactScratch& s = state.contact;
  // rad or m; rad/s or m/s. Before the move, the velocity solve's own tolerance moves a held row
  // by up to Δt·kSlowestApproach a step: the push-out leaves such drift until it is kRestingSlop's
  // thousandth, instead of pushing (and re-projecting) every step.
  const double tolerance = !position ? kSlowestApproach : constraints_before_move(state) ? 1e-3 * kRestingSlop : 1e-9;
  bool changed_any = false;
  for (int t = group.first_limit; t < group.last_limit; ++t) {
    const LimitIsland& limit = s.limit_islands[static_cast<std::size_t>(t)];
    IslandSolveScratch& scratch = s.island_scratch[static_cast<std::size_t>(limit.island)];
    const int m = gather_island_rows(state, limit, scratch, dt, position, x, tolerance);
    if (m == 0) continue;
    const Eigen::Map<const Eigen::MatrixXd> delassus(s.limit_matrix.data() + limit.matrix, m, m);
    scratch.active_set.solve(delassus, scratch.limit_value.head(m), scratch.limit_target.head(m), scratch.limit_accumulated.head(m),
                             scratch.limit_active, tolerance, scratch.limit_change.head(m), kActiveSetIterations);
    for (int i = 0; i < m; ++i) {
      if (scratch.limit_change[i] == 0) continue;
      const auto g = static_cast<std::size_t>(limit.first_block + i);
      JointLimitRow& row = state.controls.rows[static_cast<std::size_t>(s.block_source[g])];
      (position ? row.push : row.impulse) += scratch.limit_change[i];
      respond(s, g, Eigen::Vector3d(scratch.limit_change[i], 0, 0));
      changed_any = true;
    }
  }
  return changed_any;
}

}  // namespace joint_space

using namespace joint_space;

FramePose model_frame_pose(const FeatherstoneState& state, std::size_t body) {
  const auto i = static_cast<std::size_t>(state.tree_body[body]);
  const PluckerTransform& world_to_body = state.kinematics.world_to_body[i];
  const Eigen::Matrix3d rotation = world_to_body.rotation.transpose();  // body → world
  // The tree body's origin is the Model frame's point centre_offset − centre_of_mass[i] (its anchor).
  FramePose pose;
  pose.orientation = Eigen::Quaterniond(rotation);
  pose.position = world_to_body.translation - rotation * (state.shapes.centre_offset[body] - state.centre_of_mass[i]);
  return pose;
}

}  // namespace limber
