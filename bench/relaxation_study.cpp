// How the sweep converges: Gauss-Seidel by colour, the thesis's sequential Gauss-Seidel and
// Jacobi, each with the pinned end swept first or last, against the number of sweeps per step.
// Physics only (no timing); prints the README's markdown table and, with --csv FILE, the data
// for tools/plot_relaxation.py.
//
//   build/bench/relaxation_study [--csv build/relaxation_study.csv]
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"

namespace limber {
namespace {

struct Variant {
  const char* name;
  RelaxationSolver solver;
  SweepOrder order;
  SweepDirection direction;
  double relaxation_factor;
};

// The chain: 100 links of 0.1 m and 1 kg, the last 10 kg, pinned, released horizontally, 1 s at
// Δt = 1/240 s with `sweeps` sweeps a step. Returns the largest link stretch over the run,
// relative to the link length (joints are shared particles, so stretch is the only error).
double largest_stretch(const Variant& variant, int sweeps) {
  ChainSpec spec;
  spec.links = 100;
  spec.end_mass_ratio = 10;
  Model model = make_chain_model(spec);
  model.settings.sleep.enabled = false;
  model.settings.time_step = 1.0 / 240;
  VerletOptions options;
  options.verlet.joints = ParticleJoints::shared_particle;
  options.relaxation.iterations = sweeps;
  options.relaxation.over_relaxation = variant.relaxation_factor;
  options.solver = variant.solver, options.order = variant.order, options.direction = variant.direction;
  options.threads = 1;
  VerletState<double> state = compile<double>(model, options);
  double largest = 0;
  for (int s = 0; s < 240; ++s) {
    if (step(state).status != StepStatus::ok) return -1;  // diverged
    largest = std::max(largest, observe(state).max_link_stretch);
  }
  return largest;
}

}  // namespace
}  // namespace limber

int main(int argc, char** argv) {
  using namespace limber;
  std::string csv_path;
  for (int k = 1; k < argc; ++k) {
    if (std::strcmp(argv[k], "--csv") == 0 && k + 1 < argc) csv_path = argv[++k];
    else {
      std::fprintf(stderr, "relaxation_study: unknown argument '%s' (usage: relaxation_study [--csv FILE])\n", argv[k]);
      return 2;
    }
  }
  const Variant variants[] = {
      {"Gauss-Seidel by colour, pinned first", RelaxationSolver::gauss_seidel, SweepOrder::coloured, SweepDirection::pinned_first, 1.0},
      {"Gauss-Seidel by colour, pinned last", RelaxationSolver::gauss_seidel, SweepOrder::coloured, SweepDirection::pinned_last, 1.0},
      {"sequential Gauss-Seidel, pinned first", RelaxationSolver::gauss_seidel, SweepOrder::sequential, SweepDirection::pinned_first, 1.0},
      {"sequential Gauss-Seidel, pinned last", RelaxationSolver::gauss_seidel, SweepOrder::sequential, SweepDirection::pinned_last, 1.0},
      {"Gauss-Seidel by colour, ω = 1.5", RelaxationSolver::gauss_seidel, SweepOrder::coloured, SweepDirection::pinned_first, 1.5},
      {"Jacobi, ω = 1", RelaxationSolver::jacobi, SweepOrder::coloured, SweepDirection::pinned_first, 1.0},
      {"Jacobi, ω = 1.5", RelaxationSolver::jacobi, SweepOrder::coloured, SweepDirection::pinned_first, 1.5},
  };
  const std::vector<int> sweeps = {1, 2, 5, 10, 20, 50, 100, 200, 500, 1000};
  std::ofstream csv;
  if (!csv_path.empty()) {
    csv.open(csv_path);
    if (!csv) {
      std::fprintf(stderr, "relaxation_study: --csv: cannot write '%s'\n", csv_path.c_str());
      return 2;
    }
    csv << "variant,sweeps,largest_stretch\n";
  }
  std::printf("### Largest link stretch against sweeps per step (100-link chain, 10× end mass, 1 s, Δt = 1/240 s)\n\n");
  std::printf("| sweeps |");
  for (const Variant& variant : variants) std::printf(" %s |", variant.name);
  std::printf("\n|---|");
  for (std::size_t k = 0; k < std::size(variants); ++k) std::printf("---|");
  std::printf("\n");
  for (const int n : sweeps) {
    std::printf("| %d |", n);
    for (const Variant& variant : variants) {
      const double stretch = largest_stretch(variant, n);
      if (stretch < 0) std::printf(" diverged |");
      else std::printf(" %.2e |", stretch);
      if (csv.is_open()) csv << '"' << variant.name << "\"," << n << ',' << stretch << '\n';
    }
    std::printf("\n");
  }
  return 0;
}
