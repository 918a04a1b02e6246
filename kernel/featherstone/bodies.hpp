// Featherstone's side of the World's calls (kernel/methods/method_contract.hpp) where its
// reduced coordinates differ from the rigid bodies it refreshes (rigid/bodies.hpp answers the
// rest): held points, sleep, teleports and the state carried across a recompile act on (q, v).
#pragma once

#include <cstddef>
#include <string>

#include <Eigen/Core>

#include "limber/kernel/featherstone/featherstone_state.hpp"
#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/survivors.hpp"
#include "limber/kernel/rigid/bodies.hpp"

namespace limber {

/// Adds `force` (N·m on a hinge, N on a slide) to joint `joint`'s coordinate `axis` (a serial
/// joint's axis; 0 otherwise) for the next step: a generalized force, as an actuator's.
void apply_joint_force(FeatherstoneState& state, std::size_t joint, int axis, double force);
/// Actuator `actuator` at `control` for the next step: a motor's gear × control as a joint force
/// (apply_joint_force); a servo (position or velocity actuator) taken implicitly, as a drive is —
/// its force at the end of each substep (Tan, Liu & Turk 2011's stable PD), so any gain is stable
/// (MuJoCo's servos are explicit: stable while gear²·kp·h²/I and gear²·kv·h/I stay small).
void apply_actuator(FeatherstoneState& state, const Actuator& actuator, double control);
/// Joint `joint`'s coordinate `axis` (a revolute or prismatic joint's, or a serial joint's axis)
/// as the tree holds it.
CoordinateMotion coordinate_motion(const FeatherstoneState& state, std::size_t joint, int axis);
/// Where joint `joint` (to the world) holds its body: its world anchor, m.
Eigen::Vector3d world_anchor(const FeatherstoneState& state, const Model& model, std::size_t joint);
/// Refused before it is called (World::pin refuses a Featherstone world: a joint to the world
/// added while the tree moves would re-root it); throws std::logic_error.
void move_world_anchor(FeatherstoneState& state, const Model& model, std::size_t joint, const Eigen::Vector3d& target);
/// Puts the body's island to sleep and zeroes its joint velocities.
void sleep_body(FeatherstoneState& state, std::size_t body);
/// Moves a floating root (a body whose coordinates are its own) and what hangs from it; false,
/// changing nothing, for any other body.
bool teleport_body(FeatherstoneState& state, std::size_t body, const Pose& pose, const Motion& motion);
/// Copies each surviving body's joint coordinates and velocities when it hangs from the same
/// joint on the same parent (or floats) in both; false, with `problem` naming the body, when an
/// edit changes how a surviving body hangs (reduced coordinates would re-root it).
bool carry_state(const FeatherstoneState& old, const Model& old_model, FeatherstoneState& fresh, const Model& new_model,
                 const Survivors& survivors, std::string& problem);

}  // namespace limber
