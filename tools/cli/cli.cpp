#include "tools/cli/cli.hpp"

#include <array>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <CLI/CLI.hpp>

#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/metrics/knock.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/model/model.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "limber/kernel/methods/method.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/springs/step.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "limber/layouts/graph/constraint_colouring.hpp"
#include "tools/cli/trajectory.hpp"

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
  long links = 0, copies = 0, steps = 0;
  int iterations = 0, substeps = 0;
  std::string projection;
  double dt = 0, tolerance = 0, budget_us = 0, over_relaxation = 1;
  std::string out_path;
  std::string solver = "gauss-seidel", sweep = "coloured", pinned = "first", layout = "auto", threading = "workers";
  std::string ordering = "depth-parity";
  int threads = 0;
  bool scalar = false;
  int newton_iterations = 2;
  double compliance = 0;
  bool warm_start = false, long_range_attachments = false;
  double stiffness = 0, damping = 0;
  std::string integrator, linear_solver = "ldlt";
  std::string stabilization = "baumgarte", constraint_solver = "auto";

  CLI::Option *body_option, *ball_speed_option, *ball_direction_option, *ball_radius_option, *ball_mass_option,
      *ball_restitution_option, *friction_option, *links_option, *copies_option, *steps_option, *dt_option, *iterations_option,
      *tolerance_option, *budget_option, *over_relaxation_option, *out_option, *stiffness_option, *damping_option,
      *integrator_option, *linear_solver_option, *stabilization_option, *constraint_solver_option, *newton_iterations_option,
      *compliance_option, *warm_start_option, *projection_option, *substeps_option;
  std::vector<CLI::Option*> verlet_only_options;  ///< flags that only the Verlet methods take

  bool springs() const { return method == "springs-explicit" || method == "springs-implicit"; }
  bool lagrange() const { return method == "lagrange"; }
  bool featherstone() const { return method == "featherstone"; }
  bool rigid() const { return springs() || lagrange() || featherstone(); }  ///< the methods on rigid bodies
};

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

void add_run_flags(CLI::App& run, RunFlags& flags) {
  run.add_option("scene", flags.scene, "Scene file (JSON); default: the embedded humanoid (tools/scenes/humanoid.json)");
  run.add_option("--method", flags.method,
                 "weighted or unweighted relaxation (Verlet, thesis eq. 4.7 / 4.6), springs-explicit / "
                 "springs-implicit (rigid limbs joined by stiff springs, thesis 4.4.1), lagrange (rigid limbs "
                 "and joint constraints, thesis 3.1.4), or featherstone (rigid limbs in reduced coordinates, the "
                 "articulated-body algorithm)")
      ->check(CLI::IsMember({"weighted", "unweighted", "springs-explicit", "springs-implicit", "lagrange", "featherstone"}))
      ->capture_default_str();
  flags.stiffness_option = run.add_option("--stiffness", flags.stiffness, "Springs: joint stiffness k for every joint, N/m");
  flags.damping_option = run.add_option("--damping", flags.damping, "Springs: joint damping c for every joint, N s/m");
  flags.integrator_option =
      run.add_option("--integrator", flags.integrator,
                     "Rigid methods: euler, semi-implicit (default), rk2 or rk4 with springs-explicit and lagrange; "
                     "backward-euler with springs-implicit; rk4 (default) or semi-implicit with featherstone")
          ->check(CLI::IsMember({"euler", "semi-implicit", "rk2", "rk4", "backward-euler"}));
  flags.linear_solver_option =
      run.add_option("--linear-solver", flags.linear_solver, "springs-implicit: ldlt (sparse, exact) or cg (conjugate gradient)")
          ->check(CLI::IsMember({"ldlt", "cg"}));
  flags.stabilization_option =
      run.add_option("--stabilization", flags.stabilization, "lagrange: baumgarte (default) or projection (post-stabilization)")
          ->check(CLI::IsMember({"baumgarte", "projection"}));
  flags.constraint_solver_option =
      run.add_option("--constraint-solver", flags.constraint_solver,
                     "lagrange: auto (default: tree unless a joint closes a loop), tree (Baraff's linear time) or sparse")
          ->check(CLI::IsMember({"auto", "tree", "sparse"}));
  run.add_option("--precision", flags.precision, "Scalar type of the state: float or double")
      ->check(CLI::IsMember({"float", "double"}))
      ->capture_default_str();
  flags.body_option = run.add_option("--body", flags.body, "Body variant of the scene (humanoid: thin, medium, wide)");
  flags.ball_speed_option = run.add_option("--ball-speed", flags.ball_speed, "Ball launch speed (every ball's), m/s");
  flags.ball_direction_option = run.add_option("--ball-direction", flags.ball_direction, "Ball launch direction X,Y,Z (every ball's)")
                                    ->delimiter(',')
                                    ->expected(3);
  flags.ball_radius_option = run.add_option("--ball-radius", flags.ball_radius, "Ball radius (every ball's), m");
  flags.ball_mass_option = run.add_option("--ball-mass", flags.ball_mass, "Ball mass (every ball's), kg");
  flags.ball_restitution_option = run.add_option("--ball-restitution", flags.ball_restitution, "Ball restitution (every ball's), 0..1");
  flags.friction_option = run.add_option("--friction", flags.friction, "Ground Coulomb friction coefficient");
  flags.links_option = run.add_option("--links", flags.links, "Number of links of a chain or tree scene");
  flags.copies_option = run.add_option("--copies", flags.copies, "Copies of the scene's bodies, side by side");
  flags.steps_option = run.add_option("--steps", flags.steps, "Number of steps (default: the scene's duration / dt)");
  flags.dt_option = run.add_option("--dt", flags.dt, "Time step, s");
  flags.iterations_option = run.add_option("--iterations", flags.iterations, "Relaxation sweeps per step");
  flags.projection_option =
      run.add_option("--projection", flags.projection,
                     "Projection rule: pbd (end-of-step gradient, the thesis's) or rattle (start-of-step gradient and a "
                     "velocity stage: SHAKE/RATTLE, second order)")
          ->check(CLI::IsMember({"pbd", "rattle"}));
  flags.substeps_option = run.add_option("--substeps", flags.substeps, "Substeps per step, each with its own sweeps (1 to 10000)");
  flags.tolerance_option = run.add_option("--tolerance", flags.tolerance, "Stop relaxing when a sweep moves less, m");
  flags.budget_option = run.add_option("--budget-us", flags.budget_us, "Wall-clock budget for relaxation per step, µs");
  flags.over_relaxation_option =
      run.add_option("--over-relaxation", flags.over_relaxation, "Successive over-relaxation factor, in (0, 2)");
  flags.out_option = run.add_option("--out", flags.out_path, "Write the trajectory (time, particle positions) as CSV");
  run.add_option("--solver", flags.solver,
                 "Relaxation: gauss-seidel or jacobi sweeps, or direct (Newton steps of an exact global projection)")
      ->check(CLI::IsMember({"gauss-seidel", "jacobi", "direct"}))
      ->capture_default_str();
  flags.newton_iterations_option =
      run.add_option("--newton-iterations", flags.newton_iterations, "--solver direct: Newton steps per time step (replaces --iterations)")
          ->check(CLI::PositiveNumber)
          ->capture_default_str();
  flags.compliance_option = run.add_option("--compliance", flags.compliance, "--solver direct: compliance of every constraint, m/N")
                                ->check(CLI::NonNegativeNumber);
  flags.warm_start_option =
      run.add_flag("--warm-start", flags.warm_start, "--solver direct: start from the previous step's multipliers");
  run.add_flag("--long-range-attachments", flags.long_range_attachments,
               "Also hold every particle within the rest length of its path to the pin (Kim et al. 2012)");
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
  for (const char* name : {"--iterations", "--projection", "--substeps", "--tolerance", "--budget-us", "--over-relaxation",
                           "--solver", "--sweep", "--pinned",
                           "--threads", "--threading", "--layout", "--ordering", "--scalar", "--newton-iterations",
                           "--compliance", "--warm-start", "--long-range-attachments"}) {
    flags.verlet_only_options.push_back(run.get_option(name));
  }
}

