// Mass properties of rigid bodies with distributed mass (thesis 2.1.3, 2.1.7, 4.1).
//
// A body's mass properties are its mass m, its centre of mass c and its inertia tensor about c,
//   I = ∫ ρ(x) (|r|² E − r rᵀ) dV,   r = x − c,
// all expressed in one frame (the frame the inputs are given in). Shapes are in their body
// frame: centred at the origin, cylinder and capsule axes along +z (kernel/model/model.hpp).
// Units: kg, m, kg·m². Every function throws std::invalid_argument on a non-positive or
// non-finite size, mass or density, naming the argument.
#pragma once

#include <array>
#include <functional>
#include <span>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

struct MassProperties {
  double mass = 0;                                            ///< kg
  Eigen::Vector3d centre_of_mass = Eigen::Vector3d::Zero();   ///< m
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();          ///< about the centre of mass, kg·m²
};

/// Solid cylinder of `radius` and `length` along z: I_zz = m r²/2, I_xx = I_yy = m (r²/4 + L²/12).
MassProperties solid_cylinder(double mass, double radius, double length);
/// Solid capsule: a cylinder of `length` along z with hemispherical caps of `radius` (total
/// extent length + 2·radius), uniform density. Each cap's inertia about its own centre of mass
/// (3r/8 from its flat face) is moved to the capsule's centre by the parallel-axis theorem. Length
/// 0 (≥ 0) is a solid sphere, (2/5) m r².
MassProperties solid_capsule(double mass, double radius, double length);
/// Solid box of edge lengths `size` (x, y, z): I_xx = m (s_y² + s_z²)/12, and so on.
MassProperties solid_box(double mass, const Eigen::Vector3d& size);
/// Solid ellipsoid of semi-axes `semi_axes` (x, y, z): I_xx = m (b² + c²)/5, and so on.
MassProperties solid_ellipsoid(double mass, const Eigen::Vector3d& semi_axes);
/// Solid sphere: I = (2/5) m r² E.
MassProperties solid_sphere(double mass, double radius);

/// Point masses m_k at x_k (thesis eq. 4.1): m = Σ m_k, c = Σ m_k x_k / m,
/// I = Σ m_k (|r_k|² E − r_k r_kᵀ). Masses must be ≥ 0 with a positive sum; shapes must match.
MassProperties point_masses(std::span<const Eigen::Vector3d> positions, std::span<const double> masses);

/// A closed triangle mesh of uniform `density` (kg/m³), by the divergence theorem: Eberly,
/// "Polyhedral Mass Properties (Revisited)" (2002), after Mirtich (1996). Triangles index
/// `vertices` and wind counter-clockwise seen from outside. Throws std::invalid_argument on an
/// index out of range or a mesh whose enclosed volume is not positive (open, inside out).
MassProperties closed_mesh(std::span<const Eigen::Vector3d> vertices, std::span<const std::array<int, 3>> triangles,
                           double density);

/// A density field ρ(x) (kg/m³, body frame) integrated over a solid cylinder (thesis eq.
/// 4.2–4.4), by a product rule: Gauss-Legendre with `order` points in r (Jacobian r included)
/// and in z, and 2·order + 2 equally spaced angles in θ. It is exact, to rounding, for a density
/// polynomial in x, y, z of degree ≤ 2·order − 4 (the inertia integrand adds 2 to the degree in
/// r and z, the Jacobian 1 more in r); for smooth fields the error falls exponentially with the
/// order. order in [2, 64].
MassProperties cylinder_density_field(const std::function<double(const Eigen::Vector3d&)>& density, double radius,
                                      double length, int order = 8);

/// The same part seen in another frame: x' = rotation·x + translation.
MassProperties transformed(const MassProperties& part, const Eigen::Quaterniond& rotation,
                           const Eigen::Vector3d& translation);

/// Several parts (in one frame) as one body (thesis 2.1.7): masses add, the centre of mass is
/// the mass-weighted mean, and each part's inertia moves to it by the parallel-axis theorem,
/// I += m_k (|d_k|² E − d_k d_kᵀ), d_k = c_k − c.
MassProperties combine(std::span<const MassProperties> parts);

struct Body;
/// A limb's mass properties in its body frame (kernel/model/model.hpp): its Inertial when given,
/// else its point masses (eq. 4.1, each a solid sphere of its radius) when it has any, else its
/// mass spread uniformly over its shape (solid cylinder or capsule).
MassProperties body_mass_properties(const Body& body);

/// Principal moments (ascending) and axes (columns, a right-handed rotation) of an inertia
/// tensor: inertia = axes · diag(moments) · axesᵀ. A body frame aligned with `axes` has a
/// diagonal inertia tensor.
struct PrincipalAxes {
  Eigen::Vector3d moments = Eigen::Vector3d::Zero();
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();
};
PrincipalAxes principal_axes(const Eigen::Matrix3d& inertia);

}  // namespace limber
