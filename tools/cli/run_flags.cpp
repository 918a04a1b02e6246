#include "tools/cli/run_flags.hpp"

#include <array>
#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include "limber/kernel/scene/scene_file.hpp"

namespace limber::cli {
namespace {

double checked(const CLI::Option* option, double value, bool (*accept)(double), const char* expectation) {
  if (!std::isfinite(value) || !accept(value)) {
    throw InputError(format("%s: must be %s, got %g", option->get_name().c_str(), expectation, value));
  }
  return value;
}
bool unit_interval(double v) { return v >= 0 && v <= 1; }

// Limits on flags that would otherwise run for days or fill a disk: guards against a slip of the
// keyboard, not physical limits (the kernel's own are kMaxIterations, kMaxThreads, ...).
constexpr long kMaxSteps = 1'000'000'000;
constexpr double kMaxBallSpeed = 1e5;  // m/s, 100× the fastest the tunnelling study checks
constexpr double kMaxFriction = 100;    // Coulomb coefficient; rubber on rubber is about 1
constexpr double kMaxTolerance = 1;     // m, a sweep's largest correction
constexpr double kMaxBudget = 1e9;      // µs, a step's wall-clock budget: 1000 s
constexpr double kMaxStiffness = 1e12;  // N/m, the springs'; the thesis's humanoid uses 10⁴–10⁶
constexpr double kMaxDamping = 1e9;     // N·s/m
constexpr double kMaxCompliance = 1;    // m/N, XPBD's α

}  // namespace

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
  flags.ball_speed_option = run.add_option("--ball-speed", flags.ball_speed, "Ball launch speed (every ball's), m/s, in [0, 1e5]");
  flags.ball_direction_option = run.add_option("--ball-direction", flags.ball_direction, "Ball launch direction X,Y,Z (every ball's)")
                                    ->delimiter(',')
                                    ->expected(3);
  flags.ball_radius_option = run.add_option("--ball-radius", flags.ball_radius, "Ball radius (every ball's), m");
  flags.ball_mass_option = run.add_option("--ball-mass", flags.ball_mass, "Ball mass (every ball's), kg");
  flags.ball_restitution_option = run.add_option("--ball-restitution", flags.ball_restitution, "Ball restitution (every ball's), 0..1");
  flags.friction_option = run.add_option("--friction", flags.friction, "Ground Coulomb friction coefficient");
  run.add_flag("--floating-base", flags.floating_base, "A URDF robot's root link floats instead of being welded to the world");
  flags.links_option = run.add_option("--links", flags.links, "Number of links of a chain or tree scene");
  flags.copies_option = run.add_option("--copies", flags.copies, "Copies of the scene's bodies, side by side");
  flags.steps_option = run.add_option("--steps", flags.steps, "Number of steps, in [1, 1e9] (default: the scene's duration / dt)");
  flags.dt_option = run.add_option("--dt", flags.dt, "Time step, s, in (0, 1]");
  flags.iterations_option = run.add_option("--iterations", flags.iterations, "Relaxation sweeps per substep, in [1, 1e5]");
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
          ->check(CLI::Range(1, kMaxNewtonIterations))
          ->capture_default_str();
  flags.compliance_option = run.add_option("--compliance", flags.compliance, "--solver direct: compliance of every constraint, m/N")
                                ->check(CLI::NonNegativeNumber);
  flags.warm_start_option =
      run.add_flag("--warm-start", flags.warm_start, "--solver direct: start from the previous step's multipliers");
  run.add_option("--joint-solve", flags.joint_solve,
                 "Joints: rows (projected one by one in the sweeps) or tree (each limb tree solved exactly after every sweep, "
                 "limbs as rigid bodies, their contacts pushed through it); default: the scene's settings.verlet.joint_solve")
      ->check(CLI::IsMember({"rows", "tree"}));
  run.add_flag("--long-range-attachments", flags.long_range_attachments,
               "Also hold every particle within the rest length of its path to the pin (Kim et al. 2012)");
  run.add_option("--sweep", flags.sweep,
                 "Gauss-Seidel order: coloured (SIMD, threads) or sequential (the thesis's loop, scalar)")
      ->check(CLI::IsMember({"coloured", "sequential"}))
      ->capture_default_str();
  run.add_option("--pinned", flags.pinned, "Sweep the constraints at pinned particles first or last")
      ->check(CLI::IsMember({"first", "last"}))
      ->capture_default_str();
  run.add_option("--threads", flags.threads,
                 "Threads for relaxation, or for featherstone's contact groups; 0: the hardware's, where they pay off")
      ->check(CLI::Range(0, kMaxThreads))
      ->capture_default_str();
  run.add_option("--threading", flags.threading, "How a colour or the contact groups are split: workers (long-lived) or parallel-for")
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
  run.add_flag("--profile", flags.profile,
               "Time each stage of the step and print, after the summary, where the time went (a few clock reads a substep)");
  for (const char* name : {"--iterations", "--projection", "--substeps", "--tolerance", "--budget-us", "--over-relaxation",
                           "--solver", "--sweep", "--pinned",
                           "--layout", "--ordering", "--scalar", "--newton-iterations",
                           "--compliance", "--warm-start", "--long-range-attachments", "--joint-solve"}) {
    flags.verlet_only_options.push_back(run.get_option(name));
  }
  flags.thread_options = {run.get_option("--threads"), run.get_option("--threading")};
}

