// What a method is: the calls every method's compiled state answers, so that the World (and
// through it the command line, the viewer and the studies) drives any method the same way and
// visits the state once per call, with no branch on which method it is. Each method answers
// them in its own folder (verlet/bodies.hpp; rigid/bodies.hpp, which the springs, Lagrange and
// Featherstone share, with springs/, lagrange/ and featherstone/bodies.hpp where they differ);
// compile_method (method.hpp) makes the state, and a fifth method is a folder of its own plus
// one entry in MethodState, compile_method and kMethodCapabilities.
//
// Bodies are Model body indices, joints Model joint indices, balls Model ball indices. Lengths
// in m, times in s, forces in N, torques in N·m; poses and motions world, of the Model body
// frame (model.hpp, Pose and Motion). Two calls are answered outside the method folders, for
// every method at once: observe (metrics/observers.hpp) and limb_segments (the same header); the
// concept finds them by argument-dependent lookup where they are declared (world.cpp checks it).
#pragma once

#include <concepts>
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/step_status.hpp"
#include "limber/kernel/model/survivors.hpp"

namespace limber {

struct Observation;  // metrics/observation.hpp
struct LimbSegment;  // geometry/limb_collisions.hpp

template <typename State>
concept MethodContract = requires(State& state, const State& read, const State& old, const Model& model, std::size_t index,
                                  double dt, const Eigen::Vector3d& vector, const Pose& pose, const Motion& motion,
                                  const JointDrive& drive, const Survivors& survivors, std::string& problem,
                                  std::vector<LimbSegment>& segments) {
  // Step and observe.
  { step(state, dt) } -> std::same_as<StepReport>;  // one step of dt; never throws (the status says)
  { minimum_time_step(read) } -> std::same_as<double>;
  { read.time } -> std::convertible_to<double>;
  { observe(read) } -> std::same_as<Observation>;
  limb_segments(read, model, segments);  // each body's limb, then each ball, as collision sees it
  // A body: its pose, motion and centre of mass; a point of it; loads over the next step.
  { body_pose(read, index) } -> std::same_as<Pose>;
  { body_motion(read, index) } -> std::same_as<Motion>;
  { body_centre_of_mass(read, index) } -> std::same_as<Eigen::Vector3d>;
  { body_point(read, index, vector) } -> std::same_as<Eigen::Vector3d>;
  apply_body_load(state, index, vector, vector);  // force at the centre of mass, torque
  // Joints: a coordinate's force over the next step and its value now (an actuator's), drives
  // (false: compiled without one), held points (joints to the world).
  apply_joint_force(state, index, 0, 1.0);
  { coordinate_motion(read, index, 0) } -> std::same_as<CoordinateMotion>;
  { set_joint_drive(state, index, drive) } -> std::same_as<bool>;
  { world_anchor(read, model, index) } -> std::same_as<Eigen::Vector3d>;
  move_world_anchor(state, model, index, vector);  // a kinematic target for the next step
  // Sleep: a body's island.
  wake_body(state, index);
  sleep_body(state, index);
  { body_sleeping(read, index) } -> std::same_as<bool>;
  // Teleports: false when the method cannot move that body (nothing changes).
  { teleport_body(state, index, pose, motion) } -> std::same_as<bool>;
  // Balls.
  { ball_motion(read, index) } -> std::same_as<BallMotion>;
  { ball_touching(read) } -> std::same_as<bool>;
  // A recompile: the surviving bodies' and balls' state from `old` (compiled from another Model);
  // false, with `problem` saying why, when the method cannot carry it.
  { carry_state(old, model, state, model, survivors, problem) } -> std::same_as<bool>;
};

}  // namespace limber
