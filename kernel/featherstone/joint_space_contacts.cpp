#include "limber/kernel/featherstone/joint_space_contacts.hpp"

#include <algorithm>
#include <functional>
#include <cmath>
#include <limits>

#include "limber/kernel/featherstone/joint_space_limits.hpp"
#include "limber/kernel/featherstone/joint_space_response.hpp"
#include "limber/kernel/featherstone/step.hpp"

namespace limber {
namespace {

using namespace joint_space;

// --- Contacts ------------------------------------------------------------------------------------

// Contact c's rows J_c (joint_space_contacts.hpp, "Responses"): for each of its tree bodies, the
// generalized impulses of unit world impulses along x, y, z at its point — the spatial impulses
// carried from the body to the root, τ_k = S_kᵀ f on every joint k on the way (Table 5.1's inward
// pass) — b's negated.
void contact_rows(FeatherstoneState& state, const RigidContact& contact) {
  JointSpaceContactScratch& s = state.contact;
  const ArticulatedTree& tree = state.tree;
  for (const std::int32_t scene_body : {contact.a, contact.b}) {
    if (scene_body < 0) continue;  // a plane
    const double sign = scene_body == contact.a ? 1.0 : -1.0;
    int i = state.tree_body[scene_body];
    const PluckerTransform& world_to_body = state.kinematics.world_to_body[static_cast<std::size_t>(i)];
    SpatialVector f[3];
    for (int axis = 0; axis < 3; ++axis) {
      const Eigen::Vector3d impulse = sign * Eigen::Vector3d::Unit(axis);
      f[axis] << world_to_body.rotation * (contact.point - world_to_body.translation).cross(impulse), world_to_body.rotation * impulse;
    }
    for (;;) {
      const ArticulatedBody& body = tree.body(i);
      with_degrees_of_freedom(body.joint, [&](auto dofs) {
        constexpr int k = decltype(dofs)::value;
        if constexpr (k > 0) {
          Eigen::Matrix<double, k, 1> on_joint[3];
          for (int axis = 0; axis < 3; ++axis) on_joint[axis] = project_on_joint<k>(body, f[axis]);
          for (int r = 0; r < k; ++r) {
            s.row_coordinate.push_back(tree.velocity_offset(i) + r);
            s.row_value.emplace_back(on_joint[0][r], on_joint[1][r], on_joint[2][r]);
          }
        }
      });
      if (body.parent < 0) break;
      for (SpatialVector& force : f) force = state.kinematics.parent_to_body[static_cast<std::size_t>(i)].transpose_apply_force(force);
      i = body.parent;
    }
  }
  s.row_begin.push_back(static_cast<int>(s.row_coordinate.size()));
}

// The entries of limit row `row`'s block: direction on its joint's velocities, zeros on the
// rest of its path to the root (joint_space_contacts.hpp, "Constraint space").
void limit_row_entries(FeatherstoneState& state, const JointLimitRow& row) {
  JointSpaceContactScratch& s = state.contact;
  for (int i = row.body; i >= 0; i = state.tree.body(i).parent) {
    const int offset = state.tree.velocity_offset(i), dofs = joint_velocity_count(state.tree.body(i).joint);
    for (int k = offset; k < offset + dofs; ++k) {
      const int m = k - row.offset;
      s.row_coordinate.push_back(k);
      s.row_value.emplace_back(m >= 0 && m < row.dofs ? row.direction[m] : 0.0, 0.0, 0.0);
    }
  }
  s.row_begin.push_back(static_cast<int>(s.row_coordinate.size()));
}

// J_g x: block g's rows' motion (m/s for velocities x = v, m for a push-out's displacement).
Eigen::Vector3d block_motion(const JointSpaceContactScratch& s, std::size_t g, const Eigen::VectorXd& x) {
  Eigen::Vector3d motion = Eigen::Vector3d::Zero();
  for (int e = s.row_begin[g]; e < s.row_begin[g + 1]; ++e) motion += s.row_value[static_cast<std::size_t>(e)] * x[s.row_coordinate[static_cast<std::size_t>(e)]];
  return motion;
}

// Block g's half rows Y_g = L⁻ᵀ J_gᵀ (on its path) and its diagonal block Y_gᵀ D⁻¹ Y_g. Needs
// its rows and the factor.
Eigen::Matrix3d half_rows(JointSpaceContactScratch& s, std::size_t g) {
  s.path.clear();
  for (int e = s.row_begin[g]; e < s.row_begin[g + 1]; ++e) {
    const int k = s.row_coordinate[static_cast<std::size_t>(e)];
    s.scatter.row(k) += s.row_value[static_cast<std::size_t>(e)].transpose();
    s.path.push_back(k);
  }
  std::sort(s.path.begin(), s.path.end(), std::greater<>());
  s.path.erase(std::unique(s.path.begin(), s.path.end()), s.path.end());
  s.factor.solve_transposed_lower(s.scatter, s.path);
  Eigen::Matrix3d diagonal = Eigen::Matrix3d::Zero();
  for (const int k : s.path) {
    const Eigen::Vector3d y = s.scatter.row(k).transpose();
    s.scatter.row(k).setZero();
    s.half_coordinate.push_back(k);
    s.half_value.push_back(y);
    diagonal.noalias() += y * y.transpose() / s.factor.pivot(k);
  }
  s.half_begin.push_back(static_cast<int>(s.half_coordinate.size()));
  return diagonal;
}

// Sequential impulses (joint_space_contacts.hpp, "Impulses"), the contacts' and the limit rows'.
void impulse_passes(FeatherstoneState& state, double dt) {
  JointSpaceContactScratch& s = state.contact;
  for (JointLimitRow& row : state.controls.rows) row.impulse = 0;
  for (int pass = 0; pass < state.contact_iterations; ++pass) {
    bool applied = false;  // a pass that applies nothing leaves nothing for the next
    for (std::size_t c = 0; c < state.contacts.size(); ++c) {
      const RigidContact& contact = state.contacts[c];
      const Eigen::Matrix3d& k = s.contact_matrix[c];
      const Eigen::Vector3d& normal = contact.normal;
      const Eigen::Vector3d relative = block_motion(s, c, state.v) + lagging_motion(s, c);
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
      respond(s, c, impulse);
      applied = true;
    }
    // Limits: accumulated λ ≥ 0 with direction·v ≥ −max(C, 0)/Δt (restitution 0; a limit not yet
    // reached lets the joint arrive at it by the step's end), each island's rows together.
    if (!state.controls.rows.empty() && solve_limit_rows(state, dt, /*position=*/false, state.v)) applied = true;
    if (!applied) break;
  }
  settle(s, state.v);
}

// The position pass (joint_space_contacts.hpp, "Penetration").
void push_out(FeatherstoneState& state, double dt) {
  JointSpaceContactScratch& s = state.contact;
  s.displacement.setZero();
  s.push.assign(state.contacts.size(), 0.0);  // within the capacity reserved at compile
  for (JointLimitRow& row : state.controls.rows) row.push = 0;
  bool moved = false;
  for (int pass = 0; pass < state.contact_iterations; ++pass) {
    bool pushed = false;
    for (std::size_t c = 0; c < state.contacts.size(); ++c) {
      const RigidContact& contact = state.contacts[c];
      const double target = push_out_distance(contact, state.settings, dt);
      const double normal_inverse_mass = contact.normal.dot(s.contact_matrix[c] * contact.normal);
      if (!(target > 0) || !(normal_inverse_mass > 0)) continue;
      const double done = lagging_motion(s, c).dot(contact.normal);  // the displacement is all in y until settled
      if (std::abs(target - done) <= kPushTolerance * target) continue;
      const double push = std::max(s.push[c] + (target - done) / normal_inverse_mass, 0.0);
      const double change = push - s.push[c];
      if (change == 0) continue;
      s.push[c] = push;
      respond(s, c, change * contact.normal);
      moved = pushed = true;
    }
    if (!state.controls.rows.empty() && solve_limit_rows(state, dt, /*position=*/true, s.displacement)) moved = pushed = true;
    if (!pushed) break;
  }
  if (!moved) return;
  settle(s, s.displacement);
  // Every body's momentum in its own frame, I_i v_i, before the push-out (the impulses' v; the
  // poses are those detection saw).
  const ArticulatedTree& tree = state.tree;
  body_velocities(tree, state.v, state.kinematics);
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
  forward_dynamics(tree, state.kinematics, s.zero_velocities, s.generalized_momentum, nullptr, Eigen::Vector3d::Zero(), s.articulated, state.v);
}

// The step's blocks — the contacts, then the limit rows — their rows and half rows through the
// factor of H at the current q, the contacts' K, the limit rows' Delassus matrix per island,
// approach speeds and e = 0 for resting contacts; false when there are none.
bool prepare_constraints(FeatherstoneState& state, double dt) {
  find_limit_rows(state, dt);
  if (state.contacts.empty() && state.controls.rows.empty()) return false;
  JointSpaceContactScratch& s = state.contact;
  if (s.factor.size() != state.tree.velocity_count()) s.factor.assign(state.tree);  // a large tree's first use (compile.cpp)
  mass_matrix(state.tree, state.kinematics, s.composite, s.factor);  // at the poses detection saw
  if (s.factor.factor() >= 0) {
    // H is positive definite at any finite pose; it is not only once the state has gone
    // non-finite. Say so through v, which the step's status checks, instead of answering the
    // contacts with a broken factor.
    state.v.setConstant(std::numeric_limits<double>::quiet_NaN());
    return false;
  }
  s.row_begin.assign(1, 0);
  s.row_coordinate.clear(), s.row_value.clear();
  s.half_begin.assign(1, 0);
  s.half_coordinate.clear(), s.half_value.clear();
  s.contact_matrix.resize(state.contacts.size());
  for (std::size_t c = 0; c < state.contacts.size(); ++c) {
    RigidContact& contact = state.contacts[c];
    contact_rows(state, contact);
    s.contact_matrix[c] = half_rows(s, c);
    record_approach(contact, -block_motion(s, c, state.v).dot(contact.normal), state.settings, dt);
  }
  for (JointLimitRow& row : state.controls.rows) {
    limit_row_entries(state, row);
    row.inverse_mass = half_rows(s, state.contacts.size() + static_cast<std::size_t>(&row - state.controls.rows.data()))(0, 0);
  }
  form_limit_delassus(state);
  return true;
}

// The passes leave state.kinematics' poses those of q (the push-out's body_poses when it moved
// q): the rigid bodies need only the new velocities.
void mirror_new_velocities(FeatherstoneState& state) {
  body_velocities(state.tree, state.v, state.kinematics);
  mirror_rigid_bodies(state);
}

}  // namespace

void apply_joint_space_impulses(FeatherstoneState& state, double dt) {
  if (!prepare_constraints(state, dt)) return;
  impulse_passes(state, dt);
  mirror_new_velocities(state);
}

void resolve_joint_space_contacts(FeatherstoneState& state, double dt) {
  if (!prepare_constraints(state, dt)) return;
  impulse_passes(state, dt);
  push_out(state, dt);
  mirror_new_velocities(state);
}

}  // namespace limber
