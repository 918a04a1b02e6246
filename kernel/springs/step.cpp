#include "limber/kernel/springs/step.hpp"

#include <cmath>

#include "limber/kernel/collision/rigid_contacts.hpp"
#include "limber/kernel/model/guarded_step.hpp"
#include "limber/kernel/springs/implicit_step.hpp"
#include "limber/kernel/springs/spring_forces.hpp"

namespace limber {

StepReport step(SpringState& state, double dt) {
  return guarded_step(state, dt, [&](StepReport& report) {
    StageClock clock(state.options.profile);
    state.time_step = dt;
    remember_step_start(state);
    if (state.options.integrator == Integrator::backward_euler) {
      implicit_step(state, dt, report);
    } else {
      integrate_rigid_bodies(state.bodies, dt, state.options.integrator, state.scratch,
                             [&state](const RigidBodyState& y, RigidForces& forces) { accumulate_forces(state, y, forces); });
    }
    report.profile.integrate = clock.lap();
    detect_rigid_contacts(state);
    report.profile.detect = clock.lap();
    resolve_rigid_contacts(state, dt);
    report.contacts = static_cast<int>(state.contacts.size());
    state.time += dt;
    report.status = update_sleep(state, dt);
    clear_applied_loads(state);
    if (state.options.profile) count_rigid_step(state, report);
  });
}

}  // namespace limber
