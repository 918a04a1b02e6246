// validate() on models built in C++, and the Body geometry helpers.
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "limber/kernel/model/method_settings.hpp"
#include "limber/kernel/model/model.hpp"
#include "tests/support/validation.hpp"

namespace limber {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
using testing::validation_error;

/// Two limbs hanging from the world, with ground, bounds and a ball: valid as built.
Model good_model() {
  Model model;
  model.name = "two_links";
  Body upper;
  upper.name = "upper";
  upper.shape = {ShapeType::capsule, 0.2, 0.015};
  upper.mass = 2;
  upper.position = {0, 0, 1.4};
  Body lower = upper;
  lower.name = "lower";
  lower.position = {0, 0, 1.2};
  model.bodies = {upper, lower};

  Joint pin;
  pin.name = "pin";
  pin.inboard = kWorld;
  pin.outboard = 0;
  pin.inboard_anchor = {0, 0, 1.5};
  pin.outboard_anchor = {0, 0, 0.1};
  Joint elbow;
  elbow.name = "elbow";
  elbow.inboard = 0;
  elbow.outboard = 1;
  elbow.inboard_anchor = {0, 0, -0.1};
  elbow.outboard_anchor = {0, 0, 0.1};
  model.joints = {pin, elbow};

  model.ground = Ground{0, 0.1, 0.6};
  model.bounds = Bounds{{-5, -5, 0}, {5, 5, 5}, 0.5, 0.2};
  model.balls = {Ball{0.05, 2.27, 0.8, {0.8, 0, 0.25}, {-6, 0, 0}}};
  return model;
}

/// Breaks one field of the good model and returns the message.
std::string error_after(const std::function<void(Model&)>& break_it) {
  Model model = good_model();
  break_it(model);
  return validation_error(model);
}

TEST(ModelValidation, ValidateAcceptsAWellFormedModel) {
  EXPECT_EQ(validation_error(good_model()), "");
}

TEST(ModelValidation, ValidateRejectsNegativeMassNamingTheField) {
  EXPECT_EQ(error_after([](Model& m) { m.bodies[1].mass = -1; }),
            "bodies[1].mass: must be > 0, got -1");
}

TEST(ModelValidation, ValidateRejectsZeroMass) {
  EXPECT_EQ(error_after([](Model& m) { m.bodies[0].mass = 0; }),
            "bodies[0].mass: must be > 0, got 0");
}

TEST(ModelValidation, ValidateRejectsNegativeRadius) {
  EXPECT_EQ(error_after([](Model& m) { m.bodies[0].shape.radius = -0.01; }),
            "bodies[0].shape.radius: must be >= 0, got -0.01");
}

TEST(ModelValidation, ValidateAcceptsZeroRadius) {
  EXPECT_EQ(error_after([](Model& m) { m.bodies[0].shape.radius = 0; }), "");
}

TEST(ModelValidation, ValidateRejectsZeroLength) {
  EXPECT_EQ(error_after([](Model& m) { m.bodies[1].shape = {ShapeType::cylinder, 0, 0.05}; }),
            "bodies[1].shape.length: must be > 0, got 0");
  // A capsule of length 0 is a sphere, which needs a radius.
  EXPECT_EQ(error_after([](Model& m) { m.bodies[1].shape = {ShapeType::capsule, 0, 0}; }),
            "bodies[1].shape.radius: must be > 0, got 0");
}

TEST(ModelValidation, ValidateRejectsNanInAVectorNamingTheComponent) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(error_after([&](Model& m) { m.bodies[1].linear_velocity.y() = nan; }),
            "bodies[1].linear_velocity[1]: must be a finite number, got nan");
}

TEST(ModelValidation, ValidateRejectsInfiniteGravity) {
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(error_after([&](Model& m) { m.settings.gravity.z() = -inf; }),
            "settings.gravity[2]: must be a finite number, got -inf");
}

TEST(ModelValidation, ValidateRejectsNonUnitAxis) {
  EXPECT_EQ(error_after([](Model& m) { m.bodies[0].axis = {0, 0, 2}; }),
            "bodies[0].axis: must be a unit vector, got length 2");
  EXPECT_EQ(error_after([](Model& m) { m.bodies[0].axis = {0, 0, 1 + 1e-12}; }), "");
}

