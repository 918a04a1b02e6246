// The joint-space response that the Featherstone method's contacts, limit rows and friction
// share (joint_space_contacts.hpp explains it): an impulse's change of the joint velocities and
// of the bodies' motions through the articulated-body algorithm. Internal to kernel/featherstone.
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/featherstone/featherstone_state.hpp"

namespace limber::joint_space {

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
inline Eigen::Vector3d point_motion(const PluckerTransform& world_to_body, const SpatialVector& motion, const Eigen::Vector3d& point) {
  const Eigen::Matrix3d& e = world_to_body.rotation;
  return e.transpose() * motion.tail<3>() + (e.transpose() * motion.head<3>()).cross(point - world_to_body.translation);
}

// Subtracts the spatial impulse of a world impulse J at world `point` from body i's ABA bias p
// (p = −f): f = (E((p − r) × J), E J), body coordinates.
inline void add_world_impulse(FeatherstoneState& state, int i, const Eigen::Vector3d& point, const Eigen::Vector3d& impulse) {
  const PluckerTransform& world_to_body = state.kinematics.world_to_body[static_cast<std::size_t>(i)];
  SpatialVector& bias = state.contact.spatial_impulse[static_cast<std::size_t>(i)];
  bias.head<3>() -= world_to_body.rotation * (point - world_to_body.translation).cross(impulse);
  bias.tail<3>() -= world_to_body.rotation * impulse;
}

// x·v over one joint's `dofs` (≤ 3) velocities from `offset` (element by element: GCC 12 misreads
// a dynamic head() of a fixed Vector3 under AVX-512).
inline double joint_dot(const Eigen::Vector3d& x, const Eigen::VectorXd& v, int offset, int dofs) {
  double sum = 0;
  for (int m = 0; m < dofs; ++m) sum += x[m] * v[offset + m];
  return sum;
}
// v[offset + m] += x[m] for m < dofs.
inline void add_joint_vector(const Eigen::Vector3d& x, Eigen::VectorXd& v, int offset, int dofs) {
  for (int m = 0; m < dofs; ++m) v[offset + m] += x[m];
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
void add_response(FeatherstoneState& state, std::size_t island, const ResponseTarget& target);

// The motion of contact c's material points relative to each other, a's minus b's, m/s (or m),
// for per-tree-body spatial motions `motion`.
Eigen::Vector3d relative_motion(const FeatherstoneState& state, const RigidContact& contact, const std::vector<SpatialVector>& motion);

// The impulse +J on a and −J on b at the contact's point: the change of their relative motion
// (m/s per N·s, or m per kg·m), added to `target` when given.
Eigen::Vector3d respond(FeatherstoneState& state, const RigidContact& contact, const Eigen::Vector3d& impulse,
                        const ResponseTarget* target);

}  // namespace limber::joint_space
