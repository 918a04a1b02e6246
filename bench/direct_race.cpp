// The equal-error race: the Verlet family's solvers and Bullet's btMultiBody on the
// heavy-end chain, time per step against the largest joint error over the run.
//
// Workload (bench/chains.md, "The heavy-end chain"): N links of 0.1 m and 1 kg, the last
// 2 kg; link 0's head pinned at the origin; released at rest, straight along +x; gravity 9.81 m/s²
// along −z; no contacts, no damping, no sleeping; Δt = 1/60 s; 2 s simulated; one thread.
// limber's chain is the generators' (shared-particle joints: consecutive links share a particle),
// so its joint error is the link stretch | |x_head − x_tail| − L | / L; Bullet's is the distance
// between where a joint's two links put its pivot, / L. Both are the largest over every step.
//
// The rattle contenders run the same race under the rattle projection rule (start-of-step
// gradients, velocity stage), whole or in substeps; "iters" counts sweeps or Newton steps per
// frame over all substeps.
//
// Usage: direct_race [--links N,N,...] [--csv FILE] [--only TEXT,TEXT,...]   (default 10,100,1000,10000;
// --only: just the contenders whose name contains one of the texts, Bullet always)
// Prints a table and writes the CSV the plot reads (tools/plot_race.py).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"
#ifdef LIMBER_HAVE_BULLET
#include "bench/peers/peer_chain.hpp"
#endif

namespace limber {
namespace {

constexpr double kTimeStep = 1.0 / 60;
constexpr int kSteps = 120;  // 2 s
constexpr double kLinkLength = 0.1;

struct Contender {
  std::string name;
  RelaxationSolver solver = RelaxationSolver::gauss_seidel;
  int iterations = 0;  // sweeps, or Newton steps
  double tolerance = 0;
  bool long_range_attachments = false;
  bool warm_start = false;
  ProjectionRule projection = ProjectionRule::pbd;
  int substeps = 1;  // iterations are per substep
};

// A rattle contender: `iterations` sweeps or Newton steps in each of `substeps` substeps.
Contender rattle(std::string name, RelaxationSolver solver, int iterations, int substeps, double tolerance = 0) {
  return {std::move(name), solver, iterations, tolerance, false, false, ProjectionRule::rattle, substeps};
}

struct Result {
  double seconds_per_step = 0;
  double max_error = 0;      // relative to the link length
  double energy_change = 0;  // J, end − start
  double mean_iterations = 0;
  bool finite = true;
};

Result run_limber(std::size_t links, const Contender& contender) {
  ChainSpec spec;
  spec.links = links;
  spec.link_length = kLinkLength;
  spec.end_mass_ratio = 2;
  Model model = make_chain_model(spec);
  model.settings.sleep.enabled = false;
  model.settings.time_step = kTimeStep;
  model.settings.damping = 0;
  VerletOptions options;
  options.verlet.joints = ParticleJoints::shared_particle;
  options.relaxation.iterations = contender.solver == RelaxationSolver::direct ? 1 : contender.iterations;
  options.relaxation.tolerance = contender.tolerance;
  options.relaxation.projection = contender.projection;
  options.relaxation.substeps = contender.substeps;
  options.solver = contender.solver;
  options.newton_iterations = contender.solver == RelaxationSolver::direct ? contender.iterations : 1;
  options.long_range_attachments = contender.long_range_attachments;
  options.warm_start = contender.warm_start;
  options.threads = 1;
  VerletState<double> state = compile<double>(model, options);
  const double energy_start = observe(state).energy();
  Result result;
  double seconds = 0;
  long iterations = 0;
  for (int s = 0; s < kSteps; ++s) {
    const auto start = std::chrono::steady_clock::now();
    const StepReport report = step(state);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    iterations += report.iterations;
    const Observation observation = observe(state);
    result.max_error = std::max({result.max_error, observation.max_link_stretch, observation.max_joint_gap});
    if (report.status != StepStatus::ok || !std::isfinite(observation.max_link_stretch)) {
      result.finite = false;
      break;
    }
  }
  result.seconds_per_step = seconds / kSteps;
  result.energy_change = observe(state).energy() - energy_start;
  result.mean_iterations = static_cast<double>(iterations) / kSteps;
  return result;
}

// Median of three runs' times (the machine is shared); the errors are the same bits every run.
Result median_of_three(const std::function<Result()>& run) {
  std::vector<Result> runs{run(), run(), run()};
  std::sort(runs.begin(), runs.end(), [](const Result& a, const Result& b) { return a.seconds_per_step < b.seconds_per_step; });
  return runs[1];
}

std::vector<std::size_t> parse_links(const std::string& text) {
  std::vector<std::size_t> links;
  std::stringstream stream(text);
  for (std::string item; std::getline(stream, item, ',');) links.push_back(std::stoul(item));
  return links;
}

}  // namespace
}  // namespace limber

