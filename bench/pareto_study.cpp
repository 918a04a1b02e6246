// Run time against error for every method: one scene under every method and setting,
// one CSV row per run, read by tools/plot_pareto.py for the Pareto plot and the README's table.
//
//   pareto_study <scene> [--csv FILE] [--repeats R] [--quick]
//   scenes: double-pendulum  two uniform rods 0.5 m, 1 kg, released horizontally
//           chain-5          tools/scenes/chain.json: the thesis's 5 links, the end one double mass
//           chain-100        100 links of 0.1 m, 1 kg, the last 2 kg (the heavy-end chain, bench/chains.md)
//           humanoid         tools/scenes/humanoid.json: the medium body hit by the ball at 10 m/s
//
// Per run: wall time per simulated second (median of R fresh runs, stepping only), and the
// errors of one observed run (kernel/study/run_metrics.hpp): largest and RMS joint gap, largest
// link stretch, largest energy change relative to m·|g|·ΣL, and — on the chains — the
// trajectory error: the largest over samples every 0.05 s of the RMS distance between the
// run's limb heads and tails and the reference's. The reference is Featherstone with RK4 at
// Δt = 1/20000 s (its ABA agrees with MuJoCo 2.2.2's forward dynamics to 1e-12,
// tests/featherstone/featherstone_mujoco_test.cpp; its own error is printed as the distance to
// the same run at Δt = 1/40000 s). A horizontally released chain is chaotic, so every run
// lasts 2 s. The humanoid's contacts make trajectories non-smooth: its error is the
// joint gap or stretch and the energy change only.
//
// The rattle series run frames of 1/60 s in substeps (verlet rattle gauss-seidel: 1 or 4 sweeps a
// substep; verlet rattle direct: one Newton step a substep); "time_step" is the frame.
//
// On the chains the particle methods run with LimbMasses::inertia (three particles per limb
// reproduce a uniform rod's mass, centre and inertia), so every method simulates the same body;
// the series "verlet gauss-seidel, thesis masses" keeps the thesis's half-mass-at-each-end
// limbs, whose rods are 3x too hard to turn: its trajectory error does not fall with Δt.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/study/run_metrics.hpp"
#include "limber/kernel/study/workloads.hpp"

