#include "tools/cli/cli.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "kernel/metrics/knock.hpp"
#include "kernel/metrics/observers.hpp"
#include "kernel/model/model.hpp"
#include "kernel/scene/scene_file.hpp"
#include "kernel/verlet/compile.hpp"
#include "kernel/verlet/step.hpp"
#include "layouts/graph/constraint_colouring.hpp"

namespace limber::cli {
namespace {

// A bad flag value; what() is the one line printed after "limber: ".
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

std::string format(const char* pattern, auto... values) {
  char buffer[512];
  std::snprintf(buffer, sizeof buffer, pattern, values...);
  return buffer;
}

// The flags of `limber run`, with the option handles that tell whether each was given.
struct RunFlags {
  std::string scene;
  std::string method = "weighted";
  std::string precision = "double";
  std::string body;
  double ball_speed = 0, ball_radius = 0, ball_mass = 0, ball_restitution = 0, friction = 0;
  std::vector<double> ball_direction;
  long links = 0, steps = 0;
  int iterations = 0;
  double dt = 0, tolerance = 0, budget_us = 0, over_relaxation = 1;
  std::string out_path;
  std::string solver = "gauss-seidel", sweep = "coloured", pinned = "first", layout = "auto", threading = "workers";
  std::string ordering = "depth-parity";
  int threads = 0;
  bool scalar = false;

