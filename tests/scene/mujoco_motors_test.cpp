// MuJoCo's humanoid driven by its motors, in flight, under each of `limber run`'s configurations
// against MuJoCo 2.2.2's RK4 at 10⁻⁴ s, body by body (tests/support/mujoco_motors.hpp says how).
// A configuration either refuses the file or its motors by name (the particles: a body of
// several hinges takes no actuator, kernel/model/capabilities.hpp) or moves it as MuJoCo does:
// with all 21 motors on for 0.2 s at 0.001 s every body within 5 mm of MuJoCo's, the error
// shrinking with the step, and each motor alone moving the body MuJoCo moves most by 0.9–1.1 of
// MuJoCo's motion.
// Skipped, with a message, where the model file is missing (Debian's libmujoco-samples).
#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/mujoco_motors.hpp"

namespace limber {
namespace {

using namespace mujoco_motors;

constexpr double kDuration = 0.2;  // s in flight
constexpr double kStep = 0.001;    // s

// The scene, MuJoCo and its controls, made once a process (ctest runs each test in its own).
struct Comparison {
  Scene scene = lifted_scene(kHumanoid);
  Mujoco mujoco{kHumanoid, body_names(scene)};
  std::vector<double> all = all_motor_controls(static_cast<std::size_t>(mujoco.actuators()));
  std::vector<double> none = std::vector<double>(all.size(), 0.0);

  std::vector<double> one_motor(std::size_t motor) const {
    std::vector<double> controls = none;
    controls[motor] = 0.05;
    return controls;
  }
  static Comparison& get() {
    static const std::unique_ptr<Comparison> comparison = std::make_unique<Comparison>();
    return *comparison;
  }
};

class MujocoMotors : public ::testing::TestWithParam<std::string> {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(kHumanoid)) GTEST_SKIP() << kHumanoid << " is missing: install libmujoco-samples";
    const Comparison& comparison = Comparison::get();
    const MotorRun first = run_limber(comparison.scene, GetParam(), kStep, comparison.all, kStep);
    if (first.failure.rfind("refused: ", 0) == 0) GTEST_SKIP() << GetParam() << " " << first.failure;
  }
};

TEST_P(MujocoMotors, EveryBodyStartsAtItsGeom) {
  Comparison& comparison = Comparison::get();
  const MotorRun start = comparison.mujoco.run(comparison.none, 0);
  const MotorRun run = run_limber(comparison.scene, GetParam(), kStep, comparison.none, kStep);
  for (std::size_t b = 0; b < run.samples[0].size(); ++b) {
    EXPECT_LT((run.samples[0][b] - start.samples[0][b]).norm(), 1e-9) << comparison.scene.model.bodies[b].name;
  }
}

TEST_P(MujocoMotors, AllMotorsOnEveryBodyFollowsMujocoAndTheErrorShrinksWithTheStep) {
  Comparison& comparison = Comparison::get();
  const MotorRun reference = comparison.mujoco.run(comparison.all, kDuration);
  ASSERT_FALSE(reference.touched) << "MuJoCo's run touched a limb: the set-up is no longer contact-free";
  const MotorRun coarse = run_limber(comparison.scene, GetParam(), 5 * kStep, comparison.all, kDuration);
  const MotorRun fine = run_limber(comparison.scene, GetParam(), kStep, comparison.all, kDuration);
  ASSERT_EQ(fine.failure, "");
  const double fine_error = largest_distance(fine, reference), coarse_error = largest_distance(coarse, reference);
  EXPECT_LT(fine_error, 5e-3) << "m, the largest body-centre distance from MuJoCo's RK4 at dt " << kStep << " s";
  EXPECT_GT(coarse_error, 2.5 * fine_error) << "a 5× longer step should cost at least 2.5× the error (first order: 5×)";
}

TEST_P(MujocoMotors, EachMotorAloneMovesItsBodyAsMujocoDoes) {
  Comparison& comparison = Comparison::get();
  const MotorRun reference_rest = comparison.mujoco.run(comparison.none, kDuration);
  const MotorRun rest = run_limber(comparison.scene, GetParam(), kStep, comparison.none, kDuration);
  ASSERT_EQ(rest.failure, "");
  for (std::size_t motor = 0; motor < comparison.all.size(); ++motor) {
    const MotorRun reference = comparison.mujoco.run(comparison.one_motor(motor), kDuration);
    const MotorRun run = run_limber(comparison.scene, GetParam(), kStep, comparison.one_motor(motor), kDuration);
    const Response got = response(run, rest, reference, reference_rest);
    const std::string& name = comparison.scene.model.actuators[motor].name;
    EXPECT_EQ(run.failure, "") << name;
    EXPECT_GE(got.ratio, 0.9) << name << " moves " << comparison.scene.model.bodies[got.body].name;
    EXPECT_LE(got.ratio, 1.1) << name << " moves " << comparison.scene.model.bodies[got.body].name;
  }
}

INSTANTIATE_TEST_SUITE_P(Configurations, MujocoMotors,
                         ::testing::Values("weighted", "unweighted", "springs-explicit", "springs-implicit", "lagrange", "featherstone"),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string name = info.param;
                           for (char& c : name) c = c == '-' ? '_' : c;
                           return name;
                         });

}  // namespace
}  // namespace limber
