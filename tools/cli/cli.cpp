#include "tools/cli/cli.hpp"

#include <array>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <new>
#include <optional>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "limber/kernel/featherstone/joint_space_contacts.hpp"
#include "limber/kernel/metrics/divergence.hpp"
#include "limber/kernel/metrics/knock.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/model/capabilities.hpp"
#include "limber/kernel/model/model.hpp"
#include "limber/kernel/relaxation/joint_trees.hpp"
#include "limber/kernel/methods/method.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/study/run_metrics.hpp"
#include "limber/kernel/world/world.hpp"
#include "limber/kernel/world/world_internals.hpp"
#include "limber/layouts/graph/constraint_colouring.hpp"
#include "tools/cli/output_file.hpp"
#include "tools/cli/run_flags.hpp"
#include "tools/cli/trajectory.hpp"

namespace limber::cli {
namespace {

const char* stop_name(RelaxationStop stop) {
  switch (stop) {
    case RelaxationStop::iterations: return "iteration limit";
    case RelaxationStop::tolerance: return "tolerance";
    case RelaxationStop::budget: return "time budget";
    case RelaxationStop::idle: return "idle (all asleep)";
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
    std::size_t constraint_space = 0;
    for (const std::uint8_t flag : direct.in_constraint_space) constraint_space += flag;
    return format("solver      direct: Newton steps of a tree elimination (linear time) over %zu tree%s (%zu in constraint space, "
                  "%zu in particle blocks)%s; %zu loop-closing constraints by Gauss-Seidel; 1 thread\n",
                  trees, trees == 1 ? "" : "s", constraint_space, trees - constraint_space, state.options.warm_start ? ", warm-started" : "",
                  direct.elimination.ordering().loop_constraints.size());
  }
  std::vector<std::size_t> sizes(state.colour_count, 0);
  std::size_t overflow = 0, held = 0;
  for (std::size_t c = 0; c < state.constraints.size(); ++c) {
    const std::uint8_t colour = state.constraint_colour[c];
    const bool movable = state.particles.inverse_mass[state.constraints.particle_i[c]] > 0 ||
                         state.particles.inverse_mass[state.constraints.particle_j[c]] > 0;
    if (colour != kNoColour) ++sizes[colour];
    else if (held_by_joint_tree(state, static_cast<std::uint32_t>(c))) ++held;
    else if (movable) ++overflow;
  }
  const JointTrees& trees = state.plan.joint_trees;
  const std::string in_trees = trees.active() ? format(", %zu held by the joint trees of %zu islands", held, trees.island_components.entries.size()) : "";
  std::string batches;
  for (std::size_t k = 0; k < sizes.size() && k < 8; ++k) batches += (k ? " " : "") + std::to_string(sizes[k]);
  if (sizes.size() > 8) batches += " …";
  if (flags.sweep == "sequential") return format("solver      sequential gauss-seidel, pinned end %s, scalar, 1 thread\n", flags.pinned.c_str());
  const int threads = state.plan.runner->threads();
  const std::string threading = threads == 1 ? "1 thread"
      : format("%d threads (%s) on %scolours of %u+ constraints", threads, flags.threading.c_str(),
               joint_trees_on_threads(state.plan) ? "the joint trees' islands and " : "", state.plan.parallel_minimum_slots);
  return format("solver      %s by colour: %u colours (batches %s), %zu overflow%s; pinned end %s; %s, %s layout, %s\n",
                flags.solver.c_str(), state.colour_count, batches.c_str(), overflow, in_trees.c_str(), flags.pinned.c_str(),
                flags.scalar ? "scalar" : "SIMD", layout_name(state.plan.layout), threading.c_str());
}

// What a run measured, for the summary.
struct RunRecord {
  Observation start, end;
  study::RunErrors errors;  ///< over every step: the verdict's measures (World::observe(), study::ErrorMeter)
  double wall_seconds = 0;
  double drives_released_at = -1;      ///< s: when settings.release_drives_on_impact made the drives limp; −1 never
  long steps_done = 0;
  std::array<long, 4> relaxation_stops{};
  std::uint64_t fallbacks = 0;  ///< rattle projections that fell back to pbd
  std::vector<std::string> sleep_events;
  StepStatus status = StepStatus::ok;
  int contacts = 0, most_contacts = 0;  ///< StepReport::contacts at the end, and the most in a step
  StepProfile profile;                 ///< summed over the run's steps (zeros without --profile)
};

// Steps `world` `steps` times through World::step, the one step path (stopping at its
// divergence verdict), observing after every step. `state` is the world's state, read only.
template <typename State>
RunRecord run_steps(World& world, const State& state, long steps, std::ostream* csv, KnockMeter& knock) {
  RunRecord record;
  record.start = record.end = world.observe();
  study::ErrorMeter meter(record.start, study::energy_scale(world.model()));
  bool body_sleeping = record.start.body_sleeping;
  for (; record.steps_done < steps;) {
    const auto before = std::chrono::steady_clock::now();
    record.status = world.step();
    record.wall_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count();
    ++record.steps_done;
    const StepReport& report = world.last_report();
    record.profile += report.profile;
    if (world.drives_released() && record.drives_released_at < 0) record.drives_released_at = state.time;
    ++record.relaxation_stops[static_cast<int>(report.stop)];
    record.fallbacks += report.fallbacks;
    record.end = world.observe();
    meter.add(record.end);
    record.contacts = report.contacts;
    record.most_contacts = std::max(record.most_contacts, report.contacts);
    knock.update(record.end.time, ball_touching(state), record.end.body_centre_of_mass);
    if (record.end.body_sleeping != body_sleeping && record.sleep_events.size() < 8) {
      record.sleep_events.push_back(format("%s at t = %.3f s", record.end.body_sleeping ? "asleep" : "woke", record.end.time));
    }
    body_sleeping = record.end.body_sleeping;
    if (csv) write_trajectory_row(*csv, world.internals().state);
    if (record.status != StepStatus::ok) break;
  }
  record.errors = meter.result();
  record.errors.status = record.status;
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
  const int threads = state.runner.get() ? state.runner->threads() : 1;
  out << format("contacts    %s, impulses through H's factor (limits held on their Delassus matrix), %d passes, then a position push-out; "
                "each group of islands the contacts join a task, on %d thread%s\n",
                constraints_before_move(state) ? "before the move (speculative)" : "after the move", state.contact_iterations, threads,
                threads == 1 ? "" : "s");
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
                  end.limited_joints == 1 ? "" : "s", record.errors.max_limit_violation, unit(limited_rotation, limited_slide),
                  end.limit_violation);
  }
  if (end.driven_joints > 0) {
    line += format("%s%d drive%s: tracking error %.3g %s at end", line.empty() ? "" : "; ", end.driven_joints,
                   end.driven_joints == 1 ? "" : "s", end.drive_error, unit(driven_rotation, driven_slide));
    if (record.drives_released_at >= 0) line += format(" (limp since the ball hit, t = %.3f s)", record.drives_released_at);
  }
  return "limits      " + (line.empty() ? std::string("none") : line) + "\n";
}

