#include "limber/kernel/mass/mass_properties.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "limber/kernel/model/model.hpp"

namespace limber {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

void require_positive(double value, const char* name) {
  if (!(value > 0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string(name) + ": must be a positive finite number, got " + std::to_string(value));
  }
}

// (|d|² E − d dᵀ): the inertia of a unit point mass at offset d.
Matrix3d point_inertia(const Vector3d& d) { return d.squaredNorm() * Matrix3d::Identity() - d * d.transpose(); }

MassProperties diagonal(double mass, double xx, double yy, double zz) {
  MassProperties result;
  result.mass = mass;
  result.inertia = Vector3d(xx, yy, zz).asDiagonal();
  return result;
}

// Gauss-Legendre nodes and weights on [−1, 1] (Golub-Welsch: the eigenvalues of the Jacobi
// matrix of the Legendre polynomials are the nodes; the weights are 2·(first component)²).
void gauss_legendre(int order, std::vector<double>& nodes, std::vector<double>& weights) {
  Eigen::MatrixXd jacobi = Eigen::MatrixXd::Zero(order, order);
  for (int k = 1; k < order; ++k) {
    const double b = k / std::sqrt(4.0 * k * k - 1.0);
    jacobi(k - 1, k) = jacobi(k, k - 1) = b;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(jacobi);
  nodes.resize(static_cast<std::size_t>(order));
  weights.resize(static_cast<std::size_t>(order));
  for (int k = 0; k < order; ++k) {
    nodes[k] = solver.eigenvalues()(k);
    weights[k] = 2.0 * solver.eigenvectors()(0, k) * solver.eigenvectors()(0, k);
  }
}

}  // namespace

MassProperties solid_cylinder(double mass, double radius, double length) {
  require_positive(mass, "mass");
  require_positive(length, "length");
  if (!(radius >= 0) || !std::isfinite(radius)) throw std::invalid_argument("radius: must be finite and >= 0");
  const double r2 = radius * radius, l2 = length * length;
  return diagonal(mass, mass * (r2 / 4 + l2 / 12), mass * (r2 / 4 + l2 / 12), mass * r2 / 2);
}

MassProperties solid_capsule(double mass, double radius, double length) {
  require_positive(mass, "mass");
  require_positive(radius, "radius");
  if (!(length >= 0) || !std::isfinite(length)) throw std::invalid_argument("length: must be finite and >= 0");
  const double pi = std::numbers::pi;
  const double cylinder_volume = pi * radius * radius * length, cap_volume = 2.0 / 3.0 * pi * radius * radius * radius;
  const double density = mass / (cylinder_volume + 2 * cap_volume);
  const double cylinder_mass = density * cylinder_volume, cap_mass = density * cap_volume;
  // Length 0: a sphere, the two caps alone.
  MassProperties result = length > 0 ? solid_cylinder(cylinder_mass, radius, length) : diagonal(mass, 0, 0, 0);
  result.mass = mass;
  // A hemisphere about its own centre of mass: I_zz = 2/5 m r², I_xx = I_yy = 83/320 m r².
  const double r2 = radius * radius, offset = length / 2 + 3.0 * radius / 8;
  const double cap_xx = cap_mass * (83.0 / 320.0 * r2 + offset * offset);
  result.inertia(0, 0) += 2 * cap_xx;
  result.inertia(1, 1) += 2 * cap_xx;
  result.inertia(2, 2) += 2 * cap_mass * 0.4 * r2;
  return result;
}

namespace {

// A solid whose principal moments are m (s_j² + s_k²) / divisor over the lengths s along x, y, z
// (a box's edges, 12; an ellipsoid's semi-axes, 5), each > 0 (`name`: what s is, for the error).
MassProperties solid_of_lengths(double mass, const Vector3d& lengths, double divisor, const std::string& name) {
  require_positive(mass, "mass");
  require_positive(lengths.x(), (name + ".x").c_str());
  require_positive(lengths.y(), (name + ".y").c_str());
  require_positive(lengths.z(), (name + ".z").c_str());
  const Vector3d s2 = lengths.cwiseProduct(lengths);
  return diagonal(mass, mass * (s2.y() + s2.z()) / divisor, mass * (s2.x() + s2.z()) / divisor, mass * (s2.x() + s2.y()) / divisor);
}

}  // namespace

MassProperties solid_box(double mass, const Vector3d& size) { return solid_of_lengths(mass, size, 12, "size"); }

MassProperties solid_ellipsoid(double mass, const Vector3d& semi_axes) { return solid_of_lengths(mass, semi_axes, 5, "semi_axes"); }

MassProperties solid_sphere(double mass, double radius) {
  require_positive(mass, "mass");
  require_positive(radius, "radius");
  const double moment = 0.4 * mass * radius * radius;
  return diagonal(mass, moment, moment, moment);
}

MassProperties point_masses(std::span<const Vector3d> positions, std::span<const double> masses) {
  if (positions.size() != masses.size()) throw std::invalid_argument("point_masses: positions and masses differ in length");
  MassProperties result;
  Vector3d moment = Vector3d::Zero();
  for (std::size_t k = 0; k < masses.size(); ++k) {
    if (!(masses[k] >= 0) || !std::isfinite(masses[k])) {
      throw std::invalid_argument("masses[" + std::to_string(k) + "]: must be finite and >= 0");
    }
    if (!positions[k].allFinite()) throw std::invalid_argument("positions[" + std::to_string(k) + "]: must be finite");
    result.mass += masses[k];
    moment += masses[k] * positions[k];
  }
  require_positive(result.mass, "point_masses: total mass");
  result.centre_of_mass = moment / result.mass;
  for (std::size_t k = 0; k < masses.size(); ++k) {
    result.inertia += masses[k] * point_inertia(positions[k] - result.centre_of_mass);
  }
  return result;
}

MassProperties closed_mesh(std::span<const Vector3d> vertices, std::span<const std::array<int, 3>> triangles,
                           double density) {
  require_positive(density, "density");
  // Integrals of 1, x, y, z, x², y², z², xy, yz, zx over the solid, each a sum over triangles of
  // (normal component) × (a polynomial in the vertex coordinates): Eberly (2002), section 3.
  double integral[10] = {};
  const auto subexpressions = [](double w0, double w1, double w2, double& f1, double& f2, double& f3, double& g0,
                                 double& g1, double& g2) {
    const double temp0 = w0 + w1, temp1 = w0 * w0, temp2 = temp1 + w1 * temp0;
    f1 = temp0 + w2;
    f2 = temp2 + w2 * f1;
    f3 = w0 * temp1 + w1 * temp2 + w2 * f2;
    g0 = f2 + w0 * (f1 + w0);
    g1 = f2 + w1 * (f1 + w1);
    g2 = f2 + w2 * (f1 + w2);
  };
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (int corner : triangles[t]) {
      if (corner < 0 || static_cast<std::size_t>(corner) >= vertices.size()) {
        throw std::invalid_argument("triangles[" + std::to_string(t) + "]: vertex index " + std::to_string(corner) +
                                    " out of range (" + std::to_string(vertices.size()) + " vertices)");
      }
    }
    const Vector3d& p0 = vertices[triangles[t][0]];
    const Vector3d& p1 = vertices[triangles[t][1]];
    const Vector3d& p2 = vertices[triangles[t][2]];
    const Vector3d d = (p1 - p0).cross(p2 - p0);
    double f1x, f2x, f3x, g0x, g1x, g2x, f1y, f2y, f3y, g0y, g1y, g2y, f1z, f2z, f3z, g0z, g1z, g2z;
    subexpressions(p0.x(), p1.x(), p2.x(), f1x, f2x, f3x, g0x, g1x, g2x);
    subexpressions(p0.y(), p1.y(), p2.y(), f1y, f2y, f3y, g0y, g1y, g2y);
    subexpressions(p0.z(), p1.z(), p2.z(), f1z, f2z, f3z, g0z, g1z, g2z);
    integral[0] += d.x() * f1x;
    integral[1] += d.x() * f2x, integral[2] += d.y() * f2y, integral[3] += d.z() * f2z;
    integral[4] += d.x() * f3x, integral[5] += d.y() * f3y, integral[6] += d.z() * f3z;
    integral[7] += d.x() * (p0.y() * g0x + p1.y() * g1x + p2.y() * g2x);
    integral[8] += d.y() * (p0.z() * g0y + p1.z() * g1y + p2.z() * g2y);
    integral[9] += d.z() * (p0.x() * g0z + p1.x() * g1z + p2.x() * g2z);
  }
  constexpr double scale[10] = {1.0 / 6, 1.0 / 24, 1.0 / 24, 1.0 / 24, 1.0 / 60, 1.0 / 60, 1.0 / 60, 1.0 / 120, 1.0 / 120, 1.0 / 120};
  for (int k = 0; k < 10; ++k) integral[k] *= scale[k] * density;
  if (!(integral[0] > 0)) {
    throw std::invalid_argument("closed_mesh: enclosed volume " + std::to_string(integral[0] / density) +
                                " is not positive (open mesh, or triangles wound clockwise from outside)");
  }
  MassProperties result;
  result.mass = integral[0];
  const Vector3d c = Vector3d(integral[1], integral[2], integral[3]) / result.mass;
  result.centre_of_mass = c;
  Matrix3d& inertia = result.inertia;
  inertia(0, 0) = integral[5] + integral[6] - result.mass * (c.y() * c.y() + c.z() * c.z());
  inertia(1, 1) = integral[4] + integral[6] - result.mass * (c.z() * c.z() + c.x() * c.x());
  inertia(2, 2) = integral[4] + integral[5] - result.mass * (c.x() * c.x() + c.y() * c.y());
  inertia(0, 1) = inertia(1, 0) = -(integral[7] - result.mass * c.x() * c.y());
  inertia(1, 2) = inertia(2, 1) = -(integral[8] - result.mass * c.y() * c.z());
  inertia(0, 2) = inertia(2, 0) = -(integral[9] - result.mass * c.z() * c.x());
  return result;
}

