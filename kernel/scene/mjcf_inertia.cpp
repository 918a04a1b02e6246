// MJCF mass properties from geoms, as MuJoCo 2.2.2's compiler computes them
// (src/user/user_objects.cc: mjCGeom::GetVolume, mjCGeom::SetInertia, mjCGeom::Compile's mass,
// mjCBody::GeomFrame), kept as full tensors about the centre (MuJoCo then diagonalizes them).
#include <cmath>
#include <numbers>

#include "limber/kernel/scene/mjcf_reader.hpp"

namespace limber::mjcf::detail {

namespace {
constexpr double pi = std::numbers::pi;
}  // namespace

double geom_volume(GeomType type, const Eigen::Vector3d& size) {
  const double r = size(0);
  switch (type) {
    case GeomType::sphere: return 4 * pi * r * r * r / 3;
    case GeomType::capsule: return pi * (r * r * 2 * size(1) + 4 * r * r * r / 3);
    case GeomType::cylinder: return pi * r * r * 2 * size(1);
    case GeomType::ellipsoid: return 4 * pi * size(0) * size(1) * size(2) / 3;
    case GeomType::box: return size(0) * size(1) * size(2) * 8;
    case GeomType::plane: return 0;
  }
  return 0;
}

// Capsule: a cylinder of height 2·half-length and two hemispheres of radius r, each displaced
// from the centre along the axis (MuJoCo's exact formula: the hemispheres' own centroids are not
// at the cylinder's ends, hence the 3r/8 terms).
Eigen::Vector3d geom_principal_moments(GeomType type, const Eigen::Vector3d& size, double mass) {
  const double r = size(0);
  switch (type) {
    case GeomType::sphere: return Eigen::Vector3d::Constant(2 * mass * r * r / 5);
    case GeomType::capsule: {
      const double height = 2 * size(1);
      const double sphere_mass = mass * 4 * r / (4 * r + 3 * height);  // the two hemispheres' share
      const double cylinder_mass = mass - sphere_mass;
      const double across = cylinder_mass * (3 * r * r + height * height) / 12 + 2 * sphere_mass * r * r / 5 +
                            sphere_mass * height * (3 * r + 2 * height) / 8;
      const double along = cylinder_mass * r * r / 2 + 2 * sphere_mass * r * r / 5;
      return {across, across, along};
    }
    case GeomType::cylinder: {
      const double height = 2 * size(1);
      const double across = mass * (3 * r * r + height * height) / 12;
      return {across, across, mass * r * r / 2};
    }
    case GeomType::ellipsoid: {
      const Eigen::Vector3d s2 = size.cwiseProduct(size);
      return mass / 5 * Eigen::Vector3d(s2(1) + s2(2), s2(0) + s2(2), s2(0) + s2(1));
    }
    case GeomType::box: {
      const Eigen::Vector3d s2 = size.cwiseProduct(size);
      return mass / 3 * Eigen::Vector3d(s2(1) + s2(2), s2(0) + s2(2), s2(0) + s2(1));
    }
    case GeomType::plane: return Eigen::Vector3d::Zero();
  }
  return Eigen::Vector3d::Zero();
}

// An explicit mass of 0 gives 0; an explicit mass on a geom without volume is dropped (0), as
// MuJoCo; else density × volume.
double geom_mass(GeomType type, const Eigen::Vector3d& size, std::optional<double> mass, double density) {
  const double volume = geom_volume(type, size);
  if (mass) return *mass != 0 && volume > mj_minval ? *mass : 0;
  return density * volume;
}

Eigen::Matrix3d rotated_inertia(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& moments) {
  const Eigen::Matrix3d r = rotation.toRotationMatrix();
  return r * moments.asDiagonal() * r.transpose();
}

std::optional<MassProperties> geoms_mass_properties(const std::vector<Geom>& geoms,
                                                    const std::array<double, 2>& groups) {
  std::vector<const Geom*> selected;
  for (const Geom& geom : geoms) {
    if (geom.group >= groups[0] && geom.group <= groups[1]) selected.push_back(&geom);
  }
  if (selected.empty()) return std::nullopt;
  MassProperties out;
  out.geoms = static_cast<int>(selected.size());
  // One geom: its own frame (MuJoCo copies it, no sum).
  if (selected.size() == 1) {
    const Geom& g = *selected[0];
    out.mass = g.mass;
    out.centre = g.position;
    out.inertia = rotated_inertia(g.orientation, geom_principal_moments(g.type, g.size, g.mass));
    return out;
  }
  for (const Geom* g : selected) {
    out.mass += g->mass;
    out.centre += g->mass * g->position;
  }
  if (out.mass < mj_minval) return out;  // the caller refuses: no centre of mass
  out.centre /= out.mass;
  // Each geom's tensor turned into the body frame, plus m (|d|² I - d dᵀ) about the centre.
  for (const Geom* g : selected) {
    const Eigen::Vector3d d = g->position - out.centre;
    out.inertia += rotated_inertia(g->orientation, geom_principal_moments(g->type, g->size, g->mass));
    out.inertia += g->mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  }
  return out;
}

}  // namespace limber::mjcf::detail