// --profile's lines: per stage, in the order the stages run, its total over the run, its share
// of the steps' time, its time a step and what it did a step (StepProfile). The rigid methods
// time their integrator and their contact detection; "rest" is the step's time outside the
// stages listed. With joint trees, indented rows after `relax` split the trees' time (theirs in
// `relax` and `velocity`; thread time) by what it does.
std::string profile_lines(const RunRecord& record, bool rigid) {
  const StepProfile& p = record.profile;
  const double steps = std::max(1L, record.steps_done);
  const auto per_step = [&](int count) { return count / steps; };
  struct Stage {
    const char* name;
    double seconds;
    std::string counts;
    bool part = false;  // a part of a stage above, not summed into "rest"
  };
  std::vector<Stage> stages{
      {"integrate", p.integrate, format("%.3g substeps", per_step(p.substeps))},
      {"detect", p.detect, rigid ? format("%.4g candidate pairs, %.4g contacts", per_step(p.candidate_pairs), per_step(p.contacts))
                                 : format("%.3g searches, %.4g candidate pairs, %.4g contact rows, %.4g contacts",
                                          per_step(p.limb_searches), per_step(p.candidate_pairs), per_step(p.contact_rows),
                                          per_step(p.contacts))}};
  if (!rigid) {
    stages.push_back({"colour", p.colour, format("%.3g contact colours", per_step(p.contact_colours))});
    std::string relax = format("%.4g position sweeps", per_step(p.position_sweeps));
    if (p.tree_solves > 0) {
      relax += format(", %.4g tree solves of %.3g Newton steps (%.3g%% capped)", per_step(p.tree_solves),
                      static_cast<double>(p.tree_newton_steps) / p.tree_solves, 100.0 * p.tree_capped / p.tree_solves);
      relax += format("; %.4g factors (in SIMD lanes %.3g%% full), %.4g inverse diagonals, %.4g back-substitutions, %.4g path solves",
                      per_step(p.tree_factors), p.tree_lane_slots > 0 ? 100.0 * p.tree_factors / p.tree_lane_slots : 0.0,
                      per_step(p.tree_inverse_diagonals), per_step(p.tree_substitutions), per_step(p.tree_path_solves));
    }
    stages.push_back({"relax", p.relax, relax});
    if (p.tree_solves > 0) {
      stages.push_back({"  staging", p.tree_staging, "trees: limb loads, joint assembly, limit measures", true});
      stages.push_back({"  eliminate", p.tree_elimination, "trees: gathers into lanes, factors, solves, scatters", true});
      stages.push_back({"  moves", p.tree_moves, "trees: the limbs' rigid moves", true});
      stages.push_back({"  contacts", p.tree_contacts, "trees: contact impulses, loads, overshoot", true});
    }
    stages.push_back({"velocity", p.velocity, format("%.4g velocity sweeps", per_step(p.velocity_sweeps))});
    stages.push_back({"restitution", p.restitution, ""});
    stages.push_back({"sleep", p.sleep, ""});
  }
  double staged = 0;
  for (const Stage& stage : stages) staged += stage.part ? 0.0 : stage.seconds;
  stages.push_back({"rest", p.step - staged, rigid ? "contact response, projections, sleep" : "outside the stages"});
  stages.push_back({"step", p.step, ""});
  std::string lines = "profile     stage        total ms  % of step    us/step  per step\n";
  for (const Stage& stage : stages) {
    lines += format("profile     %-11s %9.3f %9.1f%% %10.2f", stage.name, 1e3 * stage.seconds, p.step > 0 ? 100 * stage.seconds / p.step : 0.0,
                    1e6 * stage.seconds / steps);
    lines += (stage.counts.empty() ? "" : "  " + stage.counts) + "\n";
  }
  return lines;
}

