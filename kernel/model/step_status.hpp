// How a step ended: the same for every method.
#pragma once

#include <cmath>
#include <cstdint>

namespace limber {

/// Outcome of one step. step() never throws; divergence is reported here.
enum class StepStatus : std::uint8_t {
  ok,
  diverged_non_finite,  ///< a position became NaN or infinite
  diverged_speed,       ///< a particle or body exceeded Settings::divergence_speed
  invalid_time_step,    ///< Δt was not a positive finite number; nothing was done
};

/// Whether step() can take a step of dt seconds: a positive finite number. Every method's step()
/// reports invalid_time_step and does nothing otherwise.
inline bool valid_time_step(double dt) { return dt > 0 && std::isfinite(dt); }

}  // namespace limber
