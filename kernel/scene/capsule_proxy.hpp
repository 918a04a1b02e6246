// A box or ellipsoid on a moving body, as the capsule it collides as: limber's moving bodies are
// capsules and cylinders (every method's narrow phase, the particles' limbs), so a model file's
// box or ellipsoid geom keeps its exact mass, centre and inertia (Body::inertial) and collides as
// the capsule along its longest axis with the radius of its shortest. Lying on its largest face
// it rests at its true height; across its middle axis it is thinner by the middle half-extent
// minus the shortest (kernel/scene/MJCF.md, "Boxes and ellipsoids on moving bodies").
#pragma once

#include <Eigen/Core>

#include "limber/kernel/model/model.hpp"

namespace limber {

struct CapsuleProxy {
  Shape shape;    ///< a capsule: total extent 2·longest, radius the shortest (length 0: a sphere)
  int along = 0;  ///< 0, 1 or 2: which of the geom frame's axes the capsule lies along
};

/// The proxy of a box of half-extents, or an ellipsoid of semi-axes, `half` (m, each > 0, along
/// the geom frame's x, y, z).
inline CapsuleProxy capsule_proxy(const Eigen::Vector3d& half) {
  CapsuleProxy proxy;
  half.maxCoeff(&proxy.along);
  const double radius = half.minCoeff();
  proxy.shape = Shape{ShapeType::capsule, 2 * (half[proxy.along] - radius), radius};
  return proxy;
}

}  // namespace limber
