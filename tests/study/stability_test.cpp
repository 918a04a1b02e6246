// The stability stress, shortened for CI (bench/stability_stress.cpp is the full
// run; bench/reliability.md, "Stability stress"): what diverges, what does not, and the explicit springs'
// boundary of eq. 3.15 where the linearized spring modes put it. The StabilityStress tests
// (study_stability_tests) take seconds; StabilityStressLong, compiled into
// study_stability_stress_tests with LIMBER_STABILITY_STRESS_LONG (LABELS stress), runs 10⁵
// steps per method.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/study/run_metrics.hpp"
#include "limber/kernel/study/spring_stability.hpp"

namespace limber::study {
namespace {

constexpr double kStiffness = 2e4, kDamping = 20;  // the scene's spring: N/m, N·s/m

Model stress_chain(double end_mass_ratio) {
  return make_chain_model({.links = 10, .link_length = 0.1, .link_mass = 1, .end_mass_ratio = end_mass_ratio});
}

Method springs(Integrator integrator, double stiffness, double dt) {
  return {.series = "springs", .family = Family::springs, .time_step = dt,
          .springs = {.integrator = integrator, .stiffness = stiffness, .damping = kDamping, .newton_iterations = 2}};
}

std::vector<Method> methods_that_hold(double dt) {
  return {
      {.series = "verlet gauss-seidel 20 sweeps", .family = Family::particles, .time_step = dt, .verlet = {.threads = 1}, .sweeps = 20},
      {.series = "verlet direct 2 Newton steps", .family = Family::particles, .time_step = dt,
       .verlet = {.solver = RelaxationSolver::direct, .threads = 1, .newton_iterations = 2}},
      {.series = "lagrange projection", .family = Family::lagrange, .time_step = dt,
       .lagrange = {.stabilization = Stabilization::projection}},
  };
}

// The stated bounds (run_metrics.hpp): energy gain > 0.5 × m·g·ΣL, gap > 0.5 of a link.

#ifndef LIMBER_STABILITY_STRESS_LONG

// Divergence of the integrator alone: non-finite or energy growth (a too-weak spring tears the
// chain — a gap — without blowing up).
constexpr StabilityBounds kIntegratorOnly{.energy_gain = 0.5, .joint_gap = std::numeric_limits<double>::infinity()};

// How `duration` s of `method` on `model` end, stopped at the first divergence.
Stability run(const Model& model, const Method& method, double duration, const StabilityBounds& bounds = {}) {
  Simulation simulation(model, method);
  const auto beyond_bounds = [&](const RunErrors& errors) { return classify(errors, bounds) != Stability::stable; };
  return classify(observe_run(simulation, duration, 0, beyond_bounds).errors, bounds);
}

// The chain's bound (kernel/study/spring_stability.hpp) at the scene's damping.
double predicted_largest_stable_step(Integrator integrator, const Model& model, double stiffness) {
  return study::predicted_largest_stable_step(integrator, spring_mode_frequencies(model, stiffness), stiffness, kDamping);
}

TEST(StabilityStress, ClassifyFlagsNanEnergyGainAndGapBeyondTheStatedBounds) {
  RunErrors errors;
  errors.energy_scale = 100;  // J
  errors.energy_gain = 49, errors.max_joint_gap = 0.49, errors.max_link_stretch = 0.49;
  EXPECT_EQ(classify(errors), Stability::stable);
  RunErrors nan = errors;
  nan.max_joint_gap = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(classify(nan), Stability::non_finite);
  RunErrors too_fast = errors;
  too_fast.status = StepStatus::diverged_speed;
  EXPECT_EQ(classify(too_fast), Stability::non_finite);
  RunErrors gained = errors;
  gained.energy_gain = 51;  // 0.51 of the scale
  EXPECT_EQ(classify(gained), Stability::energy_growth);
  EXPECT_EQ(classify(gained, {.energy_gain = 0.6, .joint_gap = 0.5}), Stability::stable);
  RunErrors gap = errors;
  gap.max_joint_gap = 0.51;
  EXPECT_EQ(classify(gap), Stability::joint_gap);
  RunErrors stretched = errors;
  stretched.max_link_stretch = 0.51;
  EXPECT_EQ(classify(stretched), Stability::joint_gap);
  // Energy lost never counts: a dissipative method is stable.
  RunErrors lost = errors;
  lost.energy_gain = 0, lost.energy_drift = 1e6;
  EXPECT_EQ(classify(lost), Stability::stable);
}

// The modal bound's ingredients on a case with a closed form: one rod of mass m and length L
// pinned by a spring at its head has a transverse mode of effective mass 1/(1/m + (L/2)²/I) = m/4
// at the anchor, so ω_max = 2√(k/m).
TEST(StabilityStress, OneLinkSpringModeIsTwiceTheTranslationalFrequency) {
  const Model model = make_chain_model({.links = 1, .link_length = 0.1, .link_mass = 1});
  const std::vector<double> frequencies = spring_mode_frequencies(model, kStiffness);
  EXPECT_NEAR(*std::max_element(frequencies.begin(), frequencies.end()), 2 * std::sqrt(kStiffness / 1.0), 0.01 * 2 * std::sqrt(kStiffness));
}

TEST(StabilityStress, ExplicitSpringsDivergeJustAboveThePredictedBoundAndNotBelowIt) {
  const Model chain = stress_chain(1);
  struct Case { Integrator integrator; double stiffness; };
  for (const Case c : {Case{Integrator::semi_implicit_euler, 2e4}, Case{Integrator::semi_implicit_euler, 1e5},
                       Case{Integrator::euler, 1e4}}) {
    const double bound = predicted_largest_stable_step(c.integrator, chain, c.stiffness);
    const std::string label = (c.integrator == Integrator::euler ? "forward euler, k " : "semi-implicit euler, k ") +
                              std::to_string(c.stiffness) + ", predicted " + std::to_string(bound) + " s";
    EXPECT_EQ(run(chain, springs(c.integrator, c.stiffness, bound / 1.4), 10, kIntegratorOnly), Stability::stable) << label;
    EXPECT_NE(run(chain, springs(c.integrator, c.stiffness, bound * 1.4), 10, kIntegratorOnly), Stability::stable) << label;
  }
  // The scene's spring, measured by bench/stability_stress: 1/304 s symplectic, c/k = 1/1000 s forward.
  EXPECT_NEAR(predicted_largest_stable_step(Integrator::semi_implicit_euler, chain, kStiffness), 1.0 / 304, 0.01 / 304);
  EXPECT_DOUBLE_EQ(predicted_largest_stable_step(Integrator::euler, chain, kStiffness), kDamping / kStiffness);
}

// A light end (10⁻² kg on 1 kg links) raises the stiffest spring mode ~8×: explicit springs need
// steps below 1/4000 s and diverge at every step of the grid, while the implicit step holds.
TEST(StabilityStress, LightEndMakesExplicitSpringsDivergeButNotImplicitOnes) {
  const Model chain = stress_chain(1e-2);
  EXPECT_LT(predicted_largest_stable_step(Integrator::semi_implicit_euler, chain, kStiffness), 1.0 / 4000);
  EXPECT_NE(run(chain, springs(Integrator::semi_implicit_euler, kStiffness, 1.0 / 1000), 10), Stability::stable);
  EXPECT_EQ(run(chain, springs(Integrator::backward_euler, kStiffness, 1.0 / 240), 10), Stability::stable);
}

TEST(StabilityStress, AtEqualMassesOnlyTheExplicitIntegratorsDivergeAt240Hz) {
  const Model chain = stress_chain(1);
  const double dt = 1.0 / 240;
  std::vector<Method> stable = methods_that_hold(dt);
  stable.push_back(springs(Integrator::backward_euler, kStiffness, dt));
  stable.push_back({.series = "lagrange baumgarte", .family = Family::lagrange, .time_step = dt});
  stable.push_back({.series = "featherstone rk4", .family = Family::featherstone, .time_step = dt});
  for (const Method& method : stable) EXPECT_EQ(run(chain, method, 10), Stability::stable) << method.series;
  // Beyond their bounds (1/304 s, 1/1000 s) the explicit springs gain energy.
  EXPECT_EQ(run(chain, springs(Integrator::semi_implicit_euler, kStiffness, dt), 10), Stability::energy_growth);
  EXPECT_EQ(run(chain, springs(Integrator::euler, kStiffness, dt), 10), Stability::energy_growth);
  // Featherstone's semi-implicit Euler takes the velocity-product terms explicitly (bench/reliability.md).
  EXPECT_EQ(run(chain, {.series = "featherstone semi-implicit", .family = Family::featherstone, .time_step = dt,
                        .featherstone = {.integrator = Integrator::semi_implicit_euler}}, 10),
            Stability::energy_growth);
}

// A 100 kg end on 1 kg links: the position-level methods hold it; every spring at the scene's
// k opens beyond half a link (the end's weight alone stretches the top spring by ~0.05 m).
TEST(StabilityStress, HeavyEndIsHeldByProjectionAndTearsTheScenesSprings) {
  const Model chain = stress_chain(100);
  const double dt = 1.0 / 240;
  for (const Method& method : methods_that_hold(dt)) EXPECT_EQ(run(chain, method, 10), Stability::stable) << method.series;
  for (const Integrator integrator : {Integrator::semi_implicit_euler, Integrator::backward_euler}) {
    EXPECT_EQ(run(chain, springs(integrator, kStiffness, dt), 10), Stability::joint_gap);
  }
}

#else  // the target labelled "stress"

bool diverged(const RunErrors& errors) { return classify(errors) != Stability::stable; }

// 10⁵ steps (417 s) of the equal-mass chain at 1/240 s: no divergence, no energy gained beyond
// 1 % of m·g·ΣL, and each method's joints as closed as it can hold them.
TEST(StabilityStressLong, StableMethodsRun100000StepsWithoutGainingEnergy) {
  const Model chain = stress_chain(1);
  const double dt = 1.0 / 240;
  struct Case { Method method; double largest_gap; };
  std::vector<Case> cases;
  const std::vector<Method> hold = methods_that_hold(dt);
  cases.push_back({hold[0], 0.01});
  cases.push_back({hold[1], 1e-6});
  cases.push_back({hold[2], 1e-4});
  cases.push_back({springs(Integrator::backward_euler, kStiffness, dt), 0.2});
  cases.push_back({{.series = "featherstone rk4", .family = Family::featherstone, .time_step = dt}, 1e-9});
  for (const Case& c : cases) {
    Simulation simulation(chain, c.method);
    const RunErrors errors = observe_run(simulation, 1e5 * dt, 0, diverged).errors;
    EXPECT_EQ(classify(errors), Stability::stable) << c.method.series;
    EXPECT_EQ(errors.steps, 100000) << c.method.series;
    EXPECT_LT(errors.relative_energy_gain(), 0.01) << c.method.series;
    EXPECT_LT(std::max(errors.max_joint_gap, errors.max_link_stretch), c.largest_gap) << c.method.series;
  }
}

#endif

}  // namespace
}  // namespace limber::study