MassProperties cylinder_density_field(const std::function<double(const Vector3d&)>& density, double radius,
                                      double length, int order) {
  require_positive(radius, "radius");
  require_positive(length, "length");
  if (order < 2 || order > 64) throw std::invalid_argument("order: must be in [2, 64], got " + std::to_string(order));
  std::vector<double> nodes, weights;
  gauss_legendre(order, nodes, weights);
  const int angles = 2 * order + 2;
  const double pi = std::numbers::pi;
  // First the mass and first moments, then the second moments about the origin.
  double mass = 0;
  Vector3d moment = Vector3d::Zero();
  Matrix3d second = Matrix3d::Zero();  // ∫ ρ x xᵀ dV
  for (int i = 0; i < order; ++i) {
    const double r = 0.5 * radius * (nodes[i] + 1), w_r = 0.5 * radius * weights[i];
    for (int j = 0; j < order; ++j) {
      const double z = 0.5 * length * nodes[j], w_z = 0.5 * length * weights[j];
      for (int k = 0; k < angles; ++k) {
        const double theta = 2 * pi * k / angles;
        const Vector3d x(r * std::cos(theta), r * std::sin(theta), z);
        const double rho = density(x);
        if (!(rho >= 0) || !std::isfinite(rho)) {
          throw std::invalid_argument("density: must be finite and >= 0, got " + std::to_string(rho));
        }
        const double w = rho * r * w_r * w_z * (2 * pi / angles);  // dV = r dr dθ dz
        mass += w;
        moment += w * x;
        second += w * x * x.transpose();
      }
    }
  }
  require_positive(mass, "density field: total mass");
  MassProperties result;
  result.mass = mass;
  result.centre_of_mass = moment / mass;
  const Matrix3d central = second - mass * result.centre_of_mass * result.centre_of_mass.transpose();
  result.inertia = central.trace() * Matrix3d::Identity() - central;
  return result;
}

