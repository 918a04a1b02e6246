// The thesis's experiments as physical facts (the tables are bench/thesis_experiments):
// Verlet's accuracy on one particle against the kernel's RK2 (figure 3.12), and the heavy end of
// the 4.4 chain under the weighted and the midpoint rule.
#include <algorithm>
#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "limber/kernel/featherstone/compile.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/rigid/rigid_integration.hpp"
#include "limber/kernel/rigid/rigid_scene.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

using testing::load_shipped_scene;

const Vector3 kGravity(0, 0, -9.81);
constexpr double kOmega = 2 * std::numbers::pi;  // the spring's: period 1 s

// One free particle for the kernel's Verlet step: one short limb, no joints. Its two particles
// get the same acceleration, so the link constraint never acts and the centre moves alone.
VerletState<double> one_particle(const Vector3& position, const Vector3& velocity, const Vector3& gravity, double dt) {
  Model model;
  model.name = "particle";
  Body body;
  body.name = "particle";
  body.shape = {ShapeType::capsule, 0.01, 0.005};
  body.mass = 1;
  body.position = position, body.linear_velocity = velocity;
  model.bodies.push_back(body);
  model.settings.gravity = gravity;
  model.settings.time_step = dt;
  model.settings.sleep.enabled = false;
  VerletOptions options;
  options.relaxation.iterations = 1;
  return compile<double>(model, options);
}

// Moves x(−Δt) from compile()'s x0 − v0·Δt to the Taylor start x0 − v0·Δt + ½·a0·Δt².
void start_consistently(VerletState<double>& state, const Vector3& acceleration, double dt) {
  const Vector3 shift = 0.5 * acceleration * dt * dt;
  for (std::size_t i = 0; i < state.particles.size(); ++i) {
    state.particles.previous_x[i] += shift.x(), state.particles.previous_y[i] += shift.y(), state.particles.previous_z[i] += shift.z();
  }
}

Vector3 centre(const VerletState<double>& state) {
  return 0.5 * (state.particles.position(state.limbs.head[0]) + state.particles.position(state.limbs.tail[0]));
}
Vector3 previous_centre(const VerletState<double>& state) {
  const auto& p = state.particles;
  const std::uint32_t h = state.limbs.head[0], t = state.limbs.tail[0];
  return 0.5 * Vector3(p.previous_x[h] + p.previous_x[t], p.previous_y[h] + p.previous_y[t], p.previous_z[h] + p.previous_z[t]);
}

TEST(ThesisExperiments, VerletFollowsTheParabolaExactlyFromAConsistentStart) {
  // Störmer–Verlet is exact for a constant force once x(−Δt) is the true position: after 240
  // steps x = x0 + v0·t + ½·g·t² to rounding. compile()'s x0 − v0·Δt start misses by ½·g·Δt·t.
  const double dt = 1.0 / 240;
  const Vector3 x0(0.3, -0.2, 1), v0(1, 0.5, 5);
  auto state = one_particle(x0, v0, kGravity, dt);
  auto first_order = one_particle(x0, v0, kGravity, dt);
  start_consistently(state, kGravity, dt);
  for (int n = 0; n < 240; ++n) step(state), step(first_order);
  const Vector3 exact = x0 + v0 + 0.5 * kGravity;
  EXPECT_LT((centre(state) - exact).norm(), 1e-12);
  EXPECT_NEAR((centre(first_order) - exact).norm(), 0.5 * kGravity.norm() * dt * 1.0, 1e-9);
}

TEST(ThesisExperiments, VerletVelocityEstimateIsTheVelocityHalfAStepEarlier) {
  // The kernel's v = (x − x*)/Δt (observe(), kinetic energy) under constant g is exactly v at
  // t − Δt/2: off by g·Δt/2 from v(t), an error that halves with Δt — first order.
  const double dt = 1.0 / 60;
  const Vector3 x0(0, 0, 1), v0(0, 0, 5);
  auto state = one_particle(x0, v0, kGravity, dt);
  start_consistently(state, kGravity, dt);
  for (int n = 0; n < 60; ++n) step(state);
  const Vector3 estimate = (centre(state) - previous_centre(state)) / dt;
  EXPECT_LT((estimate - (v0 + kGravity * (1 - dt / 2))).norm(), 1e-10);
  EXPECT_NEAR((estimate - (v0 + kGravity)).norm(), kGravity.norm() * dt / 2, 1e-10);
}

