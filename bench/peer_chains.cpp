// Other engines on limber's chain workload: limber's methods and every peer engine
// found at build time (Bullet 3.24, ODE 0.16, MuJoCo 2.2.2; bench/peers/peers.cmake) on the same
// heavy-end chains, time per step and joint error measured in the same run.
//
// Workload (bench/chains.md, "The heavy-end chain"): N links of 0.1 m and 1 kg, the last
// 2 kg; link 0's inboard end pinned at the origin by a ball joint; released at rest, straight
// along +x; gravity 9.81 m/s² along −z; no contacts, no damping, no sleeping; Δt = 1/60 s (or
// --dt); 2 s; one thread. limber's chain is make_chain_model's (kernel/scene/generators.hpp:
// capsules of radius 1 mm, uniform density); the peers' links are solid cylinders of radius
// 1 cm (bench/peers/peer_chain.hpp): their transverse moments differ by 3%.
//
// Joint error: the largest over every step, relative to the link length L = 0.1 m. Rigid bodies
// (limber's Featherstone, Lagrange and spring methods, every peer): the distance between where a
// joint's two bodies put its pivot (Observation::max_joint_gap). limber's Verlet chain shares one
// particle per joint, so its error is the link stretch | |x_head − x_tail| − L | / L.
// "time / limber's best" divides a row's time per step by that of limber's fastest method at the
// same N that stayed finite with an error no larger; errors below 1e-6 L (single-precision
// rounding) count as equal, so reduced coordinates' zero gap is matched by any closed chain.
//
// Runs whose time, extrapolated from the previous N by the method's cost (O(N³) for MuJoCo's
// dense factorization and ODE's dWorldStep, O(N) for the rest), would pass 60 s are skipped and
// labelled so. A run whose stepping took under 2 s is repeated twice more and the median time
// kept (the errors are the same bits every run).
//
// Usage: peer_chains [--links N,N,...] [--dt SECONDS] [--csv FILE]   (default 5,10,100,1000,10000;
// Δt 1/60 s)
// Prints a markdown table on stdout (progress on stderr) and writes the CSV that
// tools/plot_peers.py plots.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/peers/peer_chain.hpp"
#include "limber/kernel/featherstone/compile.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/lagrange/compile.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/springs/compile.hpp"
#include "limber/kernel/springs/step.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"