TEST(ModelValidation, ValidateRejectsJointWithOutOfRangeBodyIndex) {
  EXPECT_EQ(error_after([](Model& m) { m.joints[1].outboard = 12; }),
            "joints[1].outboard: names body index 12 but there are 2 bodies");
  EXPECT_EQ(error_after([](Model& m) { m.joints[1].inboard = -2; }),
            "joints[1].inboard: names body index -2 but there are 2 bodies");
}

TEST(ModelValidation, ValidateRejectsJointJoiningABodyToItself) {
  EXPECT_EQ(error_after([](Model& m) { m.joints[1].inboard = 1; }),
            "joints[1].outboard: must differ from inboard, both are body index 1");
}

TEST(ModelValidation, ValidateRejectsDuplicateBodyName) {
  EXPECT_EQ(error_after([](Model& m) { m.bodies[1].name = "upper"; }),
            "bodies[1].name: duplicate name \"upper\" (also bodies[0])");
}

TEST(ModelValidation, ValidateRejectsDuplicateJointName) {
  EXPECT_EQ(error_after([](Model& m) { m.joints[1].name = "pin"; }),
            "joints[1].name: duplicate name \"pin\" (also joints[0])");
}

TEST(ModelValidation, ValidateRejectsEmptyAndReservedBodyNames) {
  EXPECT_THAT(error_after([](Model& m) { m.bodies[0].name = ""; }), HasSubstr("bodies[0].name: "));
  EXPECT_THAT(error_after([](Model& m) { m.bodies[0].name = "world"; }),
              HasSubstr("bodies[0].name: \"world\" is reserved"));
}

TEST(ModelValidation, ValidateRejectsNonPositiveTimeStep) {
  EXPECT_EQ(error_after([](Model& m) { m.settings.time_step = 0; }),
            "settings.time_step: must be > 0, got 0");
  EXPECT_EQ(error_after([](Model& m) { m.settings.time_step = -0.01; }),
            "settings.time_step: must be > 0, got -0.01");
}

TEST(ModelValidation, ValidateRejectsRestitutionAboveOne) {
  EXPECT_EQ(error_after([](Model& m) { m.ground->restitution = 1.5; }),
            "ground.restitution: must be in [0, 1], got 1.5");
  EXPECT_EQ(error_after([](Model& m) { m.balls.front().restitution = 1.5; }),
            "balls[0].restitution: must be in [0, 1], got 1.5");
}

TEST(ModelValidation, ValidateRejectsBoundsWhoseMaxIsNotAboveMin) {
  EXPECT_EQ(error_after([](Model& m) { m.bounds->max.y() = -5; }),
            "bounds.max[1]: must be > bounds.min[1] = -5, got -5");
  EXPECT_EQ(error_after([](Model& m) { m.bounds->max.z() = -1; }),
            "bounds.max[2]: must be > bounds.min[2] = 0, got -1");
}

// What validate(MethodSettings) throws, or "" (the scene file's names for the fields).
std::string method_settings_error(const std::function<void(MethodSettings&)>& change) {
  MethodSettings settings;
  change(settings);
  try {
    validate(settings);
  } catch (const ModelError& error) {
    return error.what();
  }
  return "";
}

TEST(ModelValidation, ValidateRejectsZeroRelaxationIterations) {
  EXPECT_EQ(method_settings_error([](MethodSettings& m) { m.relaxation.iterations = 0; }),
            "settings.relaxation.iterations: must be >= 1, got 0");
  EXPECT_EQ(method_settings_error([](MethodSettings& m) { m.relaxation.substeps = 10001; }),
            "settings.relaxation.substeps: must be <= 10000, got 10001");
  EXPECT_EQ(method_settings_error([](MethodSettings& m) { m.springs.stiffness = 0; }),
            "settings.springs.stiffness: must be > 0, got 0");
}

TEST(ModelValidation, ValidateRejectsBallWithoutSizeOrMass) {
  EXPECT_EQ(error_after([](Model& m) { m.balls.front().radius = 0; }), "balls[0].radius: must be in (0, 1000], got 0");
  EXPECT_EQ(error_after([](Model& m) { m.balls.front().mass = -2; }), "balls[0].mass: must be in (0, 1e+09], got -2");
}

