// The Featherstone method's joint limits as rows (joint_space_limits.cpp), its joint friction and
// its drives (joint_space_drives.cpp), in joint space (joint_space_contacts.hpp, "Joint limits",
// "Drives and friction"; joint_control_forces and the other public calls are declared there).
// What the contacts' passes (joint_space_contacts.cpp) and the drives take from here. Internal to
// kernel/featherstone.
#pragma once

#include <Eigen/Geometry>

#include "limber/kernel/featherstone/featherstone_state.hpp"
#include "limber/kernel/model/joint_coordinates.hpp"

namespace limber::joint_space {

// The most rounds of an active-set solve: the limit rows' (joint_space_limits.cpp, "Holding
// rows") and the stuck joints' of friction (joint_space_drives.cpp).
inline constexpr int kActiveSetIterations = 8;

// Joint k measured at the tree's current poses (state.kinematics): its bodies' Model frames, its
// coordinates, and the map from an inboard-frame angular vector to joint k's velocity coordinates,
// sign·E_child·R_inboard (orthogonal: it maps rates' rows and torques alike).
struct MeasuredJoint {
  FramePose inboard, outboard;
  JointCoordinates coordinates;
  Eigen::Matrix3d inboard_to_velocity = Eigen::Matrix3d::Identity();
};
MeasuredJoint measure_joint(const FeatherstoneState& state, std::size_t k);

// A revolute or prismatic joint's coordinate (the Model's angle or slide, rad or m): sign·q of its
// tree body, 0 at the Model's initial pose as the joint frames are. It is what measure_joint reads
// from the poses (to round-off, 10⁻¹⁵ on humanoid.xml), without the poses' quaternions and
// arc tangent; unlike that angle, a hinge's is not wrapped to (−π, π].
double tree_coordinate(const FeatherstoneState& state, const TreeJoint& held);

// The rows of every limit that is violated or may be within the step, at the current (q, v) or
// at the velocities `also`: gaps and directions (their inverse masses come with their half rows,
// prepare_group). Returns how many; `count_only` counts them and leaves state.controls.rows.
int find_limit_rows(FeatherstoneState& state, double dt, const Eigen::VectorXd* also = nullptr, bool count_only = false);
// The Delassus matrix of each of the group's islands with limit rows (joint_space_limits.cpp,
// "Holding rows"), from their half rows. Needs them (prepare_group).
void form_limit_delassus(FeatherstoneState& state, const ConstraintGroup& group);
// One pass over the group's limit rows, each island's together (joint_space_limits.cpp, "Holding
// rows"): on the velocities x = v, or (`position`) the push-out's displacement x, with the
// impulses so far in state.contact.lagging. True when it changed any.
bool solve_limit_rows(FeatherstoneState& state, const ConstraintGroup& group, double dt, bool position, const Eigen::VectorXd& x);

}  // namespace limber::joint_space
