// Stability under long runs (labelled "stress"): no divergence and no energy gained.
#include <cmath>

#include <gtest/gtest.h>

#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

// Runs `steps` steps; every step must be ok, and the total energy may never exceed the initial
// energy by more than `allowance` (J): nothing in these scenes adds energy.
template <typename Scalar>
void expect_stable(const Model& model, int steps, double allowance, const VerletOptions& options = {}) {
  auto state = compile<Scalar>(model, options);
  const double initial = observe(state).energy();
  double highest = initial;
  for (int s = 0; s < steps; ++s) {
    const StepReport report = step(state);
    ASSERT_EQ(report.status, StepStatus::ok) << "step " << s;
    if (s % 64 == 0) highest = std::max(highest, observe(state).energy());
  }
  EXPECT_LE(highest, initial + allowance) << "initial " << initial << " J, highest " << highest << " J";
}

TEST(Stability, HumanoidRuns100000StepsWithoutDivergenceOrEnergyGain) {
  Model model = testing::load_shipped_scene("humanoid.json");
  model.balls.front().velocity *= 3;  // a hard hit: 18 m/s
  const double ball_energy = 0.5 * model.balls.front().mass * model.balls.front().velocity.squaredNorm();
  expect_stable<float>(model, 100000, 0.01 * ball_energy);
  expect_stable<double>(model, 100000, 0.01 * ball_energy);
}

TEST(Stability, HundredLinkChainRuns100000StepsWithoutDivergenceOrEnergyGain) {
  const Scene chain = testing::shipped_scene("chain.json", {.variant = {}, .links = 100, .copies = {}});
  const Model& model = chain.model;
  // Released horizontally from rest: the energy scale is the drop of its centre of mass.
  const double drop_energy = model.body_mass() * 9.81 * 0.5 * 100 * 0.2;
  expect_stable<double>(model, 100000, 1e-3 * drop_energy, testing::with_scene_settings(chain));
}

}  // namespace
}  // namespace limber
