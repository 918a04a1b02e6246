// The Featherstone method's joint limits as rows, its joint friction and its drives, in joint
// space (joint_space_contacts.hpp, "Joint limits", "Drives and friction"; joint_control_forces
// and the other public calls are declared there). What the contacts' passes
// (joint_space_contacts.cpp) take from here. Internal to kernel/featherstone.
#pragma once

#include "limber/kernel/featherstone/featherstone_state.hpp"

namespace limber::joint_space {

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
