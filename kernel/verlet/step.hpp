// step(State, dt): one time step of the Verlet method.
#pragma once

#include "limber/kernel/particles/verlet_state.hpp"

namespace limber {

/// Advances `state` by dt seconds, as options.relaxation.substeps substeps of h = dt/substeps
/// (Macklin et al. 2019, "Small steps in physics simulation"), each running the passes of the
/// thesis's loop (figure 2.5; 4.2.2) under the projection rule (options.relaxation.projection;
/// kernel/relaxation/README.md):
///  1. integrate   pbd: Verlet, x' = x + k·(x − x*) + a·h² (eq. 3.6 / 4.5), over awake islands;
///                 k = exp(−damping·h) (physical damping) or the thesis's f − 1 (f = 1.99),
///                 scaled by h/h_previous when the step changes (time-corrected Verlet);
///                 rattle: damping, half a kick v += (h/2)·a, and the drift x* ← x, x ← x + h·v;
///  2. collide     the ball against every limb (waking the islands it touches), then features
///                 against planes — skipped when the scene has neither;
///  3. relax       Gauss-Seidel or Jacobi sweeps over joints and links (or Newton steps of the
///                 direct solver, VerletOptions::newton_iterations of them) — along the current
///                 gradients (pbd) or those at the substep's start (rattle: SHAKE) — then
///                 long-range attachments if asked for, limb centres (LimbMasses::inertia: each
///                 centre particle back onto its limb's axis), then contacts, until the iteration
///                 count, the tolerance or the wall-clock budget stops it (3.2.3);
///  4. velocities  rattle only: v ← (x − x*)/h, the second half kick, then as many velocity
///                 sweeps as step 3 ran (RATTLE's projection onto the constraints' tangent
///                 space), each followed by the limb centres' rate and the contacts'
///                 restitution;
///  5. restitution pbd: the velocity pass for contacts (eq. 2.33); a limb with a centre particle
///                 answers as the rigid body its three particles make (collision/contacts.hpp);
///  6. sleep       still islands fall asleep; divergence is detected.
/// A force applied before the step (apply_force) acts in every substep. Allocates nothing and
/// never throws; a bad Δt or a divergence is reported in the result (also kept in
/// state.last_report), and the report sums the substeps' sweeps and rattle's pbd fallbacks.
/// Denormals are flushed to zero while it runs (kernel/numerics/flush_denormals.hpp).
template <typename Scalar>
StepReport step(VerletState<Scalar>& state, double dt);

/// step() with the scene's own time step.
template <typename Scalar>
StepReport step(VerletState<Scalar>& state) {
  return step(state, state.settings.time_step);
}

/// Applies `force` (N, world) at the centre of mass of Model body `body`'s particles during the
/// next step, and wakes its island. It is split over the limb's particles in proportion to the
/// limb's mass at each, so each gets the same acceleration F/m and relaxation has nothing to
/// correct: with LimbMasses::ends half at each end (the force acts at the limb's centre), with
/// inertia over its three particles (it acts at the limb's centre of mass, the centre for a
/// uniform limb). It acts over the whole step, in every substep. No allocation for up to 64
/// forces a step.
template <typename Scalar>
void apply_force(VerletState<Scalar>& state, int body, const Eigen::Vector3d& force);

/// Sets joint `joint`'s drive (gains and target; Model index) from the next step on, in the
/// rows compile built for it. Returns false when the joint was compiled without a drive (it has
/// no drive row: recompile with the drive in the Model).
template <typename Scalar>
bool set_joint_drive(VerletState<Scalar>& state, std::size_t joint, const JointDrive& drive) {
  JointRowSet& rows = state.joint_rows;
  if (joint >= state.joint_controls.joints.size() || !state.joint_controls.joints[joint].drive) return false;
  state.joint_controls.joints[joint].drive = drive;
  for (std::uint32_t r = rows.joint_rows[joint].first; r < rows.joint_rows[joint].second; ++r) {
    if (rows.rows[r].drive) set_drive_row(rows.rows[r], drive);
  }
  state.plan.joint_built_for = ~std::uint64_t{0};  // the batches copy the rows: refill them
  return true;
}

extern template StepReport step<float>(VerletState<float>&, double);
extern template StepReport step<double>(VerletState<double>&, double);
extern template void apply_force<float>(VerletState<float>&, int, const Eigen::Vector3d&);
extern template void apply_force<double>(VerletState<double>&, int, const Eigen::Vector3d&);

}  // namespace limber
