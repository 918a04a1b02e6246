// The Verlet method end to end: conservation, constraint satisfaction, the thesis's experiments.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#if defined(__SSE__) || defined(__x86_64__)
#include <xmmintrin.h>
#endif

#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

using testing::load_shipped_scene;
using testing::shipped_scene;
using testing::with_scene_settings;
using testing::make_chain;

template <typename Scalar>
class VerletMethod : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(VerletMethod, Scalars);

TYPED_TEST(VerletMethod, FreeChainWithUnequalMassesConservesLinearMomentum) {
  // No gravity, no pins, no contacts: only the weighted projections act, and each keeps the
  // momentum of its pair (thesis 4.3). The midpoint rule does not, which the second run shows.
  Model model = make_chain({1.0, 3.0, 0.5, 7.0, 2.0, 1.5}, 0.2, false);
  model.settings.gravity.setZero();
  model.settings.time_step = 1.0 / 240;
  VerletOptions weighted_options;
  weighted_options.relaxation.iterations = 10;
  VerletOptions unweighted_options = weighted_options;
  unweighted_options.rule = RelaxationRule::unweighted;
  std::mt19937 random(3);
  std::uniform_real_distribution<double> speed(-2, 2);
  Vector3 momentum = Vector3::Zero();
  for (Body& body : model.bodies) {
    body.linear_velocity = Vector3(speed(random), speed(random), speed(random));
    body.angular_velocity = Vector3(speed(random), speed(random), speed(random)) * 5;
    momentum += body.mass * body.linear_velocity;
  }
  // A slow drift of the whole chain keeps it near the origin, where float still resolves the
  // per-step displacements (Verlet's velocity is a difference of positions).
  for (Body& body : model.bodies) body.linear_velocity += Vector3(0.1, 0, 0.05) - momentum / model.body_mass();
  auto weighted = compile<TypeParam>(model, weighted_options);
  auto unweighted = compile<TypeParam>(model, unweighted_options);
  // The first step turns the initial (inconsistent) velocities into ones the links allow.
  step(weighted), step(unweighted);
  const Vector3 p0 = observe(weighted).linear_momentum, q0 = observe(unweighted).linear_momentum;
  double unweighted_drift = 0;
  for (int s = 0; s < 10000; ++s) {
    ASSERT_EQ(step(weighted).status, StepStatus::ok);
    step(unweighted);
    unweighted_drift = std::max(unweighted_drift, (observe(unweighted).linear_momentum - q0).norm());
  }
  // Double: conserved to rounding. Float: each of the ~2.5e6 position roundings moves the momentum
  // by up to m·ulp(x)/Δt ≈ 1e-4 kg·m/s at random, ~0.1 kg·m/s after √N of them.
  const double tolerance = std::is_same_v<TypeParam, float> ? 0.1 : 1e-9;
  EXPECT_LT((observe(weighted).linear_momentum - p0).norm(), tolerance * p0.norm());
  EXPECT_GT(unweighted_drift, 3 * tolerance * q0.norm() + 0.05);
}

TYPED_TEST(VerletMethod, HeavyEndChainKeepsJointsClosedWith100Iterations) {
  // The thesis's 4.4 experiment: five links, the bottom one double mass, released horizontally.
  const Scene chain = shipped_scene("chain.json");
  VerletOptions options = with_scene_settings(chain);
  options.relaxation.iterations = 100;
  auto state = compile<TypeParam>(chain.model, options);
  double largest_gap = 0, largest_stretch = 0;
  for (int s = 0; s < 1200; ++s) {  // 5 s
    ASSERT_EQ(step(state).status, StepStatus::ok);
    const Observation o = observe(state);
    largest_gap = std::max(largest_gap, o.max_joint_gap);
    largest_stretch = std::max(largest_stretch, o.max_link_stretch);
  }
  EXPECT_LT(largest_gap, 1e-4);
  EXPECT_LT(largest_stretch, 1e-4);
}

// chain.json as the thesis ran it (pbd, one step, 100 sweeps, over-relaxation 1.5): the facts
// below are the pbd rule's and count sweeps per step.
Model thesis_chain(long links = 5) { return load_shipped_scene("chain.json", {.variant = {}, .links = links, .copies = {}}); }
VerletOptions thesis_options(int sweeps = 100, double over_relaxation = 1.5) {
  VerletOptions options;
  options.relaxation = testing::thesis_relaxation(sweeps, over_relaxation);
  return options;
}

