// The lagrange method's side of the World's calls (kernel/methods/method_contract.hpp): its held
// points and its motors; every other call is the rigid bodies' (rigid/bodies.hpp).
#pragma once

#include <cstddef>

#include <Eigen/Core>

#include "limber/kernel/lagrange/lagrange_state.hpp"
#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/servo.hpp"
#include "limber/kernel/rigid/bodies.hpp"

namespace limber {

/// Where joint `joint` (to the world) holds its body: the joint's world anchor, m.
inline Eigen::Vector3d world_anchor(const LagrangeState& state, const Model&, std::size_t joint) { return state.joints.inboard_anchor[joint]; }

/// Moves the joint's world anchor to `target` for the next step; the body follows through the joint.
inline void move_world_anchor(LagrangeState& state, const Model&, std::size_t joint, const Eigen::Vector3d& target) { state.joints.inboard_anchor[joint] = target; }

/// Adds `force` (N·m on a hinge, N on a slide) to joint `joint`'s coordinate `axis` for the next
/// step: the pair of loads it is on the joint's bodies (apply_coordinate_force).
inline void apply_joint_force(LagrangeState& state, std::size_t joint, int axis, double force) {
  apply_coordinate_force(state, state.coordinate_axes, joint, axis, force);
}

/// Actuator `actuator` at `control` for the next step: a motor's gear × control as a joint force
/// (apply_joint_force); a servo (position or velocity actuator) taken implicitly on its joint's
/// control row, as a drive is (JointServos), so any gain is stable (MuJoCo's servos are
/// explicit: stable while gear²·kp·h²/I and gear²·kv·h/I stay small).
inline void apply_actuator(LagrangeState& state, const Actuator& actuator, double control) {
  const auto joint = static_cast<std::size_t>(actuator.joint);
  if (actuator.kind == ActuatorKind::motor) {
    if (const double force = actuator_force(actuator, control); force != 0) apply_joint_force(state, joint, actuator.axis, force);
    return;
  }
  const std::size_t k = joint_of_axis(state.coordinate_axes.first_added_joint, joint, actuator.axis);
  const ServoPull pull = servo_pull(actuator, control);
  JointServos& servos = state.servos;
  servos.force[k] += pull.force, servos.stiffness[k] += pull.stiffness, servos.damping[k] += pull.damping;
  servos.any = true;
}

/// Joint `joint`'s coordinate `axis` now (coordinate_motion over the bodies' poses and motions).
inline CoordinateMotion coordinate_motion(const LagrangeState& state, std::size_t joint, int axis) {
  return coordinate_motion(state, state.coordinate_axes, joint, axis);
}

}  // namespace limber