// Runs the model under the flags' method and prints the summary; returns the exit code.
template <typename State>
int simulate(World& world, const State& state, const RunFlags& flags, const std::string& source, std::ostream& out) {
  const Model& model = world.model();
  const MethodState& variant = world.internals().state;
  const double dt = model.settings.time_step;
  const long steps = given(flags.steps_option) ? flags.steps : std::max(1L, std::lround(model.settings.duration / dt));
  std::optional<OutputFile> csv;  // renamed into place once the run is summed up
  if (given(flags.out_option)) {
    csv.emplace(flags.out_path, "--out", std::vector<std::filesystem::path>{flags.scene});
    write_trajectory_header(csv->stream(), model, variant);
    std::ostringstream first_row;
    write_trajectory_row(first_row, variant);
    csv->require_space(double(steps) * double(first_row.view().size()));
    csv->stream() << first_row.view();
  }
  const Observation start = world.observe();
  KnockMeter knock(model.balls.empty() ? Eigen::Vector3d::UnitX() : model.balls.front().velocity, start.body_centre_of_mass);
  const RunRecord record = run_steps(world, state, steps, csv ? &csv->stream() : nullptr, knock);
  const Observation& end = record.end;

  out << "limber run: " << model.name << " (" << source << ")\n";
  method_lines(out, model, flags, state, record);
  if (has_joint_gaps(state)) {
    out << format("joint gap   final max %.3g, rms %.3g; largest in run %.3g (relative to link length)\n",
                  end.max_joint_gap, end.rms_joint_gap, record.errors.max_joint_gap);
  } else {
    out << "joint gap   none (shared-particle joints or no joints)\n";
  }
  out << limits_line(model, record);
  out << format("contacts    %d at end, at most %d in a step; penetration %.3g m deepest in run (limbs, colliders, ground)\n",
                record.contacts, record.most_contacts, record.errors.deepest_penetration.depth);
  if (!flags.rigid()) {
    out << format("stretch     final max %.3g; largest in run %.3g (relative to link length)\n", end.max_link_stretch,
                  record.errors.max_link_stretch);
  }
  const Eigen::Vector3d travel = end.body_centre_of_mass - start.body_centre_of_mass;
  out << format("body        centre of mass %s -> %s m; travelled %.4g m horizontally\n",
                vector_text(start.body_centre_of_mass).c_str(), vector_text(end.body_centre_of_mass).c_str(),
                std::hypot(travel.x(), travel.y()));
  if (knock.touched()) {
    out << format("impact      ball first touched the body at t = %.3f s; in the next %.1f s the body's centre of mass moved %.4f m along the ball's path\n",
                  knock.first_contact_time(), knock.window(), knock.distance());
  }
  const DivergenceBounds bounds = divergence_bounds(model, start);
  const double drift = end.energy() - start.energy();
  out << format("energy      %.6g J at start (kinetic %.4g), %.6g J at end (kinetic %.4g); drift %+.4g J, %+.3g%% of the scene's "
                "energy scale (%.4g J)\n", start.energy(), start.kinetic_energy, end.energy(), end.kinetic_energy, drift,
                100 * drift / bounds.energy_scale, bounds.energy_scale);
  out << format("momentum    %s -> %s kg m/s\n", vector_text(start.linear_momentum).c_str(),
                vector_text(end.linear_momentum).c_str());
  out << "sleeping    body " << (start.body_sleeping ? "asleep" : "awake") << " at start";
  for (const std::string& event : record.sleep_events) out << "; " << event;
  out << "; " << (end.body_sleeping ? "asleep" : "awake") << " at end\n";
  out << "status      " << study::verdict(record.errors, model, study::verdict_bounds(model, start)).text << "\n";
  if (flags.profile) out << profile_lines(record, flags.rigid());
  if (csv) csv->commit();  // a diverged run's trajectory is a result too: kept up to the divergence
  return record.status == StepStatus::ok ? kSuccess : kDiverged;
}