// Flags of another method family are errors, naming the flag and the methods it applies to.
void refuse(const std::vector<const CLI::Option*>& options, const RunFlags& flags, const char* methods) {
  for (const CLI::Option* option : options) {
    if (option->count() > 0) throw InputError(option->get_name() + ": applies to " + methods + ", not --method " + flags.method);
  }
}
void refuse_verlet_flags(const RunFlags& flags) {
  refuse({flags.verlet_only_options.begin(), flags.verlet_only_options.end()}, flags, "the Verlet methods (weighted, unweighted)");
  if (flags.precision == "float") throw InputError("--precision float: the rigid-body methods run in double only");
}

// --integrator's spellings (CLI11 admits only these five).
Integrator integrator_of(const std::string& flag) {
  return flag == "euler"            ? Integrator::euler
         : flag == "rk2"            ? Integrator::rk2
         : flag == "rk4"            ? Integrator::rk4
         : flag == "backward-euler" ? Integrator::backward_euler
                                    : Integrator::semi_implicit_euler;
}

// The SpringOptions the flags ask for.
SpringOptions spring_options(const RunFlags& flags, const SpringSettings& scene) {
  refuse_verlet_flags(flags);
  refuse({flags.stabilization_option, flags.constraint_solver_option}, flags, "lagrange");
  SpringOptions options;
  options.defaults = scene;
  const bool implicit = flags.method == "springs-implicit";
  const std::string integrator = flags.integrator_option->count() ? flags.integrator : implicit ? "backward-euler" : "semi-implicit";
  if (implicit != (integrator == "backward-euler")) {
    throw InputError("--integrator " + integrator + ": " +
                     (implicit ? "springs-implicit integrates with backward-euler" : "springs-explicit takes euler, semi-implicit, rk2 or rk4"));
  }
  options.integrator = integrator_of(integrator);
  if (flags.linear_solver_option->count() && !implicit) throw InputError("--linear-solver: applies to springs-implicit only");
  options.linear_solver = flags.linear_solver == "cg" ? SpringLinearSolver::conjugate_gradient : SpringLinearSolver::ldlt;
  if (given(flags.stiffness_option)) options.stiffness = checked(flags.stiffness_option, flags.stiffness, positive, "> 0");
  if (given(flags.damping_option)) options.damping = checked(flags.damping_option, flags.damping, non_negative, ">= 0");
  return options;
}

// The LagrangeOptions the flags ask for.
LagrangeOptions lagrange_options(const RunFlags& flags) {
  refuse_verlet_flags(flags);
  refuse({flags.stiffness_option, flags.damping_option, flags.linear_solver_option}, flags, "the spring methods");
  LagrangeOptions options;
  const std::string integrator = flags.integrator_option->count() ? flags.integrator : "semi-implicit";
  if (integrator == "backward-euler") throw InputError("--integrator backward-euler: lagrange takes euler, semi-implicit, rk2 or rk4");
  options.integrator = integrator_of(integrator);
  options.stabilization = flags.stabilization == "projection" ? Stabilization::projection : Stabilization::baumgarte;
  options.solver = flags.constraint_solver == "tree"     ? MultiplierSolver::tree
                   : flags.constraint_solver == "sparse" ? MultiplierSolver::sparse
                                                         : MultiplierSolver::automatic;
  return options;
}

