// World.step and World.run: stepping with the GIL released, one step or many metered in C++ —
// the run a sweep measures (tools/python/limber/sweep.py). A run looks for signals (Ctrl-C) every
// kSignalCheck of wall time, taking the GIL for that moment only: a KeyboardInterrupt stops it
// between two steps, the World consistent and its time saying how far it went.
#include <chrono>
#include <cmath>
#include <exception>
#include <optional>
#include <vector>

#include "limber/kernel/model/checks.hpp"
#include "limber/kernel/study/run_metrics.hpp"
#include "tools/python/module.hpp"

namespace limber::python {
namespace {

using Clock = std::chrono::steady_clock;

// How often a run looks for signals: 50 ms is prompt for a person at a keyboard, and a GIL round
// trip (a few µs) each 50 ms costs nothing measurable.
constexpr Clock::duration kSignalCheck = std::chrono::milliseconds(50);

// What World.run returns: the RunErrors of the steps taken (kernel/study/run_metrics.hpp),
// the wall time spent in World::step alone, the sampled body positions, and why it stopped.
struct MeteredRun {
  long steps = 0;
  StepStatus status = StepStatus::ok;
  const char* stopped = "steps";  // "steps" (all taken), "status" (one was not ok) or "wall_limit"
  double step_seconds = 0;
  study::RunErrors errors;
  study::VerdictBounds bounds;
  std::vector<double> samples;  // K × bodies × 3, m
  std::size_t sample_count = 0;
};

// Runs with the GIL released (taken back only to look for signals); a signal's Python error (a
// KeyboardInterrupt) is thrown as py::error_already_set after the step it came during.
MeteredRun metered_run(World& world, long steps, long sample_every, bool observe, std::optional<double> wall_limit) {
  const Clock::time_point run_start = Clock::now();
  Clock::time_point next_signal_check = run_start + kSignalCheck;
  MeteredRun run;
  std::vector<Pose> poses(world.bodies().size());
  const auto sample = [&] {
    world.poses(poses);
    for (const Pose& pose : poses) run.samples.insert(run.samples.end(), {pose.position.x(), pose.position.y(), pose.position.z()});
    ++run.sample_count;
  };
  if (sample_every > 0) run.samples.reserve(static_cast<std::size_t>(steps / sample_every + 1) * poses.size() * 3);
  std::optional<study::ErrorMeter> meter;
  if (observe) {
    const Observation start = world.observe();
    meter.emplace(start, study::energy_scale(world.model()));
    run.bounds = study::verdict_bounds(world.model(), start);
  }
  if (sample_every > 0) sample();
  while (run.steps < steps) {
    const Clock::time_point before = Clock::now();
    run.status = world.step();
    const Clock::time_point after = Clock::now();
    run.step_seconds += std::chrono::duration<double>(after - before).count();
    if (run.status != StepStatus::ok) {
      run.stopped = "status";
      break;
    }
    ++run.steps;
    if (meter) meter->add(world.observe());
    if (sample_every > 0 && run.steps % sample_every == 0) sample();
    if (after >= next_signal_check) {
      next_signal_check = after + kSignalCheck;
      const py::gil_scoped_acquire gil;
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    }
    if (wall_limit && std::chrono::duration<double>(after - run_start).count() >= *wall_limit) {
      run.stopped = "wall_limit";
      break;
    }
  }
  if (run.steps == steps) run.stopped = "steps";
  if (meter) run.errors = meter->result();
  run.errors.status = run.status;
  return run;
}

py::dict as_dict(MeteredRun&& run, const Model& model, bool observe) {
  py::dict out;
  out["steps"] = run.steps;
  out["stopped"] = run.stopped;
  out["step_seconds"] = run.step_seconds;
  if (observe) {  // the command line's verdict, over every step
    const study::Verdict verdict = study::verdict(run.errors, model, run.bounds);
    out["status"] = verdict.status, out["verdict"] = verdict.text;
    const study::RunErrors& e = run.errors;
    out["max_joint_gap"] = e.max_joint_gap, out["rms_joint_gap"] = e.rms_joint_gap, out["max_link_stretch"] = e.max_link_stretch;
    out["energy_drift"] = e.energy_drift, out["energy_gain"] = e.energy_gain, out["energy_scale"] = e.energy_scale;
    out["deepest_penetration"] = e.deepest_penetration.depth, out["max_limit_violation"] = e.max_limit_violation;
  } else {
    out["status"] = name(run.status);
  }
  const std::size_t bodies = run.sample_count ? run.samples.size() / (3 * run.sample_count) : 0;
  Array samples({static_cast<py::ssize_t>(run.sample_count), static_cast<py::ssize_t>(bodies), py::ssize_t{3}});
  std::copy(run.samples.begin(), run.samples.end(), samples.mutable_data());
  out["samples"] = samples;
  return out;
}

}  // namespace

void bind_running(WorldMethods& world) {
  world
      .def(
          "step", [](World& w, std::optional<double> dt, const py::object& poses) {
            std::optional<std::array<py::array, 2>> arrays;
            if (!poses.is_none()) arrays = pose_arrays(w, poses);  // checked before the step: a bad call changes nothing
            StepStatus status;
            {
              py::gil_scoped_release release;
              status = dt ? w.step(*dt) : w.step();
            }
            if (arrays) fill_poses(w, *arrays);
            return name(status);
          },
          py::arg("dt") = py::none(), py::kw_only(), py::arg("poses") = py::none(),
          "One step of dt s (the scene's time step by default). Returns the status: 'ok' or why not. poses=(positions N×3, "
          "orientations N×4): arrays as poses(out=) takes, filled after the step — a loop that reads every pose each step makes "
          "one call a step, not two.")
      .def(
          "run", [](World& w, long steps, long sample_every, bool observe, std::optional<double> wall_limit) {
            if (steps < 0) throw WorldError("run: steps must be ≥ 0, got " + std::to_string(steps));
            if (sample_every < 0) throw WorldError("run: sample_every must be ≥ 0, got " + std::to_string(sample_every));
            if (wall_limit && !(*wall_limit > 0)) {
              throw WorldError("run: wall_limit must be > 0 s (or None: no limit), got " + checks::format_number(*wall_limit));
            }
            MeteredRun run;
            {
              py::gil_scoped_release release;
              run = metered_run(w, steps, sample_every, observe, wall_limit);
            }
            return as_dict(std::move(run), w.model(), observe);
          },
          py::arg("steps"), py::kw_only(), py::arg("sample_every") = 0, py::arg("observe") = true, py::arg("wall_limit") = py::none(),
          "`steps` steps of the scene's time step in C++, stopping at the first that is not 'ok', or after the step that ends "
          "past wall_limit s of wall time (None: no limit), as a dict: steps (taken), stopped ('steps': all taken, 'status': a "
          "step was not ok, 'wall_limit'), step_seconds (wall time inside the steps alone, s); status: with observe, the run's "
          "verdict over every step, the command line's ('ok', 'inaccurate' when a joint gap, penetration, limit violation or "
          "energy gain passed the scene's settings.tolerances at some step, or the stopping step's status, e.g. "
          "'diverged_speed'), and verdict, the summary's sentence; without, the stopping step's status or 'ok'. With observe, "
          "the run's errors over every step (kernel/study/run_metrics.hpp): max_joint_gap, rms_joint_gap, max_link_stretch "
          "(relative to link length), energy_drift = max |E − E0| and energy_gain = max (E − E0) (J), energy_scale = m·|g|·ΣL "
          "(J), deepest_penetration (m), max_limit_violation (rad; m for a slide); samples: the body positions (K × N × 3 m) "
          "before the first step and after every sample_every steps (K = 0 when sample_every is 0). Ctrl-C (a signal whose "
          "handler raises, looked for every 50 ms) stops it between two steps with that exception (KeyboardInterrupt); "
          "World.time then says how far it went.");
}

}  // namespace limber::python
