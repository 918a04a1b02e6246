// Boxes and ellipsoids collide as themselves under the rigid methods (springs, Lagrange,
// Featherstone; the shape-pair table, kernel/geometry/shape_pairs.hpp): a box on an edge falls
// onto a face, a box on a slope slides above the friction angle at Coulomb's acceleration and
// holds below it (to the creep of the loop that moves before it collides), a stack of boxes stands, and a box resting on a face keeps four contact points
// whose ids do not change from step to step.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "limber/kernel/geometry/limb_collisions.hpp"
#include "limber/kernel/model/capabilities.hpp"
#include "limber/kernel/world/world.hpp"

namespace limber {
namespace {

// The methods that collide boxes as themselves (MethodCapabilities::true_shapes).
std::vector<Method> true_shape_methods_of_table() {
  std::vector<Method> methods;
  for (const MethodCapabilities& entry : kMethodCapabilities) {
    if (entry.true_shapes) methods.push_back(entry.method);
  }
  return methods;
}

// A free box of half-extents `half` (m), 1 kg, its centre at `centre`, turned by `turn` (world).
Body crate_body(const std::string& name, const Eigen::Vector3d& half, const Eigen::Vector3d& centre,
         const Eigen::Quaterniond& turn = Eigen::Quaterniond::Identity()) {
  Body body;
  body.name = name;
  body.shape.type = ShapeType::box;
  body.shape.half_extents = half;
  body.mass = 1;
  body.position = centre;
  body.axis = Eigen::Vector3d::UnitZ();
  body.shape.rotation = turn;  // the body frame is the world's: the shape frame is the turn
  return body;
}

Model crate_floor(double friction) {
  Model model;
  model.name = "boxes";
  model.ground = Ground{0.0, 0.0, friction};
  model.settings.time_step = 1.0 / 240;
  return model;
}

WorldOptions crate_options(Method method) {
  WorldOptions options;
  options.method = method;
  return options;
}

std::string crate_test_name(const ::testing::TestParamInfo<Method>& info) { return std::string(method_name(info.param)); }

// The largest |z| component of the box's three axes in the world: 1 when a face lies flat.
double crate_flatness(const Pose& pose, const Shape& shape) {
  const Eigen::Matrix3d axes = (pose.orientation * shape.rotation).toRotationMatrix();
  return axes.row(2).cwiseAbs().maxCoeff();
}

class RigidBoxes : public ::testing::TestWithParam<Method> {};

TEST_P(RigidBoxes, ABoxOnItsEdgeFallsOntoAFace) {
  Model model = crate_floor(0.6);
  // 0.4 × 0.2 × 0.1 m, stood on a long edge 30° from its broad face: its centre of mass is
  // outside the edge, so it falls back onto the broad face (a capsule proxy would roll).
  const Eigen::Vector3d half(0.2, 0.1, 0.05);
  const double tilt = 30 * std::numbers::pi / 180;
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX()));
  const double height = half.y() * std::sin(tilt) + half.z() * std::cos(tilt);  // the lowest edge on the floor
  model.bodies.push_back(crate_body("crate", half, Eigen::Vector3d(0, 0, height + 1e-3), turn));
  World world(model, crate_options(GetParam()));
  for (int n = 0; n < 480; ++n) ASSERT_EQ(world.step(), StepStatus::ok) << "step " << n;
  std::vector<Pose> poses(1);
  world.poses(poses);
  EXPECT_GT(crate_flatness(poses[0], model.bodies[0].shape), 0.999) << "a face lies on the floor";
  EXPECT_NEAR(poses[0].position.z(), half.z(), 2e-3) << "on its broad face, its centre at its half-height, m";
}

// A box at rest on the floor under gravity tilted by `slope` (rad) from −z towards +x, as on a
// slope of that angle: its displacement along x after `seconds`.
double crate_slide(const WorldOptions& options, double slope, double friction, double seconds) {
  Model model = crate_floor(friction);
  model.settings.gravity = 9.81 * Eigen::Vector3d(std::sin(slope), 0, -std::cos(slope));
  model.settings.sleep.enabled = false;
  const Eigen::Vector3d half(0.1, 0.1, 0.05);
  model.bodies.push_back(crate_body("crate", half, Eigen::Vector3d(0, 0, half.z())));
  World world(model, options);
  const int steps = static_cast<int>(std::lround(seconds / model.settings.time_step));
  for (int n = 0; n < steps; ++n) EXPECT_EQ(world.step(), StepStatus::ok) << "step " << n;
  std::vector<Pose> poses(1);
  world.poses(poses);
  return poses[0].position.x();
}

