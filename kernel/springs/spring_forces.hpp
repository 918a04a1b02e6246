// Forces of the stiff-spring method: gravity, drag and the joints' springs (thesis 3.3, 4.4.1).
#pragma once

#include <Eigen/Core>

#include "limber/kernel/springs/spring_state.hpp"

namespace limber {

/// Spring s's two ends at state y, world frame: d = p_inboard − p_outboard (m), its rate
/// ḋ (m/s), and each end's lever from its body's centre of mass (m; zero for a world anchor).
struct SpringEnds {
  Eigen::Vector3d separation = Eigen::Vector3d::Zero(), separation_rate = Eigen::Vector3d::Zero();
  Eigen::Vector3d inboard_lever = Eigen::Vector3d::Zero(), outboard_lever = Eigen::Vector3d::Zero();
};

/// Needs state.velocity and state.angular_velocity filled for y (body_velocities()).
SpringEnds spring_ends(const SpringState& state, const RigidBodyState& y, std::size_t s);

/// Adds the applied forces at state y (accumulate_applied_forces, kernel/rigid/rigid_scene.hpp)
/// and every spring's force f = −k·d − c·ḋ on its inboard end and −f on its outboard end, with
/// torques r × f.
void accumulate_forces(SpringState& state, const RigidBodyState& y, RigidForces& forces);

/// Potential energy stored in the springs at the current state, Σ ½ k |d|², J.
double spring_energy(const SpringState& state);

}  // namespace limber
