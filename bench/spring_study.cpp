// The stiff-spring method's two figures (bench/accuracy.md, "Stiff springs"):
//  gap        the joint gaps of the thesis's 5-link heavy-end chain (tools/scenes/chain.json,
//             released horizontally) against stiffness, for explicit (semi-implicit Euler) and
//             implicit (backward Euler) springs, with weighted Verlet as the reference;
//  stable-dt  the largest stable time step against stiffness for every spring integrator.
// Usage: spring_study gap|stable-dt [--damping C]; writes CSV to stdout.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/springs/compile.hpp"
#include "limber/kernel/springs/spring_forces.hpp"
#include "limber/kernel/springs/step.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"

namespace {

using namespace limber;

const double kStiffnesses[] = {1e3, 3e3, 1e4, 3e4, 1e5, 3e5, 1e6, 1e7, 1e8};

Model chain_scene() { return load_scene_file(std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/chain.json", {}).model; }

struct Run {
  bool stable = true;
  double top_gap = 0;    // largest gap of the top (world) joint over the run, relative to the link length
  double other_gap = 0;  // largest gap of any other joint
  double energy_gain = 0;  // largest energy above the start, J
};

// Runs `seconds` of the chain under springs. Stable: no divergence status, no joint opened
// beyond a link length, and the energy never more than 1 J + 10 % above its start (diverging
// runs gain orders of magnitude more; the implicit step's energy wanders by up to ~2 % at
// k ≥ 10⁶ N/m, README).
Run run_springs(const Model& model, const SpringOptions& options, double dt, double seconds) {
  SpringState state = compile_springs(model, options);
  Run run;
  const double start = observe(state).energy();
  const long steps = std::lround(seconds / dt);
  for (long s = 0; s < steps; ++s) {
    if (step(state, dt).status != StepStatus::ok) return run.stable = false, run;
    for (std::size_t j = 0; j < state.springs.size(); ++j) {
      const double gap = joint_separation(state.springs, state.bodies.state, j).norm() / state.springs.reference_length[j];
      (state.springs.inboard[j] < 0 ? run.top_gap : run.other_gap) = std::max(gap, state.springs.inboard[j] < 0 ? run.top_gap : run.other_gap);
    }
    run.energy_gain = std::max(run.energy_gain, observe(state).energy() - start);
    if (run.top_gap > 1 || run.other_gap > 1 || run.energy_gain > 1 + 0.1 * std::abs(start)) return run.stable = false, run;
  }
  return run;
}

void gap_table(double damping) {
  const Model model = chain_scene();
  const double dt = model.settings.time_step, seconds = 5;
  std::printf("method,stiffness,damping,dt,stable,top_gap,other_gap,energy_gain\n");
  for (const double k : kStiffnesses) {
    struct Variant { const char* name; Integrator integrator; int newton_iterations; };
    for (const Variant& variant : {Variant{"springs-explicit", Integrator::semi_implicit_euler, 1},
                                   Variant{"springs-implicit-linearized", Integrator::backward_euler, 1},
                                   Variant{"springs-implicit", Integrator::backward_euler, 2}}) {
      const char* name = variant.name;
      const Run run = run_springs(model, {.integrator = variant.integrator, .stiffness = k, .damping = damping,
                                          .newton_iterations = variant.newton_iterations}, dt, seconds);
      std::printf("%s,%g,%g,%.6g,%d,%.6g,%.6g,%.4g\n", name, k, damping, dt, run.stable, run.top_gap, run.other_gap, run.energy_gain);
    }
  }
  // Weighted Verlet with the scene's 100 sweeps: the reference the springs are compared with.
  VerletState<double> verlet = compile<double>(model);
  double top = 0, other = 0;
  for (long s = 0; s < std::lround(seconds / dt); ++s) {
    step(verlet);
    for (const auto& [c, reference] : verlet.joint_constraints) {
      const auto& x = verlet.particles;
      const double gap = (x.position(verlet.constraints.particle_i[c]) - x.position(verlet.constraints.particle_j[c])).norm() / reference;
      const bool is_top = x.inverse_mass[verlet.constraints.particle_i[c]] == 0 || x.inverse_mass[verlet.constraints.particle_j[c]] == 0;
      (is_top ? top : other) = std::max(gap, is_top ? top : other);
    }
  }
  std::printf("weighted-verlet,0,0,%.6g,1,%.6g,%.6g,0\n", dt, top, other);
}

void stable_dt_table(double damping) {
  const Model model = chain_scene();
  std::printf("integrator,stiffness,damping,largest_stable_dt,symplectic_bound\n");
  struct Named { const char* name; Integrator integrator; int newton_iterations; };
  for (const Named& method : {Named{"euler", Integrator::euler, 1}, Named{"semi-implicit", Integrator::semi_implicit_euler, 1},
                              Named{"rk4", Integrator::rk4, 1}, Named{"backward-euler-linearized", Integrator::backward_euler, 1},
                              Named{"backward-euler", Integrator::backward_euler, 2}}) {
    for (const double k : kStiffnesses) {
      // Time steps from 1/15 s down by 2^(1/4); the first that runs 2 s stably.
      double largest = 0;
      for (double dt = 1.0 / 15; dt > 1e-6; dt /= std::pow(2.0, 0.25)) {
        if (run_springs(model, {.integrator = method.integrator, .stiffness = k, .damping = damping,
                                .newton_iterations = method.newton_iterations}, dt, 2.0).stable) {
          largest = dt;
          break;
        }
      }
      // h·ω = 2 for a lone link end on one spring: ω² = k/m for the lightest link.
      const double bound = 2 / std::sqrt(k / model.bodies.front().mass);
      std::printf("%s,%g,%g,%.6g,%.6g\n", method.name, k, damping, largest, bound);
      std::fflush(stdout);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  double damping = 20;
  for (int a = 2; a + 1 < argc; ++a) {
    if (std::strcmp(argv[a], "--damping") == 0) damping = std::atof(argv[a + 1]);
  }
  const std::string what = argc > 1 ? argv[1] : "";
  if (what == "gap") gap_table(damping);
  else if (what == "stable-dt") stable_dt_table(damping);
  else {
    std::fprintf(stderr, "usage: spring_study gap|stable-dt [--damping C]\n");
    return 2;
  }
  return 0;
}