namespace {

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
  refuse({flags.thread_options.begin(), flags.thread_options.end()}, flags, "the Verlet methods and featherstone");
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
  if (given(flags.stiffness_option)) options.stiffness = checked(flags.stiffness_option, flags.stiffness, [](double k) { return k > 0 && k <= kMaxStiffness; }, "in (0, 1e12]");
  if (given(flags.damping_option)) options.damping = checked(flags.damping_option, flags.damping, [](double c) { return c >= 0 && c <= kMaxDamping; }, "in [0, 1e9]");
  return options;
}

// The LagrangeOptions the flags ask for.
LagrangeOptions lagrange_options(const RunFlags& flags) {
  refuse_verlet_flags(flags);
  refuse({flags.thread_options.begin(), flags.thread_options.end()}, flags, "the Verlet methods and featherstone");
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
  options.threads = flags.threads;
  options.threading = flags.threading == "parallel-for" ? Threading::parallel_for : Threading::workers;
  return options;
}

// The scene's relaxation settings with the flags' changes (--iterations, --projection, ...).
RelaxationSettings relaxation_settings(const RunFlags& flags, RelaxationSettings relaxation) {
  if (given(flags.iterations_option)) {
    if (flags.iterations < 1 || flags.iterations > kMaxIterations) {
      throw InputError(format("--iterations: must be in [1, %d], got %d", kMaxIterations, flags.iterations));
    }
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
    relaxation.tolerance = checked(flags.tolerance_option, flags.tolerance, [](double t) { return t >= 0 && t <= kMaxTolerance; }, "in [0, 1]");
  }
  if (given(flags.budget_option)) {
    relaxation.budget_us = checked(flags.budget_option, flags.budget_us, [](double b) { return b >= 0 && b <= kMaxBudget; }, "in [0, 1e9]");
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
    options.compliance = given(flags.compliance_option) ? checked(flags.compliance_option, flags.compliance, [](double a) { return a >= 0 && a <= kMaxCompliance; }, "in [0, 1]") : 0;
    options.warm_start = flags.warm_start;
  } else {
    for (const CLI::Option* option : {flags.newton_iterations_option, flags.compliance_option, flags.warm_start_option}) {
      if (given(option)) throw InputError(option->get_name() + ": applies to --solver direct");
    }
  }
  options.order = flags.sweep == "sequential" ? SweepOrder::sequential : SweepOrder::coloured;
  if (!flags.joint_solve.empty()) options.verlet.joint_solve = flags.joint_solve == "tree" ? JointSolve::tree : JointSolve::rows;
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
  if (given(flags.ball_radius_option)) ball.radius = checked(flags.ball_radius_option, flags.ball_radius, [](double r) { return r > 0 && r <= kMaxBallRadius; }, "in (0, 1000]");
  if (given(flags.ball_mass_option)) ball.mass = checked(flags.ball_mass_option, flags.ball_mass, [](double m) { return m > 0 && m <= kMaxBallMass; }, "in (0, 1e9]");
  if (given(flags.ball_restitution_option)) {
    ball.restitution = checked(flags.ball_restitution_option, flags.ball_restitution, unit_interval, "in [0, 1]");
  }
  if (given(flags.ball_speed_option) || given(flags.ball_direction_option)) {
    double speed = ball.velocity.norm();
    Vector3 direction = speed > 0 ? Vector3(ball.velocity / speed) : Vector3(-1, 0, 0);
    if (given(flags.ball_speed_option)) {
      speed = checked(flags.ball_speed_option, flags.ball_speed, [](double v) { return v >= 0 && v <= kMaxBallSpeed; }, "in [0, 1e5]");
    }
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
    model.ground->friction = checked(flags.friction_option, flags.friction, [](double f) { return f >= 0 && f <= kMaxFriction; }, "in [0, 100]");
  }
  if (given(flags.dt_option)) model.settings.time_step = checked(flags.dt_option, flags.dt, [](double v) { return v >= kMinimumTimeStep && v <= 1; }, "in [1e-09, 1]");
  if (given(flags.steps_option) && (flags.steps < 1 || flags.steps > kMaxSteps)) {
    throw InputError(format("--steps: must be in [1, %ld], got %ld", kMaxSteps, flags.steps));
  }
  validate(model);
}

}  // namespace

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
  options.particles.profile = options.springs.profile = options.lagrange.profile = options.featherstone.profile = flags.profile;
  return options;
}