TYPED_TEST(VerletMethod, OverRelaxationConvergesFasterWithoutGainingEnergy) {
  auto run = [](double omega, int sweeps) {
    auto state = compile<TypeParam>(thesis_chain(), thesis_options(sweeps, omega));
    const double initial = observe(state).energy();
    double largest_gap = 0, highest = initial;
    for (int s = 0; s < 1200; ++s) {
      EXPECT_EQ(step(state).status, StepStatus::ok);
      const Observation o = observe(state);
      largest_gap = std::max(largest_gap, o.max_joint_gap);
      highest = std::max(highest, o.energy());
    }
    EXPECT_LE(highest, initial * (1 + 1e-6)) << "ω " << omega << ", " << sweeps << " sweeps";
    return largest_gap;
  };
  for (int sweeps : {1, 2, 5}) run(1.8, sweeps);
  EXPECT_LT(run(1.5, 100), 0.2 * run(1.0, 100));
}

TYPED_TEST(VerletMethod, SharedParticleJointsMoveLikeClosedZeroLengthJoints) {
  // Thesis 3.2.5: a spherical joint is two limbs sharing a particle. Converged zero-length
  // constraints are the same joint, so the chains must move together.
  const Model model = thesis_chain();
  VerletOptions options = thesis_options(1000);
  auto constrained = compile<TypeParam>(model, options);
  options.verlet.joints = ParticleJoints::shared_particle;
  auto shared = compile<TypeParam>(model, options);
  EXPECT_EQ(shared.particles.size(), 6u);  // a pin and five limb tails
  EXPECT_TRUE(shared.joint_constraints.empty());
  for (int s = 0; s < 120; ++s) step(constrained), step(shared);  // 0.5 s, before chaos sets in
  const auto end = [](const auto& state) { return state.particles.position(state.limbs.tail.back()).template cast<double>().eval(); };
  EXPECT_LT((end(constrained) - end(shared)).norm(), 1e-3);
  EXPECT_GT((end(shared) - Eigen::Vector3d(1.0, 0, 1.5)).norm(), 0.3) << "the chain must have swung";
}

TYPED_TEST(VerletMethod, WeightedAndUnweightedDifferOnlyWhenMassesDiffer) {
  const VerletOptions scene_options = with_scene_settings(shipped_scene("chain.json"));
  auto run = [&](const Model& model, RelaxationRule rule) {
    VerletOptions options = scene_options;
    options.rule = rule;
    auto state = compile<TypeParam>(model, options);
    for (int s = 0; s < 480; ++s) step(state);
    return state;
  };
  Model equal = load_shipped_scene("chain.json");
  for (Body& body : equal.bodies) body.mass = equal.bodies.front().mass;
  const auto a = run(equal, RelaxationRule::weighted), b = run(equal, RelaxationRule::unweighted);
  EXPECT_TRUE(bitwise_equal(a.particles, b.particles)) << "equal masses: the two rules are the same arithmetic";

  Model heavy_end = load_shipped_scene("chain.json");
  const auto c = run(heavy_end, RelaxationRule::weighted), d = run(heavy_end, RelaxationRule::unweighted);
  double largest_difference = 0;
  for (std::size_t p = 0; p < c.particles.size(); ++p) {
    largest_difference = std::max(largest_difference, double((c.particles.position(p) - d.particles.position(p)).norm()));
  }
  EXPECT_GT(largest_difference, 0.05) << "a double-mass end link must change the motion under the weighted rule";
}

TYPED_TEST(VerletMethod, StickStaysInsideTheBox) {
  const Scene scene = shipped_scene("stick_in_box.json");
  const Model& model = scene.model;
  auto state = compile<TypeParam>(model, with_scene_settings(scene));
  const double slack = std::is_same_v<TypeParam, float> ? 1e-5 : 1e-12;
  int wall_contacts = 0;
  for (int s = 0; s < 2400; ++s) {
    ASSERT_EQ(step(state).status, StepStatus::ok);
    wall_contacts += !state.plane_contacts.empty();
    for (std::size_t p = 0; p < state.particles.size(); ++p) {
      const Eigen::Vector3d x = state.particles.position(p).template cast<double>();
      ASSERT_GE(x.minCoeff(), model.bounds->min.minCoeff() - slack) << "step " << s;
      ASSERT_LE(x.maxCoeff(), model.bounds->max.maxCoeff() + slack) << "step " << s;
    }
  }
  EXPECT_GT(wall_contacts, 10) << "the stick must actually hit the walls for this test to mean anything";
}