TEST_P(RigidBoxes, ABoxOnASlopeSlidesAtCoulombsAccelerationAboveTheFrictionAngle) {
  const double friction = 0.5, seconds = 1.0, steep = 35 * std::numbers::pi / 180;  // the friction angle: atan 0.5 = 26.6°
  const double expected = 0.5 * 9.81 * (std::sin(steep) - friction * std::cos(steep)) * seconds * seconds;
  // After the move, the friction of springs (sequential impulses) and Lagrange (on free bodies)
  // falls a little short: 3.1 % and 2.5 % farther, measured; Featherstone within 1 %.
  const double tolerance = GetParam() == Method::featherstone ? 0.02 : 0.05;
  EXPECT_NEAR(crate_slide(crate_options(GetParam()), steep, friction, seconds), expected, tolerance * expected) << "m, ½(g sin θ − μ g cos θ)t²";
}

TEST_P(RigidBoxes, ABoxOnASlopeBelowTheFrictionAngleCreepsNoMoreThanTheMoveBeforeTheContactsAllows) {
  // A step that moves the bodies before it finds the contacts (the thesis's loop) lets the box
  // slip g sin θ Δt²/2 in a step before friction stops it in v (as the capsule chains do,
  // featherstone_method_test.cpp), 7 mm in 1 s at 20° and 1/240 s: Featherstone under RK4 within
  // twice that; springs and Lagrange, whose friction after the move falls a little short (above),
  // within three times (18 and 14 mm, measured). The method whose contacts come before the move
  // (Featherstone under semi-implicit Euler) holds it.
  const double friction = 0.5, seconds = 1.0, shallow = 20 * std::numbers::pi / 180, dt = 1.0 / 240;
  const double creep = seconds / dt * 9.81 * std::sin(shallow) * dt * dt / 2;
  const double bound = (GetParam() == Method::featherstone ? 2 : 3) * creep;
  EXPECT_LT(std::abs(crate_slide(crate_options(GetParam()), shallow, friction, seconds)), bound) << "m";
  if (GetParam() != Method::featherstone) return;
  WorldOptions before_the_move = crate_options(Method::featherstone);
  before_the_move.featherstone.integrator = Integrator::semi_implicit_euler;
  EXPECT_LT(std::abs(crate_slide(before_the_move, shallow, friction, seconds)), 1e-4) << "m, held by static friction";
}

TEST_P(RigidBoxes, ABallThrownAtABoxBouncesOffItsFace) {
  // A ball of 5 cm radius at 3 m/s towards a 0.4 × 0.4 × 0.2 m box of 10 kg resting on the floor,
  // level with the box's middle and off its long axis (so neither the box's bounding sphere nor
  // its centre is what the ball meets first): it stops at the face, x ≤ −(0.2 + 0.05) m, and
  // leaves backwards (restitution 0.5).
  Model model = crate_floor(0.0);
  Body crate = crate_body("crate", Eigen::Vector3d(0.2, 0.2, 0.1), Eigen::Vector3d(0, 0, 0.1));
  crate.mass = 10;
  model.bodies.push_back(crate);
  Ball ball;
  ball.radius = 0.05, ball.mass = 0.5, ball.restitution = 0.5;
  ball.position = Eigen::Vector3d(-0.6, 0.15, 0.1), ball.velocity = Eigen::Vector3d(3, 0, 0);
  model.balls.push_back(ball);
  model.settings.gravity.setZero();
  World world(model, crate_options(GetParam()));
  double farthest = -1;
  for (int n = 0; n < 120; ++n) {
    ASSERT_EQ(world.step(), StepStatus::ok) << "step " << n;
    farthest = std::max(farthest, world.ball(world.balls().front()).position.x());
  }
  EXPECT_LT(farthest, -0.25 + 2e-3) << "the ball's centre never passed the box's face less its radius, m";
  EXPECT_LT(world.ball(world.balls().front()).velocity.x(), -0.5) << "it bounced back, m/s";
}

INSTANTIATE_TEST_SUITE_P(Methods, RigidBoxes, ::testing::ValuesIn(true_shape_methods_of_table()), crate_test_name);

// A stack of five boxes, 0.3 × 0.2 × 0.1 m, 0.5 mm apart at the start: after 1 s to settle, none
// moves more than 1 mm over 3 s, each rests on the one below and lies flat.
class BoxStack : public ::testing::TestWithParam<Method> {};

