// The lagrange method's side of the World's calls (kernel/methods/method_contract.hpp): its held
// points and its motors; every other call is the rigid bodies' (rigid/bodies.hpp).
#pragma once

#include <cstddef>

#include <Eigen/Core>

#include "limber/kernel/lagrange/lagrange_state.hpp"
#include "limber/kernel/model/model.hpp"
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

/// Joint `joint`'s coordinate `axis` now (coordinate_motion over the bodies' poses and motions).
inline CoordinateMotion coordinate_motion(const LagrangeState& state, std::size_t joint, int axis) {
  return coordinate_motion(state, state.coordinate_axes, joint, axis);
}

}  // namespace limber
