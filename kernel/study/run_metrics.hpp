// What a run costs and how wrong it is: the measures of the run-time-against-error studies and
// the stability classification of the stress runs. Every method is measured by the
// same code from the same Observation (kernel/metrics/observers.hpp) and the same limb points
// (Simulation::limb_points), so the numbers compare across methods.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/study/simulation.hpp"

namespace limber::study {

/// The scale energy errors are measured against, J: the bodies' weight times the sum of their
/// limbs' lengths, m·|g|·ΣL — the potential energy a chain exchanges when it swings from
/// horizontal to hanging, within a factor of 2. Never 0 for a valid model with gravity; with
/// zero gravity, the bodies' mass × (1 m/s)² instead.
double energy_scale(const Model& model);

/// Errors of one run, largest or averaged over every step.
struct RunErrors {
  /// Joint gaps and link stretch, relative (Observation's definitions): the largest over the
  /// run, and the root mean square over steps of each step's RMS gap over joints.
  double max_joint_gap = 0, rms_joint_gap = 0, max_link_stretch = 0;
  /// max |E(t) − E(0)| and max (E(t) − E(0)) over the run, J (kinetic + gravitational; the
  /// particle methods' kinetic energy uses v = (x − x*)/Δt, so it is only first-order accurate).
  double energy_drift = 0, energy_gain = 0;
  double energy_scale = 1;  ///< J, energy_scale(model)
  /// The largest limit violation over the run (rad; m for a prismatic range; Observation::joints).
  double max_limit_violation = 0;
  /// The deepest penetration over the run (Observation::penetration, which World::observe()
  /// measures) and when (s); the times of the largest joint gap and limit violation.
  Penetration deepest_penetration;
  double joint_gap_time = 0, penetration_time = 0, limit_time = 0;
  int widest_joint = -1;  ///< the joint open by max_joint_gap (Observation::widest_joint), −1 none
  /// Pointwise trajectory error against a reference, m: the largest over common sample times of
  /// the RMS distance between the two runs' limb points (trajectory_error()). NaN: not measured.
  double trajectory_error = std::numeric_limits<double>::quiet_NaN();
  long steps = 0;                    ///< steps taken (fewer than asked when the run stopped)
  StepStatus status = StepStatus::ok;  ///< the step that stopped the run, or ok

  double relative_energy_drift() const { return energy_drift / energy_scale; }
  double relative_energy_gain() const { return energy_gain / energy_scale; }
};

/// Accumulates RunErrors from one observation per step.
class ErrorMeter {
 public:
  /// `start`: the observation before the first step.
  ErrorMeter(const Observation& start, double energy_scale);
  void add(const Observation& observation);
  RunErrors result() const;

 private:
  void add_worst(const Observation& observation);

  RunErrors errors_;
  double start_energy_ = 0, squared_rms_sum_ = 0;
};

/// What a run's verdict measures against: Settings::tolerances with the absent bounds derived
/// (model.hpp says how), and the World's energy scale (divergence_bounds: M·|g|·extent plus the
/// start's kinetic energy), J.
struct VerdictBounds {
  double joint_gap = 0, penetration = 0, limit = 0, energy_gain = 0;
  double energy_scale = 1;
};
/// The bounds for a run of `model` from the observation `start`.
VerdictBounds verdict_bounds(const Model& model, const Observation& start);

/// A run's verdict, the one the command line's summary, Python's World.run and a sweep give:
/// `status` is "ok", "inaccurate" (it held together but some measure passed its bound at some
/// step), or the stopping step's status (name(StepStatus): "diverged_speed", …); `text` says it
/// in a line — "ok", "inaccurate: penetration 0.52 m (…); …" or the divergence's description.
struct Verdict {
  std::string status;
  std::string text;
};
/// The verdict of `errors` (an ErrorMeter's, over every step with World::observe()'s
/// penetration), naming `model`'s bodies.
Verdict verdict(const RunErrors& errors, const Model& model, const VerdictBounds& bounds);

/// Where `penetration` is, by `model`'s names: "shin into the ground", "forearm into upper_arm",
/// "ball into stairs", or "nothing".
std::string penetration_place(const Model& model, const Penetration& penetration);

/// Limb points (Simulation::limb_points) sampled every `sample_interval` seconds from t = 0.
struct Trajectory {
  double sample_interval = 0;                         ///< s
  std::vector<std::vector<Eigen::Vector3d>> samples;  ///< samples[k]: the points at t = k·interval
};

/// The largest, over the sample times both trajectories have, of the RMS distance between their
/// points, m. A run that stopped early (fewer samples than `reference`) or produced a
/// non-finite point is infinitely wrong. Throws std::invalid_argument when the sample
/// intervals differ by more than 10⁻⁹ s or the point counts differ.
double trajectory_error(const Trajectory& run, const Trajectory& reference);

/// The largest, over the common sample times and the points, of the distance between a point
/// and the reference's, m — the worst point at its worst moment (the heavy end, usually);
/// infinite like trajectory_error() for a run that stopped early or went non-finite. Throws
/// std::invalid_argument as trajectory_error() does.
double max_point_error(const Trajectory& run, const Trajectory& reference);

/// One run of `duration` seconds, observed after every step.
struct ObservedRun {
  RunErrors errors;
  Trajectory trajectory;  ///< empty unless a sample interval was given
};

/// Steps `simulation` for `duration` s (rounded to whole steps), observing after every step;
/// stops at a diverged step. With `sample_interval` > 0 (which must be a whole number of time
/// steps, to 10⁻⁶ of a step, or std::invalid_argument is thrown) it records the trajectory.
/// `stop_when` (optional) ends the run early when it returns true for the errors so far — the
/// stress runs stop at the first sign of divergence.
ObservedRun observe_run(Simulation& simulation, double duration, double sample_interval = 0,
                        const std::function<bool(const RunErrors&)>& stop_when = {});

/// Median over `repeats` fresh runs of the wall time per simulated second (s/s) of stepping
/// `method` on `scene` for `duration` s, compile excluded and nothing observed — the cost of
/// the method alone. A run that diverges stops there; its time is per simulated second done.
double wall_time_per_simulated_second(const Scene& scene, const Method& method, double duration, int repeats);

/// How a stress run ended (bench/reliability.md, "Stability stress").
enum class Stability : std::uint8_t {
  stable,
  non_finite,     ///< NaN or infinite state, or a speed beyond Settings::divergence_speed
  energy_growth,  ///< gained more energy than StabilityBounds::energy_gain allows
  joint_gap,      ///< a joint gap or link stretch beyond StabilityBounds::joint_gap
};

/// What counts as diverged. Gains are relative to energy_scale(): a conservative or dissipative
/// method gains nothing but rounding (and the particle methods' first-order kinetic energy, a
/// few percent at large steps); a method blowing up gains orders of magnitude. Gaps are relative
/// to link length: beyond half a link a joint has come apart.
struct StabilityBounds {
  double energy_gain = 0.5;
  double joint_gap = 0.5;
};

Stability classify(const RunErrors& errors, const StabilityBounds& bounds = {});
const char* name(Stability stability);

}  // namespace limber::study
