// A box or ellipsoid as the particle method collides it: the capsule along the body's axis.
//
// The particle method's limbs are segments between particles (thesis 4.1): their contacts are
// rows on the segment's points, so a limb collides as a capsule or a cylinder. A box or an
// ellipsoid limb keeps its exact mass, centre and inertia (Body::inertial, from the true shape) and
// collides as the capsule along the body's axis that spans the shape's extent along it, with the
// radius of its shortest half-extent. The importers put a box's or ellipsoid's longest axis on
// the body's axis, so the capsule runs along it: lying on its largest face such a limb rests at
// its true height; across its middle axis it is thinner by the middle half-extent less the
// shortest. The rigid methods collide the shape itself (kernel/geometry/shape_pairs.hpp).
#pragma once

#include <cmath>

#include <Eigen/Core>

#include "limber/kernel/mass/mass_properties.hpp"
#include "limber/kernel/model/model.hpp"

namespace limber {

/// The capsule a box or ellipsoid shape collides as under the particle method (above); any other
/// shape unchanged.
inline Shape capsule_proxy(const Shape& shape) {
  if (!has_half_extents(shape)) return shape;
  // The shape's half-extent along the body's axis (local z): its support along z.
  const Eigen::Vector3d z_in_shape = shape.rotation.conjugate() * Eigen::Vector3d::UnitZ();
  const double along = shape.type == ShapeType::box ? z_in_shape.cwiseAbs().dot(shape.half_extents)
                                                    : z_in_shape.cwiseProduct(shape.half_extents).norm();
  const double radius = shape.half_extents.minCoeff();
  Shape proxy;
  proxy.type = ShapeType::capsule;
  proxy.radius = radius;
  proxy.length = 2 * std::max(along - radius, 0.0);
  return proxy;
}

/// `model` with every box and ellipsoid limb as its capsule proxy, keeping its mass distribution
/// (its Body::inertial set from the true shape when neither inertial nor point masses give it).
inline Model with_capsule_proxies(Model model) {
  for (Body& body : model.bodies) {
    if (!has_half_extents(body.shape)) continue;
    if (!body.inertial && body.point_masses.empty()) {
      const MassProperties solid = body_mass_properties(body);
      body.inertial = Inertial{solid.centre_of_mass, solid.inertia};
    }
    body.shape = capsule_proxy(body.shape);
  }
  return model;
}

/// Whether `model` has a box or ellipsoid limb.
inline bool has_box_or_ellipsoid(const Model& model) {
  for (const Body& body : model.bodies) {
    if (has_half_extents(body.shape)) return true;
  }
  return false;
}

}  // namespace limber