TYPED_TEST(VerletMethod, StickLengthErrorFallsAsIterationsGrow) {
  // Thesis 3.2.3: looping the length and box constraints more often satisfies both better.
  // The length is only disturbed when a wall pushes one end, so measure over wall contacts.
  auto mean_stretch = [](int iterations) {
    const Scene scene = shipped_scene("stick_in_box.json");
    VerletOptions options = with_scene_settings(scene);
    options.relaxation.iterations = iterations;
    auto state = compile<TypeParam>(scene.model, options);
    double total = 0;
    int samples = 0;
    for (int s = 0; s < 1200; ++s) {
      step(state);
      if (state.plane_contacts.empty()) continue;
      total += observe(state).max_link_stretch;
      ++samples;
    }
    return total / std::max(samples, 1);
  };
  const double one = mean_stretch(1), four = mean_stretch(4), sixteen = mean_stretch(16);
  EXPECT_GT(one, 0) << "a single sweep must leave some error at the walls";
  EXPECT_LT(four, one);
  EXPECT_LT(sixteen, four);
}

TYPED_TEST(VerletMethod, ScenesWithoutBallOrGroundSkipThoseStages) {
  const Scene chain = shipped_scene("chain.json");
  auto state = compile<TypeParam>(chain.model, with_scene_settings(chain));
  EXPECT_TRUE(state.planes.empty());
  EXPECT_TRUE(state.features.empty());
  EXPECT_TRUE(state.balls.empty());
  for (int s = 0; s < 100; ++s) step(state);
  EXPECT_EQ(state.counters.contact_projections, 0u);
}

TYPED_TEST(VerletMethod, SameInputGivesSameBits) {
  const Model model = load_shipped_scene("humanoid.json");
  auto a = compile<TypeParam>(model), b = compile<TypeParam>(model);
  for (int s = 0; s < 600; ++s) step(a), step(b);
  EXPECT_TRUE(bitwise_equal(a.particles, b.particles));
  EXPECT_EQ(hash_live_elements(a.particles), hash_live_elements(b.particles));
}

TYPED_TEST(VerletMethod, RelaxationReportsWhichCriterionStoppedIt) {
  const Model model = thesis_chain();
  VerletOptions options = thesis_options(50);
  auto by_count = compile<TypeParam>(model, options);
  StepReport report = step(by_count);
  EXPECT_EQ(report.stop, RelaxationStop::iterations);
  EXPECT_EQ(report.iterations, 50);

  options.relaxation.tolerance = 1e-3;  // a chain released at rest converges at once
  auto by_tolerance = compile<TypeParam>(model, options);
  report = step(by_tolerance);
  EXPECT_EQ(report.stop, RelaxationStop::tolerance);
  EXPECT_LT(report.iterations, 50);
  EXPECT_LT(report.largest_correction, 1e-3);

  VerletOptions budget_options = thesis_options(kMaxIterations);
  budget_options.relaxation.budget_us = 200;
  auto by_budget = compile<TypeParam>(thesis_chain(2000), budget_options);
  report = step(by_budget);
  EXPECT_EQ(report.stop, RelaxationStop::budget);
  EXPECT_LT(report.iterations, kMaxIterations);
}

TYPED_TEST(VerletMethod, DampingIsARatePerSecondWhateverTheStep) {
  // One free limb, no gravity: its speed must decay as exp(−damping·t) for any Δt. In float the
  // implicit velocity resolves only ulp(x)/Δt (~1e-4 m/s at 1 m and 1 ms): test smaller Δt in double.
  const std::vector<double> steps = std::is_same_v<TypeParam, float> ? std::vector<double>{1.0 / 30, 1.0 / 240}
                                                                      : std::vector<double>{1.0 / 30, 1.0 / 240, 1.0 / 1000};
  for (double dt : steps) {
    Model model = make_chain({2.0}, 0.5, false);
    model.settings.gravity.setZero();
    model.settings.damping = 0.8;
    model.settings.time_step = dt;
    model.bodies[0].linear_velocity = Vector3(1.0, 0, 0);
    auto state = compile<TypeParam>(model);
    const int steps = static_cast<int>(std::lround(2.0 / dt));
    for (int s = 0; s < steps; ++s) step(state);
    const double speed = observe(state).linear_momentum.norm() / 2.0;
    EXPECT_NEAR(speed, std::exp(-0.8 * 2.0), 1e-4) << "dt " << dt;
  }
}