namespace limber::study {
namespace {

constexpr double kDuration = 2;           // s: trajectories of a chaotic chain compare for ~2 s
constexpr double kSampleInterval = 0.05;  // s: a whole number of steps of every Δt below
constexpr double kReferenceStep = 1.0 / 20000;

Scene scene_model(const std::string& scene) {
  if (scene == "double-pendulum") return double_pendulum();
  if (scene == "chain-5") return load_scene_file(std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/chain.json");
  if (scene == "chain-100") {
    Scene chain{make_chain_model({.links = 100, .link_length = 0.1, .link_mass = 1, .end_mass_ratio = 2}), {}, {}};
    chain.methods.verlet.joints = ParticleJoints::shared_particle;  // one particle a joint, as measured
    return chain;
  }
  if (scene == "humanoid") {
    Scene humanoid = load_scene_file(std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/humanoid.json");
    humanoid.model.settings.sleep.start_asleep = false;  // every method steps the whole body from t = 0
    return humanoid;
  }
  throw std::invalid_argument("scene: '" + scene + "' is not one of double-pendulum, chain-5, chain-100, humanoid");
}

// The settings every scene is run at. Time steps divide kSampleInterval. `limb_masses`: the
// particle methods' mass model (unset: the scene's).
std::vector<Method> methods(bool quick, std::optional<LimbMasses> limb_masses) {
  const std::vector<double> all_steps = quick ? std::vector<double>{1.0 / 240} : std::vector<double>{1.0 / 60, 1.0 / 120, 1.0 / 240, 1.0 / 480, 1.0 / 1000, 1.0 / 2000};
  const std::vector<double> three_steps = quick ? std::vector<double>{1.0 / 240} : std::vector<double>{1.0 / 60, 1.0 / 240, 1.0 / 1000};
  std::vector<Method> out;
  auto verlet = [&](const char* series, RelaxationSolver solver, int sweeps, double dt, std::optional<LimbMasses> masses) {
    Method m{.series = series, .family = Family::particles, .time_step = dt};
    m.verlet.solver = solver;
    m.sweeps = sweeps;
    m.limb_masses = masses;
    if (solver == RelaxationSolver::direct) m.verlet.newton_iterations = sweeps;
    m.setting = std::to_string(sweeps) + (solver == RelaxationSolver::direct ? " Newton steps" : " sweeps");
    out.push_back(m);
  };
  for (const double dt : three_steps) {
    for (const int sweeps : {2, 5, 20, 100}) verlet("verlet gauss-seidel", RelaxationSolver::gauss_seidel, sweeps, dt, limb_masses);
    for (const int sweeps : {5, 20, 100}) verlet("verlet jacobi", RelaxationSolver::jacobi, sweeps, dt, limb_masses);
    if (limb_masses) verlet("verlet gauss-seidel thesis masses", RelaxationSolver::gauss_seidel, 20, dt, LimbMasses::ends);
  }
  for (const double dt : all_steps) {
    for (const int newton : {1, 2, 5}) verlet("verlet direct", RelaxationSolver::direct, newton, dt, limb_masses);
  }
  // The rattle rule (kernel/relaxation/README.md): frames of 1/60 s in substeps, each with a few
  // Gauss-Seidel sweeps or Newton steps.
  const auto rattle = [&](const char* series, RelaxationSolver solver, int iterations, int substeps) {
    verlet(series, solver, iterations, 1.0 / 60, limb_masses);
    Method& m = out.back();
    m.projection = ProjectionRule::rattle, m.substeps = substeps;
    m.setting = std::to_string(substeps) + " substeps x " + m.setting;
  };
  for (const int substeps : quick ? std::vector<int>{16} : std::vector<int>{2, 8, 32, 128}) {
    for (const int sweeps : {1, 4}) rattle("verlet rattle gauss-seidel", RelaxationSolver::gauss_seidel, sweeps, substeps);
    rattle("verlet rattle direct", RelaxationSolver::direct, 1, substeps);
  }
  for (const double dt : quick ? std::vector<double>{1.0 / 1000} : std::vector<double>{1.0 / 240, 1.0 / 1000, 1.0 / 2000}) {
    for (const double k : {1e4, 1e5, 1e6}) {
      Method m{.series = "springs explicit", .setting = "k " + std::to_string(int(k)) + " N/m", .family = Family::springs, .time_step = dt};
      m.springs.integrator = Integrator::semi_implicit_euler;
      m.springs.stiffness = k;
      out.push_back(m);
    }
  }
  for (const double dt : three_steps) {
    for (const double k : {1e4, 1e5, 1e6, 1e7}) {
      Method m{.series = "springs implicit", .setting = "k " + std::to_string(int(k)) + " N/m", .family = Family::springs, .time_step = dt};
      m.springs.integrator = Integrator::backward_euler;
      m.springs.stiffness = k;
      out.push_back(m);
    }
  }
  for (const double dt : all_steps) {
    struct Lagrange { const char* series; Integrator integrator; Stabilization stabilization; };
    for (const Lagrange& l : {Lagrange{"lagrange baumgarte", Integrator::semi_implicit_euler, Stabilization::baumgarte},
                              Lagrange{"lagrange projection", Integrator::semi_implicit_euler, Stabilization::projection},
                              Lagrange{"lagrange rk4 projection", Integrator::rk4, Stabilization::projection}}) {
      Method m{.series = l.series, .setting = "", .family = Family::lagrange, .time_step = dt};
      m.lagrange.integrator = l.integrator;
      m.lagrange.stabilization = l.stabilization;
      out.push_back(m);
    }
    for (const Integrator integrator : {Integrator::rk4, Integrator::semi_implicit_euler}) {
      Method m{.series = integrator == Integrator::rk4 ? "featherstone rk4" : "featherstone semi-implicit",
               .setting = "", .family = Family::featherstone, .time_step = dt};
      m.featherstone.integrator = integrator;
      out.push_back(m);
    }
  }
  return out;
}

Method reference_method(double dt) {
  return {.series = "reference", .setting = "featherstone rk4", .family = Family::featherstone, .time_step = dt};
}

int run(int argc, char** argv) {
  if (argc < 2) throw std::invalid_argument("usage: pareto_study <double-pendulum|chain-5|chain-100|humanoid> [--csv FILE] [--repeats R] [--quick]");
  const std::string scene = argv[1];
  std::string csv_path;
  int repeats = 3;
  bool quick = false;
  for (int i = 2; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--quick") quick = true;
    else if (flag == "--csv" && i + 1 < argc) csv_path = argv[++i];
    else if (flag == "--repeats" && i + 1 < argc) {
      repeats = std::atoi(argv[++i]);
      if (repeats < 1) throw std::invalid_argument("--repeats: must be an integer ≥ 1");
    } else throw std::invalid_argument(flag + ": unknown flag (or missing value)");
  }
  const Scene model = scene_model(scene);
  const bool has_trajectory = scene != "humanoid";

  Trajectory reference;
  if (has_trajectory) {
    Simulation fine(model, reference_method(kReferenceStep));
    reference = observe_run(fine, kDuration, kSampleInterval).trajectory;
    Simulation finer(model, reference_method(kReferenceStep / 2));
    const double uncertainty = trajectory_error(observe_run(finer, kDuration, kSampleInterval).trajectory, reference);
    std::fprintf(stderr, "%s: reference featherstone rk4 at dt 1/%.0f s; distance to dt 1/%.0f s: %.2e m\n", scene.c_str(),
                 1 / kReferenceStep, 2 / kReferenceStep, uncertainty);
  }

  std::FILE* out = stdout;
  if (!csv_path.empty()) {
    out = std::fopen(csv_path.c_str(), "w");
    if (!out) throw std::invalid_argument("--csv: cannot write " + csv_path);
  }
  std::fprintf(out, "scene,series,setting,time_step,wall_per_simulated_second,max_joint_gap,rms_joint_gap,max_link_stretch,"
                    "relative_energy_drift,relative_energy_gain,trajectory_error,stability\n");
  // The humanoid's wide limbs (basin, torso) have more inertia than three particles on the axis
  // can carry: it keeps the scene's particle masses (half at each end).
  const std::optional<LimbMasses> limb_masses = has_trajectory ? std::optional(LimbMasses::inertia) : std::nullopt;
  for (const Method& method : methods(quick, limb_masses)) {
    Simulation simulation(model, method);
    const ObservedRun observed = observe_run(simulation, kDuration, has_trajectory ? kSampleInterval : 0);
    RunErrors errors = observed.errors;
    if (has_trajectory) errors.trajectory_error = trajectory_error(observed.trajectory, reference);
    const double wall = wall_time_per_simulated_second(model, method, kDuration, repeats);
    std::fprintf(out, "%s,%s,%s,%.9g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%s\n", scene.c_str(), method.series.c_str(),
                 method.setting.c_str(), method.time_step, wall, errors.max_joint_gap, errors.rms_joint_gap,
                 errors.max_link_stretch, errors.relative_energy_drift(), errors.relative_energy_gain(), errors.trajectory_error,
                 name(classify(errors)));
    std::fflush(out);
  }
  if (out != stdout) std::fclose(out);
  return 0;
}

}  // namespace
}  // namespace limber::study

int main(int argc, char** argv) {
  try {
    return limber::study::run(argc, argv);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "pareto_study: %s\n", error.what());
    return 2;
  }
}
