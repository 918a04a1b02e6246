// Helpers the Featherstone method's contacts, limit rows and joint friction share
// (joint_space_contacts.hpp explains them): projections on a joint's motion subspace, sums over
// a joint's velocities, and the passes' tolerances. Internal to kernel/featherstone.
#pragma once

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

// J_g of the impulses not yet in x: Y_gᵀ y (JointSpaceContactScratch::lagging).
inline Eigen::Vector3d lagging_motion(const JointSpaceContactScratch& s, std::size_t g) {
  Eigen::Vector3d motion = Eigen::Vector3d::Zero();
  for (int e = s.row_begin[g]; e < s.half_end[g]; ++e) {
    motion += s.half_value[static_cast<std::size_t>(e)] * s.lagging[s.half_coordinate[static_cast<std::size_t>(e)]];
  }
  return motion;
}

// The impulse ι on block g's rows: y += D⁻¹ Y_g ι, on its path alone; its motion
// H⁻¹ J_gᵀ ι = L⁻¹ D⁻¹ Y_g ι joins x when the passes settle (joint_space_contacts.cpp).
inline void respond(JointSpaceContactScratch& s, std::size_t g, const Eigen::Vector3d& impulse) {
  for (int e = s.row_begin[g]; e < s.half_end[g]; ++e) {
    const int k = s.half_coordinate[static_cast<std::size_t>(e)];
    s.lagging[k] += s.half_value[static_cast<std::size_t>(e)].dot(impulse) * s.factor.inverse_pivot(k);
  }
}

// A change of a contact's impulse that moves no speed by this is not applied (it would cost the
// contact's paths and change nothing that matters), and a pass that applies none ends the
// passes; a limit row's rate is held to it, m/s.
constexpr double kSlowestApproach = 1e-6;
// The push-out leaves a contact alone once what is still to push is below this fraction of its
// target (the rest is pushed out in the next step).
constexpr double kPushTolerance = 0.01;

}  // namespace limber::joint_space