// The FeatherstoneOptions the flags ask for.
FeatherstoneOptions featherstone_options(const RunFlags& flags) {
  refuse_verlet_flags(flags);
  refuse({flags.stiffness_option, flags.damping_option, flags.linear_solver_option}, flags, "the spring methods");
  refuse({flags.stabilization_option, flags.constraint_solver_option}, flags, "lagrange");
  FeatherstoneOptions options;
  const std::string integrator = flags.integrator_option->count() ? flags.integrator : "rk4";  // featherstone_state.hpp says why
  if (integrator != "semi-implicit" && integrator != "rk4") {
    throw InputError("--integrator " + integrator + ": featherstone takes semi-implicit or rk4");
  }
  options.integrator = integrator_of(integrator);
  return options;
}

// The scene's relaxation settings with the flags' changes (--iterations, --projection, ...).
RelaxationSettings relaxation_settings(const RunFlags& flags, RelaxationSettings relaxation) {
  if (given(flags.iterations_option)) {
    if (flags.iterations < 1) throw InputError(format("--iterations: must be >= 1, got %d", flags.iterations));
    relaxation.iterations = flags.iterations;
  }
  if (given(flags.projection_option)) {
    relaxation.projection = flags.projection == "rattle" ? ProjectionRule::rattle : ProjectionRule::pbd;
  }
  if (given(flags.substeps_option)) {
    if (flags.substeps < 1 || flags.substeps > kMaxSubsteps) {
      throw InputError(format("--substeps: must be in [1, %d], got %d", kMaxSubsteps, flags.substeps));
    }
    relaxation.substeps = flags.substeps;
  }
  if (given(flags.tolerance_option)) {
    relaxation.tolerance = checked(flags.tolerance_option, flags.tolerance, non_negative, ">= 0");
  }
  if (given(flags.budget_option)) {
    relaxation.budget_us = checked(flags.budget_option, flags.budget_us, non_negative, ">= 0");
  }
  if (given(flags.over_relaxation_option)) {
    relaxation.over_relaxation =
        checked(flags.over_relaxation_option, flags.over_relaxation, [](double w) { return w > 0 && w < 2; }, "in (0, 2)");
  }
  return relaxation;
}

