// The Featherstone method's drives and joint friction in joint space (joint_space_contacts.hpp,
// "Drives and friction"): the forces they hold over a step, found before the integrator, and the
// friction's held joints. Internal to kernel/featherstone; it shares joint_space_limits.hpp's
// measures.
#include <algorithm>
#include <cmath>
#include <type_traits>

#include "limber/kernel/featherstone/joint_space_contacts.hpp"
#include "limber/kernel/featherstone/joint_space_limits.hpp"
#include "limber/kernel/featherstone/joint_space_response.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/model/joint_coordinates.hpp"
#include "limber/kernel/rigid/rigid_integration.hpp"

namespace limber {
namespace joint_space {
namespace {

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

}  // namespace
}  // namespace joint_space

using namespace joint_space;

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
      Eigen::Quaterniond error = drive_target_rotation(drive, frame) * rotation_quaternion(q.rotation).conjugate();
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
