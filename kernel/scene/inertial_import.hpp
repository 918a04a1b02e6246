// A model file's explicit mass distribution moved into a limber body's frame: MJCF's
// <inertial> (kernel/scene/mjcf_model.cpp) and URDF's (kernel/scene/urdf.cpp) alike.
#pragma once

#include <Eigen/Core>

#include "limber/kernel/model/model.hpp"

namespace limber {

/// The Inertial of `body` (its position and orientation set) for a centre of mass at `centre`
/// (m, world) and an inertia tensor `inertia` (kg·m², about that centre) given in a frame whose
/// rotation to world is `rotation`. Exact: a change of frame, symmetrized against round-off.
inline Inertial inertial_in_body_frame(const Body& body, const Eigen::Vector3d& centre, const Eigen::Matrix3d& rotation,
                                       const Eigen::Matrix3d& inertia) {
  const Eigen::Matrix3d to_body = body.orientation().toRotationMatrix().transpose() * rotation;
  Inertial inertial;
  inertial.centre_of_mass = body.orientation().conjugate() * (centre - body.position);
  inertial.inertia = to_body * inertia * to_body.transpose();
  inertial.inertia = 0.5 * (inertial.inertia + inertial.inertia.transpose()).eval();
  return inertial;
}

}  // namespace limber
