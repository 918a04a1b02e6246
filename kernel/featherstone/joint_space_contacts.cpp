#include "limber/kernel/featherstone/joint_space_contacts.hpp"

#include <algorithm>
#include <cmath>

#include "limber/kernel/featherstone/joint_space_limits.hpp"
#include "limber/kernel/featherstone/joint_space_response.hpp"
#include "limber/kernel/featherstone/step.hpp"

namespace limber {
namespace {

using namespace joint_space;

// --- Contacts ------------------------------------------------------------------------------------

// Contact matrices K (three unit test impulses each), approach speeds, and e = 0 for resting
// contacts. Needs the articulated inertias at the current q.
void prepare_contacts(FeatherstoneState& state, double dt) {
  JointSpaceContactScratch& s = state.contact;
  s.contact_matrix.resize(state.contacts.size());
  for (std::size_t c = 0; c < state.contacts.size(); ++c) {
    RigidContact& contact = state.contacts[c];
    Eigen::Matrix3d& k = s.contact_matrix[c];
    for (int axis = 0; axis < 3; ++axis) k.col(axis) = respond(state, contact, Eigen::Vector3d::Unit(axis), nullptr);
    k = 0.5 * (k + k.transpose()).eval();  // symmetric in exact arithmetic
    record_approach(contact, -relative_motion(state, contact, state.kinematics.velocity).dot(contact.normal), state.settings, dt);
  }
}

// Sequential impulses (joint_space_contacts.hpp, "Impulses"), the contacts' and the limit rows'.
void impulse_passes(FeatherstoneState& state, double dt) {
  JointSpaceContactScratch& s = state.contact;
  const ResponseTarget velocities{&state.v, &state.kinematics.velocity};
  for (int pass = 0; pass < state.contact_iterations; ++pass) {
    bool applied = false;  // a pass that applies nothing leaves nothing for the next
    for (std::size_t c = 0; c < state.contacts.size(); ++c) {
      const RigidContact& contact = state.contacts[c];
      const Eigen::Matrix3d& k = s.contact_matrix[c];
      const Eigen::Vector3d& normal = contact.normal;
      const Eigen::Vector3d relative = relative_motion(state, contact, state.kinematics.velocity);
      const double normal_speed = relative.dot(normal);
      const double normal_inverse_mass = normal.dot(k * normal);
      if (normal_speed >= -kSlowestApproach || !(normal_inverse_mass > 0)) continue;
      const double normal_impulse = -(1 + contact.restitution) * normal_speed / normal_inverse_mass;
      Eigen::Vector3d impulse = normal_impulse * normal;
      const Eigen::Vector3d after = relative + k * impulse;
      const Eigen::Vector3d sliding = after - after.dot(normal) * normal;
      const double sliding_speed = sliding.norm();
      if (contact.friction > 0 && sliding_speed > 1e-12 * relative.norm()) {
        const Eigen::Vector3d tangent = sliding / sliding_speed;
        const double tangent_inverse_mass = tangent.dot(k * tangent);
        if (tangent_inverse_mass > 0) impulse -= std::min(sliding_speed / tangent_inverse_mass, contact.friction * normal_impulse) * tangent;
      }
      respond(state, contact, impulse, &velocities);
      applied = true;
    }
    // Limits: accumulated λ ≥ 0 with direction·v ≥ −max(C, 0)/Δt (restitution 0; a limit not yet
    // reached lets the joint arrive at it by the step's end), each island's rows together.
    if (solve_limit_rows(state, dt, /*position=*/false)) applied = true;
    if (!applied) break;
  }
}

// The position pass (joint_space_contacts.hpp, "Penetration").
void push_out(FeatherstoneState& state, double dt) {
  JointSpaceContactScratch& s = state.contact;
  s.displacement.setZero();
  for (SpatialVector& d : s.body_displacement) d.setZero();
  s.push.assign(state.contacts.size(), 0.0);  // within the capacity reserved at compile
  const ResponseTarget displacements{&s.displacement, &s.body_displacement};
  bool moved = false;
  for (int pass = 0; pass < state.contact_iterations; ++pass) {
    bool pushed = false;
    for (std::size_t c = 0; c < state.contacts.size(); ++c) {
      const RigidContact& contact = state.contacts[c];
      const double target = push_out_distance(contact, state.settings, dt);
      const double normal_inverse_mass = contact.normal.dot(s.contact_matrix[c] * contact.normal);
      if (!(target > 0) || !(normal_inverse_mass > 0)) continue;
      const double done = relative_motion(state, contact, s.body_displacement).dot(contact.normal);
      if (std::abs(target - done) <= kPushTolerance * target) continue;
      const double push = std::max(s.push[c] + (target - done) / normal_inverse_mass, 0.0);
      const double change = push - s.push[c];
      if (change == 0) continue;
      s.push[c] = push;
      respond(state, contact, change * contact.normal, &displacements);
      moved = pushed = true;
    }
    if (solve_limit_rows(state, dt, /*position=*/true)) moved = pushed = true;
    if (!pushed) break;
  }
  if (!moved) return;
  // Every body's momentum in its own frame, I_i v_i, before the push-out.
  const ArticulatedTree& tree = state.tree;
  for (int i = 0; i < tree.body_count(); ++i) {
    const auto index = static_cast<std::size_t>(i);
    s.body_momentum[index] = tree.body(i).inertia * state.kinematics.velocity[index];
  }
  displace_positions(tree, state.q, s.displacement, state.q);
  body_poses(tree, state.q, state.kinematics);
  // The joint velocities that keep every body's motion in its own frame as closely as the joints
  // allow at the new pose, in the kinetic-energy metric: v = H⁻¹ Σ J_iᵀ I_i v_i, by the inward
  // pass and ABA with v = 0, g = 0. An H-orthogonal projection of motions whose energy is the old
  // one, so it never adds kinetic energy — where keeping v would: v holds relative velocities in
  // the child frames the push-out turned, and a limb spinning fast about its axis relative to its
  // parent would swing that spin onto its neighbours.
  joint_forces_of_body_forces(state, s.body_momentum, s.generalized_momentum);
  forward_dynamics(tree, state.q, s.zero_velocities, s.generalized_momentum, Eigen::Vector3d::Zero(), s.articulated, state.v);
}

// The contacts and limit rows of the step, their matrices and inverse masses; false when there are
// none.
bool prepare_constraints(FeatherstoneState& state, double dt) {
  find_limit_rows(state, dt);
  if (state.contacts.empty() && state.controls.rows.empty()) return false;
  JointSpaceContactScratch& s = state.contact;
  forward_dynamics(state.tree, state.q, s.zero_velocities, s.zero_forces, Eigen::Vector3d::Zero(), s.articulated, s.unused_accelerations);
  prepare_contacts(state, dt);
  measure_limit_rows(state);
  return true;
}

}  // namespace

void apply_joint_space_impulses(FeatherstoneState& state, double dt) {
  if (!prepare_constraints(state, dt)) return;
  impulse_passes(state, dt);
  refresh_rigid_bodies(state);
}

void resolve_joint_space_contacts(FeatherstoneState& state, double dt) {
  if (!prepare_constraints(state, dt)) return;
  impulse_passes(state, dt);
  push_out(state, dt);
  refresh_rigid_bodies(state);
}

}  // namespace limber
