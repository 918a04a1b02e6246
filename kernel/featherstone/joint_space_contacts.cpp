// GCC 12 false positive inside Eigen's AVX-512 code (bug 105593); must precede Eigen's headers.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "limber/kernel/featherstone/joint_space_contacts.hpp"

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "limber/kernel/featherstone/step.hpp"

namespace limber {
namespace {

// Sᵀ f (k values) for body i's joint (Table 4.1's S, child coordinates).
template <int k>
Eigen::Matrix<double, k, 1> project_on_joint(const ArticulatedBody& body, const SpatialVector& f) {
  if constexpr (k == 1) {
    const double value = body.joint == ArticulatedJoint::revolute ? body.joint_axis.dot(f.head<3>()) : body.joint_axis.dot(f.tail<3>());
    return Eigen::Matrix<double, 1, 1>(value);
  } else if constexpr (k == 3) {
    return f.head<3>();
  } else {
    return f;
  }
}

// S x: the spatial motion of joint rates x.
template <int k>
SpatialVector joint_motion(const ArticulatedBody& body, const Eigen::Matrix<double, k, 1>& x) {
  SpatialVector out = SpatialVector::Zero();
  if constexpr (k == 1) {
    if (body.joint == ArticulatedJoint::revolute) {
      out.head<3>() = body.joint_axis * x[0];
    } else {
      out.tail<3>() = body.joint_axis * x[0];
    }
  } else if constexpr (k == 3) {
    out.head<3>() = x;
  } else {
    out = x;
  }
  return out;
}

// The world velocity (m/s) of body i's material point at world `point`, for its spatial
// velocity `motion` (body coordinates; or a displacement, m): Eᵀv + Eᵀω × (p − r).
Eigen::Vector3d point_motion(const PluckerTransform& world_to_body, const SpatialVector& motion, const Eigen::Vector3d& point) {
  const Eigen::Matrix3d& e = world_to_body.rotation;
  return e.transpose() * motion.tail<3>() + (e.transpose() * motion.head<3>()).cross(point - world_to_body.translation);
}

// Subtracts the spatial impulse of a world impulse J at world `point` from body i's ABA bias p
// (p = −f): f = (E((p − r) × J), E J), body coordinates.
void add_world_impulse(FeatherstoneState& state, int i, const Eigen::Vector3d& point, const Eigen::Vector3d& impulse) {
  const PluckerTransform& world_to_body = state.kinematics.world_to_body[static_cast<std::size_t>(i)];
  SpatialVector& bias = state.contact.spatial_impulse[static_cast<std::size_t>(i)];
  bias.head<3>() -= world_to_body.rotation * (point - world_to_body.translation).cross(impulse);
  bias.tail<3>() -= world_to_body.rotation * impulse;
}

// The response of island `island` to the biases p = −f in contact.spatial_impulse (which it
// clears): ABA with v = 0, g = 0, τ = 0 (joint_space_contacts.hpp), into contact.body_change
// (Δa_i, every body of the island) and contact.joint_change (Δv, the island's slice).
void impulse_response(FeatherstoneState& state, std::size_t island) {
  const ArticulatedTree& tree = state.tree;
  JointSpaceContactScratch& s = state.contact;
  const DynamicsWorkspace& w = s.articulated;
  const int begin = state.island_begin[island], end = state.island_begin[island + 1];
  // Inward: u_i = −S_iᵀ p_i (the generalized impulse), p_λ += λX_i*(p_i + U_i D_i⁻¹ u_i).
  for (int i = end - 1; i >= begin; --i) {
    const ArticulatedBody& body = tree.body(i);
    const auto index = static_cast<std::size_t>(i);
    const int offset = tree.velocity_offset(i);
    SpatialVector through = s.spatial_impulse[index];
    s.spatial_impulse[index].setZero();
    const bool untouched = through.isZero(0);  // no impulse on this body or below it: u_i = 0
    with_degrees_of_freedom(body.joint, [&](auto dofs) {
      constexpr int k = decltype(dofs)::value;
      if constexpr (k > 0) {
        if (untouched) {
          s.joint_bias.template segment<k>(offset).setZero();
          return;
        }
        const Eigen::Matrix<double, k, 1> u = -project_on_joint<k>(body, through);
        s.joint_bias.template segment<k>(offset) = u;
        through.noalias() += w.projected_inertia.template middleCols<k>(offset) * (w.joint_inertia_inverse.template block<k, k>(0, offset) * u);
      }
    });
    if (body.parent >= 0 && !untouched) {
      s.spatial_impulse[static_cast<std::size_t>(body.parent)] += w.parent_to_body[index].transpose_apply_force(through);
    }
  }
  // Outward: Δv_i = D_i⁻¹(u_i − U_iᵀ a'), Δa_i = a' + S_i Δv_i with a' = ⁱX_λ Δa_λ.
  for (int i = begin; i < end; ++i) {
    const ArticulatedBody& body = tree.body(i);
    const auto index = static_cast<std::size_t>(i);
    const int offset = tree.velocity_offset(i);
    SpatialVector change = body.parent >= 0 ? w.parent_to_body[index].apply_motion(s.body_change[static_cast<std::size_t>(body.parent)])
                                            : SpatialVector::Zero();
    with_degrees_of_freedom(body.joint, [&](auto dofs) {
      constexpr int k = decltype(dofs)::value;
      if constexpr (k > 0) {
        const Eigen::Matrix<double, k, 1> rates =
            w.joint_inertia_inverse.template block<k, k>(0, offset) *
            (s.joint_bias.template segment<k>(offset) - w.projected_inertia.template middleCols<k>(offset).transpose() * change);
        s.joint_change.template segment<k>(offset) = rates;
        change += joint_motion<k>(body, rates);
      }
    });
    s.body_change[index] = change;
  }
}

// Approach speeds below this are left to the push-out (an impulse for them would cost a pass
// over the island and change nothing that matters), m/s.
constexpr double kSlowestApproach = 1e-6;
// The push-out leaves a contact alone once what is still to push is below this fraction of its
// target (the rest is pushed out in the next step).
constexpr double kPushTolerance = 0.01;

// What an impulse changes: joint velocities and bodies' spatial velocities, or the push-out's
// displacement and bodies' spatial displacements.
struct ResponseTarget {
  Eigen::VectorXd* joints = nullptr;              // nv
  std::vector<SpatialVector>* bodies = nullptr;   // per tree body
};

// Adds the last response of island `island` to `target`.
void add_response(FeatherstoneState& state, std::size_t island, const ResponseTarget& target) {
  const auto [first, last] = island_velocities(state, island);
  target.joints->segment(first, last - first) += state.contact.joint_change.segment(first, last - first);
  for (std::int32_t i = state.island_begin[island]; i < state.island_begin[island + 1]; ++i) {
    (*target.bodies)[static_cast<std::size_t>(i)] += state.contact.body_change[static_cast<std::size_t>(i)];
  }
}

// The motion of contact c's material points relative to each other, a's minus b's, m/s (or m),
// for per-tree-body spatial motions `motion`.
Eigen::Vector3d relative_motion(const FeatherstoneState& state, const RigidContact& contact, const std::vector<SpatialVector>& motion) {
  const auto point_of = [&](std::int32_t body) -> Eigen::Vector3d {
    if (body < 0) return Eigen::Vector3d::Zero();
    const auto i = static_cast<std::size_t>(state.tree_body[body]);
    return point_motion(state.kinematics.world_to_body[i], motion[i], contact.point);
  };
  return point_of(contact.a) - point_of(contact.b);
}

// The impulse +J on a and −J on b at the contact's point: the change of their relative motion
// (m/s per N·s, or m per kg·m), added to `target` when given.
Eigen::Vector3d respond(FeatherstoneState& state, const RigidContact& contact, const Eigen::Vector3d& impulse,
                        const ResponseTarget* target) {
  const JointSpaceContactScratch& s = state.contact;
  const auto point_change = [&](std::int32_t body) {
    const auto i = static_cast<std::size_t>(state.tree_body[body]);
    return point_motion(state.kinematics.world_to_body[i], s.body_change[i], contact.point);
  };
  const auto solve = [&](std::size_t island) {
    impulse_response(state, island);
    if (target) add_response(state, island, *target);
  };
  const std::size_t island_a = state.island_of_body[contact.a];
  add_world_impulse(state, state.tree_body[contact.a], contact.point, impulse);
  if (contact.b < 0) {  // a plane
    solve(island_a);
    return point_change(contact.a);
  }
  const std::size_t island_b = state.island_of_body[contact.b];
  if (island_b == island_a) {  // one response for both impulses
    add_world_impulse(state, state.tree_body[contact.b], contact.point, -impulse);
    solve(island_a);
    return point_change(contact.a) - point_change(contact.b);
  }
  solve(island_a);
  Eigen::Vector3d change = point_change(contact.a);
  add_world_impulse(state, state.tree_body[contact.b], contact.point, -impulse);
  solve(island_b);
  return change - point_change(contact.b);
}

// Contact matrices K (three unit test impulses each), approach speeds, and e = 0 for resting
// contacts. Needs the articulated inertias at the current q.
void prepare_contacts(FeatherstoneState& state, double dt) {
  JointSpaceContactScratch& s = state.contact;
  forward_dynamics(state.tree, state.q, s.zero_velocities, s.zero_forces, Eigen::Vector3d::Zero(), s.articulated, s.unused_accelerations);
  const double resting_speed = 2 * state.settings.gravity.norm() * dt;
  s.contact_matrix.resize(state.contacts.size());
  for (std::size_t c = 0; c < state.contacts.size(); ++c) {
    RigidContact& contact = state.contacts[c];
    Eigen::Matrix3d& k = s.contact_matrix[c];
    for (int axis = 0; axis < 3; ++axis) k.col(axis) = respond(state, contact, Eigen::Vector3d::Unit(axis), nullptr);
    k = 0.5 * (k + k.transpose()).eval();  // symmetric in exact arithmetic
    const double approach = -relative_motion(state, contact, state.kinematics.velocity).dot(contact.normal);
    if (approach < resting_speed) contact.restitution = 0;
    contact.approach_speed = std::max(approach, 0.0);
  }
}

// Sequential impulses (joint_space_contacts.hpp, "Impulses").
void impulse_passes(FeatherstoneState& state) {
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
    if (!applied) break;
  }
}

// The position pass (joint_space_contacts.hpp, "Penetration").
void push_out(FeatherstoneState& state, double dt) {
  JointSpaceContactScratch& s = state.contact;
  s.displacement.setZero();
  for (SpatialVector& d : s.body_displacement) d.setZero();
  s.push.assign(state.contacts.size(), 0.0);
  const ResponseTarget displacements{&s.displacement, &s.body_displacement};
  bool moved = false;
  for (int pass = 0; pass < state.contact_iterations; ++pass) {
    bool pushed = false;
    for (std::size_t c = 0; c < state.contacts.size(); ++c) {
      const RigidContact& contact = state.contacts[c];
      // allowed_separation with the separation at the step's start, −depth + approach·Δt.
      const double target =
          contact.depth + allowed_separation(contact.approach_speed * dt - contact.depth, state.settings.contact_recovery_speed * dt);
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

}  // namespace

void apply_joint_space_impulses(FeatherstoneState& state, double dt) {
  if (state.contacts.empty()) return;
  prepare_contacts(state, dt);
  impulse_passes(state);
  refresh_rigid_bodies(state);
}

void resolve_joint_space_contacts(FeatherstoneState& state, double dt) {
  if (state.contacts.empty()) return;
  prepare_contacts(state, dt);
  impulse_passes(state);
  push_out(state, dt);
  refresh_rigid_bodies(state);
}

void joint_forces_of_body_forces(const FeatherstoneState& state, std::vector<SpatialVector>& body_forces, Eigen::VectorXd& joint_forces) {
  const ArticulatedTree& tree = state.tree;
  for (int i = tree.body_count() - 1; i >= 0; --i) {
    const ArticulatedBody& body = tree.body(i);
    const auto index = static_cast<std::size_t>(i);
    const int offset = tree.velocity_offset(i);
    with_degrees_of_freedom(body.joint, [&](auto dofs) {
      constexpr int k = decltype(dofs)::value;
      if constexpr (k > 0) joint_forces.template segment<k>(offset) = project_on_joint<k>(body, body_forces[index]);
    });
    if (body.parent >= 0) {
      body_forces[static_cast<std::size_t>(body.parent)] += state.kinematics.parent_to_body[index].transpose_apply_force(body_forces[index]);
    }
    body_forces[index].setZero();
  }
}

}  // namespace limber