std::optional<double> available_memory() {
  std::ifstream meminfo("/proc/meminfo");
  std::string key, unit;
  double kilobytes = 0;
  while (meminfo >> key >> kilobytes >> unit) {
    if (key == "MemAvailable:") return kilobytes * 1024;
  }
  return std::nullopt;
}

double bytes_per_body(const RunFlags& flags) {
  // Peak resident memory over bodies, the larger of a 10⁶-link chain.json and 10⁵ copies of
  // the humanoid (9·10⁵ bodies), rounded up: `/usr/bin/time -v limber run ... --steps 1`
  // (bench/speed.md, "Linear costs").
  if (flags.method == "springs-implicit") return 9500;  // the implicit step's sparse system
  if (flags.springs()) return 2900;
  if (flags.lagrange()) return 6300;
  if (flags.featherstone()) return 7700;
  return flags.precision == "float" ? 2300 : 2500;
}

void require_memory_for(double bodies, const std::string& source, const std::string& path, const RunFlags& flags,
                        double available) {
  const double needed = bodies * bytes_per_body(flags);
  if (needed <= available) return;
  throw OutOfMemoryError(format("%s: %s: %.4g bodies need about %.3g GB under %s (%.2g kB a body), more than the %.3g GB of memory "
                                "available; ask for fewer, or run on a machine with more memory",
                                source.c_str(), path.c_str(), bodies, needed / 1e9, flags.method.c_str(),
                                bytes_per_body(flags) / 1e3, available / 1e9));
}

LoadedRun load(const RunFlags& flags) {
  SceneOptions scene_options;
  if (given(flags.body_option)) scene_options.variant = flags.body;
  if (given(flags.links_option)) scene_options.links = flags.links;
  scene_options.floating_base = flags.floating_base;
  if (given(flags.copies_option)) scene_options.copies = flags.copies;
  const bool embedded = flags.scene.empty();
  LoadedRun loaded;
  loaded.source = embedded ? "embedded tools/scenes/humanoid.json" : flags.scene;
  // Refuse, before generating them, bodies the memory available cannot hold: not minutes of
  // work ending in an allocation failure (or the kernel's out-of-memory killer).
  if (const std::optional<double> available = available_memory()) {
    scene_options.before_generating = [&flags, &loaded, memory = *available](double bodies, const std::string& path) {
      require_memory_for(bodies, loaded.source, path, flags, memory);
    };
  }
  loaded.scene_path = flags.scene;
  loaded.scene = embedded ? load_scene_text(embedded_humanoid_scene(), loaded.source, scene_options)
                          : load_scene_file(flags.scene, scene_options);
  apply_overrides(loaded.scene.model, flags);
  loaded.options = method_options(flags, loaded.scene.methods);
  if (given(flags.out_option)) loaded.out_path = flags.out_path;
  return loaded;
}

namespace {

// Parses `arguments` as `limber run`'s flags and hands them to `use` while the app that owns
// their option handles lives. Throws std::runtime_error with CLI11's one line.
template <typename Use>
auto with_run_flags(const std::vector<std::string>& arguments, Use use) {
  CLI::App app{"limber run's flags", "limber run"};
  RunFlags flags;
  add_run_flags(app, flags);
  std::vector<const char*> argv{"limber run"};
  for (const std::string& argument : arguments) argv.push_back(argument.c_str());
  try {
    app.parse(int(argv.size()), argv.data());
  } catch (const CLI::ParseError& error) {
    throw std::runtime_error(error.what());
  }
  return use(flags);
}

}  // namespace

LoadedRun load_run(const std::vector<std::string>& run_arguments) {
  return with_run_flags(run_arguments, [](const RunFlags& flags) { return load(flags); });
}

WorldOptions options_for_method(const std::string& method, const MethodSettings& scene) {
  return with_run_flags({"--method", method}, [&](const RunFlags& flags) { return method_options(flags, scene); });
}

WorldOptions options_for_scene(Scene& scene, const std::vector<std::string>& run_arguments) {
  return with_run_flags(run_arguments, [&](const RunFlags& flags) {
    if (!flags.scene.empty()) throw InputError("'" + flags.scene + "': a scene file is loaded by load_scene, not given with the options");
    for (const CLI::Option* option : {flags.body_option, flags.links_option, flags.copies_option, flags.steps_option, flags.out_option}) {
      if (given(option)) throw InputError(option->get_name() + ": is not an option of a loaded scene's World (load_scene takes --body, --links, --copies; a run's --steps and --out are the caller's)");
    }
    if (flags.floating_base) throw InputError("--floating-base: is not an option of a loaded scene's World (load_scene takes it)");
    apply_overrides(scene.model, flags);
    return method_options(flags, scene.methods);
  });
}

}  // namespace limber::cli
