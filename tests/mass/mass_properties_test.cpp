// Mass properties against closed forms, point-mass collections, meshes and each other.
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/mass/mass_properties.hpp"

namespace limber {
namespace {

using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector3d;

void expect_near(const MassProperties& a, const MassProperties& b, double tolerance) {
  EXPECT_NEAR(a.mass, b.mass, tolerance * b.mass);
  EXPECT_LT((a.centre_of_mass - b.centre_of_mass).norm(), tolerance) << a.centre_of_mass.transpose();
  EXPECT_LT((a.inertia - b.inertia).norm(), tolerance * b.inertia.norm()) << "\n" << a.inertia << "\n---\n" << b.inertia;
}

// The 12 triangles of an axis-aligned box centred at the origin, wound counter-clockwise from outside.
void box_mesh(const Vector3d& size, std::vector<Vector3d>& vertices, std::vector<std::array<int, 3>>& triangles) {
  vertices.clear();
  for (int k = 0; k < 8; ++k) {
    vertices.push_back(0.5 * Vector3d(k & 1 ? size.x() : -size.x(), k & 2 ? size.y() : -size.y(), k & 4 ? size.z() : -size.z()));
  }
  triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6},   // z = −, z = +
               {0, 1, 4}, {1, 5, 4}, {2, 6, 3}, {3, 6, 7},   // y = −, y = +
               {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};  // x = −, x = +
}

TEST(MassProperties, RodIsTheZeroRadiusCylinder) {
  // A uniform rod about its centre: m L² / 12 (thesis 2.1.3).
  const MassProperties rod = solid_cylinder(3.0, 0.0, 2.0);
  EXPECT_DOUBLE_EQ(rod.inertia(0, 0), 3.0 * 4.0 / 12);
  EXPECT_DOUBLE_EQ(rod.inertia(2, 2), 0.0);
}

TEST(MassProperties, PointMassesApproachTheSolidsTheySample) {
  // A fine lattice of equal point masses filling a box converges on the box formula; the
  // midpoint rule's error falls as 1/n².
  const Vector3d size(0.4, 0.6, 1.0);
  const int n = 40;
  std::vector<Vector3d> points;
  std::vector<double> masses;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        points.push_back(Vector3d((i + 0.5) / n - 0.5, (j + 0.5) / n - 0.5, (k + 0.5) / n - 0.5).cwiseProduct(size) +
                         Vector3d(1, 2, 3));
        masses.push_back(5.0 / (n * n * n));
      }
  MassProperties expected = solid_box(5.0, size);
  expected.centre_of_mass = Vector3d(1, 2, 3);
  expect_near(point_masses(points, masses), expected, 1e-3);
}

TEST(MassProperties, BoxMeshEqualsTheBoxFormula) {
  std::vector<Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;
  const Vector3d size(0.3, 0.5, 2.0);
  box_mesh(size, vertices, triangles);
  const double density = 700;
  expect_near(closed_mesh(vertices, triangles, density), solid_box(density * size.prod(), size), 1e-12);
  // Moved and turned, the mesh's properties move and turn with it.
  const Quaterniond q = Quaterniond(Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()));
  for (Vector3d& v : vertices) v = q * v + Vector3d(4, -1, 2);
  expect_near(closed_mesh(vertices, triangles, density),
              transformed(solid_box(density * size.prod(), size), q, Vector3d(4, -1, 2)), 1e-12);
}

TEST(MassProperties, InsideOutOrBrokenMeshIsRejected) {
  std::vector<Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;
  box_mesh(Vector3d(1, 1, 1), vertices, triangles);
  for (auto& t : triangles) std::swap(t[1], t[2]);
  EXPECT_THROW(closed_mesh(vertices, triangles, 1.0), std::invalid_argument);
  triangles[0][0] = 8;
  EXPECT_THROW(closed_mesh(vertices, triangles, 1.0), std::invalid_argument);
}

TEST(MassProperties, CapsuleIsCylinderPlusTwoHemispheres) {
  // Two hemispheres joined flat face to flat face are a sphere: a capsule of vanishing length.
  expect_near(solid_capsule(2.0, 0.3, 1e-9), solid_sphere(2.0, 0.3), 1e-8);
  // And the capsule is the density-weighted union of a cylinder and a sphere split at its
  // middle: compare with a point-sampled capsule.
  const double r = 0.1, l = 0.5, m = 3.0;
  std::vector<Vector3d> points;
  const int n = 120;
  const double h = (l + 2 * r) / n;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const Vector3d x(-r + (i + 0.5) * h * 2 * r / (l + 2 * r), -r + (j + 0.5) * h * 2 * r / (l + 2 * r),
                         -(l / 2 + r) + (k + 0.5) * h);
        const double axial = std::max(0.0, std::abs(x.z()) - l / 2);
        if (x.x() * x.x() + x.y() * x.y() + axial * axial <= r * r) points.push_back(x);
      }
  const std::vector<double> masses(points.size(), m / points.size());
  expect_near(point_masses(points, masses), solid_capsule(m, r, l), 5e-3);
}