namespace limber {
namespace {

constexpr double kSimulated = 2;       // s
constexpr double kLinkLength = 0.1;     // m
constexpr double kEqualErrorFloor = 1e-6;       // relative: errors below it count as equal
constexpr double kLongestRun = 60;              // s of stepping, estimated, above which a run is skipped
constexpr double kRepeatBelow = 2;              // s of stepping under which a run is repeated (median of 3)
constexpr int kBulletRigidIterations = 10;      // Bullet's default (btContactSolverInfo::m_numIterations)
constexpr int kOdeQuickStepIterations = 20;     // ODE's default (dWorldSetQuickStepNumIterations)

/// The step every contender takes (s) and how many: 2 s simulated.
struct Workload {
  double time_step = 1.0 / 60;
  int steps = 120;
};

/// One run's outcome, in the table's units.
struct Measurement {
  double seconds_per_step = 0;
  double max_error = 0;      // relative to the link length
  double energy_change = 0;  // J, end − start
  bool finite = true;
  int steps_taken = 0;
  std::string note;  // what the engine did silently (clamps), or why the run stopped
};

/// A method of limber's or a peer's, run on a chain of N links.
struct Contender {
  std::string engine, method;
  bool is_limber = false;
  int cost_exponent = 1;  // time per step grows as N^cost_exponent
  std::function<Measurement(std::size_t links, const Workload& workload)> run;
  std::string label = method;  // short name, for the ratio column
};

// ---------------------------------------------------------------------------------------------
// limber's methods

Model chain_model(std::size_t links, const Workload& workload) {
  Model model = make_chain_model({.links = links, .link_length = kLinkLength, .link_mass = 1, .end_mass_ratio = 2});
  model.settings.sleep.enabled = false;
  model.settings.time_step = workload.time_step;
  model.settings.damping = 0;
  return model;
}

// Steps `state` workload.steps times (only step() timed), observing after each.
template <typename State>
Measurement simulate(State& state, const Workload& workload) {
  Measurement result;
  const double energy_start = observe(state).energy();
  double seconds = 0;
  for (int s = 0; s < workload.steps; ++s) {
    const auto start = std::chrono::steady_clock::now();
    const auto report = step(state);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ++result.steps_taken;
    const Observation observation = observe(state);
    result.max_error = std::max({result.max_error, observation.max_link_stretch, observation.max_joint_gap});
    if (report.status != StepStatus::ok || !std::isfinite(observation.max_link_stretch) || !std::isfinite(observation.max_joint_gap)) {
      result.finite = false;
      result.note = "diverged at step " + std::to_string(result.steps_taken) +
                    (report.status == StepStatus::diverged_speed ? " (a body passed Settings::divergence_speed, 1000 m/s)"
                                                                  : " (non-finite state)");
      break;
    }
  }
  result.seconds_per_step = seconds / result.steps_taken;
  result.energy_change = observe(state).energy() - energy_start;
  return result;
}

Measurement run_verlet(std::size_t links, const Workload& workload, RelaxationSolver solver, int iterations, double tolerance) {
  Model model = chain_model(links, workload);
  VerletOptions options;
  options.verlet.joints = ParticleJoints::shared_particle;  // make_chain_model's chain, one particle a joint
  options.relaxation.iterations = solver == RelaxationSolver::direct ? 1 : iterations;
  options.relaxation.tolerance = tolerance;
  options.solver = solver;
  options.newton_iterations = solver == RelaxationSolver::direct ? iterations : 1;
  options.threads = 1;
  VerletState<double> state = compile<double>(model, options);
  return simulate(state, workload);
}

std::vector<Contender> limber_contenders() {
  return {
      {"limber", "Verlet, direct solver to 1e-5 m (at most 50 Newton steps)", true, 1,
       [](std::size_t links, const Workload& workload) { return run_verlet(links, workload, RelaxationSolver::direct, 50, 1e-5); }, "Verlet direct"},
      {"limber", "Verlet, Gauss-Seidel 100 sweeps", true, 1,
       [](std::size_t links, const Workload& workload) { return run_verlet(links, workload, RelaxationSolver::gauss_seidel, 100, 0); }, "Verlet Gauss-Seidel"},
      {"limber", "Featherstone ABA, RK4", true, 1,
       [](std::size_t links, const Workload& workload) {
         FeatherstoneState state = compile_featherstone(chain_model(links, workload), {.integrator = Integrator::rk4});
         return simulate(state, workload);
       },
       "Featherstone"},
      {"limber", "Featherstone ABA, semi-implicit Euler", true, 1,
       [](std::size_t links, const Workload& workload) {
         FeatherstoneState state = compile_featherstone(chain_model(links, workload), {.integrator = Integrator::semi_implicit_euler});
         return simulate(state, workload);
       },
       "Featherstone semi-implicit"},
      {"limber", "Lagrange, semi-implicit Euler + Baumgarte", true, 1,
       [](std::size_t links, const Workload& workload) {
         LagrangeState state = compile_lagrange(
             chain_model(links, workload), {.integrator = Integrator::semi_implicit_euler, .stabilization = Stabilization::baumgarte});
         return simulate(state, workload);
       },
       "Lagrange"},
      {"limber", "implicit springs (backward Euler, k 2e4 N/m, c 20 N s/m)", true, 1,
       [](std::size_t links, const Workload& workload) {
         SpringState state = compile_springs(chain_model(links, workload), {.integrator = Integrator::backward_euler});
         return simulate(state, workload);
       },
       "springs"},
  };
}

// ---------------------------------------------------------------------------------------------
// The peers

[[maybe_unused]] Measurement from_peer(const peers::PeerChainResult& peer) {
  Measurement result;
  result.seconds_per_step = peer.seconds_per_step;
  result.max_error = peer.max_joint_gap / kLinkLength;
  result.energy_change = peer.final_kinetic_plus_potential - peer.initial_kinetic_plus_potential;
  result.finite = peer.finite;
  result.steps_taken = peer.steps_taken;
  if (!peer.finite) result.note = "diverged at step " + std::to_string(peer.steps_taken);
  if (peer.steps_with_clamped_rotation > 0)
    result.note += std::string(result.note.empty() ? "" : "; ") + "rotation clamped to pi/4 per step in " +
                   std::to_string(peer.steps_with_clamped_rotation) + " of " + std::to_string(peer.steps_taken) + " steps";
  return result;
}

std::vector<Contender> peer_contenders() {
  std::vector<Contender> contenders;
#ifdef LIMBER_HAVE_BULLET
  const std::string bullet_precision = peers::bullet_uses_double_precision() ? "f64" : "f32";
  contenders.push_back({"Bullet 3.24", "btMultiBody (" + bullet_precision + ", joint-velocity clamp 100 rad/s)", false, 1,
                        [](std::size_t links, const Workload& workload) {
                          return from_peer(peers::run_bullet_multibody_chain(int(links), workload.time_step, workload.steps, false));
                        }});
  contenders.push_back({"Bullet 3.24",
                        "btRigidBody + point-to-point (" + bullet_precision + ", " + std::to_string(kBulletRigidIterations) +
                            " iterations)",
                        false, 1, [](std::size_t links, const Workload& workload) {
                          return from_peer(peers::run_bullet_rigid_chain(int(links), workload.time_step, workload.steps, kBulletRigidIterations));
                        }});
#endif
#ifdef LIMBER_HAVE_ODE
  const std::string ode_precision = peers::ode_uses_double_precision() ? "f64" : "f32";
  contenders.push_back({"ODE 0.16", "dWorldStep (" + ode_precision + ", dense LCP)", false, 3, [](std::size_t links, const Workload& workload) {
                          return from_peer(peers::run_ode_chain(int(links), workload.time_step, workload.steps, peers::OdeStepper::world_step, 1));
                        }});
  contenders.push_back({"ODE 0.16", "dWorldQuickStep (" + ode_precision + ", " + std::to_string(kOdeQuickStepIterations) + " iterations)",
                        false, 1, [](std::size_t links, const Workload& workload) {
                          return from_peer(peers::run_ode_chain(int(links), workload.time_step, workload.steps, peers::OdeStepper::quick_step,
                                                                kOdeQuickStepIterations));
                        }});
#endif
#ifdef LIMBER_HAVE_MUJOCO
  for (const peers::MujocoIntegrator integrator : {peers::MujocoIntegrator::euler, peers::MujocoIntegrator::rk4}) {
    const std::string name = integrator == peers::MujocoIntegrator::euler ? "Euler" : "RK4";
    contenders.push_back({"MuJoCo 2.2.2", "mj_step, " + name + " (f64)", false, 3, [integrator](std::size_t links, const Workload& workload) {
                            Measurement result = from_peer(peers::run_mujoco_chain(int(links), workload.time_step, workload.steps, integrator));
                            if (!result.finite) result.note += " (MuJoCo warned and reset the state)";
                            return result;
                          }});
  }
#endif
  return contenders;
}

// ---------------------------------------------------------------------------------------------
// Running, comparing, reporting

struct Row {
  const Contender* contender = nullptr;
  std::size_t links = 0;
  std::optional<Measurement> measured;  // empty: skipped
  double estimated_seconds_per_step = 0;  // skipped rows: the extrapolation
  std::size_t estimated_from = 0;         // … from this N
  // Filled by compare(): this row's time over limber's best at equal or better error.
  std::optional<double> ratio;
  std::string limber_best;
};

// Median of three runs' times when one run is quick; one run otherwise.
Measurement measure(const Contender& contender, std::size_t links, const Workload& workload) {
  const Measurement first = contender.run(links, workload);
  if (first.seconds_per_step * first.steps_taken >= kRepeatBelow) return first;
  std::vector<Measurement> runs{first, contender.run(links, workload), contender.run(links, workload)};
  std::sort(runs.begin(), runs.end(), [](const Measurement& a, const Measurement& b) { return a.seconds_per_step < b.seconds_per_step; });
  return runs[1];
}

// Errors below the floor are rounding: equal.
double compared_error(double error) { return std::max(error, kEqualErrorFloor); }

void compare(std::vector<Row>& rows) {
  for (Row& row : rows) {
    if (!row.measured || !row.measured->finite) continue;
    const Row* best = nullptr;
    for (const Row& candidate : rows) {
      if (candidate.links != row.links || !candidate.contender->is_limber || !candidate.measured || !candidate.measured->finite) continue;
      if (compared_error(candidate.measured->max_error) > compared_error(row.measured->max_error)) continue;
      if (!best || candidate.measured->seconds_per_step < best->measured->seconds_per_step) best = &candidate;
    }
    if (best) {
      row.ratio = row.measured->seconds_per_step / best->measured->seconds_per_step;
      row.limber_best = best->contender->label;
    }
  }
}

std::string format(const char* pattern, double value) {
  char text[64];
  std::snprintf(text, sizeof text, pattern, value);
  return text;
}

std::string csv_quoted(const std::string& text) {
  std::string quoted = "\"";
  for (const char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

std::string status_of(const Row& row) {
  if (!row.measured) {
    return "skipped (O(N^" + std::to_string(row.contender->cost_exponent) + "), ~" + format("%.3g", row.estimated_seconds_per_step) +
           " s/step extrapolated from N = " + std::to_string(row.estimated_from) + ")";
  }
  if (!row.measured->finite) return row.measured->note;
  return row.measured->note.empty() ? "ok" : "ok; " + row.measured->note;
}

void print_table(const std::vector<Row>& rows) {
  std::printf("| N | engine | method | µs/step | max error / L | energy end − start (J) | status | time / limber's best at ≤ error |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (const Row& row : rows) {
    const bool measured = row.measured.has_value();
    std::printf("| %zu | %s | %s | %s | %s | %s | %s | %s |\n", row.links, row.contender->engine.c_str(), row.contender->method.c_str(),
                measured ? format("%.4g", row.measured->seconds_per_step * 1e6).c_str() : "—",
                measured ? format("%.2g", row.measured->max_error).c_str() : "—",
                measured && row.measured->finite ? format("%.3g", row.measured->energy_change).c_str() : "—", status_of(row).c_str(),
                row.ratio ? (format("%.2f", *row.ratio) + " (" + row.limber_best + ")").c_str() : "—");
  }
}

void write_csv(const std::vector<Row>& rows, std::ofstream& csv) {
  csv.precision(6);
  csv << "engine,method,links,seconds_per_step,max_error,energy_change,finite,steps_taken,status,ratio_to_limber_best,limber_best\n";
  for (const Row& row : rows) {
    csv << csv_quoted(row.contender->engine) << ',' << csv_quoted(row.contender->method) << ',' << row.links << ',';
    if (row.measured) {
      csv << row.measured->seconds_per_step << ',' << row.measured->max_error << ',' << row.measured->energy_change << ','
          << (row.measured->finite ? 1 : 0) << ',' << row.measured->steps_taken << ',';
    } else {
      csv << ",,,,,";
    }
    csv << csv_quoted(status_of(row)) << ',';
    if (row.ratio) csv << *row.ratio;
    csv << ',' << csv_quoted(row.limber_best) << '\n';
  }
}

// "5,10,100": each a whole number ≥ 1, else std::invalid_argument.
std::vector<std::size_t> parse_links(const std::string& text) {
  std::vector<std::size_t> links;
  std::stringstream stream(text);
  for (std::string item; std::getline(stream, item, ',');) {
    std::size_t used = 0;
    long long value = 0;
    try {
      value = std::stoll(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || value < 1 || value > 10'000'000)
      throw std::invalid_argument("--links: '" + item + "' is not a link count from 1 to 10^7");
    links.push_back(static_cast<std::size_t>(value));
  }
  if (links.empty()) throw std::invalid_argument("--links: no link counts given");
  std::sort(links.begin(), links.end());  // extrapolation goes from smaller N to larger
  links.erase(std::unique(links.begin(), links.end()), links.end());
  return links;
}

// --dt: a time step in [1e-5, 1] s, and the steps that simulate kSimulated with it.
Workload parse_time_step(const std::string& text) {
  std::size_t used = 0;
  double value = 0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !(value >= 1e-5 && value <= 1))
    throw std::invalid_argument("--dt: '" + text + "' is not a time step from 1e-5 to 1 s");
  return {.time_step = value, .steps = static_cast<int>(std::lround(kSimulated / value))};
}

}  // namespace
}  // namespace limber

int main(int argc, char** argv) {
  using namespace limber;
  std::vector<std::size_t> link_counts{5, 10, 100, 1000, 10000};
  std::string csv_path;
  Workload workload;
  try {
    for (int k = 1; k < argc; k += 2) {
      const std::string flag = argv[k];
      if (flag != "--links" && flag != "--csv" && flag != "--dt")
        throw std::invalid_argument("unknown flag " + flag + " (use --links N,N,... --dt SECONDS --csv FILE)");
      if (k + 1 >= argc) throw std::invalid_argument(flag + " needs a value");
      if (flag == "--links") link_counts = parse_links(argv[k + 1]);
      else if (flag == "--dt") workload = parse_time_step(argv[k + 1]);
      else csv_path = argv[k + 1];
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "peer_chains: %s\n", error.what());
    return 2;
  }
  std::ofstream csv;  // opened before the runs, so a bad path fails at once
  if (!csv_path.empty()) {
    csv.open(csv_path);
    if (!csv) {
      std::fprintf(stderr, "peer_chains: cannot write %s\n", csv_path.c_str());
      return 2;
    }
  }

  std::vector<Contender> contenders = limber_contenders();
  for (Contender& peer : peer_contenders()) contenders.push_back(std::move(peer));

  std::vector<Row> rows;
  try {
    for (const Contender& contender : contenders) {
      std::optional<std::size_t> previous_links;  // the last N this contender ran at
      double previous_seconds_per_step = 0;
      for (const std::size_t links : link_counts) {
        Row row;
        row.contender = &contender;
        row.links = links;
        if (previous_links) {
          row.estimated_from = *previous_links;
          row.estimated_seconds_per_step =
              previous_seconds_per_step * std::pow(double(links) / double(*previous_links), contender.cost_exponent);
        }
        if (row.estimated_seconds_per_step * workload.steps > kLongestRun) {
          std::fprintf(stderr, "%6zu  %s, %s: skipped (~%.3g s/step)\n", links, contender.engine.c_str(), contender.method.c_str(),
                       row.estimated_seconds_per_step);
        } else {
          row.measured = measure(contender, links, workload);
          previous_links = links;
          previous_seconds_per_step = row.measured->seconds_per_step;
          std::fprintf(stderr, "%6zu  %s, %s: %.4g us/step, error %.2g L, %s\n", links, contender.engine.c_str(), contender.method.c_str(),
                       row.measured->seconds_per_step * 1e6, row.measured->max_error,
                       row.measured->finite ? "finite" : row.measured->note.c_str());
        }
        rows.push_back(std::move(row));
      }
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "peer_chains: %s\n", error.what());
    return 1;
  }

  std::stable_sort(rows.begin(), rows.end(), [](const Row& a, const Row& b) { return a.links < b.links; });
  compare(rows);
  print_table(rows);
  if (csv.is_open()) {
    write_csv(rows, csv);
    if (!csv.flush()) {
      std::fprintf(stderr, "peer_chains: writing %s failed\n", csv_path.c_str());
      return 1;
    }
  }
  return 0;
}
