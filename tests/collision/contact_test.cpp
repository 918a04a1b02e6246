// Contact geometry against closed forms, and the physics of contact: impulse exchange,
// restitution, Coulomb friction.
#include <cmath>

#include <gtest/gtest.h>

#include "limber/kernel/geometry/geometry.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"

namespace limber {
namespace {

const Eigen::Vector3d kHead(0, 0, 1), kTail(0, 0, -1);  // a limb of length 2 along z

TEST(ContactGeometry, SphereBesideCapsuleIsDistanceToAxisLessBothRadii) {
  const auto c = sphere_limb_contact({0.5, 0, 0.25}, 0.1, kHead, kTail, ShapeType::capsule, 0.2);
  EXPECT_NEAR(c.separation, 0.5 - 0.2 - 0.1, 1e-15);
  EXPECT_TRUE(c.normal.isApprox(Eigen::Vector3d::UnitX()));
  EXPECT_NEAR(c.axial, 0.375, 1e-15);  // 0.75 of the way down from the head, over length 2
}

TEST(ContactGeometry, SpherePastCapsuleEndMeetsTheCap) {
  const auto c = sphere_limb_contact({0.3, 0, 1.4}, 0.1, kHead, kTail, ShapeType::capsule, 0.2);
  EXPECT_NEAR(c.separation, 0.5 - 0.3, 1e-15);  // distance to the head point (0.3, 0.4) is 0.5
  EXPECT_NEAR(c.axial, 0.0, 1e-15);
}

TEST(ContactGeometry, SphereAboveCylinderEndMeetsTheFlatFace) {
  // A capsule would round this off; a cylinder's end face is flat out to its radius.
  const auto c = sphere_limb_contact({0.15, 0, 1.3}, 0.1, kHead, kTail, ShapeType::cylinder, 0.2);
  EXPECT_NEAR(c.separation, 0.3 - 0.1, 1e-15);
  EXPECT_TRUE(c.normal.isApprox(Eigen::Vector3d::UnitZ()));
}

TEST(ContactGeometry, SphereBeyondCylinderRimMeetsTheEdge) {
  const auto c = sphere_limb_contact({0.5, 0, 1.4}, 0.1, kHead, kTail, ShapeType::cylinder, 0.2);
  EXPECT_NEAR(c.separation, 0.5 - 0.1, 1e-15);  // rim point (0.2, 1): offset (0.3, 0.4)
}

TEST(ContactGeometry, CentreInsideCylinderLeavesThroughTheNearestFace) {
  const auto side = sphere_limb_contact({0.15, 0, 0}, 0.1, kHead, kTail, ShapeType::cylinder, 0.2);
  EXPECT_NEAR(side.separation, -0.05 - 0.1, 1e-15);
  EXPECT_TRUE(side.normal.isApprox(Eigen::Vector3d::UnitX()));
  const auto face = sphere_limb_contact({0.0, 0.05, -0.97}, 0.1, kHead, kTail, ShapeType::cylinder, 0.2);
  EXPECT_NEAR(face.separation, -0.03 - 0.1, 1e-12);
  EXPECT_TRUE(face.normal.isApprox(-Eigen::Vector3d::UnitZ()));
}

// The lowest point of a disk of radius 0.2 centred at (0, 0, 1) whose limb runs along `axis`.
double disk_separation(const Eigen::Vector3d& axis, bool is_disk = true, double offset = 0) {
  const Eigen::Vector3d point(0, 0, 1);
  return plane_feature_constraint(Eigen::Vector3d::UnitZ(), offset, point, point - 0.5 * axis, 0.2, is_disk).separation;
}

TEST(ContactGeometry, CylinderEndReachesDownByItsTilt) {
  EXPECT_NEAR(disk_separation(Eigen::Vector3d::UnitZ()), 1.0, 1e-15);  // standing on its face
  EXPECT_NEAR(disk_separation(Eigen::Vector3d::UnitX()), 0.8, 1e-15);  // lying on its side
  const Eigen::Vector3d tilted = Eigen::Vector3d(1, 0, 1).normalized();
  EXPECT_NEAR(disk_separation(tilted), 1 - 0.2 / std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(disk_separation(tilted, false, 0.5), 0.3, 1e-15);  // a sphere
}

TEST(ContactGeometry, DiskContactGradientsMatchFiniteDifferences) {
  // The rim term couples both particles: pushing one end tilts the axis and moves the rim.
  const Eigen::Vector3d normal = Eigen::Vector3d(0.1, -0.2, 1).normalized();
  const Eigen::Vector3d point(0.3, 0.1, 0.2), partner(0.25, 0.05, 0.27);  // short, fat: r/L ≈ 2.6
  const double radius = 0.25, h = 1e-7;
  const auto constraint = plane_feature_constraint(normal, 0.05, point, partner, radius, true);
  for (int axis = 0; axis < 3; ++axis) {
    const Eigen::Vector3d step = h * Eigen::Vector3d::Unit(axis);
    const auto c = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
      return plane_feature_constraint(normal, 0.05, p, q, radius, true).separation;
    };
    EXPECT_NEAR(constraint.gradient_point[axis], (c(point + step, partner) - c(point - step, partner)) / (2 * h), 1e-6);
    EXPECT_NEAR(constraint.gradient_partner[axis], (c(point, partner + step) - c(point, partner - step)) / (2 * h), 1e-6);
  }
}

// A free limb of mass M across the x axis and a ball of mass m flying at it along −x.
Model ball_meets_limb(double ball_mass, double restitution, double hit_offset) {
  Model model;
  model.name = "ball_meets_limb";
  Body limb;
  limb.name = "target";
  limb.shape = {ShapeType::capsule, 0.4, 0.02};
  limb.mass = 2.0;
  limb.axis = Vector3::UnitY();
  model.bodies.push_back(limb);
  model.balls = {Ball{0.05, ball_mass, restitution, Vector3(0.3, hit_offset, 0), Vector3(-2, 0, 0)}};
  model.settings.gravity.setZero();
  model.settings.sleep.enabled = false;
  return model;
}

// 20 sweeps a step: the ball's hits converge.
VerletOptions twenty_sweeps() {
  VerletOptions options;
  options.relaxation.iterations = 20;
  return options;
}

Eigen::Vector3d velocity(const VerletState<double>& state, std::uint32_t p) {
  return (state.particles.position(p) - state.particles.previous(p)) / state.previous_time_step;
}

TEST(BallContact, ElasticHitOnTheMiddleOfAnEqualMassLimbExchangesVelocities) {
  // Hit at the centre, the limb responds with its whole mass (effective inverse mass
  // ¼·w_head + ¼·w_tail = 1/M); e = 1 and m = M: the ball stops, the limb leaves at 2 m/s.
  auto state = compile<double>(ball_meets_limb(2.0, 1.0, 0.0), twenty_sweeps());
  const Eigen::Vector3d momentum = observe(state).linear_momentum;
  for (int s = 0; s < 120; ++s) step(state);
  const auto ball = state.balls.front().particle;
  EXPECT_NEAR(velocity(state, ball).norm(), 0.0, 1e-9);
  EXPECT_NEAR(velocity(state, 0).x(), -2.0, 1e-9);
  EXPECT_NEAR(velocity(state, 1).x(), -2.0, 1e-9);
  EXPECT_LT((observe(state).linear_momentum - momentum).norm(), 1e-12);
}

TEST(BallContact, InelasticHitLeavesBothAtTheCommonVelocity) {
  auto state = compile<double>(ball_meets_limb(2.0, 0.0, 0.0), twenty_sweeps());
  for (int s = 0; s < 120; ++s) step(state);
  const auto ball = state.balls.front().particle;
  EXPECT_NEAR(velocity(state, ball).x(), -1.0, 1e-9);
  EXPECT_NEAR(0.5 * (velocity(state, 0).x() + velocity(state, 1).x()), -1.0, 1e-9);
}

TEST(BallContact, OffCentreHitConservesMomentumAndSpinsTheLimb) {
  for (double restitution : {0.0, 0.5, 1.0}) {
    auto state = compile<double>(ball_meets_limb(0.7, restitution, 0.12), twenty_sweeps());
    const Eigen::Vector3d momentum = observe(state).linear_momentum;
    for (int s = 0; s < 120; ++s) step(state);
    EXPECT_LT((observe(state).linear_momentum - momentum).norm(), 1e-12) << "e = " << restitution;
    // The struck end (the head, at +y) is driven along −x faster than the far end: the limb turns.
    EXPECT_LT(velocity(state, 0).x(), velocity(state, 1).x()) << "e = " << restitution;
  }
}

Model ball_over_ground(double height, double restitution) {
  Model model;
  model.name = "ball_over_ground";
  model.balls = {Ball{0.05, 1.0, restitution, Vector3(0, 0, height), Vector3::Zero()}};
  model.ground = Ground{0.0, restitution, 0.0};
  model.settings.time_step = 1.0 / 1000;
  model.settings.sleep.enabled = false;
  return model;
}

TEST(PlaneContact, BouncingBallKeepsTheRestitutionShareOfItsHeight) {
  // Rebound apex = e² · drop height (speed ratio e), measured from the ball's resting height.
  const double drop = 1.0, restitution = 0.6;
  auto state = compile<double>(ball_over_ground(drop + 0.05, restitution));
  bool bounced = false;
  double apex = 0;
  for (int s = 0; s < 3000; ++s) {
    step(state);
    const double z = state.particles.position_z[0] - 0.05;
    const double vz = velocity(state, 0).z();
    bounced = bounced || !state.plane_contacts.empty();
    if (bounced && vz > 0) apex = std::max(apex, z);
    if (bounced && vz < 0 && apex > 0) break;
    ASSERT_GE(z, -1e-12) << "the ball sank into the ground";
  }
  EXPECT_NEAR(apex / drop, restitution * restitution, 0.02);
}

TEST(PlaneContact, SlidingLimbStopsAfterTheCoulombDistance) {
  // A capsule lying on the ground, pushed along its axis at v0: d = v0² / (2 μ g).
  Model model;
  model.name = "sliding";
  Body bar;
  bar.name = "bar";
  bar.shape = {ShapeType::capsule, 0.5, 0.03};
  bar.mass = 4.0;
  bar.axis = Vector3::UnitX();
  bar.position = Vector3(0, 0, 0.03);
  bar.linear_velocity = Vector3(3, 0, 0);
  model.bodies.push_back(bar);
  const double friction = 0.4;
  model.ground = Ground{0.0, 0.0, friction};
  model.settings.time_step = 1.0 / 1000;
  model.settings.sleep.enabled = false;
  auto state = compile<double>(model);
  const double start = observe(state).body_centre_of_mass.x();
  for (int s = 0; s < 3000; ++s) step(state);
  const double expected = 3.0 * 3.0 / (2 * friction * 9.81);
  EXPECT_NEAR(observe(state).body_centre_of_mass.x() - start, expected, 0.02 * expected);
  EXPECT_NEAR(observe(state).linear_momentum.norm(), 0.0, 1e-9) << "static friction holds it once stopped";
}

}  // namespace
}  // namespace limber