TEST(MassProperties, DensityFieldIsExactForPolynomialDensities) {
  // Uniform density: the cylinder formula.
  const double r = 0.05, l = 0.4, rho = 1000;
  const double mass = rho * std::numbers::pi * r * r * l;
  expect_near(cylinder_density_field([&](const Vector3d&) { return rho; }, r, l, 4), solid_cylinder(mass, r, l), 1e-12);
  // Density growing along the axis, ρ = a + b z (a limb heavier at one end, thesis eq. 4.2):
  // the centre of mass moves to z_c = b L² / (12 a), exactly, at any order ≥ 3.
  const double a = 1000, b = 2000;
  const MassProperties graded = cylinder_density_field([&](const Vector3d& x) { return a + b * x.z(); }, r, l, 3);
  EXPECT_NEAR(graded.mass, mass, 1e-12 * mass);
  EXPECT_NEAR(graded.centre_of_mass.z(), b * l * l / (12 * a), 1e-14);
  EXPECT_NEAR(graded.centre_of_mass.head<2>().norm(), 0, 1e-15);
  // A smooth non-polynomial field converges as the order grows.
  const auto field = [&](const Vector3d& x) { return rho * std::exp(3 * x.z() / l) * (1 + x.x() / r); };
  const MassProperties reference = cylinder_density_field(field, r, l, 40);
  const MassProperties coarse = cylinder_density_field(field, r, l, 3), fine = cylinder_density_field(field, r, l, 6);
  EXPECT_LT(std::abs(fine.inertia(0, 0) - reference.inertia(0, 0)), 1e-3 * std::abs(coarse.inertia(0, 0) - reference.inertia(0, 0)));
  EXPECT_THROW(cylinder_density_field(field, r, l, 1), std::invalid_argument);
  EXPECT_THROW(cylinder_density_field([](const Vector3d&) { return -1.0; }, r, l), std::invalid_argument);
}

TEST(MassProperties, CombiningPartsIsTheParallelAxisTheorem) {
  // Two halves of a box, each at its own centre, combine into the whole box.
  const Vector3d size(0.2, 0.4, 1.0), half(0.2, 0.4, 0.5);
  MassProperties lower = solid_box(1.0, half), upper = solid_box(1.0, half);
  lower.centre_of_mass = Vector3d(0, 0, -0.25), upper.centre_of_mass = Vector3d(0, 0, 0.25);
  const std::array<MassProperties, 2> parts{lower, upper};
  expect_near(combine(parts), solid_box(2.0, size), 1e-14);
  // A humanoid-like body: a torso and two arms, rotated as a whole, equals the rotated parts combined.
  const MassProperties torso = solid_cylinder(30, 0.15, 0.6);
  const MassProperties arm = transformed(solid_capsule(3, 0.04, 0.5), Quaterniond(Eigen::AngleAxisd(1.2, Vector3d::UnitY())),
                                         Vector3d(0.3, 0, 0.2));
  const std::array<MassProperties, 2> body{torso, arm};
  const Quaterniond q(Eigen::AngleAxisd(0.4, Vector3d(0, 1, 1).normalized()));
  const std::array<MassProperties, 2> turned{transformed(torso, q, Vector3d(1, 1, 1)), transformed(arm, q, Vector3d(1, 1, 1))};
  expect_near(combine(turned), transformed(combine(body), q, Vector3d(1, 1, 1)), 1e-13);
}

TEST(MassProperties, PrincipalAxesDiagonalizeTheInertia) {
  const Quaterniond q(Eigen::AngleAxisd(0.9, Vector3d(3, -1, 2).normalized()));
  const MassProperties box = transformed(solid_box(2.0, Vector3d(0.1, 0.5, 1.2)), q, Vector3d::Zero());
  const PrincipalAxes principal = principal_axes(box.inertia);
  EXPECT_NEAR(principal.axes.determinant(), 1.0, 1e-12);
  const Matrix3d diagonalized = principal.axes.transpose() * box.inertia * principal.axes;
  EXPECT_LT((diagonalized - Matrix3d(principal.moments.asDiagonal())).norm(), 1e-12);
  // The moments are the box's own, smallest about its longest edge.
  const Vector3d own = solid_box(2.0, Vector3d(0.1, 0.5, 1.2)).inertia.diagonal();
  EXPECT_NEAR(principal.moments(0), own.minCoeff(), 1e-12);
  EXPECT_NEAR(principal.moments(2), own.maxCoeff(), 1e-12);
}

TEST(MassProperties, BadSizesAreRejectedByName) {
  EXPECT_THROW(solid_sphere(-1, 1), std::invalid_argument);
  EXPECT_THROW(solid_box(1, Vector3d(1, 0, 1)), std::invalid_argument);
  EXPECT_THROW(solid_capsule(1, 0.1, std::nan("")), std::invalid_argument);
  const std::vector<Vector3d> points{Vector3d::Zero()};
  const std::vector<double> none{0.0};
  EXPECT_THROW(point_masses(points, none), std::invalid_argument);
  try {
    solid_cylinder(1, 0.1, -2);
    FAIL();
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("length"), std::string::npos);
  }
}

}  // namespace
}  // namespace limber