// A ball past the stated limits is refused as the ball it is: a radius of 1e300 m once passed
// validation and was refused by Featherstone's compile as "bodies[9]" (the rigid body it becomes).
TEST(ModelValidation, ValidateRejectsABallPastItsLimitsNamingTheBall) {
  EXPECT_EQ(error_after([](Model& m) { m.balls.front().radius = 1e300; }), "balls[0].radius: must be in (0, 1000], got 1e+300");
  EXPECT_EQ(error_after([](Model& m) { m.balls.front().mass = 1e300; }), "balls[0].mass: must be in (0, 1e+09], got 1e+300");
}

TEST(ModelValidation, ValidateRejectsATimeStepShorterThanAnyMethodTakes) {
  EXPECT_EQ(error_after([](Model& m) { m.settings.time_step = 1e-12; }),
            "settings.time_step: must be >= 1e-09 s (the shortest step a method takes), got 1e-12");
}

TEST(ModelValidation, ValidateChecksDragFactorOnlyWhenSet) {
  EXPECT_EQ(method_settings_error([](MethodSettings& m) { m.verlet.drag_factor = 1.99; }), "");
  EXPECT_EQ(method_settings_error([](MethodSettings& m) { m.verlet.drag_factor = 1; }),
            "settings.verlet.drag_factor: must be in (1, 2], got 1");
}

TEST(ModelValidation, ValidateMessagesAreOneLine) {
  const std::string message = error_after([](Model& m) { m.settings.sleep.time_to_sleep = -1; });
  EXPECT_EQ(message, "settings.sleep.time_to_sleep: must be >= 0, got -1");
  EXPECT_THAT(message, Not(HasSubstr("\n")));
}

TEST(ShapeVolume, CylinderVolumeIsPiRSquaredL) {
  const Shape cylinder{ShapeType::cylinder, 0.3, 0.02};
  EXPECT_DOUBLE_EQ(volume(cylinder), std::numbers::pi * 0.02 * 0.02 * 0.3);
}

TEST(ShapeVolume, CapsuleVolumeAddsASphereForItsTwoCaps) {
  const Shape capsule{ShapeType::capsule, 0.2, 0.015};
  const double r = 0.015;
  EXPECT_DOUBLE_EQ(volume(capsule),
                   std::numbers::pi * r * r * 0.2 + 4.0 / 3.0 * std::numbers::pi * r * r * r);
}

/// A tilted, moving, spinning limb.
Body tilted_body() {
  Body body;
  body.shape = {ShapeType::cylinder, 0.4, 0.03};
  body.mass = 1;
  body.position = {1, 2, 3};
  body.axis = Vector3(1, -2, 2).normalized();
  body.linear_velocity = {0.5, 0, -1};
  body.angular_velocity = {0, 3, 1};
  return body;
}

TEST(BodyFrame, ToWorldOfTheLocalHeadIsTheHead) {
  const Body body = tilted_body();
  EXPECT_LT((body.to_world({0, 0, 0.2}) - body.head()).norm(), 1e-12);
  EXPECT_LT((body.to_world({0, 0, -0.2}) - body.tail()).norm(), 1e-12);
  EXPECT_LT((body.to_world(Vector3::Zero()) - body.position).norm(), 1e-12);
}

TEST(BodyFrame, OrientationMapsLocalZOntoTheAxis) {
  Body body = tilted_body();
  EXPECT_LT((body.orientation() * Vector3::UnitZ() - body.axis).norm(), 1e-12);
  body.axis = -Vector3::UnitZ();  // the antiparallel case has no unique shortest arc
  EXPECT_LT((body.orientation() * Vector3::UnitZ() - body.axis).norm(), 1e-12);
}

TEST(BodyFrame, VelocityAtAddsOmegaCrossR) {
  const Body body = tilted_body();
  const Vector3 local(0.03, 0, 0.2);
  const Vector3 r = body.to_world(local) - body.position;
  const Vector3 expected = body.linear_velocity + body.angular_velocity.cross(r);
  EXPECT_LT((body.velocity_at(local) - expected).norm(), 1e-12);
  EXPECT_GT((expected - body.linear_velocity).norm(), 0.1);  // the rotation part is not tiny
}

TEST(ModelQueries, FindBodyAndBodyMass) {
  const Model model = good_model();
  EXPECT_EQ(model.find_body("lower"), 1);
  EXPECT_EQ(model.find_body("nobody"), -1);
  EXPECT_DOUBLE_EQ(model.body_mass(), 4);  // the ball is not a body
}

}  // namespace
}  // namespace limber
