// Several balls (Model::balls) under every method, through the World: two balls thrown at each
// other bounce apart with their restitution and keep their momentum; the volley scene's eight
// balls each strike the ragdoll or another ball; balls thrown in and taken out through the
// World keep every other ball's and body's state.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/world/world.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

using Eigen::Vector3d;

std::string param_name(const ::testing::TestParamInfo<Method>& info) { return std::string(method_name(info.param)); }

constexpr double kRadius = 0.05, kMass = 2.26796185;  // the thesis's ball
constexpr double kStep = 1.0 / 240;                   // s

// A limb far from everything (a Model has at least one body), no gravity, no sleep, and two
// balls of restitution e flying at each other along x at `speed`, `aside` m apart in y.
Model two_balls(double restitution, double speed, double aside) {
  Model model;
  model.name = "two_balls";
  model.settings.gravity = Vector3d::Zero();
  model.settings.time_step = kStep;
  model.settings.sleep.enabled = false;
  Body limb;
  limb.name = "far";
  limb.shape = {ShapeType::capsule, 0.3, 0.03};
  limb.mass = 1;
  limb.position = Vector3d(0, 10, 0);
  model.bodies.push_back(limb);
  model.balls = {Ball{kRadius, kMass, restitution, Vector3d(-0.25, 0, 0), Vector3d(speed, 0, 0)},
                 Ball{kRadius, kMass, restitution, Vector3d(0.25, aside, 0), Vector3d(-speed, 0, 0)}};
  return model;
}

class Balls : public ::testing::TestWithParam<Method> {};

TEST_P(Balls, TwoBallsThrownAtEachOtherBounceApartWithTheirRestitution) {
  constexpr double kSpeed = 5, kRestitution = 0.8;
  World world(two_balls(kRestitution, kSpeed, 0), WorldOptions{.method = GetParam()});
  const std::vector<BallId> balls = world.balls();
  ASSERT_EQ(balls.size(), 2u);
  // They meet after (0.5 − 2r)/(2·speed) = 0.04 s; 0.2 s leaves them well apart again.
  for (int step = 0; step < 48; ++step) {
    ASSERT_EQ(world.step(kStep), StepStatus::ok) << "step " << step;
    // Neither passes through the other: the left ball stays left, never more than 5 mm inside.
    const double gap = world.ball(balls[1]).position.x() - world.ball(balls[0]).position.x();
    EXPECT_GT(gap, 2 * kRadius - 0.005) << "centre distance at step " << step << ", m";
  }
  const Vector3d first = world.ball(balls[0]).velocity, second = world.ball(balls[1]).velocity;
  // Equal masses, head-on: each comes back at e times its speed (thesis eq. 2.33), 5% for the
  // methods' contact resolution; the total momentum stays zero and nothing turns sideways.
  EXPECT_NEAR(second.x() - first.x(), kRestitution * 2 * kSpeed, 0.05 * kRestitution * 2 * kSpeed) << "separating speed, m/s";
  EXPECT_LT((first + second).norm(), 1e-6 * kSpeed) << "total momentum / mass, m/s";
  EXPECT_LT(first.tail<2>().norm() + second.tail<2>().norm(), 1e-6 * kSpeed) << "sideways speed, m/s";
}

// Passing 2 cm apart, within each other's speculative reach (Featherstone under RK4 finds them
// after its move): a bouncing contact found after the move bounces only where the step would close
// its gap (contact_target_speed), so neither turns; bounced across the gap, each left at 4.0 m/s
// of its 5 and 2.8 m/s sideways.
TEST_P(Balls, BallsThatPassEachOtherByFlyOnUntouched) {
  constexpr double kSpeed = 5;
  World world(two_balls(0.8, kSpeed, 2 * kRadius + 0.02), WorldOptions{.method = GetParam()});
  for (int step = 0; step < 48; ++step) ASSERT_EQ(world.step(kStep), StepStatus::ok);
  for (const BallId ball : world.balls()) EXPECT_NEAR(std::abs(world.ball(ball).velocity.x()), kSpeed, 1e-9);
}

// A ball strikes something other than the ground in a step when its velocity changes by more
// than gravity's g·Δt (plus 0.2 m/s) while it is clear of the ground.
TEST_P(Balls, EveryBallOfTheVolleyStrikesTheRagdollOrAnotherBall) {
  const Scene scene = testing::shipped_scene("volley.json");
  World world(scene, GetParam());
  const std::vector<BallId> balls = world.balls();
  ASSERT_EQ(balls.size(), 8u);
  const double dt = scene.model.settings.time_step, gravity = scene.model.settings.gravity.norm();
  std::vector<bool> struck(balls.size(), false);
  std::vector<Vector3d> before(balls.size());
  for (double time = 0; time < 0.4; time += dt) {
    for (std::size_t k = 0; k < balls.size(); ++k) before[k] = world.ball(balls[k]).velocity;
    ASSERT_EQ(world.step(dt), StepStatus::ok) << "t = " << time << " s";
    for (std::size_t k = 0; k < balls.size(); ++k) {
      const BallMotion now = world.ball(balls[k]);
      const bool clear_of_ground = now.position.z() > kRadius + 0.01;
      if (clear_of_ground && (now.velocity - before[k]).norm() > gravity * dt + 0.2) struck[k] = true;
    }
  }
  for (std::size_t k = 0; k < balls.size(); ++k) EXPECT_TRUE(struck[k]) << "ball " << k << " struck nothing in 0.4 s";
}

// Throwing a ball in and taking another out recompiles the state; every other body and ball
// carries on from where it was, as if nothing had happened (the third ball is far away).
TEST_P(Balls, AddingAndRemovingABallKeepsEveryOtherStateBits) {
  Model model = two_balls(0.8, 5, 0);
  World edited(model, WorldOptions{.method = GetParam()});
  World reference(model, WorldOptions{.method = GetParam()});
  for (int step = 0; step < 5; ++step) edited.step(kStep), reference.step(kStep);
  const BallId far = edited.add_ball(Ball{kRadius, kMass, 0.5, Vector3d(0, -10, 0), Vector3d(0, -1, 0)});
  EXPECT_EQ(edited.balls().size(), 3u);
  for (int step = 0; step < 20; ++step) edited.step(kStep), reference.step(kStep);
  EXPECT_NEAR(edited.ball(far).position.y(), -10 - 20 * kStep, 1e-9) << "the thrown ball flies on";
  edited.remove_ball(edited.balls().front());
  reference.remove_ball(reference.balls().front());
  for (int step = 0; step < 20; ++step) edited.step(kStep), reference.step(kStep);
  const BallMotion kept = edited.ball(edited.balls().front()), expected = reference.ball(reference.balls().front());
  EXPECT_EQ(kept.position, expected.position);
  EXPECT_EQ(kept.velocity, expected.velocity);
  EXPECT_THROW(edited.ball(BallId{12345}), WorldError);
}

INSTANTIATE_TEST_SUITE_P(Methods, Balls, ::testing::Values(Method::particles, Method::springs, Method::lagrange, Method::featherstone),
                         param_name);

}  // namespace
}  // namespace limber
