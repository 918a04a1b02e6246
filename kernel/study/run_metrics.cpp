#include "limber/kernel/study/run_metrics.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "limber/kernel/metrics/divergence.hpp"

namespace limber::study {

double energy_scale(const Model& model) {
  double length = 0;
  for (const Body& body : model.bodies) length += has_half_extents(body.shape) ? 2 * body.shape.half_extents.maxCoeff() : body.shape.length;
  const double mass = model.body_mass(), gravity = model.settings.gravity.norm();
  return gravity > 0 ? mass * gravity * length : mass * 1.0;
}

ErrorMeter::ErrorMeter(const Observation& start, double energy_scale) : start_energy_(start.energy()) {
  errors_.energy_scale = energy_scale;
  errors_.max_link_stretch = start.max_link_stretch;
  add_worst(start);
}

// The worst joint gap, limit violation and penetration so far, and when.
void ErrorMeter::add_worst(const Observation& observation) {
  if (observation.max_joint_gap > errors_.max_joint_gap) {
    errors_.max_joint_gap = observation.max_joint_gap, errors_.joint_gap_time = observation.time;
    errors_.widest_joint = observation.widest_joint;
  }
  if (observation.joints.limit_violation > errors_.max_limit_violation) {
    errors_.max_limit_violation = observation.joints.limit_violation, errors_.limit_time = observation.time;
  }
  if (observation.penetration.depth > errors_.deepest_penetration.depth) {
    errors_.deepest_penetration = observation.penetration, errors_.penetration_time = observation.time;
  }
}

void ErrorMeter::add(const Observation& observation) {
  ++errors_.steps;
  add_worst(observation);
  errors_.max_link_stretch = std::max(errors_.max_link_stretch, observation.max_link_stretch);
  squared_rms_sum_ += observation.rms_joint_gap * observation.rms_joint_gap;
  errors_.rms_joint_gap = std::sqrt(squared_rms_sum_ / errors_.steps);
  const double change = observation.energy() - start_energy_;
  // NaN compares false: carry it through explicitly so a non-finite run cannot look exact.
  if (!std::isfinite(change)) {
    errors_.energy_drift = errors_.energy_gain = std::numeric_limits<double>::infinity();
    return;
  }
  errors_.energy_drift = std::max(errors_.energy_drift, std::abs(change));
  errors_.energy_gain = std::max(errors_.energy_gain, change);
}

RunErrors ErrorMeter::result() const { return errors_; }

namespace {

// printf into a std::string, for the verdict's sentence.
template <typename... Values>
std::string text(const char* pattern, Values... values) {
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, pattern, values...);
  return buffer;
}

// A body or ball of Penetration's numbering, by name.
std::string side_name(const Model& model, int side) {
  const auto index = static_cast<std::size_t>(side);
  return index < model.bodies.size() ? model.bodies[index].name : ball_name(model, index - model.bodies.size());
}

// The unit of a limit violation: rad, m for a prismatic range, or both.
const char* limit_unit(const Model& model) {
  bool turns = false, slides = false;
  for (const Joint& joint : model.joints) {
    if (joint.limits.any()) (joint.type == JointType::prismatic ? slides : turns) = true;
    for (const SerialAxis& axis : joint.serial_axes) {
      if (axis.range) (axis.slide ? slides : turns) = true;
    }
  }
  return slides && turns ? "rad (m for a slide)" : slides ? "m" : "rad";
}

}  // namespace

std::string penetration_place(const Model& model, const Penetration& penetration) {
  if (penetration.first < 0) return "nothing";
  const std::string other = penetration.second >= 0 ? side_name(model, penetration.second)
                            : penetration.collider >= 0 ? model.colliders[static_cast<std::size_t>(penetration.collider)].name
                                                        : std::string("the ground");
  return side_name(model, penetration.first) + " into " + other;
}

VerdictBounds verdict_bounds(const Model& model, const Observation& start) {
  const Tolerances& tolerances = model.settings.tolerances;
  VerdictBounds bounds;
  bounds.joint_gap = tolerances.joint_gap, bounds.limit = tolerances.limit;
  double thinnest = std::numeric_limits<double>::infinity();
  for (const Body& body : model.bodies) {
    const double half_thickness = has_half_extents(body.shape) ? body.shape.half_extents.minCoeff() : body.shape.radius;
    if (half_thickness > 0) thinnest = std::min(thinnest, half_thickness);
  }
  bounds.penetration = tolerances.penetration.value_or(std::isfinite(thinnest) ? thinnest : 0.01);
  const bool driven = !model.actuators.empty() ||
                      std::any_of(model.joints.begin(), model.joints.end(), [](const Joint& joint) { return joint.drive.has_value(); });
  bounds.energy_gain = tolerances.energy_gain.value_or(driven ? 1.0 : kAccuracyEnergyGain);
  bounds.energy_scale = divergence_bounds(model, start).energy_scale;
  return bounds;
}

