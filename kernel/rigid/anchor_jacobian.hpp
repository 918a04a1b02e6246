// The velocity of a point fixed in a rigid body: ṗ = v + ω × r = G·(v, ω), G = [E, −[r]×].
// Every joint Jacobian of the rigid-body methods is built from these blocks (thesis figure 3.5).
#pragma once

#include <Eigen/Core>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// [r]×, the matrix with [r]×·x = r × x.
inline Eigen::Matrix3d cross_matrix(const Eigen::Vector3d& r) {
  Eigen::Matrix3d m;
  m << 0, -r.z(), r.y(), r.z(), 0, -r.x(), -r.y(), r.x(), 0;
  return m;
}

using AnchorJacobian = Eigen::Matrix<double, 3, 6>;

/// G = [E, −[r]×] (3×6): the anchor's velocity from its body's (v, ω); `lever` r is the anchor
/// minus the centre of mass, world frame, m.
inline AnchorJacobian anchor_jacobian(const Eigen::Vector3d& lever) {
  AnchorJacobian g;
  g.leftCols<3>().setIdentity();
  g.rightCols<3>() = -cross_matrix(lever);
  return g;
}

}  // namespace limber
