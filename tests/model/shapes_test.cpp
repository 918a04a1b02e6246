// Boxes and ellipsoids as shapes of their own (model.hpp's Shape): their volume, bounding radius,
// uniform mass properties against the closed forms, validate()'s refusals naming the field, and
// the capsule the particle method collides them as (capsule_proxy.hpp).
#include <cmath>
#include <numbers>
#include <string>

#include <gtest/gtest.h>

#include "limber/kernel/mass/mass_properties.hpp"
#include "limber/kernel/model/model.hpp"
#include "limber/kernel/scene/capsule_proxy.hpp"
#include "tests/support/validation.hpp"

namespace limber {
namespace {

using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector3d;
using testing::validation_error;

Shape box_or_ellipsoid(ShapeType type, const Vector3d& half_extents, const Quaterniond& rotation = Quaterniond::Identity()) {
  Shape shape;
  shape.type = type;
  shape.half_extents = half_extents;
  shape.rotation = rotation;
  return shape;
}

Body body_of(const Shape& shape, double mass) {
  Body body;
  body.name = "solid";
  body.shape = shape;
  body.mass = mass;
  body.position = {0, 0, 1};
  return body;
}

// Half-extents a, b, c along x, y, z.
constexpr double a = 0.1, b = 0.25, c = 0.4;

TEST(ShapeVolume, BoxAndEllipsoidAreTheClosedForms) {
  EXPECT_DOUBLE_EQ(volume(box_or_ellipsoid(ShapeType::box, {a, b, c})), 8 * a * b * c);
  EXPECT_DOUBLE_EQ(volume(box_or_ellipsoid(ShapeType::ellipsoid, {a, b, c})), 4.0 / 3.0 * std::numbers::pi * a * b * c);
  // A rotation changes neither.
  const Quaterniond turn(Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()));
  EXPECT_DOUBLE_EQ(volume(box_or_ellipsoid(ShapeType::box, {a, b, c}, turn)), 8 * a * b * c);
}

TEST(ShapeBoundingRadius, HoldsEachShapeAboutItsCentre) {
  EXPECT_DOUBLE_EQ(bounding_radius(Shape{ShapeType::capsule, 0.4, 0.05}), 0.25);
  EXPECT_DOUBLE_EQ(bounding_radius(Shape{ShapeType::cylinder, 0.6, 0.4}), 0.5);
  EXPECT_DOUBLE_EQ(bounding_radius(box_or_ellipsoid(ShapeType::box, {a, b, c})), std::sqrt(a * a + b * b + c * c)) << "a corner";
  EXPECT_DOUBLE_EQ(bounding_radius(box_or_ellipsoid(ShapeType::ellipsoid, {a, b, c})), c) << "the longest semi-axis";
}

TEST(ShapeMassProperties, BoxAboutItsCentreIsMOverThreeTimesTheOtherHalfExtentsSquared) {
  const double m = 3;
  const MassProperties solid = body_mass_properties(body_of(box_or_ellipsoid(ShapeType::box, {a, b, c}), m));
  EXPECT_EQ(solid.mass, m);
  EXPECT_EQ(solid.centre_of_mass, Vector3d::Zero());
  const Matrix3d expected = Vector3d(m / 3 * (b * b + c * c), m / 3 * (a * a + c * c), m / 3 * (a * a + b * b)).asDiagonal();
  EXPECT_LT((solid.inertia - expected).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(ShapeMassProperties, EllipsoidAboutItsCentreIsMOverFiveTimesTheOtherSemiAxesSquared) {
  const double m = 2;
  const MassProperties solid = body_mass_properties(body_of(box_or_ellipsoid(ShapeType::ellipsoid, {a, b, c}), m));
  EXPECT_EQ(solid.mass, m);
  EXPECT_EQ(solid.centre_of_mass, Vector3d::Zero());
  const Matrix3d expected = Vector3d(m / 5 * (b * b + c * c), m / 5 * (a * a + c * c), m / 5 * (a * a + b * b)).asDiagonal();
  EXPECT_LT((solid.inertia - expected).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(ShapeMassProperties, ATurnedShapesInertiaIsTheTurnOfItsPrincipalOne) {
  const double m = 1.5;
  const Quaterniond turn(Eigen::AngleAxisd(0.9, Vector3d(1, -2, 0.5).normalized()));
  const Matrix3d r = turn.toRotationMatrix();
  for (const ShapeType type : {ShapeType::box, ShapeType::ellipsoid}) {
    SCOPED_TRACE(std::string(shape_type_name(type)));
    const double k = type == ShapeType::box ? m / 3 : m / 5;
    const Matrix3d principal = Vector3d(k * (b * b + c * c), k * (a * a + c * c), k * (a * a + b * b)).asDiagonal();
    const MassProperties solid = body_mass_properties(body_of(box_or_ellipsoid(type, {a, b, c}, turn), m));
    EXPECT_LT((solid.inertia - r * principal * r.transpose()).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_LT((solid.inertia - solid.inertia.transpose()).cwiseAbs().maxCoeff(), 1e-17);
  }
  // A quarter turn about z swaps the x and y moments exactly as the closed form says.
  const Quaterniond quarter(Eigen::AngleAxisd(std::numbers::pi / 2, Vector3d::UnitZ()));
  const MassProperties swapped = body_mass_properties(body_of(box_or_ellipsoid(ShapeType::box, {a, b, c}, quarter), m));
  EXPECT_NEAR(swapped.inertia(0, 0), m / 3 * (a * a + c * c), 1e-15);
  EXPECT_NEAR(swapped.inertia(1, 1), m / 3 * (b * b + c * c), 1e-15);
}

// ---- validate(): each bad field named

std::string error_of(const Shape& shape) {
  Model model;
  model.name = "one";
  model.bodies = {body_of(shape, 1)};
  return validation_error(model);
}

TEST(ShapeValidation, GoodBoxesAndEllipsoidsPass) {
  const Quaterniond turn(Eigen::AngleAxisd(0.3, Vector3d::UnitX()));
  EXPECT_EQ(error_of(box_or_ellipsoid(ShapeType::box, {a, b, c}, turn)), "");
  EXPECT_EQ(error_of(box_or_ellipsoid(ShapeType::ellipsoid, {a, b, c})), "");
}

TEST(ShapeValidation, EachBadFieldIsNamed) {
  Shape box = box_or_ellipsoid(ShapeType::box, {a, b, c});
  box.length = 0.2;
  EXPECT_EQ(error_of(box), "bodies[0].shape.length: a box has half_extents, not this field; leave it out");
  Shape egg = box_or_ellipsoid(ShapeType::ellipsoid, {a, b, c});
  egg.radius = 0.1;
  EXPECT_EQ(error_of(egg), "bodies[0].shape.radius: an ellipsoid has half_extents, not this field; leave it out");
  EXPECT_EQ(error_of(box_or_ellipsoid(ShapeType::box, Vector3d::Zero())), "bodies[0].shape.half_extents[0]: must be > 0, got 0")
      << "half_extents left out";
  EXPECT_EQ(error_of(box_or_ellipsoid(ShapeType::box, {a, 0, c})), "bodies[0].shape.half_extents[1]: must be > 0, got 0");
  EXPECT_EQ(error_of(box_or_ellipsoid(ShapeType::ellipsoid, {a, b, NAN})), "bodies[0].shape.half_extents[2]: must be a finite number, got nan");
  EXPECT_EQ(error_of(box_or_ellipsoid(ShapeType::box, {a, b, c}, Quaterniond(1, 0, 0, 1e-4))),
            "bodies[0].shape.rotation: must be a unit quaternion");
  EXPECT_EQ(error_of(box_or_ellipsoid(ShapeType::box, {a, b, c}, Quaterniond(NAN, 0, 0, 0))), "bodies[0].shape.rotation: must be a unit quaternion");
  Shape capsule{ShapeType::capsule, 0.3, 0.05};
  capsule.half_extents = {a, b, c};
  EXPECT_EQ(error_of(capsule), "bodies[0].shape.half_extents: a capsule has a length and a radius, not this field; leave it out");
  Shape cylinder{ShapeType::cylinder, 0.3, 0.05};
  cylinder.rotation = Quaterniond(Eigen::AngleAxisd(0.3, Vector3d::UnitX()));
  EXPECT_EQ(error_of(cylinder), "bodies[0].shape.rotation: a cylinder has its axis along the body's, not this field; leave it out");
  EXPECT_EQ(error_of(box_or_ellipsoid(ShapeType::box, Vector3d::Constant(1e200))),
            "bodies[0].shape: half_extents [1e+200, 1e+200, 1e+200] m with mass 1 kg: the body's extent squared, or its inertia (mass × "
            "extent²), is not a finite number");
}

// ---- The particle method's stand-in

TEST(CapsuleProxy, ABoxAlongTheBodysAxisIsTheCapsuleSpanningItsLongestSideWithItsShortestHalfSide) {
  const Shape proxy = capsule_proxy(box_or_ellipsoid(ShapeType::box, {a, b, c}));  // c, the longest, on body z
  EXPECT_EQ(proxy.type, ShapeType::capsule);
  EXPECT_DOUBLE_EQ(proxy.radius, a);
  EXPECT_DOUBLE_EQ(proxy.length, 2 * (c - a));
  EXPECT_EQ(proxy.half_extents, Vector3d::Zero()) << "a capsule as validate() takes it";
  // The same box with its longest side on its own x, turned so that x lies along the body's z.
  const Quaterniond x_to_z = Quaterniond::FromTwoVectors(Vector3d::UnitX(), Vector3d::UnitZ());
  const Shape turned = capsule_proxy(box_or_ellipsoid(ShapeType::box, {c, b, a}, x_to_z));
  EXPECT_DOUBLE_EQ(turned.radius, a);
  EXPECT_NEAR(turned.length, 2 * (c - a), 1e-15);
  // An ellipsoid's is the same capsule: its support along z is its semi-axis there.
  const Shape egg = capsule_proxy(box_or_ellipsoid(ShapeType::ellipsoid, {a, b, c}));
  EXPECT_DOUBLE_EQ(egg.radius, a);
  EXPECT_DOUBLE_EQ(egg.length, 2 * (c - a));
  // Other shapes are their own.
  const Shape capsule{ShapeType::capsule, 0.3, 0.05};
  EXPECT_EQ(capsule_proxy(capsule).length, 0.3);
  EXPECT_EQ(capsule_proxy(capsule).radius, 0.05);
}

}  // namespace
}  // namespace limber
