// GCC 12 false positive inside Eigen's AVX-512 code (bug 105593); must precede Eigen's headers.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "limber/kernel/springs/step.hpp"

#include <cmath>

#include "limber/kernel/numerics/flush_denormals.hpp"
#include "limber/kernel/collision/rigid_contacts.hpp"
#include "limber/kernel/springs/implicit_step.hpp"
#include "limber/kernel/springs/spring_forces.hpp"

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

}  // namespace

SpringStepReport step(SpringState& state, double dt) {
  SpringStepReport report;
  if (!valid_time_step(dt)) {
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
  clear_applied_loads(state);
  return state.last_report = report;
}

}  // namespace limber
