// How a step ended and what it did, the same for every method, and the guard every method's
// step() runs inside.
#pragma once

#include <cmath>
#include <cstdint>
#include <utility>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build
#include "limber/kernel/numerics/flush_denormals.hpp"

namespace limber {

/// Outcome of one step. step() never throws; divergence is reported here.
enum class StepStatus : std::uint8_t {
  ok,
  diverged_non_finite,  ///< a position became NaN or infinite
  diverged_speed,       ///< a particle or body exceeded Settings::divergence_speed
  diverged_energy,      ///< the energy rose past its bound (kernel/metrics/divergence.hpp)
  diverged_joint_gap,   ///< a joint came apart, or a particle limb stretched, past its bound (kernel/metrics/divergence.hpp)
  invalid_time_step,    ///< Δt was not a finite number ≥ the method's minimum (kMinimumTimeStep); nothing was done
};

/// The shortest step any method takes, s. Below it a step is refused (invalid_time_step): a
/// subnormal Δt is zero once denormals are flushed, and steps this short carry a body's motion
/// in the last digits of its coordinates (a particle moving at 1 m/s moves 10⁻⁹ m, 10⁷ ulps of
/// a double at 1 m; a float has 10⁻⁷ of a metre there, which is why float particle states
/// take their own minimum, VerletState's minimum_time_step).
inline constexpr double kMinimumTimeStep = 1e-9;

/// Whether step() can take a step of dt seconds: a finite number ≥ `minimum` (s).
inline bool valid_time_step(double dt, double minimum = kMinimumTimeStep) { return dt >= minimum && std::isfinite(dt); }

/// Why the particle method's relaxation stopped in a step (thesis 3.2.3 lists the three).
enum class RelaxationStop : std::uint8_t {
  iterations,  ///< ran the configured number of sweeps
  tolerance,   ///< the largest correction of a sweep fell below the tolerance
  budget,      ///< the wall-clock budget ran out (hard real-time stop)
  idle,        ///< nothing awake to relax
};

/// What one step did, under any method: the status, and what the method's solvers say (a field
/// another method fills stays 0). A particle step of `substeps` substeps sums their sweeps and
/// fallbacks; `stop` and `largest_correction` are the last substep's.
struct StepReport {
  StepStatus status = StepStatus::ok;
  int contacts = 0;  ///< contacts found this step (particles: the most in any one of its substeps)

  // Particles: the relaxation.
  RelaxationStop stop = RelaxationStop::idle;
  int iterations = 0;             ///< sweeps run (position sweeps; rattle runs as many velocity sweeps)
  double largest_correction = 0;  ///< largest particle displacement in the last sweep, m
  int substeps = 0;               ///< substeps run (VerletOptions::relaxation.substeps, or fewer on a divergence)
  /// Rattle: constraint projections that fell back to pbd because their start gradient had
  /// turned too far from the current one (kStartGradientMinimumCosine), once per constraint and
  /// substep.
  std::uint64_t fallbacks = 0;

  // Springs, backward Euler with conjugate gradients: the linear solve.
  int linear_solver_iterations = 0;
  double linear_solver_error = 0;  ///< its relative residual

  // Lagrange: how well the joints hold after the step.
  double constraint_error = 0;  ///< largest |C| of a joint's point and slide rows, m
  double angular_error = 0;     ///< largest |u·v| of a joint's angular rows (≈ rad)
};

/// The shortest step `state` takes, s: kMinimumTimeStep, unless an overload for its type (found
/// by argument-dependent lookup) says more.
template <typename State>
double minimum_time_step(const State&) {
  return kMinimumTimeStep;
}

/// The step guard of every method's step(): a bad dt (valid_time_step with the state's
/// minimum_time_step) is refused (invalid_time_step, nothing done); otherwise `advance(report)`
/// runs with denormals flushed to zero. The report is kept as state.last_report and returned.
template <typename State, typename Advance>
StepReport guarded_step(State& state, double dt, Advance&& advance) {
  StepReport report;
  if (!valid_time_step(dt, minimum_time_step(state))) {
    report.status = StepStatus::invalid_time_step;
  } else {
    const FlushDenormals flush;
    std::forward<Advance>(advance)(report);
  }
  return state.last_report = report;
}

}  // namespace limber
