// GCC 12 false positive inside Eigen's AVX-512 code (bug 105593); must precede Eigen's headers.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "kernel/springs/step.hpp"

#include <cmath>

#include "kernel/numerics/flush_denormals.hpp"
#include "kernel/springs/contacts.hpp"
#include "kernel/springs/implicit_step.hpp"
#include "kernel/springs/spring_forces.hpp"

namespace limber {
namespace {

RigidIntegrator explicit_integrator(SpringIntegrator integrator) {
  switch (integrator) {
    case SpringIntegrator::euler: return RigidIntegrator::euler;
    case SpringIntegrator::rk2: return RigidIntegrator::rk2;
    case SpringIntegrator::rk4: return RigidIntegrator::rk4;
    case SpringIntegrator::semi_implicit_euler:
    case SpringIntegrator::backward_euler: break;
  }
  return RigidIntegrator::semi_implicit_euler;
}

// Divergence, and sleep for islands whose bodies' fastest surface points all stayed slow for
// Settings::sleep.time_to_sleep.
StepStatus update_sleep(SpringState& state, double dt) {
  const Settings& settings = state.settings;
  StepStatus status = StepStatus::ok;
  body_velocities(state, state.bodies.state);
  for (RigidIsland& island : state.islands) {
    if (island.sleeping) continue;
    double fastest = 0;
    bool finite = true;
    for (std::uint32_t b : island.bodies) {
      // The fastest surface point: spin about the limb's axis moves it at most ω·r, the rest at
      // most |ω⊥|·(L/2 + r).
      const Eigen::Vector3d axis = state.bodies.state.orientation[b] * (state.shapes.principal_frame[b].conjugate() * Eigen::Vector3d::UnitZ());
      const Eigen::Vector3d& omega = state.angular_velocity[b];
      const double axial = omega.dot(axis);
      const double speed = state.velocity[b].norm() + std::abs(axial) * state.shapes.radius[b] +
                           (omega - axial * axis).norm() * (0.5 * state.shapes.length[b] + state.shapes.radius[b]);
      finite = finite && std::isfinite(speed) && state.bodies.state.position[b].allFinite();
      fastest = std::max(fastest, speed);
    }
    if (!finite) {
      status = StepStatus::diverged_non_finite;
      continue;
    }
    if (fastest > settings.divergence_speed && status == StepStatus::ok) status = StepStatus::diverged_speed;
    if (!settings.sleep.enabled) continue;
    island.still_time = fastest < settings.sleep.speed_threshold ? island.still_time + dt : 0.0;
    if (island.still_time >= settings.sleep.time_to_sleep && island.still_time > 0) {
      island.sleeping = true;
      for (std::uint32_t b : island.bodies) {
        state.bodies.state.linear_momentum[b].setZero();
        state.bodies.state.angular_momentum[b].setZero();
      }
    }
  }
  return status;
}

}  // namespace

SpringStepReport step(SpringState& state, double dt) {
  SpringStepReport report;
  if (!(dt > 0) || !std::isfinite(dt)) {
    report.status = StepStatus::invalid_time_step;
    return state.last_report = report;
  }
  const FlushDenormals flush;
  if (state.options.integrator == SpringIntegrator::backward_euler) {
    implicit_step(state, dt, report);
  } else {
    integrate_rigid_bodies(state.bodies, dt, explicit_integrator(state.options.integrator), state.scratch,
                           [&state](const RigidBodyState& y, RigidForces& forces) { accumulate_forces(state, y, forces); });
  }
  detect_rigid_contacts(state);
  resolve_rigid_contacts(state, dt);
  report.contacts = static_cast<int>(state.contacts.size());
  state.time += dt;
  report.status = update_sleep(state, dt);
  return state.last_report = report;
}

}  // namespace limber