// Largest errors over 2 s (two periods) on the spring x'' = −ω²x from x = 1, v = 0, at step dt.
struct SpringErrors {
  double rk2_position = 0, rk2_velocity = 0, verlet_position = 0, verlet_velocity = 0;
};
SpringErrors spring_errors(double dt) {
  const int steps = static_cast<int>(std::lround(2.0 / dt));
  const Vector3 x0(1, 0, 0);
  // The kernel's RK2 (midpoint) on one rigid body of 1 kg.
  RigidBodyBuffer bodies;
  bodies.resize(1);
  bodies.mass[0] = bodies.inverse_mass[0] = 1;
  bodies.body_inertia[0] = bodies.body_inverse_inertia[0] = Eigen::Matrix3d::Identity();
  bodies.state.position[0] = x0;
  RigidIntegratorScratch scratch;
  scratch.resize(1);
  // The kernel's Verlet, the spring force applied at x(t) each step.
  auto verlet = one_particle(x0, Vector3::Zero(), Vector3::Zero(), dt);
  start_consistently(verlet, -kOmega * kOmega * x0, dt);
  SpringErrors e;
  for (int n = 1; n <= steps; ++n) {
    integrate_rigid_bodies(bodies, dt, Integrator::rk2, scratch,
                           [](const RigidBodyState& y, RigidForces& forces) { forces.force[0] -= kOmega * kOmega * y.position[0]; });
    apply_force(verlet, 0, Eigen::Vector3d(-kOmega * kOmega * centre(verlet)));
    step(verlet);
    const double t = n * dt;
    const Vector3 exact_position = x0 * std::cos(kOmega * t), exact_velocity = -x0 * kOmega * std::sin(kOmega * t);
    e.rk2_position = std::max(e.rk2_position, (bodies.state.position[0] - exact_position).norm());
    e.rk2_velocity = std::max(e.rk2_velocity, (bodies.linear_velocity(bodies.state, 0) - exact_velocity).norm());
    e.verlet_position = std::max(e.verlet_position, (centre(verlet) - exact_position).norm());
    e.verlet_velocity = std::max(e.verlet_velocity, ((centre(verlet) - previous_centre(verlet)) / dt - exact_velocity).norm());
  }
  return e;
}

TEST(ThesisExperiments, RungeKutta2AndVerletPositionsAreSecondOrderVerletVelocityFirst) {
  // Halving Δt divides a p-th order error by 2^p: RK2's position and velocity and Verlet's
  // position by ~4, Verlet's (x − x*)/Δt by ~2 — figure 3.12's "Verlet is less precise" is about
  // that velocity estimate, not Verlet's positions.
  const SpringErrors coarse = spring_errors(1.0 / 120), fine = spring_errors(1.0 / 240);
  EXPECT_NEAR(coarse.rk2_position / fine.rk2_position, 4, 0.5);
  EXPECT_NEAR(coarse.rk2_velocity / fine.rk2_velocity, 4, 0.5);
  EXPECT_NEAR(coarse.verlet_position / fine.verlet_position, 4, 0.5);
  EXPECT_NEAR(coarse.verlet_velocity / fine.verlet_velocity, 2, 0.25);
  // At the same step, RK2's velocity beats Verlet's estimate.
  EXPECT_LT(fine.rk2_velocity, 0.5 * fine.verlet_velocity);
}

// The angle (degrees) by which the chain's free end leads its middle down at 0.3 s, about the
// pivot at (0, 0, 1.5) (chain.json, released along +x): < 0 when the end trails (whips).
double end_lead_degrees(const Vector3& end, const Vector3& middle) {
  const auto below_horizontal = [](const Vector3& point) { return std::atan2(1.5 - point.z(), point.x()); };
  return (below_horizontal(end) - below_horizontal(middle)) * 180 / std::numbers::pi;
}

double verlet_lead(const Model& model, RelaxationRule rule, const VerletOptions& scene_options) {
  VerletOptions options = scene_options;
  options.rule = rule;
  auto state = compile<double>(model, options);
  for (int n = 0; n < 72; ++n) step(state);  // 0.3 s
  const auto& p = state.particles;
  const std::uint32_t last = state.body_limb.back(), middle = state.body_limb[model.bodies.size() / 2];
  return end_lead_degrees(p.position(state.limbs.tail[last]), 0.5 * (p.position(state.limbs.head[middle]) + p.position(state.limbs.tail[middle])));
}

TEST(ThesisExperiments, HeavyEndLeadsUnderTheWeightedRuleOnly) {
  // Thesis 4.4.2: with the weighted rule the heavy end "has more control over the global
  // motion"; with the midpoint rule mass makes no difference at all. The exact rigid chain
  // (Featherstone) says which is right.
  const Scene chain = testing::shipped_scene("chain.json");
  const VerletOptions options = testing::with_scene_settings(chain);
  const Model& heavy = chain.model;
  Model equal = heavy;
  equal.bodies.back().mass = equal.bodies.front().mass;
  const double weighted_heavy = verlet_lead(heavy, RelaxationRule::weighted, options),
               weighted_equal = verlet_lead(equal, RelaxationRule::weighted, options);
  const double midpoint_heavy = verlet_lead(heavy, RelaxationRule::unweighted, options),
               midpoint_equal = verlet_lead(equal, RelaxationRule::unweighted, options);
  EXPECT_GT(weighted_heavy - weighted_equal, 1.0);  // degrees: the heavy end trails its chain less
  EXPECT_EQ(midpoint_heavy, midpoint_equal);        // the midpoint rule never reads a mass

  FeatherstoneState exact = compile_featherstone(heavy);
  for (int n = 0; n < 72; ++n) step(exact);
  const double length = heavy.bodies.front().shape.length;
  const double exact_lead = end_lead_degrees(world_point(exact, heavy.bodies.size() - 1, Vector3(0, 0, -0.5 * length)),
                                             world_point(exact, heavy.bodies.size() / 2, Vector3::Zero()));
  EXPECT_LT(std::abs(weighted_heavy - exact_lead), std::abs(midpoint_heavy - exact_lead));
}

}  // namespace
}  // namespace limber
