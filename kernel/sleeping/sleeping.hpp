// Sleeping islands (thesis 4.5.3): bodies at rest cost nothing until a contact or force wakes them.
//
// An island is a connected set of particles stored contiguously (compile.cpp), so every pass
// walks state.awake_islands — a few index ranges — and a sleeping island is simply absent. An
// island falls asleep once all its particles have stayed below Settings::sleep.speed_threshold
// for sleep.time_to_sleep (IslandSleep, kernel/model/island_sleep.hpp: the rule every method
// shares); its velocity is then zeroed (x_previous = x, and v = 0 under the rattle rule), so it
// wakes at rest.
#pragma once

#include <cmath>
#include <cstdint>

#include "limber/kernel/particles/verlet_state.hpp"

namespace limber {

/// Refreshes state.awake_islands (ascending island order) after islands slept or woke.
template <typename Scalar>
void rebuild_awake_islands(VerletState<Scalar>& state) {
  state.awake_islands.clear();
  ++state.awake_generation;
  for (std::uint32_t k = 0; k < state.islands.size(); ++k) {
    if (!state.islands[k].sleeping) state.awake_islands.push_back(k);
  }
}

/// Wakes island `k` (no-op when awake). Returns true when it was asleep.
template <typename Scalar>
bool wake_island(VerletState<Scalar>& state, std::uint32_t k) {
  if (!state.islands[k].wake()) return false;
  rebuild_awake_islands(state);
  return true;
}

/// Puts island k to sleep at rest (its particles' velocities zeroed, so it wakes at rest): what
/// falling asleep does, and what an engine asks for with World::sleep. The caller rebuilds the
/// awake islands.
template <typename Scalar>
void rest_island(VerletState<Scalar>& state, std::uint32_t k) {
  Island& island = state.islands[k];
  island.sleeping = true;
  for (std::uint32_t p = island.particle_begin; p < island.particle_end; ++p) {
    state.particles.set_previous(p, state.particles.position(p));
    state.particles.set_velocity(p, ParticleBuffer<Scalar>::Vector3::Zero());
  }
}

/// After a step of length dt: measures each awake island's fastest particle, reports divergence
/// (non-finite or faster than settings.divergence_speed), and puts islands that have been still
/// for long enough to sleep.
template <typename Scalar>
StepStatus update_sleep(VerletState<Scalar>& state, double dt) {
  const auto& x = state.particles;
  StepStatus status = StepStatus::ok;
  bool changed = false;
  const bool rattle = uses_rattle(state);
  for (std::uint32_t k : state.awake_islands) {
    Island& island = state.islands[k];
    double largest_step2 = 0;
    for (std::uint32_t p = island.particle_begin; p < island.particle_end; ++p) {
      // The step's displacement (pbd), or v·Δt (rattle: v comes from the positions, so a
      // non-finite position makes it non-finite too).
      const double dx = rattle ? x.velocity_x[p] * dt : x.position_x[p] - x.previous_x[p];
      const double dy = rattle ? x.velocity_y[p] * dt : x.position_y[p] - x.previous_y[p];
      const double dz = rattle ? x.velocity_z[p] * dt : x.position_z[p] - x.previous_z[p];
      const double step2 = dx * dx + dy * dy + dz * dz;
      largest_step2 = step2 > largest_step2 || std::isnan(step2) ? step2 : largest_step2;
    }
    if (island.settle(std::sqrt(largest_step2) / dt, dt, state.settings, status)) {
      changed = true;
      rest_island(state, k);
    }
  }
  if (changed) rebuild_awake_islands(state);
  return status;
}

}  // namespace limber
