// The step guard every method's step() runs inside (kernel/PIPELINE.md): a bad time step refused,
// denormals flushed, the step timed and its report kept. Kept apart from step_status.hpp so that
// what reads a report (world.hpp) does not include the floating-point mode's header.
#pragma once

#include <utility>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build
#include "limber/kernel/model/step_status.hpp"
#include "limber/kernel/numerics/flush_denormals.hpp"

namespace limber {

/// The step guard of every method's step(): a bad dt (valid_time_step with the state's
/// minimum_time_step) is refused (invalid_time_step, nothing done); otherwise `advance(report)`
/// runs with denormals flushed to zero. With state.options.profile, the whole step's time is
/// report.profile.step. The report is kept as state.last_report and returned.
template <typename State, typename Advance>
StepReport guarded_step(State& state, double dt, Advance&& advance) {
  StageClock clock(state.options.profile);
  StepReport report;
  if (!valid_time_step(dt, minimum_time_step(state))) {
    report.status = StepStatus::invalid_time_step;
  } else {
    const FlushDenormals flush;
    std::forward<Advance>(advance)(report);
  }
  report.profile.step = clock.lap();
  return state.last_report = report;
}

}  // namespace limber
