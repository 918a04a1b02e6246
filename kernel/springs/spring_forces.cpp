#include "limber/kernel/springs/spring_forces.hpp"

#include <algorithm>
#include <cmath>

#include "limber/kernel/model/joint_coordinates.hpp"

namespace limber {
namespace {

// A body's Model frame (the shape's centre, Model axes) from its rigid state; the world's for −1.
FramePose model_frame_pose(const SpringState& state, const RigidBodyState& y, std::int32_t body) {
  if (body < 0) return {};
  const auto b = static_cast<std::size_t>(body);
  const Eigen::Quaterniond orientation = y.orientation[b] * state.shapes.principal_frame[b].conjugate();
  return {orientation, y.position[b] - orientation * state.shapes.centre_offset[b]};
}

}  // namespace

JointControlTorques joint_control_torques(const SpringState& state, const RigidBodyState& y, std::size_t k) {
  JointControlTorques out;
  const Joint& joint = state.joint_controls.joints[k];
  const JointFrame& frame = state.joint_controls.frames[k];
  const SpringBuffer& springs = state.springs;
  const std::int32_t i = springs.inboard[k], o = springs.outboard[k];
  const FramePose inboard = model_frame_pose(state, y, i), outboard = model_frame_pose(state, y, o);
  const JointCoordinates q = joint_coordinates(joint, frame, inboard, outboard);
  const Eigen::Vector3d w_i = i >= 0 ? state.angular_velocity[i] : Eigen::Vector3d::Zero();
  const Eigen::Vector3d relative = state.angular_velocity[o] - w_i;
  // The two bodies' inverse inertia (world, about their centres of mass) and reduced mass.
  Eigen::Matrix3d inverse_inertia = state.bodies.world_inverse_inertia(y, static_cast<std::size_t>(o));
  if (i >= 0) inverse_inertia += state.bodies.world_inverse_inertia(y, static_cast<std::size_t>(i));
  const double mass = i >= 0 ? 1 / (state.bodies.inverse_mass[o] + state.bodies.inverse_mass[i]) : state.bodies.mass[o];

  const JointLimits& limits = joint.limits;
  const auto add_limit = [&](const Eigen::Vector3d& direction, double excess) {
    // The coordinate's acceleration per unit of its generalized force is dᵀ(I_o⁻¹ + I_i⁻¹)d.
    const double scale = 1 / (mass * direction.dot(inverse_inertia * direction));
    const double stiffness = springs.stiffness[k] * scale, damping = springs.damping[k] * scale;
    out.limits -= std::max(0.0, stiffness * excess + damping * direction.dot(relative)) * direction;
    out.limit_direction[out.limit_count] = direction;
    out.limit_stiffness[out.limit_count] = stiffness, out.limit_damping[out.limit_count] = damping;
    ++out.limit_count;
  };

  if (joint.type == JointType::revolute) {
    // The hinge axis as each body carries it, h_i = q_i·h and h_o = q_o·R₀⁻¹·h, and the angle's
    // gradient g = (h_i + h_o)/(1 + h_i·h_o) (the twist formula of joint_coordinates.hpp about h).
    const Eigen::Vector3d axis_i = inboard.orientation * frame.axis;
    const Eigen::Vector3d axis_o = outboard.orientation * (frame.rest_relative.conjugate() * frame.axis);
    const Eigen::Vector3d gradient = twist_gradient(axis_o, axis_i);
    const double rate = gradient.dot(relative);
    if (joint.drive) {
      const JointDrive& drive = *joint.drive;
      const double error = shorter_way_round(drive.target - q.angle);
      out.drive = (drive.stiffness * error + drive.damping * (drive.target_velocity - rate)) * gradient;
      out.drive_stiffness = drive.stiffness, out.drive_damping = drive.damping;
      out.drive_axis = gradient;
    }
    if (limits.range && q.angle > limits.range->max) add_limit(gradient, q.angle - limits.range->max);
    if (limits.range && q.angle < limits.range->min) add_limit(-gradient, limits.range->min - q.angle);
    if (joint.friction > 0) {
      const Eigen::Vector3d axis = gradient.normalized();
      const double stop = -axis.dot(relative) / (state.time_step * axis.dot(inverse_inertia * axis));
      out.friction = std::clamp(stop, -joint.friction, joint.friction) * axis;
    }
    return out;
  }

  if (joint.drive) {
    const JointDrive& drive = *joint.drive;
    Eigen::Quaterniond error = drive_target_rotation(drive, frame) * Eigen::Quaterniond(rotation_quaternion(q.rotation)).conjugate();
    if (error.w() < 0) error.coeffs() = -error.coeffs();
    const Eigen::AngleAxisd turn(error.normalized());
    const Eigen::Vector3d error_vector = inboard.orientation * (turn.angle() * turn.axis());
    const Eigen::Vector3d target_rate = inboard.orientation * (frame.inboard_rest.conjugate() * drive.target_angular_velocity);
    out.drive = drive.stiffness * error_vector + drive.damping * (target_rate - relative);
    out.drive_stiffness = drive.stiffness, out.drive_damping = drive.damping;
  }

  const Eigen::Vector3d a = outboard.orientation * Eigen::Vector3d::UnitZ();
  if (limits.swing && q.swing > *limits.swing) {
    const Eigen::Vector3d across = (inboard.orientation * frame.cone_axis).cross(a);
    if (across.norm() > 1e-12) add_limit(across.normalized(), q.swing - *limits.swing);
  }
  if (limits.twist && (q.twist > limits.twist->max || q.twist < limits.twist->min)) {
    // The twist's gradient (a + c)/(1 + a·c), c the cone axis (joint_coordinates.hpp's decomposition).
    const Eigen::Vector3d gradient = twist_gradient(a, inboard.orientation * frame.cone_axis);
    if (q.twist > limits.twist->max) add_limit(gradient, q.twist - limits.twist->max);
    else add_limit(-gradient, limits.twist->min - q.twist);
  }

  if (joint.friction > 0) {
    // The torque that would stop the relative spin within the step, through the reduced inertia,
    // clamped to the friction.
    const Eigen::Vector3d stop = -inverse_inertia.inverse() * relative / state.time_step;
    const double size = stop.norm();
    out.friction = size > joint.friction ? Eigen::Vector3d(stop * (joint.friction / size)) : stop;
  }
  return out;
}

SpringEnds spring_ends(const SpringState& state, const RigidBodyState& y, std::size_t s, int side) {
  const SpringBuffer& springs = state.springs;
  SpringEnds ends;
  const std::int32_t inboard = springs.inboard[s], outboard = springs.outboard[s];
  // The ends in each body's frame (world for a world anchor): the anchors, or a hinge's anchor ± offset.
  const Eigen::Vector3d inboard_anchor =
      side == 0 ? springs.inboard_anchor[s] : Eigen::Vector3d(springs.inboard_anchor[s] + side * springs.inboard_offset[s]);
  const Eigen::Vector3d outboard_anchor =
      side == 0 ? springs.outboard_anchor[s] : Eigen::Vector3d(springs.outboard_anchor[s] + side * springs.outboard_offset[s]);
  ends.outboard_lever = y.orientation[outboard] * outboard_anchor;
  const Eigen::Vector3d outboard_point = y.position[outboard] + ends.outboard_lever;
  const Eigen::Vector3d outboard_velocity = state.velocity[outboard] + state.angular_velocity[outboard].cross(ends.outboard_lever);
  Eigen::Vector3d inboard_point = inboard_anchor, inboard_velocity = Eigen::Vector3d::Zero();
  if (inboard >= 0) {
    ends.inboard_lever = y.orientation[inboard] * inboard_anchor;
    inboard_point = y.position[inboard] + ends.inboard_lever;
    inboard_velocity = state.velocity[inboard] + state.angular_velocity[inboard].cross(ends.inboard_lever);
  }
  ends.separation = inboard_point - outboard_point;
  ends.separation_rate = inboard_velocity - outboard_velocity;
  return ends;
}

void accumulate_forces(SpringState& state, const RigidBodyState& y, RigidForces& forces) {
  accumulate_applied_forces(state, y, forces);
  const SpringBuffer& springs = state.springs;
  for (std::size_t s = 0; s < springs.size(); ++s) {
    const std::int32_t inboard = springs.inboard[s], outboard = springs.outboard[s];
    if (state.islands[state.island_of_body[outboard]].sleeping) continue;  // both ends share an island
    for (int e = 0; e < springs.count[s]; ++e) {
      const SpringEnds ends = spring_ends(state, y, s, spring_side(springs, s, e));
      const Eigen::Vector3d force = -springs.stiffness[s] * ends.separation - springs.damping[s] * ends.separation_rate;
      if (inboard >= 0) {
        forces.force[inboard] += force;
        forces.torque[inboard] += ends.inboard_lever.cross(force);
      }
      forces.force[outboard] -= force;
      forces.torque[outboard] -= ends.outboard_lever.cross(force);
    }
  }
  for (const std::uint32_t k : state.controlled_joints) {
    const std::int32_t inboard = springs.inboard[k], outboard = springs.outboard[k];
    if (state.islands[state.island_of_body[outboard]].sleeping) continue;
    const JointControlTorques torques = joint_control_torques(state, y, k);
    const Eigen::Vector3d torque = torques.drive + torques.limits + torques.friction;
    forces.torque[outboard] += torque;
    if (inboard >= 0) forces.torque[inboard] -= torque;
  }
}

double spring_energy(const SpringState& state) {
  const SpringBuffer& springs = state.springs;
  const RigidBodyState& y = state.bodies.state;
  double energy = 0;
  for (std::size_t s = 0; s < springs.size(); ++s) {
    if (springs.count[s] == 1) {
      energy += 0.5 * springs.stiffness[s] * joint_separation(springs, y, s).squaredNorm();
      continue;
    }
    // A hinge's two springs: the anchors' separation d and the offsets' turn δ give d ± δ.
    const std::int32_t inboard = springs.inboard[s], outboard = springs.outboard[s];
    const Eigen::Vector3d inboard_offset =
        inboard >= 0 ? Eigen::Vector3d(y.orientation[inboard] * springs.inboard_offset[s]) : springs.inboard_offset[s];
    const Eigen::Vector3d turn = inboard_offset - y.orientation[outboard] * springs.outboard_offset[s];
    const Eigen::Vector3d separation = joint_separation(springs, y, s);
    energy += 0.5 * springs.stiffness[s] * ((separation + turn).squaredNorm() + (separation - turn).squaredNorm());
  }
  return energy;
}

}  // namespace limber