// The VerletOptions the flags ask for; a combination the sequential sweep cannot run is an error.
VerletOptions verlet_options(const RunFlags& flags, const MethodSettings& scene) {
  refuse({flags.stiffness_option, flags.damping_option, flags.integrator_option, flags.linear_solver_option}, flags,
         "the rigid-body methods (springs-explicit, springs-implicit, lagrange, featherstone)");
  refuse({flags.stabilization_option, flags.constraint_solver_option}, flags, "lagrange");
  VerletOptions options;
  options.relaxation = relaxation_settings(flags, scene.relaxation);
  options.verlet = scene.verlet;
  options.rule = flags.method == "unweighted" ? RelaxationRule::unweighted : RelaxationRule::weighted;
  options.solver = flags.solver == "jacobi"   ? RelaxationSolver::jacobi
                   : flags.solver == "direct" ? RelaxationSolver::direct
                                              : RelaxationSolver::gauss_seidel;
  options.long_range_attachments = flags.long_range_attachments;
  if (options.solver == RelaxationSolver::direct) {
    for (const CLI::Option* option : {flags.iterations_option, flags.over_relaxation_option}) {
      if (given(option)) throw InputError(option->get_name() + ": applies to the gauss-seidel and jacobi sweeps; --solver direct takes --newton-iterations");
    }
    if (flags.sweep == "sequential") throw InputError("--sweep sequential: is Gauss-Seidel; it cannot run with --solver direct");
    options.newton_iterations = flags.newton_iterations;
    options.compliance = flags.compliance;
    options.warm_start = flags.warm_start;
  } else {
    for (const CLI::Option* option : {flags.newton_iterations_option, flags.compliance_option, flags.warm_start_option}) {
      if (given(option)) throw InputError(option->get_name() + ": applies to --solver direct");
    }
  }
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

// The --ball-* flags, on one ball (a volley's balls all take them).
void apply_ball_overrides(Ball& ball, const RunFlags& flags) {
  if (given(flags.ball_radius_option)) ball.radius = checked(flags.ball_radius_option, flags.ball_radius, positive, "> 0");
  if (given(flags.ball_mass_option)) ball.mass = checked(flags.ball_mass_option, flags.ball_mass, positive, "> 0");
  if (given(flags.ball_restitution_option)) {
    ball.restitution = checked(flags.ball_restitution_option, flags.ball_restitution, unit_interval, "in [0, 1]");
  }
  if (given(flags.ball_speed_option) || given(flags.ball_direction_option)) {
    double speed = ball.velocity.norm();
    Vector3 direction = speed > 0 ? Vector3(ball.velocity / speed) : Vector3(-1, 0, 0);
    if (given(flags.ball_speed_option)) speed = checked(flags.ball_speed_option, flags.ball_speed, non_negative, ">= 0");
    if (given(flags.ball_direction_option)) {
      const Vector3 d(flags.ball_direction[0], flags.ball_direction[1], flags.ball_direction[2]);
      if (!d.allFinite() || d.norm() == 0) {
        throw InputError(format("--ball-direction: must be three finite numbers, not all zero, got %g,%g,%g", d.x(), d.y(), d.z()));
      }
      direction = d.normalized();
    }
    ball.velocity = speed * direction;
  }
}

// Applies the flags that change the model, each checked and named in its error.
void apply_overrides(Model& model, const RunFlags& flags) {
  const bool ball_flag = given(flags.ball_speed_option) || given(flags.ball_direction_option) ||
                         given(flags.ball_radius_option) || given(flags.ball_mass_option) ||
                         given(flags.ball_restitution_option);
  if (ball_flag && model.balls.empty()) throw InputError(format("--ball-*: the scene '%s' has no ball", model.name.c_str()));
  for (Ball& ball : model.balls) apply_ball_overrides(ball, flags);
  if (given(flags.friction_option)) {
    if (!model.ground) throw InputError(format("--friction: the scene '%s' has no ground", model.name.c_str()));
    model.ground->friction = checked(flags.friction_option, flags.friction, non_negative, ">= 0");
  }
  if (given(flags.dt_option)) model.settings.time_step = checked(flags.dt_option, flags.dt, positive, "> 0");
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

// --- What each method family shows the run loop and the summary ---

template <typename Scalar>
bool has_joint_gaps(const VerletState<Scalar>& state) { return !state.joint_constraints.empty(); }
bool has_joint_gaps(const SpringState& state) { return state.springs.size() > 0; }
bool has_joint_gaps(const LagrangeState& state) { return state.joints.size() > 0; }
bool has_joint_gaps(const FeatherstoneState& state) { return state.joints.size() > 0; }

template <typename Scalar>
bool ball_touching(const VerletState<Scalar>& state) { return state.ball_touched; }
bool ball_touching(const RigidScene& state) { return state.ball_touching; }

const char* layout_name(ParticleLayout layout) {
  switch (layout) {
    case ParticleLayout::aos: return "aos";
    case ParticleLayout::aosoa: return "aosoa";
    case ParticleLayout::soa: return "soa";
    case ParticleLayout::automatic: break;
  }
  return "auto";
}

// "solver" line: the sweep, the colour count and batch sizes, the overflow, lanes, layout, threads;
// or the direct solver's Newton steps and trees.
template <typename Scalar>
std::string solver_line(const RunFlags& flags, const VerletState<Scalar>& state) {
  if (state.options.solver == RelaxationSolver::direct) {
    const DirectProjection<Scalar>& direct = state.plan.direct;
    const std::size_t trees = direct.elimination.ordering().components.size();
    return format("solver      direct: Newton steps of Baraff's tree elimination (linear time) over %zu tree%s%s; "
                  "%zu loop-closing constraints by Gauss-Seidel; 1 thread\n",
                  trees, trees == 1 ? "" : "s", state.options.warm_start ? ", warm-started" : "",
                  direct.elimination.ordering().loop_constraints.size());
  }
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

// What a run measured, for the summary.
struct RunRecord {
  Observation start, end;
  double largest_gap = 0, largest_stretch = 0, wall_seconds = 0;
  double largest_limit_violation = 0;  ///< over the joints with limits, rad (m for a prismatic range)
  double drives_released_at = -1;      ///< s: when settings.release_drives_on_impact made the drives limp; −1 never
  long steps_done = 0;
  std::array<long, 4> relaxation_stops{};
  std::uint64_t fallbacks = 0;  ///< rattle projections that fell back to pbd
  std::vector<std::string> sleep_events;
  StepStatus status = StepStatus::ok;
  int contacts = 0, most_contacts = 0;  ///< StepReport::contacts at the end, and the most in a step
  double deepest_penetration = 0;      ///< m, over the run: limbs into limbs, colliders, the ground
};

// The deepest overlap of `state`'s limbs now, measured alike for every method (observers.hpp).
template <typename State>
double penetration_now(const State& state, const Model& model, LimbCollisions& collisions, std::vector<LimbSegment>& segments) {
  if constexpr (requires { state.particles; }) {
    limb_segments(state, segments);
  } else {
    limb_segments(static_cast<const RigidScene&>(state), model, segments);
  }
  const double between = collisions.active() ? collisions.deepest_penetration(segments) : 0.0;
  return std::max(between, ground_penetration(model, segments));
}

// Steps `state` `steps` times (stopping at a divergence), observing after every step. `variant`
// holds `state`: the drives go limp through it when the scene asks (release_drives_on_impact).
template <typename State>
RunRecord run_steps(State& state, MethodState& variant, const Model& model, long steps, std::ofstream& csv, KnockMeter& knock) {
  RunRecord record;
  LimbCollisions collisions(model);
  std::vector<LimbSegment> segments;
  record.deepest_penetration = penetration_now(state, model, collisions, segments);
  record.start = record.end = observe(state);
  record.largest_gap = record.start.max_joint_gap, record.largest_stretch = record.start.max_link_stretch;
  record.largest_limit_violation = record.start.joints.limit_violation;
  bool body_sleeping = record.start.body_sleeping;
  for (; record.steps_done < steps;) {
    const auto before = std::chrono::steady_clock::now();
    const auto report = step(state);
    record.wall_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count();
    ++record.steps_done;
    if (release_drives_after_impact(variant) && record.drives_released_at < 0) record.drives_released_at = state.time;
    if constexpr (requires { report.stop; }) {
      ++record.relaxation_stops[static_cast<int>(report.stop)];
      record.fallbacks += report.fallbacks;
    }
    record.end = observe(state);
    record.contacts = report.contacts;
    record.most_contacts = std::max(record.most_contacts, report.contacts);
    record.deepest_penetration = std::max(record.deepest_penetration, penetration_now(state, model, collisions, segments));
    knock.update(record.end.time, ball_touching(state), record.end.body_centre_of_mass);
    record.largest_gap = std::max(record.largest_gap, record.end.max_joint_gap);
    record.largest_stretch = std::max(record.largest_stretch, record.end.max_link_stretch);
    record.largest_limit_violation = std::max(record.largest_limit_violation, record.end.joints.limit_violation);
    if (record.end.body_sleeping != body_sleeping && record.sleep_events.size() < 8) {
      record.sleep_events.push_back(format("%s at t = %.3f s", record.end.body_sleeping ? "asleep" : "woke", record.end.time));
    }
    body_sleeping = record.end.body_sleeping;
    if (csv.is_open()) write_trajectory_row(csv, variant);
    record.status = report.status;
    if (report.status != StepStatus::ok) break;
  }
  return record;
}

// The model line's balls: "", ", ball" or ", 5 balls".
std::string balls_clause(const Model& model) {
  const std::size_t count = model.balls.size();
  return count == 0 ? "" : count == 1 ? ", ball" : format(", %zu balls", count);
}

// The method's own lines: what it is, how the model became its state, how it solved.
template <typename Scalar>
void method_lines(std::ostream& out, const Model& model, const RunFlags& flags, const VerletState<Scalar>& state, const RunRecord& record) {
  out << format("method      %s relaxation (Verlet), %s precision\n", flags.method.c_str(), flags.precision.c_str());
  out << format("model       %zu limbs, %zu joints%s%s%s; %zu particles, %zu constraints, %zu island%s\n",
                model.bodies.size(), model.joints.size(), model.ground ? ", ground" : "", model.bounds ? ", bounds" : "",
                balls_clause(model).c_str(), state.particles.size(), state.constraints.size(), state.islands.size(),
                state.islands.size() == 1 ? "" : "s");
  out << solver_line(flags, state);
  out << format("run         %ld steps of %.6g s = %.4g s simulated in %.4g s wall (%.0f steps/s)\n", record.steps_done,
                model.settings.time_step, state.time, record.wall_seconds,
                record.wall_seconds > 0 ? record.steps_done / record.wall_seconds : 0.0);
  const RelaxationSettings& relaxation = state.options.relaxation;
  const bool rattle = relaxation.projection == ProjectionRule::rattle;
  const std::string per = relaxation.substeps > 1 ? format(" a substep, %d substeps a step", relaxation.substeps) : std::string(" a step");
  if (state.options.solver == RelaxationSolver::direct) {
    out << format("relaxation  %s projection; up to %d Newton steps%s (tolerance %g m, budget %g us); stopped by:",
                  rattle ? "rattle" : "pbd", state.options.newton_iterations, per.c_str(), relaxation.tolerance, relaxation.budget_us);
  } else {
    out << format("relaxation  %s projection; up to %d sweeps%s (over-relaxation %g, tolerance %g m, budget %g us); stopped by:",
                  rattle ? "rattle" : "pbd", relaxation.iterations, per.c_str(), relaxation.over_relaxation, relaxation.tolerance,
                  relaxation.budget_us);
  }
  for (int k = 0; k < 4; ++k) {
    if (record.relaxation_stops[k]) out << format(" %s %ld", stop_name(static_cast<RelaxationStop>(k)), record.relaxation_stops[k]);
  }
  if (rattle) out << format("; pbd fallbacks %llu", static_cast<unsigned long long>(record.fallbacks));
  out << "\n";
}

void method_lines(std::ostream& out, const Model& model, const RunFlags& flags, const SpringState& state, const RunRecord& record) {
  out << format("method      %s: rigid limbs joined by stiff springs, %s, double precision\n", flags.method.c_str(),
                integrator_name(state.options.integrator));
  double k_min = INFINITY, k_max = 0, c_min = INFINITY, c_max = 0;
  for (std::size_t s = 0; s < state.springs.size(); ++s) {
    k_min = std::min(k_min, state.springs.stiffness[s]), k_max = std::max(k_max, state.springs.stiffness[s]);
    c_min = std::min(c_min, state.springs.damping[s]), c_max = std::max(c_max, state.springs.damping[s]);
  }
  const std::string range = state.springs.size() == 0 ? std::string("no springs")
      : k_min == k_max && c_min == c_max ? format("stiffness %g N/m, damping %g N s/m", k_min, c_min)
                                         : format("stiffness %g..%g N/m, damping %g..%g N s/m", k_min, k_max, c_min, c_max);
  std::size_t spring_count = 0;  // a hinge is two springs
  for (const std::uint8_t count : state.springs.count) spring_count += count;
  out << format("model       %zu limbs, %zu joints%s%s%s; %zu rigid bodies, %zu springs (%s), %zu island%s\n",
                model.bodies.size(), model.joints.size(), model.ground ? ", ground" : "", model.bounds ? ", bounds" : "",
                balls_clause(model).c_str(), state.bodies.size(), spring_count, range.c_str(), state.islands.size(),
                state.islands.size() == 1 ? "" : "s");
  if (state.options.integrator == Integrator::backward_euler) {
    out << format("solver      sparse %s over %zu unknowns\n",
                  state.options.linear_solver == SpringLinearSolver::ldlt ? "LDLT (AMD ordering)" : "conjugate gradient (Jacobi)",
                  6 * state.bodies.size());
  }
  out << format("run         %ld steps of %.6g s = %.4g s simulated in %.4g s wall (%.0f steps/s)\n", record.steps_done,
                model.settings.time_step, state.time, record.wall_seconds,
                record.wall_seconds > 0 ? record.steps_done / record.wall_seconds : 0.0);
}

void method_lines(std::ostream& out, const Model& model, const RunFlags&, const LagrangeState& state, const RunRecord& record) {
  const char* integrators[] = {"forward Euler", "semi-implicit Euler (velocity-level joints)", "RK2", "RK4"};
  out << format("method      lagrange: rigid limbs and joint constraints, %s, %s stabilization, double precision\n",
                integrators[static_cast<int>(state.options.integrator)],
                state.options.stabilization == Stabilization::projection ? "projection" : "Baumgarte");
  const std::string gears = model.gears.empty() ? "" : format(", %zu gear%s", model.gears.size(), model.gears.size() == 1 ? "" : "s");
  out << format("model       %zu limbs, %zu joints%s%s%s%s; %zu rigid bodies, %zu constraint rows, %zu island%s\n",
                model.bodies.size(), model.joints.size(), gears.c_str(), model.ground ? ", ground" : "",
                model.bounds ? ", bounds" : "", balls_clause(model).c_str(), state.bodies.size(), state.constraints.total_rows(),
                state.islands.size(), state.islands.size() == 1 ? "" : "s");
  out << format("solver      %s\n", state.uses_tree ? "Baraff's tree-ordered block LDLT (linear time)"
                                                      : "sparse LDLT of J M^-1 J^T (the constraints close a loop, or asked for)");
  out << format("run         %ld steps of %.6g s = %.4g s simulated in %.4g s wall (%.0f steps/s)\n", record.steps_done,
                model.settings.time_step, state.time, record.wall_seconds,
                record.wall_seconds > 0 ? record.steps_done / record.wall_seconds : 0.0);
}

void method_lines(std::ostream& out, const Model& model, const RunFlags&, const FeatherstoneState& state, const RunRecord& record) {
  out << format("method      featherstone: rigid limbs in reduced coordinates (articulated-body algorithm), %s, double precision\n",
                state.options.integrator == Integrator::rk4 ? "RK4" : "semi-implicit Euler");
  out << format("model       %zu limbs, %zu joints%s%s%s; %zu island%s\n", model.bodies.size(), model.joints.size(),
                model.ground ? ", ground" : "", model.bounds ? ", bounds" : "", balls_clause(model).c_str(), state.islands.size(),
                state.islands.size() == 1 ? "" : "s");
  std::string roots;
  for (std::int32_t i : state.floating_roots) roots += (roots.empty() ? "" : ", ") + state.tree.body(i).name;
  out << format("tree        %d bodies, %d degrees of freedom (nv; nq %d), %zu floating root%s%s%s\n", state.tree.body_count(),
                state.tree.velocity_count(), state.tree.position_count(), state.floating_roots.size(),
                state.floating_roots.size() == 1 ? "" : "s", roots.empty() ? "" : ": ", roots.c_str());
  out << format("contacts    impulses through the joint-space inertia (articulated-body response), %d passes, then a position push-out\n",
                state.contact_iterations);
  out << format("run         %ld steps of %.6g s = %.4g s simulated in %.4g s wall (%.0f steps/s)\n", record.steps_done,
                model.settings.time_step, state.time, record.wall_seconds,
                record.wall_seconds > 0 ? record.steps_done / record.wall_seconds : 0.0);
}

// The "limits" line: the joints' limits and drives (Observation::joints, measured alike by every
// method): the largest limit violation in the run and at its end, the drives' tracking error at
// the end; "none" without limited or driven joints.
std::string limits_line(const Model& model, const RunRecord& record) {
  bool limited_rotation = false, limited_slide = false, driven_rotation = false, driven_slide = false;
  for (const Joint& joint : model.joints) {
    const bool slide = joint.type == JointType::prismatic;
    if (joint.limits.any()) (slide ? limited_slide : limited_rotation) = true;
    if (joint.drive) (slide ? driven_slide : driven_rotation) = true;
  }
  const auto unit = [](bool rotation, bool slide) { return rotation && slide ? "rad (m for slides)" : slide ? "m" : "rad"; };
  const JointMeasures& end = record.end.joints;
  std::string line;
  if (end.limited_joints > 0) {
    line = format("%d limited joint%s: largest violation %.3g %s in run, %.3g at end", end.limited_joints,
                  end.limited_joints == 1 ? "" : "s", record.largest_limit_violation, unit(limited_rotation, limited_slide),
                  end.limit_violation);
  }
  if (end.driven_joints > 0) {
    line += format("%s%d drive%s: tracking error %.3g %s at end", line.empty() ? "" : "; ", end.driven_joints,
                   end.driven_joints == 1 ? "" : "s", end.drive_error, unit(driven_rotation, driven_slide));
    if (record.drives_released_at >= 0) line += format(" (limp since the ball hit, t = %.3f s)", record.drives_released_at);
  }
  return "limits      " + (line.empty() ? std::string("none") : line) + "\n";
}

// Runs the model under the flags' method and prints the summary; returns the exit code.
template <typename State>
int simulate(State& state, MethodState& variant, const Model& model, const RunFlags& flags, const std::string& source,
             std::ostream& out) {
  const double dt = model.settings.time_step;
  const long steps = given(flags.steps_option) ? flags.steps : std::max(1L, std::lround(model.settings.duration / dt));
  std::ofstream csv;
  if (given(flags.out_option)) {
    csv.open(flags.out_path);
    if (!csv) throw InputError(format("--out: cannot write '%s'", flags.out_path.c_str()));
    write_trajectory_header(csv, model, variant);
    write_trajectory_row(csv, variant);
  }
  const Observation start = observe(state);
  KnockMeter knock(model.balls.empty() ? Eigen::Vector3d::UnitX() : model.balls.front().velocity, start.body_centre_of_mass);
  const RunRecord record = run_steps(state, variant, model, steps, csv, knock);
  const Observation& end = record.end;

  out << "limber run: " << model.name << " (" << source << ")\n";
  method_lines(out, model, flags, state, record);
  if (has_joint_gaps(state)) {
    out << format("joint gap   final max %.3g, rms %.3g; largest in run %.3g (relative to link length)\n",
                  end.max_joint_gap, end.rms_joint_gap, record.largest_gap);
  } else {
    out << "joint gap   none (shared-particle joints or no joints)\n";
  }
  out << limits_line(model, record);
  out << format("contacts    %d at end, at most %d in a step; penetration %.3g m deepest in run (limbs, colliders, ground)\n",
                record.contacts, record.most_contacts, record.deepest_penetration);
  if (!flags.rigid()) {
    out << format("stretch     final max %.3g; largest in run %.3g (relative to link length)\n", end.max_link_stretch,
                  record.largest_stretch);
  }
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
  for (const std::string& event : record.sleep_events) out << "; " << event;
  out << "; " << (end.body_sleeping ? "asleep" : "awake") << " at end\n";
  out << "status      " << status_name(record.status) << "\n";
  return record.status == StepStatus::ok ? kSuccess : kDiverged;
}

// The method and its options the flags ask for, over the scene's method settings (each reader
// refuses the other methods' flags).
WorldOptions method_options(const RunFlags& flags, const MethodSettings& scene) {
  WorldOptions options;
  if (flags.springs()) {
    options.method = Method::springs, options.springs = spring_options(flags, scene.springs);
  } else if (flags.lagrange()) {
    options.method = Method::lagrange, options.lagrange = lagrange_options(flags);
  } else if (flags.featherstone()) {
    options.method = Method::featherstone, options.featherstone = featherstone_options(flags);
  } else {
    options.method = Method::particles, options.particles = verlet_options(flags, scene);
    options.single_precision = flags.precision == "float";
  }
  return options;
}

int simulate(const LoadedRun& loaded, const RunFlags& flags, std::ostream& out) {
  MethodState state = compile_method(loaded.scene.model, loaded.options);
  return std::visit([&](auto& compiled) { return simulate(compiled, state, loaded.scene.model, flags, loaded.source, out); }, state);
}

// The scene and method that parsed run flags ask for. Throws ModelError, InputError or
// std::invalid_argument (options that do not go together), each one line.
LoadedRun load(const RunFlags& flags) {
  SceneOptions scene_options;
  if (given(flags.body_option)) scene_options.variant = flags.body;
  if (given(flags.links_option)) scene_options.links = flags.links;
  if (given(flags.copies_option)) scene_options.copies = flags.copies;
  const bool embedded = flags.scene.empty();
  LoadedRun loaded;
  loaded.source = embedded ? "embedded tools/scenes/humanoid.json" : flags.scene;
  loaded.scene = embedded ? load_scene_text(embedded_humanoid_scene(), loaded.source, scene_options)
                          : load_scene_file(flags.scene, scene_options);
  apply_overrides(loaded.scene.model, flags);
  loaded.options = method_options(flags, loaded.scene.methods);
  if (given(flags.out_option)) loaded.out_path = flags.out_path;
  return loaded;
}

// `limber view`'s own flags, which `limber run` does not take.
struct ViewFlags {
  long frames = -1;
  std::string screenshot;
  bool hide_ui = false;
  int width = 1280, height = 720;
  std::vector<std::string> overlays;
  std::vector<double> camera;
};
constexpr std::array<const char*, 6> kViewValueFlags{"--frames", "--screenshot", "--width", "--height", "--overlay", "--camera"};

void add_view_flags(CLI::App& view, ViewFlags& flags) {
  view.add_option("--frames", flags.frames, "Headless: simulate and draw this many frames (1/60 s each) offscreen, then exit")
      ->check(CLI::Range(0L, 100'000'000L));
  view.add_option("--screenshot", flags.screenshot, "Headless: write the last frame as PNG to this file");
  view.add_flag("--hide-ui", flags.hide_ui, "Draw the scene without the control panels");
  view.add_option("--width", flags.width, "Frame width, pixels")->check(CLI::Range(64, 8192))->capture_default_str();
  view.add_option("--height", flags.height, "Frame height, pixels")->check(CLI::Range(64, 8192))->capture_default_str();
  view.add_option("--overlay", flags.overlays, "Show an overlay from the start (repeatable)")
      ->check(CLI::IsMember({"bounding-spheres", "contacts", "joint-gaps", "centre-of-mass", "forces"}))
      ->allow_extra_args(false);  // one name per --overlay, so a scene after it stays the scene
  view.add_option("--camera", flags.camera,
                  "Camera YAW,PITCH,DISTANCE[,X,Y,Z]: degrees about z and above the horizon, m from the point it looks at "
                  "(default: the bodies' centre)")
      ->delimiter(',')
      ->expected(3, 6);
}

// The arguments after "view" less the view's own flags: the run flags the viewer reloads with.
std::vector<std::string> run_arguments_of_view(int argc, const char* const* argv) {
  std::vector<std::string> kept;
  int first = 1;
  while (first < argc && std::string_view(argv[first]) != "view") ++first;
  for (int i = first + 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const auto named = [&](const char* flag) { return arg == flag || arg.starts_with(std::string(flag) + "="); };
    if (named("--hide-ui")) continue;
    const auto value_flag = std::find_if(kViewValueFlags.begin(), kViewValueFlags.end(), named);
    if (value_flag != kViewValueFlags.end()) {
      if (arg == *value_flag) ++i;  // its value is the next argument
      continue;
    }
    kept.emplace_back(arg);
  }
  return kept;
}

// `limber view`: checks the request, then hands it to the viewer this program was built with.
int view(const ViewFlags& flags, std::vector<std::string> run_arguments, const RunFlags& run_flags, Viewer viewer,
         std::ostream& out, std::ostream& err) {
  if (!flags.screenshot.empty() && flags.frames < 0) throw InputError("--screenshot: needs --frames (the headless mode)");
  if (!flags.camera.empty()) {
    if (flags.camera.size() != 3 && flags.camera.size() != 6) {
      throw InputError(format("--camera: YAW,PITCH,DISTANCE or YAW,PITCH,DISTANCE,X,Y,Z; got %zu numbers", flags.camera.size()));
    }
    if (!std::all_of(flags.camera.begin(), flags.camera.end(), [](double v) { return std::isfinite(v); })) {
      throw InputError("--camera: must be finite numbers");
    }
    const double yaw = flags.camera[0], pitch = flags.camera[1], distance = flags.camera[2];
    if (!std::isfinite(yaw) || !(std::abs(pitch) <= 85) || !(distance >= 0.1 && distance <= 500)) {
      throw InputError(format("--camera: yaw finite, pitch in [-85, 85] degrees, distance in [0.1, 500] m; got %g,%g,%g", yaw, pitch, distance));
    }
  }
  if (!flags.screenshot.empty() && !run_flags.scene.empty()) {
    std::error_code ignored;
    if (std::filesystem::equivalent(flags.screenshot, run_flags.scene, ignored)) {
      throw InputError(format("--screenshot: '%s' is the scene file; refusing to write over it", flags.screenshot.c_str()));
    }
  }
  (void)load(run_flags);  // a bad scene or flag is the same one line as `limber run`'s, before any window
  if (viewer == nullptr) {
    throw InputError("view: this limber was built without the viewer (it needs GLFW, OpenGL and Dear ImGui: tools/setup.sh --viewer)");
  }
  ViewRequest request{std::move(run_arguments), flags.frames, flags.screenshot, flags.hide_ui, flags.overlays, flags.camera, flags.width, flags.height};
  return viewer(request, out, err);
}

}  // namespace

LoadedRun load_run(const std::vector<std::string>& run_arguments) {
  CLI::App app{"limber run's flags", "limber run"};
  RunFlags flags;
  add_run_flags(app, flags);
  std::vector<const char*> argv{"limber run"};
  for (const std::string& argument : run_arguments) argv.push_back(argument.c_str());
  try {
    app.parse(int(argv.size()), argv.data());
  } catch (const CLI::ParseError& error) {
    throw std::runtime_error(error.what());
  }
  return load(flags);
}

WorldOptions options_for_method(const std::string& method, const MethodSettings& scene) {
  CLI::App app{"limber run's flags", "limber run"};
  RunFlags flags;
  add_run_flags(app, flags);
  const std::array<const char*, 3> argv{"limber run", "--method", method.c_str()};
  try {
    app.parse(int(argv.size()), argv.data());
  } catch (const CLI::ParseError& error) {
    throw std::runtime_error(error.what());
  }
  return method_options(flags, scene);
}

int run_main(int argc, const char* const* argv, std::ostream& out, std::ostream& err, Viewer viewer) {
  CLI::App app{"limber: articulated bodies with distributed mass (Verlet with weighted relaxation, and more)", "limber"};
  app.set_version_flag("--version", "limber 0.1.0");
  app.require_subcommand(1);
  CLI::App* run = app.add_subcommand("run", "Simulate a scene and print a summary");
  RunFlags flags;
  add_run_flags(*run, flags);
  CLI::App* view_command =
      app.add_subcommand("view", "Show a scene in a window (OpenGL), or render it headless with --frames and --screenshot");
  RunFlags view_run_flags;
  ViewFlags view_flags;
  add_run_flags(*view_command, view_run_flags);
  add_view_flags(*view_command, view_flags);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    if (error.get_exit_code() == 0) return app.exit(error, out, err);  // --help, --version
    const char* command = view_command->parsed() ? "view" : "run";
    err << "limber: " << error.what() << " (see 'limber " << command << " --help')\n";
    return kBadInput;
  }

  try {
    if (view_command->parsed()) {
      return view(view_flags, run_arguments_of_view(argc, argv), view_run_flags, viewer, out, err);
    }
    return simulate(load(flags), flags, out);
  } catch (const ModelError& error) {
    err << "limber: " << error.what() << "\n";
  } catch (const InputError& error) {
    err << "limber: " << error.what() << "\n";
  } catch (const std::invalid_argument& error) {  // options that do not go together (compile's)
    err << "limber: " << error.what() << "\n";
  } catch (const std::exception& error) {
    err << "limber: unexpected error: " << error.what() << "\n";
  }
  return kBadInput;
}

}  // namespace limber::cli
