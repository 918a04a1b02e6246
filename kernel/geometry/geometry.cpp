#include "limber/kernel/geometry/geometry.hpp"

#include <algorithm>
#include <cmath>

namespace limber {

Eigen::Vector3d any_perpendicular(const Eigen::Vector3d& u) {
  const Eigen::Vector3d n = u.normalized();
  const Eigen::Vector3d other = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  return n.cross(other).normalized();
}

bool projects_inside(const std::array<Eigen::Vector3d, 3>& t, const Eigen::Vector3d& n, const Eigen::Vector3d& p) {
  for (std::size_t k = 0; k < 3; ++k) {
    if ((t[(k + 1) % 3] - t[k]).cross(p - t[k]).dot(n) < 0) return false;
  }
  return true;
}

SphereLimbContact sphere_limb_contact(const Eigen::Vector3d& centre, double sphere_radius,
                                      const Eigen::Vector3d& head, const Eigen::Vector3d& tail,
                                      ShapeType shape, double limb_radius) {
  SphereLimbContact contact;
  const Eigen::Vector3d segment = tail - head;
  const double length = segment.norm();
  const Eigen::Vector3d axis = length > 0 ? Eigen::Vector3d(segment / length) : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d relative = centre - head;
  const double along = relative.dot(axis);                  // m from the head
  const Eigen::Vector3d radial = relative - along * axis;   // from the axis to the centre
  const double radial_distance = radial.norm();
  const Eigen::Vector3d radial_direction = radial_distance > 0 ? Eigen::Vector3d(radial / radial_distance)
                                                               : any_perpendicular(axis);
  const double clamped = std::clamp(along, 0.0, length);
  contact.axial = length > 0 ? clamped / length : 0.0;

  if (shape == ShapeType::capsule || limb_radius == 0) {
    // Distance to the segment, less both radii.
    const Eigen::Vector3d offset = centre - (head + clamped * axis);
    const double distance = offset.norm();
    contact.normal = distance > 0 ? Eigen::Vector3d(offset / distance) : radial_direction;
    contact.separation = distance - limb_radius - sphere_radius;
    return contact;
  }

  const bool inside = along >= 0 && along <= length && radial_distance <= limb_radius;
  if (!inside) {
    // Closest point of the solid cylinder: clamp along the axis, then radially.
    const Eigen::Vector3d closest =
        head + clamped * axis + std::min(radial_distance, limb_radius) * radial_direction;
    const Eigen::Vector3d offset = centre - closest;
    const double distance = offset.norm();
    contact.normal = distance > 0 ? Eigen::Vector3d(offset / distance) : radial_direction;
    contact.separation = distance - sphere_radius;
    return contact;
  }
  // Centre inside: leave through the nearest of the side, the head face and the tail face.
  const double to_side = limb_radius - radial_distance, to_head = along, to_tail = length - along;
  if (to_side <= to_head && to_side <= to_tail) {
    contact.normal = radial_direction;
    contact.separation = -to_side - sphere_radius;
  } else if (to_head <= to_tail) {
    contact.normal = -axis;
    contact.separation = -to_head - sphere_radius;
  } else {
    contact.normal = axis;
    contact.separation = -to_tail - sphere_radius;
  }
  return contact;
}

EndSupport end_support(const Eigen::Vector3d& normal, const Eigen::Vector3d& axis, double radius, bool is_disk) {
  EndSupport support;
  if (!is_disk) {
    support.offset = -radius * normal;
    support.reach = radius;
    return support;
  }
  support.cosine = normal.dot(axis);
  support.sine = std::sqrt(std::max(0.0, 1.0 - support.cosine * support.cosine));
  support.reach = radius * support.sine;
  if (support.sine > 1e-9) support.offset = -(radius / support.sine) * (normal - support.cosine * axis);
  return support;
}

PlaneFeatureConstraint plane_feature_constraint(const Eigen::Vector3d& normal, double offset,
                                                const Eigen::Vector3d& point, const Eigen::Vector3d& partner,
                                                double radius, bool is_disk, bool at_midpoint) {
  PlaneFeatureConstraint constraint;
  if (at_midpoint) {
    constraint.separation = normal.dot(0.5 * (point + partner)) - offset - radius;
    constraint.gradient_point = constraint.gradient_partner = 0.5 * normal;
    return constraint;
  }
  constraint.gradient_point = normal;
  const Eigen::Vector3d along = point - partner;
  const double length = along.norm();
  const bool disk = is_disk && length > 0;
  const EndSupport support = end_support(normal, disk ? Eigen::Vector3d(along / length) : Eigen::Vector3d::UnitZ(), radius, disk);
  constraint.separation = normal.dot(point) - offset - support.reach;
  if (disk && support.sine > 1e-9) {
    const double cosine = support.cosine, sine = support.sine;
    const Eigen::Vector3d tilt = (radius * cosine / (sine * length)) * (normal - cosine * (along / length));
    constraint.gradient_point += tilt;
    constraint.gradient_partner = -tilt;
  }
  return constraint;
}

std::vector<Plane> scene_planes(const Model& model) {
  std::vector<Plane> planes;
  if (model.ground) planes.push_back({Eigen::Vector3d::UnitZ(), model.ground->height, model.ground->restitution, model.ground->friction});
  if (model.bounds) {
    const Bounds& box = *model.bounds;
    for (int axis = 0; axis < 3; ++axis) {
      const Eigen::Vector3d normal = Eigen::Vector3d::Unit(axis);
      planes.push_back({normal, box.min[axis], box.restitution, box.friction});
      planes.push_back({-normal, -box.max[axis], box.restitution, box.friction});
    }
  }
  return planes;
}

}  // namespace limber
