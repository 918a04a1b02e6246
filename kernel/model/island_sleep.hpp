// Sleeping islands (thesis 4.5.3): the rule Settings::sleep describes, one implementation for
// every method. An island (bodies or particles joined by joints) falls asleep once its fastest
// point has stayed below sleep.speed_threshold for sleep.time_to_sleep; the same measure finds a
// divergence (a speed above divergence_speed, or a non-finite one). The particle state's Island
// and the rigid scene's RigidIsland carry it; kernel/sleeping/ applies it to each.
#pragma once

#include <cmath>

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/step_status.hpp"

namespace limber {

struct IslandSleep {
  bool sleeping = false;
  double still_time = 0;  ///< s spent below the sleep speed threshold

  /// Wakes the island; true when it was asleep.
  bool wake() {
    if (!sleeping) return false;
    sleeping = false;
    still_time = 0;
    return true;
  }

  /// After a step of dt s in which the island's fastest point moved at `fastest` m/s (NaN or ∞
  /// when a position became non-finite): folds a divergence into `status` (non-finite outranks
  /// too fast) and returns true when the island falls asleep now — its caller then zeroes its
  /// velocities, so it wakes at rest.
  bool settle(double fastest, double dt, const Settings& settings, StepStatus& status) {
    if (!std::isfinite(fastest)) {
      status = StepStatus::diverged_non_finite;
      return false;
    }
    if (fastest > settings.divergence_speed && status == StepStatus::ok) status = StepStatus::diverged_speed;
    if (!settings.sleep.enabled) return false;
    still_time = fastest < settings.sleep.speed_threshold ? still_time + dt : 0.0;
    sleeping = still_time >= settings.sleep.time_to_sleep && still_time > 0;
    return sleeping;
  }
};

}  // namespace limber
