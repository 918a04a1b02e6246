// Random kinematic trees and states for the Featherstone tests: chains and branching trees of
// random joints, frames and mass distributions (real ones: each body's inertia is that of a
// solid box, so MuJoCo's compiler accepts it too).
#pragma once

#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/kernel/featherstone/articulated_tree.hpp"

namespace limber::testing {

struct RandomTreeOptions {
  int bodies = 8;
  bool branching = false;      ///< false: a chain (parent i − 1); true: a random earlier parent
  bool floating_base = false;  ///< body 0 is a floating joint on the world
  std::vector<ArticulatedJoint> joints = {ArticulatedJoint::revolute, ArticulatedJoint::prismatic, ArticulatedJoint::spherical, ArticulatedJoint::fixed};
};

inline double uniform(std::mt19937& rng, double low, double high) { return std::uniform_real_distribution<double>(low, high)(rng); }

inline Eigen::Vector3d uniform_vector(std::mt19937& rng, double low, double high) {
  return {uniform(rng, low, high), uniform(rng, low, high), uniform(rng, low, high)};
}

inline Eigen::Vector3d random_unit_vector(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::Vector3d u;
  do u = Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  while (u.norm() < 1e-3);
  return u.normalized();
}

/// Uniformly distributed over rotations (a normalized 4-D Gaussian).
inline Eigen::Quaterniond random_rotation(std::mt19937& rng) {
  std::normal_distribution<double> normal;
  Eigen::Quaterniond q;
  do q = Eigen::Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng));
  while (q.norm() < 1e-3);
  return q.normalized();
}

/// A solid box of random mass (0.5–2 kg) and sides (0.05–0.5 m), turned by a random rotation and
/// centred at a random point within 0.2 m of the frame origin.
inline SpatialInertia random_inertia(std::mt19937& rng) {
  const double mass = uniform(rng, 0.5, 2);
  const Eigen::Vector3d sides = uniform_vector(rng, 0.05, 0.5);
  const Eigen::Vector3d squares = sides.cwiseProduct(sides);
  const Eigen::Vector3d moments = mass / 12 * Eigen::Vector3d(squares.y() + squares.z(), squares.x() + squares.z(), squares.x() + squares.y());
  const Eigen::Matrix3d turn = random_rotation(rng).toRotationMatrix();
  const Eigen::Matrix3d about_centre = turn * moments.asDiagonal() * turn.transpose();
  return SpatialInertia::from_mass_properties(mass, uniform_vector(rng, -0.2, 0.2), 0.5 * (about_centre + about_centre.transpose()));
}

inline ArticulatedTree random_tree(std::mt19937& rng, const RandomTreeOptions& options) {
  ArticulatedTree tree;
  for (int i = 0; i < options.bodies; ++i) {
    ArticulatedBody body;
    body.name = "body_" + std::to_string(i);
    if (options.floating_base && i == 0) {
      body.parent = -1;
      body.joint = ArticulatedJoint::floating;
    } else {
      const int lowest = options.floating_base ? 0 : -1;
      body.parent = options.branching ? std::uniform_int_distribution<int>(lowest, i - 1)(rng) : i - 1;
      body.joint = options.joints[std::uniform_int_distribution<std::size_t>(0, options.joints.size() - 1)(rng)];
      body.tree_transform = PluckerTransform::from_pose(random_rotation(rng).toRotationMatrix(), uniform_vector(rng, -0.5, 0.5));
    }
    body.joint_axis = random_unit_vector(rng);
    body.inertia = random_inertia(rng);
    tree.add_body(body);
  }
  return tree;
}

/// Random positions: angles in [−π, π], displacements in [−0.5, 0.5] m, uniform quaternions,
/// floating positions within 1 m.
inline Eigen::VectorXd random_positions(std::mt19937& rng, const ArticulatedTree& tree) {
  Eigen::VectorXd q(tree.position_count());
  for (int i = 0; i < tree.body_count(); ++i) {
    const int p = tree.position_offset(i);
    Eigen::Quaterniond orientation;
    switch (tree.body(i).joint) {
      case ArticulatedJoint::revolute: q[p] = uniform(rng, -std::numbers::pi, std::numbers::pi); break;
      case ArticulatedJoint::prismatic: q[p] = uniform(rng, -0.5, 0.5); break;
      case ArticulatedJoint::spherical:
        orientation = random_rotation(rng);
        q.segment<4>(p) << orientation.w(), orientation.x(), orientation.y(), orientation.z();
        break;
      case ArticulatedJoint::floating:
        orientation = random_rotation(rng);
        q.segment<3>(p) = uniform_vector(rng, -1, 1);
        q.segment<4>(p + 3) << orientation.w(), orientation.x(), orientation.y(), orientation.z();
        break;
      case ArticulatedJoint::fixed: break;
    }
  }
  return q;
}

inline Eigen::VectorXd random_vector(std::mt19937& rng, int size, double magnitude) {
  Eigen::VectorXd x(size);
  for (int k = 0; k < size; ++k) x[k] = uniform(rng, -magnitude, magnitude);
  return x;
}

/// Chains and branching trees of 1–15 bodies, with and without a floating base; a chain of
/// spherical joints; a branching tree of revolute and fixed joints.
inline std::vector<RandomTreeOptions> random_tree_kinds() {
  std::vector<RandomTreeOptions> kinds;
  for (const bool branching : {false, true}) {
    for (const bool floating_base : {false, true}) {
      for (const int bodies : {1, 2, 7, 15}) kinds.push_back({.bodies = bodies, .branching = branching, .floating_base = floating_base});
    }
  }
  kinds.push_back({.bodies = 10, .joints = {ArticulatedJoint::spherical}});
  kinds.push_back({.bodies = 10, .branching = true, .joints = {ArticulatedJoint::revolute, ArticulatedJoint::fixed}});
  return kinds;
}

}  // namespace limber::testing
