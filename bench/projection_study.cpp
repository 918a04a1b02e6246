// The projection rules measured (bench/accuracy.md, "The rattle rule"): how the pbd and rattle rules
// converge with the step, what frames of 1/60 s cost and keep, and energy over long runs.
//
//   projection_study order  [--csv FILE]   error against Δt for both rules on three workloads
//   projection_study frames [--csv FILE]   frames of 1/60 s: substeps × sweeps grid, time, error, energy
//   projection_study pendulum              the double pendulum over 10 s at frames of 1/60 s,
//                                          released horizontally (chaotic) and at 30°
//   projection_study long                  energy over 10⁶ substeps (converged and not)
//
// Workloads (kernel/study/workloads.hpp): the heavy-end chain (5 rods of 0.1 m, point masses 1,
// 1, 1, 1, 2 kg; limb_masses "lumps", so the particle model is that point-mass system exactly)
// released from its arc or in a small 3-D swing, and the double pendulum of two uniform rods
// (limb_masses "inertia": three particles carry a rod's mass, centre and inertia exactly, for the
// planar motion). The reference is Featherstone with RK4 at 1/24000 s (its own error is printed:
// the distance to the same run at 1/48000 s). Errors are max_point_error: the largest distance of
// any rod end from the reference's over samples every 1/60 s — the worst point at its worst
// moment. Energy drift is max |E(t) − E(0)|, relative to m·g·ΣL (run_metrics.hpp).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "limber/kernel/study/run_metrics.hpp"
#include "limber/kernel/study/workloads.hpp"