int main(int argc, char** argv) {
  using namespace limber;
  std::vector<std::size_t> link_counts{10, 100, 1000, 10000};
  std::string csv_path;
  std::vector<std::string> only;
  for (int k = 1; k + 1 < argc; k += 2) {
    const std::string flag = argv[k];
    if (flag == "--links") link_counts = parse_links(argv[k + 1]);
    else if (flag == "--csv") csv_path = argv[k + 1];
    else if (flag == "--only") {
      std::stringstream texts(argv[k + 1]);
      for (std::string text; std::getline(texts, text, ',');) only.push_back(text);
    } else {
      std::fprintf(stderr, "direct_race: unknown flag %s (use --links N,N,... --csv FILE --only TEXT,...)\n", flag.c_str());
      return 2;
    }
  }
  const std::vector<Contender> contenders{
      {"gauss-seidel 10", RelaxationSolver::gauss_seidel, 10},
      {"gauss-seidel 100", RelaxationSolver::gauss_seidel, 100},
      {"gauss-seidel 1000", RelaxationSolver::gauss_seidel, 1000},
      {"jacobi 100", RelaxationSolver::jacobi, 100},
      {"jacobi 1000", RelaxationSolver::jacobi, 1000},
      {"gauss-seidel 10 + long-range attachments", RelaxationSolver::gauss_seidel, 10, 0, true},
      {"gauss-seidel 100 + long-range attachments", RelaxationSolver::gauss_seidel, 100, 0, true},
      {"direct 1", RelaxationSolver::direct, 1},
      {"direct 2", RelaxationSolver::direct, 2},
      {"direct 3", RelaxationSolver::direct, 3},
      {"direct to 1e-5 m (at most 50)", RelaxationSolver::direct, 50, 1e-5},
      {"direct to 1e-9 m (at most 50)", RelaxationSolver::direct, 50, 1e-9},
      {"direct to 1e-9 m (at most 50) (warm start)", RelaxationSolver::direct, 50, 1e-9, false, true},
      rattle("rattle direct to 1e-9 m (at most 50)", RelaxationSolver::direct, 50, 1, 1e-9),
      rattle("rattle direct 1 x 4 substeps", RelaxationSolver::direct, 1, 4),
      rattle("rattle direct 1 x 8 substeps", RelaxationSolver::direct, 1, 8),
      rattle("rattle direct 1 x 16 substeps", RelaxationSolver::direct, 1, 16),
      rattle("rattle direct 1 x 64 substeps", RelaxationSolver::direct, 1, 64),
      rattle("rattle direct to 1e-9 m x 16 substeps", RelaxationSolver::direct, 50, 16, 1e-9),
      rattle("rattle gauss-seidel 2 x 64 substeps", RelaxationSolver::gauss_seidel, 2, 64),
  };
  std::ofstream csv;
  if (!csv_path.empty()) {
    csv.open(csv_path);
    csv << "links,method,seconds_per_step,max_error,energy_change,mean_iterations,finite\n";
  }
  std::printf("%6s  %-42s %14s %12s %14s %8s %s\n", "links", "method", "us/step", "max error/L", "energy gain J", "iters", "");
  const auto report = [&](std::size_t links, const std::string& name, const Result& result) {
    std::printf("%6zu  %-42s %14.1f %12.3g %14.3g %8.2f %s\n", links, name.c_str(), result.seconds_per_step * 1e6,
                result.max_error, result.energy_change, result.mean_iterations, result.finite ? "" : "diverged");
    std::fflush(stdout);
    if (csv.is_open()) {
      csv << links << ",\"" << name << "\"," << result.seconds_per_step << ',' << result.max_error << ',' << result.energy_change
          << ',' << result.mean_iterations << ',' << (result.finite ? 1 : 0) << std::endl;  // kept if a peer crashes
    }
  };
  for (const std::size_t links : link_counts) {
    for (const Contender& contender : contenders) {
      if (!only.empty() && std::none_of(only.begin(), only.end(), [&](const std::string& text) { return contender.name.find(text) != std::string::npos; })) {
        continue;
      }
      // Thousands of sweeps over 10^4 links: one run (minutes), its time is not the point.
      const bool slow = links >= 10000 && contender.iterations >= 1000;
      const Result result = slow ? run_limber(links, contender) : median_of_three([&] { return run_limber(links, contender); });
      report(links, contender.name, result);
    }
#ifdef LIMBER_HAVE_BULLET
    for (const bool raised : {false, true}) {
      const auto run = [&] {
        const peers::PeerChainResult peer = peers::run_bullet_multibody_chain(static_cast<int>(links), kTimeStep, kSteps, raised);
        Result result;
        result.seconds_per_step = peer.seconds_per_step;
        result.max_error = peer.max_joint_gap / kLinkLength;
        result.energy_change = peer.final_kinetic_plus_potential - peer.initial_kinetic_plus_potential;
        result.finite = peer.finite;
        return result;
      };
      const std::string precision = peers::bullet_uses_double_precision() ? "f64" : "f32";
      const std::string name = "bullet btMultiBody (" + precision + (raised ? ", clamp 1e4 rad/s)" : ", clamp 100 rad/s)");
      report(links, name, links >= 10000 ? run() : median_of_three(run));
    }
#endif
  }
  return 0;
}