int simulate(LoadedRun loaded, const RunFlags& flags, std::ostream& out) {
  World world(std::move(loaded.scene.model), loaded.options);
  return std::visit([&](const auto& state) { return simulate(world, state, flags, loaded.source, out); }, world.internals().state);
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
  if (!flags.screenshot.empty()) (void)checked_output_path(flags.screenshot, "--screenshot", {run_flags.scene});
  (void)load(run_flags);  // a bad scene or flag is the same one line as `limber run`'s, before any window
  if (viewer == nullptr) {
    throw InputError("view: this limber was built without the viewer (it needs GLFW, OpenGL and Dear ImGui: tools/setup.sh --viewer)");
  }
  ViewRequest request{std::move(run_arguments), flags.frames, flags.screenshot, flags.hide_ui, flags.overlays, flags.camera, flags.width, flags.height};
  return viewer(request, out, err);
}


// The note a method that collides boxes and ellipsoids as capsule proxies gives (capsule_proxy.hpp),
// naming the first such body and how many more; empty when none or when the method collides them
// as themselves (MethodCapabilities::true_shapes).
std::string capsule_proxy_note(const LoadedRun& loaded) {
  if (capabilities(loaded.options.method).true_shapes) return {};
  const std::vector<Body>& bodies = loaded.scene.model.bodies;
  const auto first = std::find_if(bodies.begin(), bodies.end(), [](const Body& body) { return has_half_extents(body.shape); });
  if (first == bodies.end()) return {};
  const auto more = std::count_if(first + 1, bodies.end(), [](const Body& body) { return has_half_extents(body.shape); });
  std::string exact;  // the methods that collide them as themselves
  for (const MethodCapabilities& entry : kMethodCapabilities) {
    if (entry.true_shapes) exact += (exact.empty() ? "" : ", ") + std::string(method_name(entry.method));
  }
  return "bodies[" + std::to_string(first - bodies.begin()) + "] '" + first->name + "'" +
         (more > 0 ? " and " + std::to_string(more) + " more box and ellipsoid bodies" : ", a " + std::string(shape_type_name(first->shape.type)) + ",") +
         " collide as capsule proxies under the " + std::string(method_name(loaded.options.method)) +
         " method (the capsule along the longest axis, radius the shortest half-extent; mass and inertia exact); " + exact +
         " collide them as themselves";
}
}  // namespace

int run_main(int argc, const char* const* argv, std::ostream& out, std::ostream& err, Viewer viewer) {
  CLI::App app{"limber: articulated bodies with distributed mass (Verlet with weighted relaxation, and more)", "limber"};
  app.set_version_flag("--version", "limber " LIMBER_VERSION);  // the project() version in CMakeLists.txt
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
    LoadedRun loaded = load(flags);
    for (const std::string& note : loaded.scene.notes) err << "limber: note: " << note << "\n";  // what a model file's loader dropped
    if (const std::string proxies = capsule_proxy_note(loaded); !proxies.empty()) err << "limber: note: " << proxies << "\n";
    return simulate(std::move(loaded), flags, out);
  } catch (const ModelError& error) {
    err << "limber: " << error.what() << "\n";
  } catch (const InputError& error) {
    err << "limber: " << error.what() << "\n";
  } catch (const std::invalid_argument& error) {  // options that do not go together (compile's)
    err << "limber: " << error.what() << "\n";
  } catch (const OutOfMemoryError& error) {
    err << "limber: " << error.what() << "\n";
    return kOutOfMemory;
  } catch (const std::bad_alloc&) {
    err << "limber: out of memory: an allocation failed (std::bad_alloc); ask for fewer bodies or steps, or run on a "
           "machine with more memory\n";
    return kOutOfMemory;
  } catch (const std::exception& error) {
    err << "limber: unexpected error: " << error.what() << "\n";
  }
  return kBadInput;
}

}  // namespace limber::cli