  CLI::Option *body_option, *ball_speed_option, *ball_direction_option, *ball_radius_option, *ball_mass_option,
      *ball_restitution_option, *friction_option, *links_option, *steps_option, *dt_option, *iterations_option,
      *tolerance_option, *budget_option, *over_relaxation_option, *out_option;
};

void add_run_flags(CLI::App& run, RunFlags& flags) {
  run.add_option("scene", flags.scene, "Scene file (JSON); default: the embedded humanoid (tools/scenes/humanoid.json)");
  run.add_option("--method", flags.method, "Relaxation rule: weighted (thesis eq. 4.7) or unweighted (eq. 4.6)")
      ->check(CLI::IsMember({"weighted", "unweighted"}))
      ->capture_default_str();
  run.add_option("--precision", flags.precision, "Scalar type of the state: float or double")
      ->check(CLI::IsMember({"float", "double"}))
      ->capture_default_str();
  flags.body_option = run.add_option("--body", flags.body, "Body variant of the scene (humanoid: thin, medium, wide)");
  flags.ball_speed_option = run.add_option("--ball-speed", flags.ball_speed, "Ball launch speed, m/s");
  flags.ball_direction_option = run.add_option("--ball-direction", flags.ball_direction, "Ball launch direction X,Y,Z")
                                    ->delimiter(',')
                                    ->expected(3);
  flags.ball_radius_option = run.add_option("--ball-radius", flags.ball_radius, "Ball radius, m");
  flags.ball_mass_option = run.add_option("--ball-mass", flags.ball_mass, "Ball mass, kg");
  flags.ball_restitution_option = run.add_option("--ball-restitution", flags.ball_restitution, "Ball restitution, 0..1");
  flags.friction_option = run.add_option("--friction", flags.friction, "Ground Coulomb friction coefficient");
  flags.links_option = run.add_option("--links", flags.links, "Number of links of a chain scene");
  flags.steps_option = run.add_option("--steps", flags.steps, "Number of steps (default: the scene's duration / dt)");
  flags.dt_option = run.add_option("--dt", flags.dt, "Time step, s");
  flags.iterations_option = run.add_option("--iterations", flags.iterations, "Relaxation sweeps per step");
  flags.tolerance_option = run.add_option("--tolerance", flags.tolerance, "Stop relaxing when a sweep moves less, m");
  flags.budget_option = run.add_option("--budget-us", flags.budget_us, "Wall-clock budget for relaxation per step, µs");
  flags.over_relaxation_option =
      run.add_option("--over-relaxation", flags.over_relaxation, "Successive over-relaxation factor, in (0, 2)");
  flags.out_option = run.add_option("--out", flags.out_path, "Write the trajectory (time, particle positions) as CSV");
  run.add_option("--solver", flags.solver, "Relaxation sweep: gauss-seidel or jacobi")
      ->check(CLI::IsMember({"gauss-seidel", "jacobi"}))
      ->capture_default_str();
  run.add_option("--sweep", flags.sweep,
                 "Gauss-Seidel order: coloured (SIMD, threads) or sequential (the thesis's loop, scalar)")
      ->check(CLI::IsMember({"coloured", "sequential"}))
      ->capture_default_str();
  run.add_option("--pinned", flags.pinned, "Sweep the constraints at pinned particles first or last")
      ->check(CLI::IsMember({"first", "last"}))
      ->capture_default_str();
  run.add_option("--threads", flags.threads, "Threads for relaxation; 0: the hardware's, where they pay off")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  run.add_option("--threading", flags.threading, "How a colour is split: workers (long-lived) or parallel-for")
      ->check(CLI::IsMember({"workers", "parallel-for"}))
      ->capture_default_str();
  run.add_option("--layout", flags.layout, "Particle storage for relaxation: auto, soa, aos or aosoa")
      ->check(CLI::IsMember({"auto", "soa", "aos", "aosoa"}))
      ->capture_default_str();
  run.add_option("--ordering", flags.ordering,
                 "Particle numbering: depth-parity (red-black), breadth-first, rcm (reverse Cuthill-McKee) or shuffled")
      ->check(CLI::IsMember({"depth-parity", "breadth-first", "rcm", "shuffled"}))
      ->capture_default_str();
  run.add_flag("--scalar", flags.scalar, "Relax one constraint at a time instead of in SIMD lanes");
}

// The VerletOptions the flags ask for; a combination the sequential sweep cannot run is an error.
VerletOptions verlet_options(const RunFlags& flags) {
  VerletOptions options;
  options.rule = flags.method == "unweighted" ? RelaxationRule::unweighted : RelaxationRule::weighted;
  options.solver = flags.solver == "jacobi" ? RelaxationSolver::jacobi : RelaxationSolver::gauss_seidel;
  options.order = flags.sweep == "sequential" ? SweepOrder::sequential : SweepOrder::coloured;
  options.direction = flags.pinned == "last" ? SweepDirection::pinned_last : SweepDirection::pinned_first;
  options.threads = flags.threads;
  options.threading = flags.threading == "parallel-for" ? Threading::parallel_for : Threading::workers;
  options.layout = flags.layout == "aos"     ? ParticleLayout::aos
                   : flags.layout == "aosoa" ? ParticleLayout::aosoa
                   : flags.layout == "soa"   ? ParticleLayout::soa
                                             : ParticleLayout::automatic;
  options.simd = !flags.scalar;
  options.ordering = flags.ordering == "rcm"             ? ParticleOrder::reverse_cuthill_mckee
                     : flags.ordering == "shuffled"      ? ParticleOrder::shuffled
                     : flags.ordering == "breadth-first" ? ParticleOrder::breadth_first
                                                         : ParticleOrder::depth_parity;
  if (options.order == SweepOrder::sequential) {
    if (options.solver == RelaxationSolver::jacobi) throw InputError("--sweep sequential: is Gauss-Seidel; it cannot run with --solver jacobi");
    if (options.layout != ParticleLayout::soa && options.layout != ParticleLayout::automatic) throw InputError("--sweep sequential: runs on the soa layout only, got --layout " + flags.layout);
  }
  return options;
}

bool given(const CLI::Option* option) { return option->count() > 0; }

double checked(const CLI::Option* option, double value, bool (*accept)(double), const char* expectation) {
  if (!std::isfinite(value) || !accept(value)) {
    throw InputError(format("%s: must be %s, got %g", option->get_name().c_str(), expectation, value));
  }
  return value;
}
bool positive(double v) { return v > 0; }
bool non_negative(double v) { return v >= 0; }
bool unit_interval(double v) { return v >= 0 && v <= 1; }

// Applies the flags that change the model, each checked and named in its error.
void apply_overrides(Model& model, const RunFlags& flags) {
  const bool ball_flag = given(flags.ball_speed_option) || given(flags.ball_direction_option) ||
                         given(flags.ball_radius_option) || given(flags.ball_mass_option) ||
                         given(flags.ball_restitution_option);
  if (ball_flag && !model.ball) throw InputError(format("--ball-*: the scene '%s' has no ball", model.name.c_str()));
  if (given(flags.ball_radius_option)) model.ball->radius = checked(flags.ball_radius_option, flags.ball_radius, positive, "> 0");
  if (given(flags.ball_mass_option)) model.ball->mass = checked(flags.ball_mass_option, flags.ball_mass, positive, "> 0");
  if (given(flags.ball_restitution_option)) {
    model.ball->restitution = checked(flags.ball_restitution_option, flags.ball_restitution, unit_interval, "in [0, 1]");
  }
  if (given(flags.ball_speed_option) || given(flags.ball_direction_option)) {
    double speed = model.ball->velocity.norm();
    Vector3 direction = speed > 0 ? Vector3(model.ball->velocity / speed) : Vector3(-1, 0, 0);
    if (given(flags.ball_speed_option)) speed = checked(flags.ball_speed_option, flags.ball_speed, non_negative, ">= 0");
    if (given(flags.ball_direction_option)) {
      const Vector3 d(flags.ball_direction[0], flags.ball_direction[1], flags.ball_direction[2]);
      if (!d.allFinite() || d.norm() == 0) {
        throw InputError(format("--ball-direction: must be three finite numbers, not all zero, got %g,%g,%g", d.x(), d.y(), d.z()));
      }
      direction = d.normalized();
    }
    model.ball->velocity = speed * direction;
  }
  if (given(flags.friction_option)) {
    if (!model.ground) throw InputError(format("--friction: the scene '%s' has no ground", model.name.c_str()));
    model.ground->friction = checked(flags.friction_option, flags.friction, non_negative, ">= 0");
  }
  if (given(flags.dt_option)) model.settings.time_step = checked(flags.dt_option, flags.dt, positive, "> 0");
  if (given(flags.iterations_option)) {
    if (flags.iterations < 1) throw InputError(format("--iterations: must be >= 1, got %d", flags.iterations));
    model.settings.relaxation.iterations = flags.iterations;
  }
  if (given(flags.tolerance_option)) {
    model.settings.relaxation.tolerance = checked(flags.tolerance_option, flags.tolerance, non_negative, ">= 0");
  }
  if (given(flags.budget_option)) {
    model.settings.relaxation.budget_us = checked(flags.budget_option, flags.budget_us, non_negative, ">= 0");
  }
  if (given(flags.over_relaxation_option)) {
    model.settings.relaxation.over_relaxation =
        checked(flags.over_relaxation_option, flags.over_relaxation, [](double w) { return w > 0 && w < 2; }, "in (0, 2)");
  }
  if (given(flags.steps_option) && flags.steps < 1) throw InputError(format("--steps: must be >= 1, got %ld", flags.steps));
  validate(model);
}

const char* stop_name(RelaxationStop stop) {
  switch (stop) {
    case RelaxationStop::iterations: return "iteration limit";
    case RelaxationStop::tolerance: return "tolerance";
    case RelaxationStop::budget: return "time budget";
    case RelaxationStop::idle: return "idle (all asleep)";
  }
  return "?";
}
const char* status_name(StepStatus status) {
  switch (status) {
    case StepStatus::ok: return "ok";
    case StepStatus::diverged_non_finite: return "DIVERGED (non-finite position)";
    case StepStatus::diverged_speed: return "DIVERGED (speed above settings.divergence_speed)";
    case StepStatus::invalid_time_step: return "invalid time step";
  }
  return "?";
}
std::string vector_text(const Eigen::Vector3d& v) { return format("(%.3f, %.3f, %.3f)", v.x(), v.y(), v.z()); }

template <typename Scalar>
void write_csv_header(std::ostream& csv, const Model& model, const VerletState<Scalar>& state) {
  csv << "time";
  for (const ParticleOrigin& origin : state.particle_origins) {
    const std::string name = particle_name(model, origin);
    csv << ',' << name << "_x," << name << "_y," << name << "_z";
  }
  csv << '\n';
}
template <typename Scalar>
void write_csv_row(std::ostream& csv, const VerletState<Scalar>& state) {
  char cell[96];
  std::snprintf(cell, sizeof cell, "%.9g", state.time);
  csv << cell;
  const auto& p = state.particles;
  for (std::size_t i = 0; i < p.size(); ++i) {
    std::snprintf(cell, sizeof cell, ",%.9g,%.9g,%.9g", double(p.position_x[i]), double(p.position_y[i]), double(p.position_z[i]));
    csv << cell;
  }
  csv << '\n';
}

const char* layout_name(ParticleLayout layout) {
  switch (layout) {
    case ParticleLayout::aos: return "aos";
    case ParticleLayout::aosoa: return "aosoa";
    case ParticleLayout::soa: return "soa";
    case ParticleLayout::automatic: break;
  }
  return "auto";
}

// "solver" line: the sweep, the colour count and batch sizes, the overflow, lanes, layout, threads.
template <typename Scalar>
std::string solver_line(const RunFlags& flags, const VerletState<Scalar>& state) {
  std::vector<std::size_t> sizes(state.colour_count, 0);
  std::size_t overflow = 0;
  for (std::size_t c = 0; c < state.constraints.size(); ++c) {
    const std::uint8_t colour = state.constraint_colour[c];
    const bool movable = state.particles.inverse_mass[state.constraints.particle_i[c]] > 0 ||
                         state.particles.inverse_mass[state.constraints.particle_j[c]] > 0;
    if (colour != kNoColour) ++sizes[colour];
    else if (movable) ++overflow;
  }
  std::string batches;
  for (std::size_t k = 0; k < sizes.size() && k < 8; ++k) batches += (k ? " " : "") + std::to_string(sizes[k]);
  if (sizes.size() > 8) batches += " …";
  if (flags.sweep == "sequential") return format("solver      sequential gauss-seidel, pinned end %s, scalar, 1 thread\n", flags.pinned.c_str());
  const int threads = state.plan.runner->threads();
  const std::string threading = threads == 1 ? "1 thread"
      : format("%d threads (%s) on colours of %u+ constraints", threads, flags.threading.c_str(),
               state.plan.parallel_minimum_slots);
  return format("solver      %s by colour: %u colours (batches %s), %zu overflow; pinned end %s; %s, %s layout, %s\n",
                flags.solver.c_str(), state.colour_count, batches.c_str(), overflow, flags.pinned.c_str(),
                flags.scalar ? "scalar" : "SIMD", layout_name(state.plan.layout), threading.c_str());
}

// Runs the model and prints the summary; returns the exit code.
template <typename Scalar>
int simulate(const Model& model, const RunFlags& flags, const std::string& source, std::ostream& out) {
  VerletState<Scalar> state = compile<Scalar>(model, verlet_options(flags));

  const double dt = model.settings.time_step;
  const long steps = given(flags.steps_option) ? flags.steps : std::max(1L, std::lround(model.settings.duration / dt));
  std::ofstream csv;
  if (given(flags.out_option)) {
    csv.open(flags.out_path);
    if (!csv) throw InputError(format("--out: cannot write '%s'", flags.out_path.c_str()));
    write_csv_header(csv, model, state);
    write_csv_row(csv, state);
  }

  const Observation start = observe(state);
  double largest_gap = start.max_joint_gap, largest_stretch = start.max_link_stretch;
  std::array<long, 4> stops{};
  std::vector<std::string> sleep_events;
  bool body_sleeping = start.body_sleeping;
  KnockMeter knock(model.ball ? model.ball->velocity : Eigen::Vector3d::UnitX(), start.body_centre_of_mass);
  double wall_seconds = 0;
  long steps_done = 0;
  StepReport report;
  Observation end = start;
  for (; steps_done < steps; ++steps_done) {
    const auto before = std::chrono::steady_clock::now();
    report = step(state);
    wall_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count();
    ++stops[static_cast<int>(report.stop)];
    end = observe(state);
    knock.update(end.time, !state.ball_contacts.empty(), end.body_centre_of_mass);
    largest_gap = std::max(largest_gap, end.max_joint_gap);
    largest_stretch = std::max(largest_stretch, end.max_link_stretch);
    if (end.body_sleeping != body_sleeping && sleep_events.size() < 8) {
      sleep_events.push_back(format("%s at t = %.3f s", end.body_sleeping ? "asleep" : "woke", end.time));
    }
    body_sleeping = end.body_sleeping;
    if (csv.is_open()) write_csv_row(csv, state);
    if (report.status != StepStatus::ok) {
      ++steps_done;
      break;
    }
  }

  std::size_t joints = state.joint_constraints.size();
  out << "limber run: " << model.name << " (" << source << ")\n";
  out << format("method      %s relaxation (Verlet), %s precision\n", flags.method.c_str(), flags.precision.c_str());
  out << format("model       %zu limbs, %zu joints%s%s%s; %zu particles, %zu constraints, %zu island%s\n",
                model.bodies.size(), model.joints.size(), model.ground ? ", ground" : "", model.bounds ? ", bounds" : "",
                model.ball ? ", ball" : "", state.particles.size(), state.constraints.size(), state.islands.size(),
                state.islands.size() == 1 ? "" : "s");
  out << solver_line(flags, state);
  out << format("run         %ld steps of %.6g s = %.4g s simulated in %.4g s wall (%.0f steps/s)\n", steps_done, dt,
                state.time, wall_seconds, wall_seconds > 0 ? steps_done / wall_seconds : 0.0);
  out << format("relaxation  up to %d sweeps a step (over-relaxation %g, tolerance %g m, budget %g us); stopped by:",
                model.settings.relaxation.iterations, model.settings.relaxation.over_relaxation,
                model.settings.relaxation.tolerance, model.settings.relaxation.budget_us);
  for (int k = 0; k < 4; ++k) {
    if (stops[k]) out << format(" %s %ld", stop_name(static_cast<RelaxationStop>(k)), stops[k]);
  }
  out << "\n";
  if (joints > 0) {
    out << format("joint gap   final max %.3g, rms %.3g; largest in run %.3g (relative to link length)\n",
                  end.max_joint_gap, end.rms_joint_gap, largest_gap);
  } else {
    out << "joint gap   none (shared-particle joints or no joints)\n";
  }
  out << format("stretch     final max %.3g; largest in run %.3g (relative to link length)\n", end.max_link_stretch,
                largest_stretch);
  const Eigen::Vector3d travel = end.body_centre_of_mass - start.body_centre_of_mass;
  out << format("body        centre of mass %s -> %s m; travelled %.4g m horizontally\n",
                vector_text(start.body_centre_of_mass).c_str(), vector_text(end.body_centre_of_mass).c_str(),
                std::hypot(travel.x(), travel.y()));
  if (knock.touched()) {
    out << format("impact      ball first touched the body at t = %.3f s; in the next %.1f s the body's centre of mass moved %.4f m along the ball's path\n",
                  knock.first_contact_time(), knock.window(), knock.distance());
  }
  out << format("energy      %.6g J at start (kinetic %.4g), %.6g J at end (kinetic %.4g)\n", start.energy(),
                start.kinetic_energy, end.energy(), end.kinetic_energy);
  out << format("momentum    %s -> %s kg m/s\n", vector_text(start.linear_momentum).c_str(),
                vector_text(end.linear_momentum).c_str());
  out << "sleeping    body " << (start.body_sleeping ? "asleep" : "awake") << " at start";
  for (const std::string& event : sleep_events) out << "; " << event;
  out << "; " << (end.body_sleeping ? "asleep" : "awake") << " at end\n";
  out << "status      " << status_name(report.status) << "\n";
  return report.status == StepStatus::ok ? kSuccess : kDiverged;
}

}  // namespace

int run_main(int argc, const char* const* argv, std::ostream& out, std::ostream& err) {
  CLI::App app{"limber: articulated bodies with distributed mass (Verlet with weighted relaxation, and more)", "limber"};
  app.set_version_flag("--version", "limber 0.1.0");
  app.require_subcommand(1);
  CLI::App* run = app.add_subcommand("run", "Simulate a scene and print a summary");
  RunFlags flags;
  add_run_flags(*run, flags);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    if (error.get_exit_code() == 0) return app.exit(error, out, err);  // --help, --version
    err << "limber: " << error.what() << " (see 'limber run --help')\n";
    return kBadInput;
  }

  try {
    SceneOptions scene_options;
    if (given(flags.body_option)) scene_options.variant = flags.body;
    if (given(flags.links_option)) scene_options.links = flags.links;
    const bool embedded = flags.scene.empty();
    Model model = embedded ? load_scene_text(embedded_humanoid_scene(), "embedded tools/scenes/humanoid.json", scene_options)
                           : load_scene_file(flags.scene, scene_options);
    apply_overrides(model, flags);
    const std::string source = embedded ? "embedded tools/scenes/humanoid.json" : flags.scene;
    return flags.precision == "float" ? simulate<float>(model, flags, source, out)
                                      : simulate<double>(model, flags, source, out);
  } catch (const ModelError& error) {
    err << "limber: " << error.what() << "\n";
  } catch (const InputError& error) {
    err << "limber: " << error.what() << "\n";
  } catch (const std::exception& error) {
    err << "limber: unexpected error: " << error.what() << "\n";
  }
  return kBadInput;
}

}  // namespace limber::cli
