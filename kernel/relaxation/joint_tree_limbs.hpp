// What the joint trees' build (joint_trees.cpp) and solve (joint_tree_solve.cpp) share: a
// limb's particles as a rigid body. Internal to kernel/relaxation.
#pragma once

#include <Eigen/Core>

#include "limber/kernel/particles/verlet_state.hpp"

namespace limber::joint_tree_limbs {

inline constexpr int kSide = JointTrees::kLimbParticles;

// A limb's pose from its particles x[0..n) (head, tail, then F⁺ F⁻ if framed): its centre of
// mass and its frame (v, w, u); a stick's is the identity but for u in the third column.
struct LimbPose {
  Eigen::Vector3d centre;
  Eigen::Matrix3d frame;
};
inline LimbPose limb_pose(const Eigen::Vector3d* x, const double* mass, int n, bool framed) {
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  double total = 0;
  for (int k = 0; k < n; ++k) moment += mass[k] * x[k], total += mass[k];
  Eigen::Vector3d u = x[0] - x[1];
  u = u.norm() > 0 ? Eigen::Vector3d(u.normalized()) : Eigen::Vector3d::UnitZ();
  Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();
  frame.col(2) = u;
  if (framed) {
    Eigen::Vector3d v = x[2] - x[3];
    v -= v.dot(u) * u;
    v = v.norm() > 0 ? Eigen::Vector3d(v.normalized()) : Eigen::Vector3d::UnitX();
    frame.col(0) = v, frame.col(1) = u.cross(v);
  }
  return {moment / total, frame};
}

// A limb's particles' positions and masses; returns their count.
template <typename Scalar>
int limb_particles(const VerletState<Scalar>& state, const JointTrees& trees, std::size_t limb, Eigen::Vector3d* x, double* mass) {
  const auto& particles = trees.limb_particles[limb];
  int n = 0;
  for (; n < kSide && particles[n] != state.particles.null_particle(); ++n) {
    x[n] = state.particles.position(particles[n]).template cast<double>();
    mass[n] = 1.0 / static_cast<double>(state.particles.inverse_mass[particles[n]]);
  }
  return n;
}


}  // namespace limber::joint_tree_limbs
