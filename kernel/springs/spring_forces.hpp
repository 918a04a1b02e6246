// Forces of the stiff-spring method: gravity, drag and the joints' springs (thesis 3.3, 4.4.1).
#pragma once

#include <Eigen/Core>

#include "limber/kernel/springs/spring_state.hpp"

namespace limber {

/// A spring's two ends at state y, world frame: d = p_inboard − p_outboard (m), its rate
/// ḋ (m/s), and each end's lever from its body's centre of mass (m; zero for a world anchor).
struct SpringEnds {
  Eigen::Vector3d separation = Eigen::Vector3d::Zero(), separation_rate = Eigen::Vector3d::Zero();
  Eigen::Vector3d inboard_lever = Eigen::Vector3d::Zero(), outboard_lever = Eigen::Vector3d::Zero();
};

/// Joint s's spring on `side` (spring_side(): 0 at the anchors; ±1 a hinge's spring at anchor ±
/// offset). Needs state.velocity and state.angular_velocity filled for y (body_velocities()).
SpringEnds spring_ends(const SpringState& state, const RigidBodyState& y, std::size_t s, int side = 0);

/// Adds the applied forces at state y (accumulate_applied_forces, kernel/rigid/rigid_scene.hpp)
/// and every spring's force f = −k·d − c·ḋ on its inboard end and −f on its outboard end, with
/// torques r × f (a hinge's two springs each so); and the joints' limit, friction and drive
/// torques (joint_control_torques).
void accumulate_forces(SpringState& state, const RigidBodyState& y, RigidForces& forces);

/// A joint's limit, friction and drive torques at a state, on the relative rotation of its
/// outboard body (−τ on the inboard), world frame; Ω = ω_o − ω_i, I⁻¹ = I_o⁻¹ + I_i⁻¹ (world,
/// about the centres of mass), m the reduced mass:
/// - the drive: τ = k·e + c·(Ω* − Ω), e the rotation vector of D_target·D⁻¹ (isotropic);
/// - each limit past its bound: τ = −max(0, k_l·x + c_l·(d·Ω))·d, x the excess and d its
///   gradient (the swing direction c×a/|c×a|; ±(a + c)/(1 + a·c) for the twist, c the cone axis), with
///   k_l = k/(m·dᵀI⁻¹d) and c_l = c/(m·dᵀI⁻¹d) from the joint's spring (k, c): the excess then
///   rings at the joint spring's own √(k/m) with its damping ratio, so an integrator that holds
///   the joint holds the limit;
/// - friction: the torque that would stop the relative spin within the step, −(I⁻¹)⁻¹·Ω/h,
///   clamped to |τ| ≤ f: dry friction while that is above f; below, the joint is brought to rest
///   rather than reversed (so it does not chatter about Ω = 0).
/// A revolute joint's act about its hinge alone (its two springs hold the other turns): with θ
/// its angle (joint_coordinates()) and g = (h_i + h_o)/(1 + h_i·h_o) θ's gradient (h_i, h_o the
/// hinge axis carried by each body; g = h while the hinge holds), θ̇ = g·Ω and
/// - the drive: τ = (k·(θ* − θ) + c·(θ̇* − θ̇))·g, θ* − θ wrapped to [−π, π];
/// - the range: a limit as above with d = ±g, x = θ − max or min − θ;
/// - friction: along n = g/|g|, the torque that would stop n·Ω within the step,
///   −(n·Ω)/(h·nᵀI⁻¹n)·n, clamped to |τ| ≤ f.
struct JointControlTorques {
  Eigen::Vector3d drive = Eigen::Vector3d::Zero(), limits = Eigen::Vector3d::Zero(), friction = Eigen::Vector3d::Zero();
  double drive_stiffness = 0, drive_damping = 0;  ///< the drive's k, c (N·m/rad, N·m·s/rad)
  /// A revolute joint's drive acts along this axis (its g): k and c on g·gᵀ. Zero for a
  /// spherical joint's drive, isotropic.
  Eigen::Vector3d drive_axis = Eigen::Vector3d::Zero();
  int limit_count = 0;                            ///< limits past their bounds (≤ 2)
  Eigen::Vector3d limit_direction[2];             ///< their d
  double limit_stiffness[2] = {0, 0}, limit_damping[2] = {0, 0};
};
/// Needs state.velocity and state.angular_velocity filled for y.
JointControlTorques joint_control_torques(const SpringState& state, const RigidBodyState& y, std::size_t joint);

/// Potential energy stored in the springs at the current state, Σ ½ k |d|² over every spring
/// (a hinge's two), J.
double spring_energy(const SpringState& state);

}  // namespace limber
