// validate() on static colliders and limb friction: each bad field is named in one line, in the
// Model's terms ("colliders[2].mesh.triangles[1]: ...").
#include <cmath>
#include <limits>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "limber/kernel/model/model.hpp"
#include "tests/support/validation.hpp"

namespace limber {
namespace {

using testing::validation_error;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

/// One limb above a box, a capsule and a one-triangle mesh: valid as built.
Model model_with_colliders() {
  Model model;
  model.name = "colliders";
  Body limb;
  limb.name = "limb";
  limb.shape = {ShapeType::capsule, 0.2, 0.015};
  limb.mass = 1;
  limb.position = {0, 0, 2};
  model.bodies = {limb};

  StaticCollider box;
  box.name = "box";
  box.type = ColliderType::box;
  box.half_extents = {1, 1, 0.1};
  box.orientation = Eigen::AngleAxisd(0.3, Vector3::UnitZ());
  StaticCollider bar;
  bar.name = "bar";
  bar.type = ColliderType::capsule;
  bar.position = {0, 0, 1};
  bar.length = 1, bar.radius = 0.05;
  StaticCollider floor;
  floor.name = "floor";
  floor.type = ColliderType::mesh;
  floor.mesh.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  floor.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  model.colliders = {box, bar, floor};
  return model;
}

/// The message for the model with `edit` applied.
template <typename Edit>
std::string error_after(Edit edit) {
  Model model = model_with_colliders();
  edit(model);
  return validation_error(model);
}

TEST(ColliderValidation, AcceptsABoxACapsuleAndAMesh) { EXPECT_EQ(validation_error(model_with_colliders()), ""); }

TEST(ColliderValidation, NamesMustBeNonEmptyUniqueAndNoBodysName) {
  EXPECT_EQ(error_after([](Model& m) { m.colliders[1].name = ""; }), "colliders[1].name: must be a non-empty name");
  EXPECT_EQ(error_after([](Model& m) { m.colliders[2].name = "box"; }), "colliders[2].name: duplicate name \"box\" (also colliders[0])");
  EXPECT_EQ(error_after([](Model& m) { m.colliders[1].name = "limb"; }), "colliders[1].name: \"limb\" is also a body's name");
}

TEST(ColliderValidation, BoxesAndCapsulesNeedTheirSizes) {
  EXPECT_EQ(error_after([](Model& m) { m.colliders[0].half_extents.y() = 0; }), "colliders[0].half_extents[1]: must be > 0, got 0");
  EXPECT_EQ(error_after([](Model& m) { m.colliders[0].half_extents.z() = kNan; }),
            "colliders[0].half_extents[2]: must be a finite number, got nan");
  EXPECT_EQ(error_after([](Model& m) { m.colliders[1].radius = 0; }), "colliders[1].radius: must be > 0, got 0");
  EXPECT_EQ(error_after([](Model& m) { m.colliders[1].length = -0.5; }), "colliders[1].length: must be >= 0, got -0.5");
  EXPECT_EQ(error_after([](Model& m) { m.colliders[1].length = 0; }), "");  // a sphere
  // A field of another type is not looked at: a box's radius means nothing.
  EXPECT_EQ(error_after([](Model& m) { m.colliders[0].radius = -1; }), "");
}

TEST(ColliderValidation, PositionsAreFiniteAndOrientationsUnit) {
  EXPECT_EQ(error_after([](Model& m) { m.colliders[1].position.x() = kNan; }), "colliders[1].position[0]: must be a finite number, got nan");
  EXPECT_EQ(error_after([](Model& m) { m.colliders[0].orientation = Eigen::Quaterniond(2, 0, 0, 0); }),
            "colliders[0].orientation: must be a unit quaternion (normalize it), got norm 2");
  EXPECT_EQ(error_after([](Model& m) { m.colliders[0].orientation = Eigen::Quaterniond(0, 0, 0, 0); }),
            "colliders[0].orientation: must be a unit quaternion (normalize it), got norm 0");
  EXPECT_EQ(error_after([](Model& m) { m.colliders[0].orientation = Eigen::Quaterniond(kNan, 0, 0, 0); }),
            "colliders[0].orientation.coeffs[3]: must be a finite number, got nan");  // coeffs are x, y, z, w
}

TEST(ColliderValidation, MeshesNeedTrianglesOnFiniteVerticesWithArea) {
  EXPECT_EQ(error_after([](Model& m) { m.colliders[2].mesh.triangles.clear(); }), "colliders[2].mesh.triangles: must list at least one triangle");
  EXPECT_EQ(error_after([](Model& m) { m.colliders[2].mesh.triangles[1][2] = 4; }),
            "colliders[2].mesh.triangles[1]: vertex index 4 names no vertex (there are 4)");
  EXPECT_EQ(error_after([](Model& m) { m.colliders[2].mesh.triangles[1] = {0, 2, 0}; }),
            "colliders[2].mesh.triangles[1]: is degenerate (area 0 m^2): its vertices are repeated or in a line");
  EXPECT_EQ(error_after([](Model& m) { m.colliders[2].mesh.vertices[3] = {2, 2, 0}; }),  // on the line 0–2
            "colliders[2].mesh.triangles[1]: is degenerate (area 0 m^2): its vertices are repeated or in a line");
  EXPECT_EQ(error_after([](Model& m) { m.colliders[2].mesh.vertices[3].y() = kNan; }),
            "colliders[2].mesh.vertices[3][1]: must be a finite number, got nan");
  EXPECT_EQ(error_after([](Model& m) { m.colliders[2].thickness = 0; }), "colliders[2].thickness: must be > 0, got 0");
  // A tiny triangle is fine: degeneracy is relative to its size.
  EXPECT_EQ(error_after([](Model& m) {
              for (Vector3& v : m.colliders[2].mesh.vertices) v *= 1e-6;
            }),
            "");
}

TEST(ColliderValidation, SurfaceCoefficientsAndLimbFrictionAreInRange) {
  EXPECT_EQ(error_after([](Model& m) { m.colliders[0].restitution = 1.5; }), "colliders[0].restitution: must be in [0, 1], got 1.5");
  EXPECT_EQ(error_after([](Model& m) { m.colliders[2].friction = -0.1; }), "colliders[2].friction: must be >= 0, got -0.1");
  EXPECT_EQ(error_after([](Model& m) { m.settings.limb_friction = -1; }), "settings.limb_friction: must be >= 0, got -1");
  EXPECT_EQ(error_after([](Model& m) { m.settings.limb_friction = std::numeric_limits<double>::infinity(); }),
            "settings.limb_friction: must be a finite number, got inf");
}

}  // namespace
}  // namespace limber
