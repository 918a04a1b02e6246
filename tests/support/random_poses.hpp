// Random orientations for the geometry tests' random poses.
#pragma once

#include <random>

#include <Eigen/Geometry>

namespace limber::testing {

/// A rotation drawn uniformly (a normalized 4-D Gaussian quaternion).
inline Eigen::Matrix3d random_rotation(std::mt19937& random) {
  std::normal_distribution<double> normal;
  return Eigen::Quaterniond(normal(random), normal(random), normal(random), normal(random)).normalized().toRotationMatrix();
}

}  // namespace limber::testing