namespace limber::study {
namespace {

constexpr double kFrame = 1.0 / 60;
constexpr double kReferenceStep = kFrame / 400;

struct Workload {
  std::string name;
  Scene model;
};

std::vector<Workload> workloads() {
  Scene pendulum = double_pendulum();
  pendulum.methods.verlet.limb_masses = LimbMasses::inertia;
  return {{"double-pendulum", pendulum},
          {"chain-arc", heavy_end_chain(ChainRelease::arc)},
          {"chain-3d", heavy_end_chain(ChainRelease::small_3d)}};
}

Method reference_method(double dt) { return {.series = "reference", .family = Family::featherstone, .time_step = dt}; }

// The particle method at frames of kFrame split into `substeps`: `sweeps` Gauss-Seidel sweeps a
// substep, or (sweeps = 0) the direct solver to convergence.
Method verlet(ProjectionRule projection, int substeps, int sweeps) {
  Method method{.series = projection == ProjectionRule::rattle ? "rattle" : "pbd", .family = Family::particles, .time_step = kFrame};
  method.projection = projection, method.substeps = substeps;
  if (sweeps > 0) {
    method.sweeps = sweeps;
  } else {
    method.verlet.solver = RelaxationSolver::direct;
    method.verlet.newton_iterations = 50;
    method.relaxation_tolerance = 1e-13;
  }
  method.verlet.threads = 1;
  method.setting = std::to_string(substeps) + " substeps x " + (sweeps > 0 ? std::to_string(sweeps) + " sweeps" : "converged");
  return method;
}

Trajectory reference_trajectory(const Scene& model, double duration) {
  Simulation fine(model, reference_method(kReferenceStep));
  Trajectory reference = observe_run(fine, duration, kFrame).trajectory;
  Simulation finer(model, reference_method(kReferenceStep / 2));
  std::fprintf(stderr, "%s: reference featherstone rk4 at 1/%.0f s; its distance to 1/%.0f s over %.0f s: %.2e m\n",
               model.model.name.c_str(), 1 / kReferenceStep, 2 / kReferenceStep, duration,
               max_point_error(observe_run(finer, duration, kFrame).trajectory, reference));
  return reference;
}

std::FILE* open_csv(const std::string& path) {
  if (path.empty()) return nullptr;
  std::FILE* csv = std::fopen(path.c_str(), "w");
  if (!csv) throw std::invalid_argument("--csv: cannot write " + path);
  return csv;
}

// Error against Δt: converged projections (direct solver to 1e-13 m) at frames of 1/60 s split
// into 1 … 256 substeps (pbd further, to show where its first order sets in), 2 s.
int order(const std::string& csv_path) {
  std::FILE* csv = open_csv(csv_path);
  if (csv) std::fprintf(csv, "workload,projection,substeps,time_step,max_point_error,relative_energy_drift\n");
  std::printf("%-16s %-7s %9s %12s %12s %8s %14s\n", "workload", "rule", "substeps", "dt s", "error m", "ratio", "energy drift");
  for (const Workload& workload : workloads()) {
    const Trajectory reference = reference_trajectory(workload.model, 2.0);
    for (const ProjectionRule projection : {ProjectionRule::pbd, ProjectionRule::rattle}) {
      double previous = 0;
      const int most = projection == ProjectionRule::pbd ? 1024 : 256;
      for (int substeps = 1; substeps <= most; substeps *= 2) {
        Simulation simulation(workload.model, verlet(projection, substeps, 0));
        const ObservedRun run = observe_run(simulation, 2.0, kFrame);
        const double error = max_point_error(run.trajectory, reference);
        const char* rule = projection == ProjectionRule::rattle ? "rattle" : "pbd";
        std::printf("%-16s %-7s %9d %12.3e %12.3e %8.2f %14.2e\n", workload.name.c_str(), rule, substeps, kFrame / substeps, error,
                    previous > 0 ? previous / error : 0.0, run.errors.relative_energy_drift());
        std::fflush(stdout);
        if (csv) {
          std::fprintf(csv, "%s,%s,%d,%.9g,%.6g,%.6g\n", workload.name.c_str(), rule, substeps, kFrame / substeps, error,
                       run.errors.relative_energy_drift());
        }
        previous = error;
      }
    }
  }
  if (csv) std::fclose(csv);
  return 0;
}

// Median of three runs' wall time per frame, µs (stepping only).
double microseconds_per_frame(const Scene& model, const Method& method, double duration) {
  return 1e6 * kFrame * wall_time_per_simulated_second(model, method, duration, 3);
}

// Frames of 1/60 s on the heavy-end chain (arc release): error over 2 s, energy over 10 s, pbd
// fallbacks, sweeps per frame (position and velocity sweeps counted apart) and time.
int frames(const std::string& csv_path) {
  std::FILE* csv = open_csv(csv_path);
  if (csv) {
    std::fprintf(csv, "projection,substeps,sweeps,position_sweeps_per_frame,max_point_error_2s,relative_energy_drift_10s,"
                      "fallbacks_10s,microseconds_per_frame\n");
  }
  const Scene model = heavy_end_chain(ChainRelease::arc);
  const Trajectory reference = reference_trajectory(model, 2.0);
  std::printf("%-7s %9s %7s %14s %12s %18s %10s %10s\n", "rule", "substeps", "sweeps", "sweeps/frame", "error 2 s m",
              "drift 10 s /mgL", "fallbacks", "us/frame");
  for (const ProjectionRule projection : {ProjectionRule::pbd, ProjectionRule::rattle}) {
    for (const int substeps : {1, 4, 16, 32, 64, 128}) {
      for (const int sweeps : {1, 2, 4, 8, 20}) {
        if (projection == ProjectionRule::pbd && sweeps != 4 && sweeps != 20) continue;
        const Method method = verlet(projection, substeps, sweeps);
        Simulation accuracy(model, method);
        const double error = max_point_error(observe_run(accuracy, 2.0, kFrame).trajectory, reference);
        Simulation energy(model, method);
        const ObservedRun long_run = observe_run(energy, 10.0);
        const std::uint64_t fallbacks = energy.fallbacks();
        const double micros = microseconds_per_frame(model, method, 2.0);
        const char* rule = projection == ProjectionRule::rattle ? "rattle" : "pbd";
        std::printf("%-7s %9d %7d %14d %12.3e %18.2e %10llu %10.1f\n", rule, substeps, sweeps, substeps * sweeps, error,
                    long_run.errors.relative_energy_drift(), static_cast<unsigned long long>(fallbacks), micros);
        std::fflush(stdout);
        if (csv) {
          std::fprintf(csv, "%s,%d,%d,%d,%.6g,%.6g,%llu,%.6g\n", rule, substeps, sweeps, substeps * sweeps, error,
                       long_run.errors.relative_energy_drift(), static_cast<unsigned long long>(fallbacks), micros);
        }
      }
    }
  }
  if (csv) std::fclose(csv);
  return 0;
}

// The double pendulum over 10 s at frames of 1/60 s, converged rattle in more and more
// substeps: released horizontally (chaotic: over 10 s small errors grow ~10⁶-fold, as the
// reference's own 1/24000 s against 1/48000 s shows), and released 30° from the vertical, where
// it swings regularly. The error at 2 s and over the whole 10 s.
int pendulum() {
  for (const double angle : {1.5707963267948966, 0.5235987755982988}) {
    Scene model = double_pendulum(angle);
    model.methods.verlet.limb_masses = LimbMasses::inertia;
    std::printf("released %.0f degrees from the vertical\n", angle * 180 / 3.141592653589793);
    std::fflush(stdout);
    const Trajectory reference = reference_trajectory(model, 10.0);
    std::printf("%-9s %14s %14s %16s %10s\n", "substeps", "error 2 s m", "error 10 s m", "drift 10 s /mgL", "us/frame");
    for (const int substeps : {1, 4, 16, 64, 256, 1024}) {
      const Method method = verlet(ProjectionRule::rattle, substeps, 0);
      Simulation simulation(model, method);
      const ObservedRun run = observe_run(simulation, 10.0, kFrame);
      Trajectory first = run.trajectory, reference_first = reference;
      first.samples.resize(121), reference_first.samples.resize(121);
      std::printf("%-9d %14.3e %14.3e %16.2e %10.1f\n", substeps, max_point_error(first, reference_first),
                  max_point_error(run.trajectory, reference), run.errors.relative_energy_drift(),
                  microseconds_per_frame(model, method, 1.0));
      std::fflush(stdout);
    }
  }
  return 0;
}

// Energy over 10⁶ substeps of the heavy-end chain (arc release): frames of 1/60 s in 64
// substeps (15625 frames, 260 s), converged (direct solver) and with 2 sweeps a substep, and
// pbd with 2 sweeps; the largest drift in each tenth of the run shows whether it grows.
int long_run() {
  const Scene model = heavy_end_chain(ChainRelease::arc);
  constexpr int kSubsteps = 64, kFrames = 1000000 / kSubsteps;
  for (const auto& [projection, sweeps] : {std::pair{ProjectionRule::rattle, 0}, std::pair{ProjectionRule::rattle, 2},
                                           std::pair{ProjectionRule::pbd, 2}}) {
    const Method method = verlet(projection, kSubsteps, sweeps);
    Simulation simulation(model, method);
    const double start = simulation.observe().energy(), scale = energy_scale(model.model);
    std::printf("%s, %s, %d frames (10^6 substeps): largest |E - E0| / mgL in each tenth:", method.series.c_str(),
                method.setting.c_str(), kFrames);
    double tenth = 0;
    for (int frame = 1; frame <= kFrames; ++frame) {
      if (simulation.step() != StepStatus::ok) throw std::runtime_error("the long run diverged");
      tenth = std::max(tenth, std::abs(simulation.observe().energy() - start) / scale);
      if (frame % (kFrames / 10) == 0) {
        std::printf(" %.2e", tenth);
        tenth = 0;
      }
    }
    std::printf("\n");
    std::fflush(stdout);
  }
  return 0;
}

int run(int argc, char** argv) {
  if (argc < 2) throw std::invalid_argument("usage: projection_study order|frames|pendulum|long [--csv FILE]");
  const std::string command = argv[1];
  std::string csv_path;
  for (int i = 2; i < argc; ++i) {
    const std::string flag = argv[i];
    if (flag == "--csv" && i + 1 < argc) csv_path = argv[++i];
    else throw std::invalid_argument(flag + ": unknown flag (or missing value)");
  }
  if (command == "order") return order(csv_path);
  if (command == "frames") return frames(csv_path);
  if (command == "pendulum") return pendulum();
  if (command == "long") return long_run();
  throw std::invalid_argument(command + ": not one of order, frames, pendulum, long");
}

}  // namespace
}  // namespace limber::study

int main(int argc, char** argv) {
  try {
    return limber::study::run(argc, argv);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "projection_study: %s\n", error.what());
    return 2;
  }
}
