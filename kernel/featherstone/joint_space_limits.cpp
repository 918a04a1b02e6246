#include "limber/kernel/featherstone/joint_space_limits.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "limber/kernel/featherstone/joint_space_contacts.hpp"
#include "limber/kernel/featherstone/joint_space_response.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/model/joint_coordinates.hpp"

namespace limber {
namespace joint_space {

// --- Joint limits (joint_space_contacts.hpp, "Joint limits") -------------------------------------

// Rows closer than this to their limit (rad or m), or closer than two steps of their approach, are
// solved; the others cannot reach it within the step (nor be pushed there by the contacts'
// push-out of an ordinary step).
constexpr double kLimitMargin = 0.02;

// The rotation by rotation vector `rotation` (axis × angle, rad).
Eigen::Quaterniond rotation_of(const Eigen::Vector3d& rotation) {
  const double angle = rotation.norm();
  return angle > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(angle, rotation / angle)) : Eigen::Quaterniond::Identity();
}

// Joint k measured at the tree's current poses (state.kinematics): its bodies' Model frames, its
// coordinates, and the map from an inboard-frame angular vector to joint k's velocity coordinates,
// sign·E_child·R_inboard (orthogonal: it maps rates' rows and torques alike).
struct MeasuredJoint {
  FramePose inboard, outboard;
  JointCoordinates coordinates;
  Eigen::Matrix3d inboard_to_velocity = Eigen::Matrix3d::Identity();
};
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

// A revolute or prismatic joint's coordinate (the Model's angle or slide, rad or m): sign·q of its
// tree body, 0 at the Model's initial pose as the joint frames are. It is what measure_joint reads
// from the poses (to round-off, 10⁻¹⁵ on humanoid.xml), without the poses' quaternions and
// arc tangent; unlike that angle, a hinge's is not wrapped to (−π, π].
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
    const Eigen::Vector3d axis = (rotation_of(q.rotation) * frame.rest_axis).normalized();  // a = D·a₀
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

// The block of H⁻¹ for the `dofs` (≤ 3) velocities of one joint from `offset` (island
// `island`), through state.contact.factor; top-left of a zero 3×3.
Eigen::Matrix3d inverse_block(FeatherstoneState& state, std::size_t island, int offset, int dofs) {
  JointSpaceContactScratch& s = state.contact;
  const auto [first, last] = island_velocities(state, island);
  Eigen::Matrix3d block = Eigen::Matrix3d::Zero();
  for (int m = 0; m < dofs; ++m) {
    s.response.segment(first, last - first).setZero();
    s.response[offset + m] = 1;
    s.factor.solve(s.response, first, last);
    for (int r = 0; r < dofs; ++r) block(r, m) = s.response[offset + r];
  }
  return 0.5 * (block + block.transpose());  // symmetric in exact arithmetic
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
constexpr int kActiveSetIterations = 8;

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

// Joint friction's held joints: the penalty on their block of H + h·G, in units of its inverse.
constexpr double kPenalty = 1e6;

// Clears the penalties of island `island`'s bodies.
void clear_penalties(FeatherstoneState& state, std::size_t island) {
  for (int i = state.island_begin[island]; i < state.island_begin[island + 1]; ++i) state.controls.penalty[static_cast<std::size_t>(i)].setZero();
}

// The held joints' factor of island `island`: H + h·G (state.contact.inertia) with each held
// joint's penalty on its coordinates (state.controls.penalty), into state.contact.held.
void factor_held_rows(FeatherstoneState& state, std::size_t island) {
  JointSpaceContactScratch& s = state.contact;
  const auto [first, last] = island_velocities(state, island);
  s.held.copy_inertia(s.inertia, first, last);
  for (int i = state.island_begin[island]; i < state.island_begin[island + 1]; ++i) {
    const Eigen::Matrix3d& penalty = state.controls.penalty[static_cast<std::size_t>(i)];
    const int k = joint_velocity_count(state.tree.body(i).joint), dofs = k <= 3 ? k : 0, offset = state.tree.velocity_offset(i);
    for (int a = 0; a < dofs; ++a) {
      for (int b = 0; b <= a; ++b) {
        if (penalty(a, b) != 0) s.held.add_inertia(offset + a, offset + b, penalty(a, b));
      }
    }
  }
  s.held.factor(first, last);  // the penalties only add to a factor joint_control_forces found positive
}

// The response of island `island`'s held factor to state.contact.joint_impulse (its slice,
// consumed: zeroed) into state.contact.joint_change (its slice).
void solve_held(FeatherstoneState& state, std::size_t island) {
  JointSpaceContactScratch& s = state.contact;
  const auto [first, last] = island_velocities(state, island);
  s.joint_change.segment(first, last - first) = s.joint_impulse.segment(first, last - first);
  s.joint_impulse.segment(first, last - first).setZero();
  s.held.solve(s.joint_change, first, last);
}

void respond_held(FeatherstoneState& state, std::size_t island) {
  factor_held_rows(state, island);
  solve_held(state, island);
}


// Joint friction of island k (its blocks in state.controls.friction), together: a stuck joint is
// held at rest by a penalty on its block of H + h·G (kPenalty times its block of (H + h·G)⁻¹
// inverted; the island's coordinates factored again as LᵀDL, factor_held_rows), which is exactly
// the response to the joint impulses that hold it and leaves it within 1/kPenalty of rest, refined
// once; a sliding one takes the impulse
// friction·h against the velocity it ends with; a stuck joint whose impulse would pass its bound
// slides, a sliding one that friction would turn back sticks. Adds the responses to the
// predicted velocities; the impulses stay in the blocks. Needs state.contact.inertia and factor
// holding H + h·G at the step's start (the drives' armature, state.controls.armature).
void solve_friction(FeatherstoneState& state, std::size_t k) {
  JointControlScratch& c = state.controls;
  JointSpaceContactScratch& s = state.contact;
  bool moving = false;
  for (JointFrictionBlock& block : c.friction) {
    block.stuck = true, block.impulse.setZero();
    moving = moving || block.rate.norm() > 0;
  }
  if (!moving) return;  // nothing to hold
  for (int iteration = 0;; ++iteration) {
    clear_penalties(state, k);
    for (JointFrictionBlock& block : c.friction) {
      block.held = block.stuck;
      if (block.held) {
        c.penalty[static_cast<std::size_t>(block.body)] += kPenalty * block.mass;
        add_joint_vector(-kPenalty * (block.mass * block.rate), s.joint_impulse, block.offset, block.dofs);
      } else {
        add_joint_vector(block.impulse, s.joint_impulse, block.offset, block.dofs);
      }
    }
    respond_held(state, k);
    bool changed = false;
    for (JointFrictionBlock& block : c.friction) {
      Eigen::Vector3d after = block.rate;
      for (int m = 0; m < block.dofs; ++m) after[m] += s.joint_change[block.offset + m];
      if (block.held) {
        block.impulse = -kPenalty * (block.mass * after);  // what the penalty applied
        if (block.impulse.norm() > block.bound) block.stuck = false, changed = true;
      } else if (after.dot(block.impulse) > 0) {
        block.stuck = true, changed = true;  // friction would turn it back: it sticks
      } else if (block.dofs == 3 && after.norm() > 0) {
        // Against the sliding velocity it ends with (maximal dissipation).
        const Eigen::Vector3d against = -block.bound / after.norm() * after;
        if ((against - block.impulse).norm() > 1e-6 * block.bound) block.impulse = against, changed = true;
      }
    }
    if (changed && iteration + 1 < kActiveSetIterations) {
      // The next round: a joint that slips slides at the bound along the impulse it needed.
      for (JointFrictionBlock& block : c.friction) {
        if (block.held && !block.stuck) block.impulse *= block.bound / block.impulse.norm();
      }
      continue;
    }
    const auto [first, last] = island_velocities(state, k);
    c.predicted.segment(first, last - first) += s.joint_change.segment(first, last - first);
    // One refinement of the held joints with the same factorization (as for the rows).
    for (JointFrictionBlock& block : c.friction) {
      if (!(block.held && block.stuck)) continue;
      Eigen::Vector3d after = Eigen::Vector3d::Zero();
      for (int m = 0; m < block.dofs; ++m) after[m] = c.predicted[block.offset + m];
      block.rate = after;  // now the residual
      add_joint_vector(-kPenalty * (block.mass * after), s.joint_impulse, block.offset, block.dofs);
    }
    solve_held(state, k);
    for (JointFrictionBlock& block : c.friction) {
      if (block.held && block.stuck) {
        Eigen::Vector3d residual = block.rate;
        for (int m = 0; m < block.dofs; ++m) residual[m] += s.joint_change[block.offset + m];
        block.impulse -= kPenalty * (block.mass * residual);
      }
      const double size = block.impulse.norm();  // past the bound only when the rounds ran out
      if (size > block.bound) block.impulse *= block.bound / size;
    }
    c.predicted.segment(first, last - first) += s.joint_change.segment(first, last - first);
    break;
  }
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

namespace {

// Whether a drive pulls at all.
bool acting(const std::optional<JointDrive>& drive) { return drive && (drive->stiffness > 0 || drive->damping > 0); }

// Calls visit(k) for each Model joint k with coordinates of island `island`, and visit_axis(a)
// for each of its serial axes a (indices into state.serial_axes).
template <typename VisitJoint, typename VisitAxis>
void for_each_island_joint(const FeatherstoneState& state, std::size_t island, VisitJoint&& visit, VisitAxis&& visit_axis) {
  for (std::int32_t n = state.island_joint_begin[island]; n < state.island_joint_begin[island + 1]; ++n) {
    visit(static_cast<std::size_t>(state.island_joint[static_cast<std::size_t>(n)]));
  }
  for (std::int32_t n = state.island_axis_begin[island]; n < state.island_axis_begin[island + 1]; ++n) {
    visit_axis(state.serial_axes[static_cast<std::size_t>(state.island_axis[static_cast<std::size_t>(n)])]);
  }
}

// The drives' force k·(target − x) + c·target_velocity and gain k·h + c on each driven velocity
// of island `island` (x, target and rates in the Model's coordinates, carried onto v), a serial
// joint's axes each on its own velocity; then the servos' (ServoTerms), the same terms. Needs
// state.kinematics at the current (q, v).
void gather_drive_forces(FeatherstoneState& state, double h, std::size_t island) {
  const JointControls& controls = state.joint_controls;
  JointControlScratch& c = state.controls;
  for_each_island_joint(state, island, [&](std::size_t k) {
    const Joint& joint = controls.joints[k];
    const TreeJoint& held = state.tree_joint[k];
    if (!acting(joint.drive)) return;
    const JointDrive& drive = *joint.drive;
    c.drive_gain.segment(held.offset, held.dofs).setConstant(drive.stiffness * h + drive.damping);
    if (joint.type == JointType::spherical) {
      const MeasuredJoint measured = measure_joint(state, k);
      const JointCoordinates& q = measured.coordinates;
      // The turn E = D_target·D⁻¹ that takes the deviation D to the target (inboard frame), as a
      // rotation vector, the shorter way round.
      const JointFrame& frame = controls.frames[k];
      Eigen::Quaterniond error = drive_target_rotation(drive, frame) * rotation_of(q.rotation).conjugate();
      if (error.w() < 0) error.coeffs() = -error.coeffs();
      const Eigen::AngleAxisd turn(error.normalized());
      const Eigen::Vector3d torque =
          drive.stiffness * turn.angle() * turn.axis() + drive.damping * (frame.inboard_rest.conjugate() * drive.target_angular_velocity);
      c.drive_force.segment<3>(held.offset) = measured.inboard_to_velocity * torque;
    } else {
      double error = drive.target - tree_coordinate(state, held);
      if (joint.type == JointType::revolute) error = shorter_way_round(error);
      c.drive_force[held.offset] = held.sign * (drive.stiffness * error + drive.damping * drive.target_velocity);
    }
  }, [&](const TreeSerialAxis& node) {
    // A serial joint's axes: each its own spring and damper on its own velocity.
    const SerialAxis& axis = controls.joints[static_cast<std::size_t>(node.joint)].serial_axes[static_cast<std::size_t>(node.axis)];
    if (!acting(axis.drive)) return;
    const JointDrive& drive = *axis.drive;
    double error = drive.target - state.q[state.tree.position_offset(node.body)];
    if (!axis.slide) error = shorter_way_round(error);
    c.drive_gain[node.offset] = drive.stiffness * h + drive.damping;
    c.drive_force[node.offset] = drive.stiffness * error + drive.damping * drive.target_velocity;
  });
  // The servos add to a drive on the same coordinate: their force at q, and their gain.
  const ServoTerms& servos = state.servos;
  if (!servos.island[island]) return;
  const auto [first, last] = island_velocities(state, island);
  for (int r = first; r < last; ++r) {
    if (servos.stiffness[r] == 0 && servos.damping[r] == 0) continue;
    c.drive_gain[r] += servos.stiffness[r] * h + servos.damping[r];
    c.drive_force[r] += servos.force[r] - servos.stiffness[r] * state.q[servos.position[static_cast<std::size_t>(r)]];
  }
}

// Joint friction's blocks of island `island`, per joint and per serial axis, then their impulses
// (solve_friction): the impulse j that stops each one's predicted velocity through (H + h·G)⁻¹,
// or (sliding) friction·h against the velocity it then has.
void gather_friction(FeatherstoneState& state, double h, std::size_t island) {
  const JointControls& controls = state.joint_controls;
  JointControlScratch& c = state.controls;
  for_each_island_joint(state, island, [&](std::size_t k) {
    const TreeJoint& held = state.tree_joint[k];
    if (!(controls.joints[k].friction > 0)) return;
    JointFrictionBlock block;
    block.body = held.body, block.offset = held.offset, block.dofs = held.dofs;
    block.bound = controls.joints[k].friction * h;
    const Eigen::Matrix3d response = inverse_block(state, island, held.offset, held.dofs);
    if (held.dofs == 1) {
      block.mass(0, 0) = 1 / response(0, 0);
    } else {
      block.mass = response.inverse();
    }
    for (int m = 0; m < held.dofs; ++m) block.rate[m] = c.predicted[held.offset + m];
    c.friction.push_back(block);
  }, [&](const TreeSerialAxis& node) {
    const double bound = controls.joints[static_cast<std::size_t>(node.joint)].serial_axes[static_cast<std::size_t>(node.axis)].friction;
    if (!(bound > 0)) return;
    JointFrictionBlock block;
    block.body = node.body, block.offset = node.offset, block.dofs = 1;
    block.bound = bound * h;
    block.mass(0, 0) = 1 / inverse_block(state, island, node.offset, 1)(0, 0);
    block.rate[0] = c.predicted[node.offset];
    c.friction.push_back(block);
  });
  solve_friction(state, island);
}

}  // namespace

bool joint_control_forces(FeatherstoneState& state, const Eigen::VectorXd& loads, double h, std::size_t island, bool through_factor) {
  const JointControls& controls = state.joint_controls;
  JointControlScratch& c = state.controls;
  bool drives = false, friction = false;
  for_each_island_joint(state, island, [&](std::size_t k) {
    const Joint& joint = controls.joints[k];
    drives = drives || acting(joint.drive);
    friction = friction || joint.friction > 0;
  }, [&](const TreeSerialAxis& node) {
    const SerialAxis& axis = controls.joints[static_cast<std::size_t>(node.joint)].serial_axes[static_cast<std::size_t>(node.axis)];
    drives = drives || acting(axis.drive), friction = friction || axis.friction > 0;
  });
  drives = drives || state.servos.island[island];
  if (!drives && !friction) return false;

  // The island's coordinates: element by element, the same bits as over the whole vectors.
  const BodyRange bodies = island_bodies(state, island);
  const auto [first, last] = island_velocities(state, island);
  const auto on_island = [first = first, count = last - first](auto& x) { return x.segment(first, count); };
  on_island(c.drive_force).setZero(), on_island(c.drive_gain).setZero();
  if (drives) gather_drive_forces(state, h, island);
  // Stable PD (Tan, Liu & Turk 2011): (H + h·G) v̇ = τ − C + F − G·v, G = diag(k·h + c), whose
  // v + h·v̇ is the velocity the drives' force F − G·(v + h·v̇) leaves at the step's end.
  on_island(c.armature) = h * on_island(c.drive_gain);
  on_island(c.explicit_force) = on_island(loads) + on_island(c.drive_force) - on_island(c.drive_gain).cwiseProduct(on_island(state.v));
  JointSpaceContactScratch& s = state.contact;
  if (through_factor) {
    factored_forward_dynamics(state, island, c.explicit_force, c.armature.data(), c.acceleration);
  } else {
    forward_dynamics(state.tree, state.kinematics, c.explicit_force, c.armature.data(), state.settings.gravity, s.articulated,
                     c.acceleration, bodies);
  }
  on_island(c.predicted) = on_island(state.v);
  semi_implicit_velocity(state.tree, c.predicted, c.acceleration, h, bodies);

  if (state.joint_friction) c.friction.clear();  // shared: such scenes integrate on one thread
  if (friction) {
    // Friction's impulses go through (H + h·G)⁻¹, the same system as the drives' (its held joints
    // add their penalties to it: factor_held_rows). The factors are shared by the islands:
    // friction runs on the calling thread (step.cpp).
    if (s.held.size() != state.tree.velocity_count()) s.inertia.assign(state.tree), s.held.assign(state.tree);  // a large tree's first use
    if (s.factor.size() != state.tree.velocity_count()) s.factor.assign(state.tree);
    mass_matrix(state.tree, state.kinematics, s.composite, s.inertia, bodies);
    for (int i = first; i < last; ++i) {
      if (c.armature[i] != 0) s.inertia.add_inertia(i, i, c.armature[i]);
    }
    s.factor.copy_inertia(s.inertia, first, last);
    if (s.factor.factor(first, last) < 0) gather_friction(state, h, island);  // else the state is non-finite: the step's status says so
  }

  // The forces held over the step: the loads, the drives' at the predicted velocity, friction's j/h.
  on_island(c.forces) = on_island(loads) + on_island(c.drive_force) - on_island(c.drive_gain).cwiseProduct(on_island(c.predicted));
  for (const JointFrictionBlock& block : c.friction) add_joint_vector(block.impulse / h, c.forces, block.offset, block.dofs);
  return true;
}

bool joint_control_forces(FeatherstoneState& state, const Eigen::VectorXd& loads, double h) {
  bool any = false;
  for (std::size_t k = 0; k < state.islands.size(); ++k) {
    if (state.islands[k].sleeping) continue;
    if (joint_control_forces(state, loads, h, k, /*through_factor=*/false)) {
      any = true;
    } else {
      const auto [first, last] = island_velocities(state, k);
      state.controls.forces.segment(first, last - first) = loads.segment(first, last - first);
    }
  }
  return any;
}

void joint_forces_of_body_forces(const FeatherstoneState& state, std::vector<SpatialVector>& body_forces, Eigen::VectorXd& joint_forces) {
  joint_forces_of_body_forces(state, body_forces, joint_forces, state.tree.all_bodies());
}

void joint_forces_of_body_forces(const FeatherstoneState& state, std::vector<SpatialVector>& body_forces, Eigen::VectorXd& joint_forces,
                                 BodyRange range) {
  const ArticulatedTree& tree = state.tree;
  for (int i = range.last - 1; i >= range.first; --i) {
    const ArticulatedBody& body = tree.body(i);
    const auto index = static_cast<std::size_t>(i);
    const int offset = tree.velocity_offset(i);
    with_degrees_of_freedom(body.joint, [&](auto dofs) {
      constexpr int k = decltype(dofs)::value;
      if constexpr (k > 0) joint_forces.template segment<k>(offset) = project_on_joint<k>(body, body_forces[index]);
    });
    if (body.parent >= 0) {
      body_forces[static_cast<std::size_t>(body.parent)] += state.kinematics.parent_to_body[index].transpose_apply_force(body_forces[index]);
    }
    body_forces[index].setZero();
  }
}


}  // namespace limber
