#include "limber/kernel/featherstone/bodies.hpp"

#include <stdexcept>

#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/model/servo.hpp"

namespace limber {

Eigen::Vector3d world_anchor(const FeatherstoneState& state, const Model&, std::size_t joint) { return state.joints.inboard_anchor[joint]; }

void move_world_anchor(FeatherstoneState&, const Model&, std::size_t, const Eigen::Vector3d&) {
  throw std::logic_error("move_world_anchor: Featherstone worlds hold no pins (World::pin refuses them)");
}

void sleep_body(FeatherstoneState& state, std::size_t body) {
  rest_island(state, state.island_of_body[body]);
  rest_sleeping_islands(state);
}

bool teleport_body(FeatherstoneState& state, std::size_t body, const Pose& pose, const Motion& motion) {
  const Eigen::Vector3d& position = pose.position;
  const Eigen::Quaterniond& orientation = pose.orientation;
  const std::int32_t i = state.tree_body[body];
  if (state.tree.body(i).joint != ArticulatedJoint::floating) return false;
  // A floating root's frame: the Model body frame's axes at the centre of mass; q = (p, w, x, y, z).
  const Eigen::Vector3d centre = position + orientation * state.shapes.centre_offset[body];
  const int p = state.tree.position_offset(i), v = state.tree.velocity_offset(i);
  state.q.segment<3>(p) = centre;
  state.q.segment<4>(p + 3) << orientation.w(), orientation.x(), orientation.y(), orientation.z();
  const Eigen::Matrix3d to_child = orientation.toRotationMatrix().transpose();
  state.v.segment<3>(v) = to_child * motion.angular;
  state.v.segment<3>(v + 3) = to_child * (motion.linear + motion.angular.cross(centre - position));
  refresh_rigid_bodies(state);
  // A teleport is no path: a ball's continuous collision, which sweeps the last step's path when
  // the contacts come before the move, starts from here.
  state.step_start_position[body] = state.bodies.state.position[body];
  return true;
}

void apply_joint_force(FeatherstoneState& state, std::size_t joint, int axis, double force) {
  const TreeJoint& held = state.tree_joint[joint];
  state.actuation[held.offset + axis] += held.sign * force;
}

void apply_actuator(FeatherstoneState& state, const Actuator& actuator, double control) {
  const auto joint = static_cast<std::size_t>(actuator.joint);
  if (actuator.kind == ActuatorKind::motor) {
    if (const double force = actuator_force(actuator, control); force != 0) apply_joint_force(state, joint, actuator.axis, force);
    return;
  }
  const TreeJoint& held = state.tree_joint[joint];
  const int r = held.offset + actuator.axis;
  const ServoPull pull = servo_pull(actuator, control);
  ServoTerms& servos = state.servos;
  servos.force[r] += held.sign * pull.force;
  servos.stiffness[r] += pull.stiffness, servos.damping[r] += pull.damping;
  servos.position[static_cast<std::size_t>(r)] = state.tree.position_offset(held.axis_body(actuator.axis));
  servos.island[island_of(state, held)] = 1;
}

CoordinateMotion coordinate_motion(const FeatherstoneState& state, std::size_t joint, int axis) {
  const TreeJoint& held = state.tree_joint[joint];
  return {held.sign * state.q[state.tree.position_offset(held.axis_body(axis))], held.sign * state.v[held.offset + axis]};
}

bool carry_state(const FeatherstoneState& old, const Model& old_model, FeatherstoneState& fresh, const Model& new_model,
                 const Survivors& survivors, std::string& problem) {
  // The joint a tree body hangs from, by name (empty: floating), and its parent's old index.
  const auto hangs = [](const FeatherstoneState& state, const Model& model, std::int32_t i) {
    const std::int32_t joint = state.model_joint[static_cast<std::size_t>(i)];
    return joint < 0 ? std::string() : model.joints[static_cast<std::size_t>(joint)].name;
  };
  // A serial joint's chain counts as one joint: its first tree body (the body's own otherwise).
  const auto chain_first = [](const FeatherstoneState& state, std::int32_t i) {
    while (state.tree.body(i).parent >= 0 && state.scene_body[static_cast<std::size_t>(state.tree.body(i).parent)] < 0) i = state.tree.body(i).parent;
    return i;
  };
  for (std::int32_t i = 0; i < fresh.tree.body_count(); ++i) {
    const std::int32_t b = fresh.scene_body[static_cast<std::size_t>(i)];
    if (b < 0) continue;  // a serial joint's frame: carried with its chain's child
    const std::int64_t o = rigid_bodies::old_body(old, fresh, survivors, static_cast<std::size_t>(b));
    if (o < 0) continue;
    const std::int32_t oi = old.tree_body[static_cast<std::size_t>(o)];
    const std::int32_t first = chain_first(fresh, i), old_first = chain_first(old, oi);
    const std::int32_t parent = fresh.tree.body(first).parent, old_parent = old.tree.body(old_first).parent;
    const std::int64_t parent_then =
        parent < 0 ? -1 : rigid_bodies::old_body(old, fresh, survivors, static_cast<std::size_t>(fresh.scene_body[static_cast<std::size_t>(parent)]));
    const std::int64_t old_parent_body = old_parent < 0 ? -1 : old.scene_body[static_cast<std::size_t>(old_parent)];
    if (hangs(fresh, new_model, i) != hangs(old, old_model, oi) || parent_then != old_parent_body ||
        fresh.tree.body(i).joint != old.tree.body(oi).joint || i - first != oi - old_first) {
      const std::string name = static_cast<std::size_t>(b) < new_model.bodies.size() ? new_model.bodies[static_cast<std::size_t>(b)].name
                                                                                    : ball_name(new_model, static_cast<std::size_t>(b) - new_model.bodies.size());
      problem = "keeps a moving body's state only while it hangs from the same joint on the same parent; the edit changes how '" + name +
                "' hangs (reduced coordinates would re-root it)";
      return false;
    }
    // The joint's coordinates, a serial chain's all together (1 position and velocity a body).
    const int extra = i - first;
    const ArticulatedJoint type = fresh.tree.body(i).joint;
    fresh.q.segment(fresh.tree.position_offset(first), joint_position_count(type) + extra) =
        old.q.segment(old.tree.position_offset(old_first), joint_position_count(type) + extra);
    fresh.v.segment(fresh.tree.velocity_offset(first), joint_velocity_count(type) + extra) =
        old.v.segment(old.tree.velocity_offset(old_first), joint_velocity_count(type) + extra);
  }
  fresh.time = old.time;
  rigid_bodies::carry_sleep(old, fresh, survivors);
  refresh_rigid_bodies(fresh);
  return true;
}

}  // namespace limber