Verdict verdict(const RunErrors& errors, const Model& model, const VerdictBounds& bounds) {
  if (errors.status != StepStatus::ok) return {name(errors.status), describe(errors.status)};
  std::string flags;
  const auto flag = [&](const std::string& what) { flags += (flags.empty() ? "" : "; ") + what; };
  const double gap = std::max(errors.max_joint_gap, errors.max_link_stretch);
  if (!(gap <= bounds.joint_gap)) {
    const bool joint = errors.max_joint_gap >= errors.max_link_stretch && errors.widest_joint >= 0 &&
                       static_cast<std::size_t>(errors.widest_joint) < model.joints.size();
    if (joint) {
      flag(text("joint '%s' open by %.3g of a link, at t = %.3f s (tolerance %g)",
                model.joints[static_cast<std::size_t>(errors.widest_joint)].name.c_str(), gap, errors.joint_gap_time, bounds.joint_gap));
    } else {
      flag(text("joints open (or links stretched) by %.3g of a link, at t = %.3f s (tolerance %g)", gap, errors.joint_gap_time,
                bounds.joint_gap));
    }
  }
  const Penetration& deepest = errors.deepest_penetration;
  if (!(deepest.depth <= bounds.penetration)) {
    flag(text("penetration %.3g m, %s at t = %.3f s (tolerance %g m)", deepest.depth, penetration_place(model, deepest).c_str(),
              errors.penetration_time, bounds.penetration));
  }
  if (!(errors.max_limit_violation <= bounds.limit)) {
    flag(text("a limit passed by %.3g %s, at t = %.3f s (tolerance %g)", errors.max_limit_violation, limit_unit(model),
              errors.limit_time, bounds.limit));
  }
  const double gain = errors.energy_gain / bounds.energy_scale;
  if (!(gain <= bounds.energy_gain)) {
    flag(text("energy gained %.3g of the scene's energy scale (tolerance %g)", gain, bounds.energy_gain));
  }
  return flags.empty() ? Verdict{"ok", "ok"} : Verdict{"inaccurate", "inaccurate: " + flags};
}

namespace {

// The largest over common sample times of `measure(points, reference points)`; infinite for a
// run that stopped early or measured non-finite.
template <typename Measure>
double largest_over_samples(const Trajectory& run, const Trajectory& reference, Measure&& measure) {
  if (std::abs(run.sample_interval - reference.sample_interval) > 1e-9) {
    throw std::invalid_argument("trajectory_error: sample intervals differ");
  }
  if (run.samples.size() < reference.samples.size()) return std::numeric_limits<double>::infinity();
  double largest = 0;
  for (std::size_t k = 0; k < reference.samples.size(); ++k) {
    const auto& a = run.samples[k];
    const auto& b = reference.samples[k];
    if (a.size() != b.size()) throw std::invalid_argument("trajectory_error: the trajectories have different point counts");
    const double value = measure(a, b);
    if (!std::isfinite(value)) return std::numeric_limits<double>::infinity();
    largest = std::max(largest, value);
  }
  return largest;
}

}  // namespace

double trajectory_error(const Trajectory& run, const Trajectory& reference) {
  return largest_over_samples(run, reference, [](const auto& a, const auto& b) {
    double squares = 0;
    for (std::size_t i = 0; i < a.size(); ++i) squares += (a[i] - b[i]).squaredNorm();
    return a.empty() ? 0.0 : std::sqrt(squares / a.size());
  });
}

double max_point_error(const Trajectory& run, const Trajectory& reference) {
  return largest_over_samples(run, reference, [](const auto& a, const auto& b) {
    double largest = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const double distance = (a[i] - b[i]).norm();
      largest = std::isnan(distance) ? distance : std::max(largest, distance);
    }
    return largest;
  });
}

ObservedRun observe_run(Simulation& simulation, double duration, double sample_interval,
                        const std::function<bool(const RunErrors&)>& stop_when) {
  const double dt = simulation.time_step();
  const long steps = std::lround(duration / dt);
  long steps_per_sample = 0;
  if (sample_interval > 0) {
    const double ratio = sample_interval / dt;
    steps_per_sample = std::lround(ratio);
    if (steps_per_sample < 1 || std::abs(ratio - steps_per_sample) > 1e-6) {
      throw std::invalid_argument("observe_run: the sample interval is not a whole number of time steps");
    }
  }
  ObservedRun run;
  run.trajectory.sample_interval = sample_interval;
  std::vector<Eigen::Vector3d> points;
  auto sample = [&] {
    simulation.limb_points(points);
    run.trajectory.samples.push_back(points);
  };
  if (steps_per_sample) sample();
  ErrorMeter meter(simulation.observe(), energy_scale(simulation.model()));
  for (long s = 1; s <= steps; ++s) {
    const StepStatus status = simulation.step();
    if (status != StepStatus::ok) {
      run.errors = meter.result();
      run.errors.status = status;
      return run;
    }
    meter.add(simulation.observe());
    if (steps_per_sample && s % steps_per_sample == 0) sample();
    if (stop_when && stop_when(meter.result())) break;
  }
  run.errors = meter.result();
  return run;
}

double wall_time_per_simulated_second(const Scene& scene, const Method& method, double duration, int repeats) {
  std::vector<double> times;
  const long steps = std::lround(duration / method.time_step);
  for (int r = 0; r < std::max(1, repeats); ++r) {
    Simulation simulation(scene, method);
    long done = 0;
    const auto start = std::chrono::steady_clock::now();
    while (done < steps && simulation.step() == StepStatus::ok) ++done;
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    times.push_back(seconds / (std::max<long>(done, 1) * method.time_step));
  }
  std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
  return times[times.size() / 2];
}

Stability classify(const RunErrors& errors, const StabilityBounds& bounds) {
  if (errors.status != StepStatus::ok || !std::isfinite(errors.energy_gain) || !std::isfinite(errors.max_joint_gap) ||
      !std::isfinite(errors.max_link_stretch)) {
    return Stability::non_finite;
  }
  if (errors.relative_energy_gain() > bounds.energy_gain) return Stability::energy_growth;
  if (std::max(errors.max_joint_gap, errors.max_link_stretch) > bounds.joint_gap) return Stability::joint_gap;
  return Stability::stable;
}

const char* name(Stability stability) {
  switch (stability) {
    case Stability::stable: return "stable";
    case Stability::non_finite: return "non-finite";
    case Stability::energy_growth: return "energy growth";
    case Stability::joint_gap: return "joint gap";
  }
  return "?";
}

}  // namespace limber::study