TEST_P(BoxStack, AStackOfFiveBoxesStands) {
  Model model = crate_floor(0.6);
  const Eigen::Vector3d half(0.15, 0.1, 0.05);
  constexpr int kBoxes = 5;
  for (int k = 0; k < kBoxes; ++k) {
    // 0.5 mm apart, so no two overlap at the Model's poses (such pairs never collide).
    model.bodies.push_back(crate_body("box" + std::to_string(k), half, Eigen::Vector3d(0, 0, half.z() + k * (2 * half.z() + 5e-4))));
  }
  World world(model, crate_options(GetParam()));
  std::vector<Pose> settled(kBoxes), later(kBoxes);
  for (int n = 0; n < 240; ++n) ASSERT_EQ(world.step(), StepStatus::ok) << "step " << n;  // 1 s to settle
  world.poses(settled);
  for (int n = 0; n < 720; ++n) ASSERT_EQ(world.step(), StepStatus::ok) << "step " << n;  // 3 s more
  world.poses(later);
  for (int k = 0; k < kBoxes; ++k) {
    EXPECT_LT((later[k].position - settled[k].position).norm(), 1e-3) << "box " << k << " drifts, m";
    EXPECT_NEAR(later[k].position.z(), half.z() * (2 * k + 1), 2e-3) << "box " << k << " rests on the one below, m";
    EXPECT_GT(crate_flatness(later[k], model.bodies[static_cast<std::size_t>(k)].shape), 0.999) << "box " << k;
  }
}

// Featherstone's contacts are a projected Gauss–Seidel with warm start and one push-out solved
// with the factor: the stack stands. The springs answer contacts with the thesis's sequential
// impulses, each pass's impulses on their own, and push out one contact after another through
// its effective mass: each push turns the box and moves its other corners, whose depths are not
// measured again, so the stack rocks and falls (the box at the top 0.57 m off in 3 s). Lagrange
// solves free bodies' contacts as it does jointed ones, but after the move: the upper boxes
// still drift 3–14 mm (bench/collision.md, "Boxes as themselves").
INSTANTIATE_TEST_SUITE_P(Methods, BoxStack, ::testing::Values(Method::featherstone), crate_test_name);
INSTANTIATE_TEST_SUITE_P(DISABLED_KnownFailures, BoxStack, ::testing::Values(Method::springs, Method::lagrange), crate_test_name);

TEST(BoxContacts, ABoxRestingOnAStaticBoxTouchesAtFourPointsWhoseIdsHold) {
  Model model = crate_floor(0.5);
  model.ground.reset();
  StaticCollider table;
  table.name = "table";
  table.type = ColliderType::box;
  table.half_extents = Eigen::Vector3d(1, 1, 0.1);
  table.position = Eigen::Vector3d(0, 0, -0.1);
  model.colliders.push_back(table);
  const Eigen::Vector3d half(0.2, 0.1, 0.05);
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  model.bodies.push_back(crate_body("crate", half, Eigen::Vector3d(0, 0, half.z() - 1e-4), turn));
  LimbCollisions collisions(model);
  const auto contacts_at = [&](const Eigen::Vector3d& centre, const Eigen::Quaterniond& tilt) {
    LimbSegment segment{centre, centre, bounding_radius(model.bodies[0].shape)};
    segment.orientation = tilt * turn;
    std::vector<LimbSegment> segments{segment};
    std::vector<std::uint8_t> awake{1};
    std::vector<LimbContact> contacts;
    collisions.find(segments, awake, 0.0, contacts);
    return contacts;
  };
  const std::vector<LimbContact> before = contacts_at(model.bodies[0].position, Eigen::Quaterniond::Identity());
  ASSERT_EQ(before.size(), 4u) << "a face on a face: its four corners";
  for (const LimbContact& contact : before) {
    EXPECT_NEAR(contact.separation, -1e-4, 1e-9) << "m";
    EXPECT_NEAR(contact.normal.z(), 1.0, 1e-12);
    EXPECT_EQ(contact.second, kStaticShape);
  }
  // A step later: moved 1 mm, turned 0.01 rad about z and tilted 0.0001 rad about x.
  const Eigen::Quaterniond moved(Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(1e-4, Eigen::Vector3d::UnitX()));
  const std::vector<LimbContact> after = contacts_at(model.bodies[0].position + Eigen::Vector3d(1e-3, 0, 0), moved);
  ASSERT_EQ(after.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(after[k].feature, before[k].feature) << "point " << k << ": the same corner";
    EXPECT_LT((after[k].point - before[k].point).norm(), 5e-3) << "point " << k << " moved with the box, m";
  }
}

}  // namespace
}  // namespace limber
