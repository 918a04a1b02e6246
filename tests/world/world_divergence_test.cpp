// Divergence cannot hide: a run that gains energy or comes apart is reported as diverged under
// its own name, though every number stays finite and no point passes the speed guard; and a run
// that does neither never is.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/metrics/divergence.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/world/world.hpp"
#include "limber/kernel/world/world_internals.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

using testing::make_chain;

// Steps until the status is not ok or `steps` are done; returns the status.
StepStatus run(World& world, int steps) {
  StepStatus status = StepStatus::ok;
  for (int s = 0; s < steps && status == StepStatus::ok; ++s) status = world.step();
  return status;
}

// Explicit Euler on stiff springs gains energy every step (thesis eq. 3.15: unstable for any
// h·k past its bound). With the speed guard out of reach, the energy bound must catch it while
// the state is still finite.
TEST(Divergence, EnergyGainedByAnUnstableIntegratorIsReportedBeforeAnythingIsNonFinite) {
  Model model = make_chain({1, 1, 1}, 0.5, true);
  model.settings.divergence_speed = 1e300;
  WorldOptions options;
  options.method = Method::springs;
  options.springs.integrator = Integrator::euler;
  options.springs.stiffness = 1e5;
  World world(model, options);
  const StepStatus status = run(world, 2000);
  EXPECT_EQ(status, StepStatus::diverged_energy);
  EXPECT_EQ(world.last_report().status, StepStatus::diverged_energy);
  const Observation now = world.observe();
  EXPECT_TRUE(std::isfinite(now.energy()));
}

// Springs too soft to hold the chain up let it come apart under gravity: reported as a joint
// gap past a whole link, not as "ok".
TEST(Divergence, AJointPulledApartPastAWholeLinkIsReported) {
  Model model = make_chain({1, 1, 1}, 0.5, true);
  WorldOptions options;
  options.method = Method::springs;
  options.springs.integrator = Integrator::backward_euler;
  options.springs.stiffness = 1.0;  // N/m: a 1 kg link stretches its spring by g/k ≈ 10 m
  options.springs.damping = 1.0;
  World world(model, options);
  EXPECT_EQ(run(world, 2400), StepStatus::diverged_joint_gap);
}

// A pendulum swinging for 10 s under every method stays within every bound: the checks do not
// call a sound run diverged.
TEST(Divergence, ASoundRunIsNeverCalledDiverged) {
  const Model model = make_chain({1, 2, 1}, 0.4, true);
  for (const Method method : {Method::particles, Method::springs, Method::lagrange, Method::featherstone}) {
    WorldOptions options;
    options.method = method;
    World world(model, options);
    EXPECT_EQ(run(world, 2400), StepStatus::ok) << method_name(method);
  }
}

// The bound is the scene's: its energy scale grows with its mass, gravity, extent and the
// kinetic energy it starts with (a thrown ball's).
TEST(Divergence, TheEnergyScaleIsTheScenes) {
  Model model = make_chain({1, 1}, 0.5, false);
  World still(model, WorldOptions{});
  const DivergenceBounds rest = divergence_bounds(model, still.observe());
  model.balls.push_back(Ball{.radius = 0.1, .mass = 2, .restitution = 0.5, .position = Vector3(3, 0, 1), .velocity = Vector3(-20, 0, 0)});
  World thrown(model, WorldOptions{});
  const DivergenceBounds ball = divergence_bounds(model, thrown.observe());
  EXPECT_GT(ball.energy_scale, rest.energy_scale + 0.5 * 2 * 20 * 20 - 1e-9);
  EXPECT_GE(rest.energy_scale, 1.0);
  Observation gained = still.observe();
  gained.kinetic_energy += 2 * kDivergenceEnergyFactor * rest.energy_scale;
  EXPECT_EQ(check_divergence(gained, rest), StepStatus::diverged_energy);
  gained.kinetic_energy = std::nan("");
  EXPECT_EQ(check_divergence(gained, rest), StepStatus::diverged_non_finite);
}

// A particle limb stretched past a whole link has come apart as surely as an open joint:
// unconverged relaxation on a long chain closes the joints and leaves the links stretched
// (tests/world/soak_test.cpp: a 10³-link chain at 1/30 s under the direct solver reached 2.3×
// its links' length and 5× its start energy while reported ok).
TEST(Divergence, ALinkStretchedPastAWholeLinkIsReported) {
  const Model model = make_chain({1, 1}, 0.5, true);
  World world(model, WorldOptions{});
  const DivergenceBounds bounds = divergence_bounds(model, world.observe());
  Observation stretched = world.observe();
  stretched.max_link_stretch = 0.99;
  EXPECT_EQ(check_divergence(stretched, bounds), StepStatus::ok);
  stretched.max_link_stretch = 1.01;
  EXPECT_EQ(check_divergence(stretched, bounds), StepStatus::diverged_joint_gap);
  stretched.max_link_stretch = std::nan("");
  EXPECT_EQ(check_divergence(stretched, bounds), StepStatus::diverged_non_finite);
}

// The check after every step observes only what it reads (ObservationScope::divergence), and
// reads what a full observation would have given it: on a ragdoll with limits, in flight
// and after landing, under every method.
TEST(Divergence, TheChecksObservationIsAFullObservationsEnergyMomentumAndGaps) {
  const Scene scene = testing::shipped_scene("ragdoll.json");
  for (const Method method : {Method::particles, Method::springs, Method::lagrange, Method::featherstone}) {
    World world(scene.model, world_options(method, scene.methods));
    for (int s = 0; s < 240; ++s) {
      ASSERT_EQ(world.step(), StepStatus::ok) << method_name(method);
      if (s % 60 != 0) continue;
      std::visit(
          [&](const auto& state) {
            const Observation full = observe(state), checked = observe(state, ObservationScope::divergence);
            EXPECT_EQ(checked.kinetic_energy, full.kinetic_energy) << method_name(method);
            EXPECT_EQ(checked.potential_energy, full.potential_energy) << method_name(method);
            EXPECT_EQ(checked.linear_momentum, full.linear_momentum) << method_name(method);
            EXPECT_EQ(checked.body_centre_of_mass, full.body_centre_of_mass) << method_name(method);
            EXPECT_EQ(checked.max_joint_gap, full.max_joint_gap) << method_name(method);
            EXPECT_EQ(checked.max_link_stretch, full.max_link_stretch) << method_name(method);
            EXPECT_GT(full.joints.limited_joints, 0) << method_name(method) << ": the scene has limits to measure";
          },
          world.internals().state);
    }
  }
}

}  // namespace
}  // namespace limber
