// The rigid methods (springs, Lagrange, Featherstone) answer the collision world's contacts
// (kernel/geometry/limb_collisions.hpp through rigid_contacts.hpp): a capsule dropped across
// another comes to rest on it, and one dropped on a static box rests on its top face.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/geometry/bounding_volumes.hpp"
#include "limber/kernel/world/world.hpp"

namespace limber {
namespace {

using Eigen::Vector3d;

constexpr double kStep = 1.0 / 240;  // s

Body capsule(const std::string& name, const Vector3d& centre, const Vector3d& axis, double length, double radius, double mass) {
  Body body;
  body.name = name;
  body.shape = {ShapeType::capsule, length, radius};
  body.mass = mass;
  body.position = centre;
  body.axis = axis;
  return body;
}

Model ground_model() {
  Model model;
  model.name = "limb_contacts";
  model.ground = Ground{0, 0, 0.8};
  model.settings.time_step = kStep;
  return model;
}

// The body's core segment now, from its pose (the Model's body frame: centre, +z to the head).
std::pair<Vector3d, Vector3d> segment(const World& world, BodyId body) {
  const Pose pose = world.pose(body);
  const double half = 0.5 * world.body_description(body).shape.length;
  return {pose.position + pose.orientation * Vector3d(0, 0, half), pose.position - pose.orientation * Vector3d(0, 0, half)};
}

class RigidLimbContacts : public ::testing::TestWithParam<Method> {};

std::string method_name(const ::testing::TestParamInfo<Method>& info) {
  switch (info.param) {
    case Method::springs: return "springs";
    case Method::lagrange: return "lagrange";
    case Method::featherstone: return "featherstone";
    default: return "other";
  }
}

// A thick capsule lying along x on the ground, a thinner one along y dropped 0.2 m onto its
// middle. The lower is thicker so the upper's balance on it is stable (a rod on a cylinder of
// larger radius rocks back), and the contact sits on both centres, so nothing tips.
constexpr double kLowerRadius = 0.08, kUpperRadius = 0.04;  // m

struct CrossedDrop {
  Vector3d lower, upper;      // the centres at the end, m
  double deepest = 0;         // the deepest overlap of the two capsules over the run, m
  bool lower_woke = false;    // the lower was awake after some step
};

// `asleep`: the lower starts asleep (Settings::sleep.start_asleep; the upper, thrown down at
// 0.5 m/s, does not), so only the contact can wake it.
CrossedDrop drop_across(Method method, bool collide, bool asleep = false) {
  const double r1 = kLowerRadius, r2 = kUpperRadius;
  Model model = ground_model();
  model.bodies = {capsule("lower", {0, 0, r1}, Vector3d::UnitX(), 0.6, r1, 4.0),
                  capsule("upper", {0, 0, 2 * r1 + r2 + 0.2}, Vector3d::UnitY(), 0.5, r2, 1.0)};
  if (!collide) model.bodies[1].collision.mask = 0;  // the control: the filter lets it through
  if (asleep) model.settings.sleep.start_asleep = true, model.bodies[1].linear_velocity = {0, 0, -0.5};
  World world(model, WorldOptions{.method = method});
  const BodyId lower = world.body("lower"), upper = world.body("upper");
  CrossedDrop result;
  for (int step = 0; step < 480; ++step) {
    EXPECT_EQ(world.step(kStep), StepStatus::ok) << "step " << step;
    const auto [a0, a1] = segment(world, lower);
    const auto [b0, b1] = segment(world, upper);
    result.deepest = std::max(result.deepest, r1 + r2 - closest_points_between_segments(a0, a1, b0, b1).distance);
    result.lower_woke = result.lower_woke || !world.sleeping(lower);
  }
  result.lower = world.pose(lower).position, result.upper = world.pose(upper).position;
  return result;
}

TEST_P(RigidLimbContacts, CapsuleDroppedAcrossAnotherRestsOnTop) {
  const CrossedDrop drop = drop_across(GetParam(), true);
  // On top, not through: the centres stacked by r1 + r2 within 5 mm (the method's push-out and
  // resting overlap), the upper still centred over the lower.
  EXPECT_NEAR(drop.upper.z() - drop.lower.z(), kLowerRadius + kUpperRadius, 5e-3);
  EXPECT_LT((drop.upper - drop.lower).head<2>().norm(), 0.05);
  EXPECT_NEAR(drop.lower.z(), kLowerRadius, 5e-3);  // the lower stays on the ground
  // Impact at about 2 m/s moves 8 mm a step: the overlap stays within a step's travel and a bit.
  EXPECT_LT(drop.deepest, 0.015);

  // The control: with the pair filtered out the upper falls through the lower to the ground.
  const CrossedDrop through = drop_across(GetParam(), false);
  EXPECT_NEAR(through.upper.z(), kUpperRadius, 5e-3);
}

TEST_P(RigidLimbContacts, CapsuleLandingOnASleepingOneWakesItAndRests) {
  const CrossedDrop drop = drop_across(GetParam(), true, /*asleep=*/true);
  EXPECT_TRUE(drop.lower_woke);
  EXPECT_NEAR(drop.upper.z() - drop.lower.z(), kLowerRadius + kUpperRadius, 5e-3);
  EXPECT_LT(drop.deepest, 0.015);
}

// Two limbs of one tree (one island; Featherstone's one articulated body): A lies on the ground,
// a short post C stands on its end and B, hung from the post's top, swings down onto A. A and B
// are not joined, so they collide; returns the smallest gap between them over the run (m,
// negative: overlap) and the gap at the end.
std::pair<double, double> swing_onto_own_limb(Method method, bool collide) {
  Model model = ground_model();
  model.bodies = {capsule("a", {0, 0, 0.05}, Vector3d::UnitX(), 0.8, 0.05, 3.0),
                  capsule("b", {0.05, 0, 0.35}, Vector3d::UnitX(), 0.7, 0.04, 1.0),
                  capsule("c", {0.4, 0, 0.2}, Vector3d::UnitZ(), 0.3, 0.03, 0.5)};
  model.joints = {spherical_joint("a_c", 0, 2, {0, 0, 0.4}, {0, 0, -0.15}), spherical_joint("c_b", 2, 1, {0, 0, 0.15}, {0, 0, 0.35})};
  if (!collide) model.bodies[1].collision.mask = 0;
  WorldOptions options{.method = method};
  // The post's stiff springs at this step need the implicit integrator (semi-implicit Euler
  // diverges here with or without the contact).
  options.springs.integrator = Integrator::backward_euler;
  World world(model, options);
  const BodyId a = world.body("a"), b = world.body("b");
  double smallest = 1, gap = 1;
  for (int step = 0; step < 480; ++step) {
    EXPECT_EQ(world.step(kStep), StepStatus::ok) << "step " << step;
    const auto [a0, a1] = segment(world, a);
    const auto [b0, b1] = segment(world, b);
    gap = closest_points_between_segments(a0, a1, b0, b1).distance - 0.09;
    smallest = std::min(smallest, gap);
  }
  return {smallest, gap};
}

TEST_P(RigidLimbContacts, LimbSwingingOntoAnotherOfItsTreeStopsOnIt) {
  const auto [smallest, end] = swing_onto_own_limb(GetParam(), true);
  EXPECT_GT(smallest, -0.015);  // a step's travel and a bit, never through
  EXPECT_GT(end, -0.005);
  // The control: filtered out, B swings down through A.
  EXPECT_LT(swing_onto_own_limb(GetParam(), false).first, -0.04);
}

TEST_P(RigidLimbContacts, CapsuleDroppedOnAStaticBoxRestsOnItsTop) {
  const double r = 0.05;
  Model model = ground_model();
  StaticCollider box;
  box.name = "table";
  box.type = ColliderType::box;
  box.position = {0, 0, 0.25};
  box.half_extents = {0.5, 0.5, 0.25};  // top face at z = 0.5
  box.friction = 0.8;
  model.colliders = {box};
  model.bodies = {capsule("limb", {0.1, 0, 0.8}, Vector3d(1, 0, 0.2).normalized(), 0.4, r, 1.0)};
  World world(model, WorldOptions{.method = GetParam()});
  const BodyId limb = world.body("limb");
  double deepest = 0;  // m, how far an end sphere went below the top face
  for (int step = 0; step < 480; ++step) {
    ASSERT_EQ(world.step(kStep), StepStatus::ok) << "step " << step;
    const auto [head, tail] = segment(world, limb);
    deepest = std::max(deepest, 0.5 + r - std::min(head.z(), tail.z()));
  }
  const auto [head, tail] = segment(world, limb);
  // Lying on the top face (both ends on it), not on the ground 0.5 m below.
  EXPECT_NEAR(head.z(), 0.5 + r, 5e-3);
  EXPECT_NEAR(tail.z(), 0.5 + r, 5e-3);
  EXPECT_LT(deepest, 0.015);
}

INSTANTIATE_TEST_SUITE_P(Methods, RigidLimbContacts, ::testing::Values(Method::springs, Method::lagrange, Method::featherstone),
                         method_name);

}  // namespace
}  // namespace limber