TYPED_TEST(VerletMethod, ThesisDragFactorSlowsWithoutPullingTowardsTheOrigin) {
  // x' = f·x − (f−1)·x* + a·Δt² keeps a body at rest where it is (the literal "2 → 1.99" on
  // eq. 4.5 alone would drag it towards the origin) and slows a moving one.
  Model model = make_chain({1.0}, 0.5, false, Vector3(30, -20, 10));
  model.settings.gravity.setZero();
  VerletOptions options;
  options.verlet.drag_factor = 1.99;
  auto resting = compile<TypeParam>(model, options);
  model.bodies[0].linear_velocity = Vector3(0, 0, 1);
  auto moving = compile<TypeParam>(model, options);
  const Eigen::Vector3d start = observe(resting).body_centre_of_mass;
  for (int s = 0; s < 240; ++s) step(resting), step(moving);
  EXPECT_LT((observe(resting).body_centre_of_mass - start).norm(), 1e-5);
  EXPECT_NEAR(observe(moving).linear_momentum.z(), std::pow(0.99, 240), 1e-3);
}

TYPED_TEST(VerletMethod, VelocitySurvivesAChangeOfTimeStep) {
  // Time-corrected Verlet: the implicit velocity is rescaled when Δt changes.
  Model model = make_chain({1.0}, 0.5, false);
  model.settings.gravity.setZero();
  model.bodies[0].linear_velocity = Vector3(2, 0, 0);
  auto state = compile<TypeParam>(model);
  for (double dt : {1.0 / 60, 1.0 / 240, 1.0 / 97, 1.0 / 1000}) step(state, dt);
  EXPECT_NEAR(observe(state).linear_momentum.x(), 2.0, 1e-4);
  EXPECT_EQ(step(state, 0.0).status, StepStatus::invalid_time_step);
  EXPECT_EQ(step(state, std::nan("")).status, StepStatus::invalid_time_step);
}

#if defined(__SSE__) || defined(__x86_64__)
TEST(FloatingPointMode, StepFlushesDenormalsOnlyWhileItRuns) {
  const Scene chain = shipped_scene("chain.json");
  auto state = compile<float>(chain.model, with_scene_settings(chain));
  const unsigned before = _mm_getcsr();
  step(state);
  EXPECT_EQ(_mm_getcsr(), before) << "the caller's MXCSR must be restored";
}
#endif

// --- Sleeping (thesis 4.5.3) ---

TYPED_TEST(VerletMethod, StandingHumanoidCostsNothingUntilTheBallHits) {
  const Model model = load_shipped_scene("humanoid.json");
  auto state = compile<TypeParam>(model);
  auto rest = state.particles;
  ASSERT_TRUE(observe(state).body_sleeping);
  int steps_before_contact = 0;
  while (state.ball_contacts.empty() && steps_before_contact < 1000) {
    // Until contact: only the ball particle is integrated and no constraint is projected.
    ASSERT_EQ(state.counters.particles_integrated, static_cast<std::uint64_t>(steps_before_contact));
    ASSERT_EQ(state.counters.constraint_projections, 0u);
    for (std::uint32_t p = 0; p < state.particles.size(); ++p) {
      if (state.particle_origins[p].kind == ParticleOrigin::Kind::ball) continue;
      ASSERT_EQ(state.particles.position(p), rest.position(p)) << "particle " << p << " moved while asleep";
    }
    step(state);
    ++steps_before_contact;
  }
  ASSERT_FALSE(state.ball_contacts.empty()) << "the ball never reached the body";
  EXPECT_FALSE(observe(state).body_sleeping) << "contact wakes the body";
  for (int s = 0; s < 10; ++s) step(state);
  EXPECT_GT(state.counters.constraint_projections, 0u);
}

TYPED_TEST(VerletMethod, ChainAtRestFallsAsleepAndAForceWakesIt) {
  Scene chain = shipped_scene("chain.json");
  Model& model = chain.model;
  model.settings.damping = 2.0;  // settle quickly
  model.settings.sleep = {true, false, 0.01, 0.5};
  auto state = compile<TypeParam>(model, with_scene_settings(chain));
  int steps = 0;
  while (!observe(state).body_sleeping && steps < 240 * 60) step(state), ++steps;
  ASSERT_TRUE(observe(state).body_sleeping) << "a damped hanging chain must come to rest";
  const auto counted = state.counters.particles_integrated;
  for (int s = 0; s < 100; ++s) step(state);
  EXPECT_EQ(state.counters.particles_integrated, counted);
  apply_force(state, 4, Eigen::Vector3d(0, 50, 0));
  EXPECT_FALSE(observe(state).body_sleeping);
  step(state);
  EXPECT_GT(observe(state).linear_momentum.norm(), 0.0);
}

}  // namespace
}  // namespace limber
