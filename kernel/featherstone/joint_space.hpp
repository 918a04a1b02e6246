// Joint space through the World (MuJoCo's qpos, qvel, qfrc_passive, qfrc_bias, mj_fullM,
// mj_inverse): the Featherstone state's coordinates in the Model's order, and the dynamics
// at them.
//
// The layout, walking the Model's bodies in order: a floating body's 7 positions and 6
// velocities, then the coordinates of each joint whose outboard body it is, in joint order.
// For a Model read from MJCF this is MuJoCo's qpos and qvel order: MuJoCo orders by body, and
// a free joint is the body's own.
// - A floating body: its centre of mass (m, world) and the orientation of its body frame
//   (w, x, y, z; body → world); velocities (ω, v), its angular velocity and its centre of mass's
//   velocity, both in its body frame (Featherstone's floating joint). MuJoCo's free joint instead
//   moves the body's frame origin, with ṗ in world.
// - A revolute or prismatic joint: its angle (rad) or slide (m) from the Model's poses and its rate.
// - A spherical joint: the outboard body's orientation relative to the inboard (w, x, y, z) and
//   its angular velocity relative to the inboard, in the outboard's frame.
// - A serial joint: each axis's angle or slide and rate, in order. A fixed joint has none.
// Forces are dual to the velocities: N·m or N per coordinate, (n, f) in the body frame for a
// floating body.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/featherstone/featherstone_state.hpp"

namespace limber {

/// Where each coordinate of the Model's joint-space layout lies in the tree's q and v.
struct JointSpaceLayout {
  std::vector<int> position, velocity;  ///< per layout coordinate: its index in the tree's q, v
  /// Per coordinate: −1 where the tree turned a revolute or prismatic joint round, else 1.
  std::vector<double> position_sign, velocity_sign;
  std::vector<std::string> names;       ///< per velocity: "<body or joint>.<coordinate>"
  std::vector<std::string> position_names;  ///< per position: "torso.x", "torso.qw", "knee"
  std::vector<int> angle_or_slide;      ///< per velocity: a 1-DOF coordinate's position in the layout, else −1
  std::vector<int> joint_velocity;      ///< per Model joint: its first velocity in the layout (−1: none)
};

/// The layout of `state` (compiled from `model`). Throws ModelError naming a spherical joint the
/// tree holds the other way round (its coordinates are not a permutation of the tree's).
JointSpaceLayout joint_space_layout(const FeatherstoneState& state, const Model& model);

/// q and v in the layout's order (sizes nq, nv), and setting them: the bodies follow (the rigid
/// scene is refreshed). A floating body's quaternion is normalized.
Eigen::VectorXd joint_positions(const FeatherstoneState& state, const JointSpaceLayout& layout);
Eigen::VectorXd joint_velocities(const FeatherstoneState& state, const JointSpaceLayout& layout);
void set_joint_state(FeatherstoneState& state, const JointSpaceLayout& layout, const Eigen::VectorXd& q, const Eigen::VectorXd& v);

/// The joint-space mass matrix M(q) with the armature (nv × nv), the bias forces C(q, v) (gravity,
/// Coriolis, centrifugal; nv), and the dynamics between them: M⁻¹(τ − C) (forward) and M v̇ + C
/// (inverse). No contacts, limits, springs or motors: those are passive_forces.
Eigen::MatrixXd joint_mass_matrix(const FeatherstoneState& state, const JointSpaceLayout& layout);
Eigen::VectorXd joint_bias_forces(const FeatherstoneState& state, const JointSpaceLayout& layout);
Eigen::VectorXd forward_joint_dynamics(const FeatherstoneState& state, const JointSpaceLayout& layout, const Eigen::VectorXd& forces);
Eigen::VectorXd inverse_joint_dynamics(const FeatherstoneState& state, const JointSpaceLayout& layout, const Eigen::VectorXd& accelerations);

/// What each Model joint transmits (Model::joints order) at the current state for accelerations
/// `accelerations` (layout, nv): the recursive Newton–Euler algorithm's f_i (Featherstone,
/// "Rigid Body Dynamics Algorithms", Table 5.1; MuJoCo's cfrc_int), the joint's own generalized
/// force along its axes included, the armature's not. Gravity and the bodies' inertia alone:
/// no contact forces.
std::vector<JointReaction> joint_reactions(const FeatherstoneState& state, const Model& model, const JointSpaceLayout& layout,
                                           const Eigen::VectorXd& accelerations);

/// The forces of the joints' springs and dampers (their drives: k·(target − x) + c·(target rate −
/// ẋ), explicit, as MuJoCo's qfrc_passive) and of the motors at `controls` (gear × control clamped,
/// qfrc_actuator), in the layout (nv). Revolute, prismatic and serial joints' drives; a spherical
/// joint's drive is not included (its error is a rotation: not yet).
Eigen::VectorXd joint_passive_forces(const FeatherstoneState& state, const Model& model, const JointSpaceLayout& layout,
                                     const std::vector<double>& controls);

}  // namespace limber
