// The rigid methods' side of the World's calls (kernel/methods/method_contract.hpp), on the
// arrays the springs, Lagrange and Featherstone share (RigidScene; Featherstone's refreshed from
// its (q, v) after each step): a body's pose, motion and centre of mass, loads, drives, sleep,
// teleports, balls, and the state carried across a recompile. A Model body's frame is its
// shape's: a Model point p is at x + q·principal⁻¹·(p − centre_offset).
#pragma once

#include <concepts>
#include <cstddef>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/survivors.hpp"
#include "limber/kernel/rigid/rigid_scene.hpp"

namespace limber {

Pose body_pose(const RigidScene& scene, std::size_t body);
Motion body_motion(const RigidScene& scene, std::size_t body);
Eigen::Vector3d body_centre_of_mass(const RigidScene& scene, std::size_t body);
/// A force (N) at the centre of mass and a torque (N·m), over the next step.
void apply_body_load(RigidScene& scene, std::size_t body, const Eigen::Vector3d& force, const Eigen::Vector3d& torque);
/// The world position of `local_point` (the Model body frame, m).
Eigen::Vector3d body_point(const RigidScene& scene, std::size_t body, const Eigen::Vector3d& local_point);
void wake_body(RigidScene& scene, std::size_t body);
void sleep_body(RigidScene& scene, std::size_t body);
bool body_sleeping(const RigidScene& scene, std::size_t body);
/// Sets the body's pose and motion (x, q, P, L). Any body: true.
bool teleport_body(RigidScene& scene, std::size_t body, const Pose& pose, const Motion& motion);
BallMotion ball_motion(const RigidScene& scene, std::size_t ball);
/// Whether a ball touched a limb in the last step (Settings::release_drives_on_impact).
inline bool ball_touching(const RigidScene& scene) { return scene.ball_touching; }
/// Copies every surviving body's x, q, P, L (and the balls') and the clock; an island of
/// surviving bodies sleeps if they all slept, one of new bodies as compiled. Never refuses.
bool carry_state(const RigidScene& old, const Model& old_model, RigidScene& fresh, const Model& new_model, const Survivors& survivors,
                 std::string& problem);

/// Sets joint `joint`'s drive (gains and target; Model index) from the next step on. Returns
/// false when the joint was compiled without a drive (recompile with the drive in the Model).
template <typename State>
  requires std::derived_from<State, RigidScene>
bool set_joint_drive(State& state, std::size_t joint, const JointDrive& drive) {
  if (joint >= state.joint_controls.joints.size() || !state.joint_controls.joints[joint].drive) return false;
  state.joint_controls.joints[joint].drive = drive;
  return true;
}

namespace rigid_bodies {
/// The old index of new scene body b (a limb, then the balls), −1 when new.
std::int64_t old_body(const RigidScene& old, const RigidScene& fresh, const Survivors& survivors, std::size_t b);
/// An island of surviving bodies sleeps if they all slept, else wakes; one of new bodies keeps
/// what compile decided.
void carry_sleep(const RigidScene& old, RigidScene& fresh, const Survivors& survivors);
}  // namespace rigid_bodies

}  // namespace limber
