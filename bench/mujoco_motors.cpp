// MuJoCo's humanoid under its motors, in flight, in limber's configurations against MuJoCo's RK4
// (tests/support/mujoco_motors.hpp says how): the largest body-centre distance with all motors
// on, per step, and each motor's response alone. Prints the tables of bench/models.md.
//
//   build/bench/mujoco_motors [duration s (0.2)] [configuration ...]
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "tests/support/mujoco_motors.hpp"

using namespace limber;
using namespace limber::mujoco_motors;

int main(int argc, char** argv) {
  const double duration = argc > 1 ? std::atof(argv[1]) : 0.2;
  std::vector<std::string> configurations(argv + std::min(argc, 2), argv + argc);
  if (configurations.empty()) configurations = {"weighted", "unweighted", "springs-explicit", "springs-implicit", "lagrange", "featherstone"};
  const Scene scene = lifted_scene(kHumanoid);
  // A configuration that refuses the file or its motors is said once, and left out of the tables.
  for (auto c = configurations.begin(); c != configurations.end();) {
    const MotorRun first = run_limber(scene, *c, 0.001, all_motor_controls(scene.model.actuators.size()), 0.001);
    if (first.failure.rfind("refused: ", 0) != 0) {
      ++c;
      continue;
    }
    std::printf("%s %s\n", c->c_str(), first.failure.c_str());
    c = configurations.erase(c);
  }
  Mujoco mujoco(kHumanoid, body_names(scene));
  const std::size_t motors = static_cast<std::size_t>(mujoco.actuators());
  const std::vector<double> all = all_motor_controls(motors), none(motors, 0.0);
  const MotorRun reference = mujoco.run(all, duration), rest = mujoco.run(none, duration);
  std::printf("humanoid.xml lifted %.1f m, limits off, %g s, all motors (0.1 sin(a + 1)); MuJoCo RK4 at %g s%s\n\n", kLift, duration,
              kReferenceStep, reference.touched ? " (limbs touched: the comparison is not clean)" : ", no contact");
  std::printf("| configuration | dt 0.005 s | dt 0.001 s | dt 0.0002 s |\n|---|---:|---:|---:|\n");
  for (const std::string& configuration : configurations) {
    std::printf("| %s |", configuration.c_str());
    for (const double dt : {0.005, 0.001, 0.0002}) {
      const MotorRun run = run_limber(scene, configuration, dt, all, duration);
      if (run.failure.empty()) {
        std::printf(" %.3g mm |", 1e3 * largest_distance(run, reference));
      } else {
        std::printf(" %s |", run.failure.c_str());
      }
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  std::printf("\nOne motor at a time (control 0.05), dt 0.001 s: the response of the body MuJoCo moves most, 1 = MuJoCo's\n\n| motor | body |");
  for (const std::string& configuration : configurations) std::printf(" %s |", configuration.c_str());
  std::printf("\n|---|---|");
  for (std::size_t c = 0; c < configurations.size(); ++c) std::printf("---:|");
  std::printf("\n");
  std::vector<MotorRun> rests;
  for (const std::string& configuration : configurations) rests.push_back(run_limber(scene, configuration, 0.001, none, duration));
  const std::vector<std::string> names = body_names(scene);
  for (std::size_t motor = 0; motor < motors; ++motor) {
    std::vector<double> one(motors, 0.0);
    one[motor] = 0.05;
    const MotorRun moved = mujoco.run(one, duration);
    const Response shape = response(moved, rest, moved, rest);
    std::printf("| %s | %s |", scene.model.actuators[motor].name.c_str(), names[shape.body].c_str());
    for (std::size_t c = 0; c < configurations.size(); ++c) {
      const MotorRun run = run_limber(scene, configurations[c], 0.001, one, duration);
      const Response got = response(run, rests[c], moved, rest);
      if (std::isnan(got.ratio)) {
        std::printf(" %s |", (run.failure.empty() ? rests[c].failure : run.failure).c_str());  // a divergence
      } else {
        std::printf(" %+.3g |", got.ratio);
      }
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  return 0;
}