MassProperties transformed(const MassProperties& part, const Eigen::Quaterniond& rotation, const Vector3d& translation) {
  const Matrix3d r = rotation.normalized().toRotationMatrix();
  MassProperties result;
  result.mass = part.mass;
  result.centre_of_mass = r * part.centre_of_mass + translation;
  result.inertia = r * part.inertia * r.transpose();
  return result;
}

MassProperties combine(std::span<const MassProperties> parts) {
  MassProperties result;
  Vector3d moment = Vector3d::Zero();
  for (const MassProperties& part : parts) {
    result.mass += part.mass;
    moment += part.mass * part.centre_of_mass;
  }
  require_positive(result.mass, "combine: total mass");
  result.centre_of_mass = moment / result.mass;
  for (const MassProperties& part : parts) {
    result.inertia += part.inertia + part.mass * point_inertia(part.centre_of_mass - result.centre_of_mass);
  }
  return result;
}

namespace {

// Uniform density over the shape, in the body frame.
MassProperties solid_shape(double mass, const Shape& shape) {
  switch (shape.type) {
    case ShapeType::capsule:
      if (shape.radius > 0) return solid_capsule(mass, shape.radius, shape.length);
      break;
    case ShapeType::box:
    case ShapeType::ellipsoid: {
      MassProperties solid = shape.type == ShapeType::box ? solid_box(mass, 2 * shape.half_extents) : solid_ellipsoid(mass, shape.half_extents);
      const Matrix3d turn = shape.rotation.toRotationMatrix();
      solid.inertia = turn * solid.inertia * turn.transpose();
      return solid;
    }
    case ShapeType::cylinder: break;
  }
  return solid_cylinder(mass, shape.radius, shape.length);
}

}  // namespace

MassProperties body_mass_properties(const Body& body) {
  if (body.inertial) return MassProperties{body.mass, body.inertial->centre_of_mass, body.inertial->inertia};
  if (body.point_masses.empty()) return solid_shape(body.mass, body.shape);
  std::vector<MassProperties> lumps;
  lumps.reserve(body.point_masses.size());
  for (const PointMass& lump : body.point_masses) {
    MassProperties part{lump.mass, lump.position, Eigen::Matrix3d::Zero()};
    if (lump.radius > 0) part.inertia = solid_sphere(lump.mass, lump.radius).inertia;
    lumps.push_back(part);
  }
  return combine(lumps);
}

PrincipalAxes principal_axes(const Matrix3d& inertia) {
  const Eigen::SelfAdjointEigenSolver<Matrix3d> solver(0.5 * (inertia + inertia.transpose()));
  PrincipalAxes result;
  result.moments = solver.eigenvalues();
  result.axes = solver.eigenvectors();
  if (result.axes.determinant() < 0) result.axes.col(2) = -result.axes.col(2);  // a rotation, not a reflection
  return result;
}

}  // namespace limber
