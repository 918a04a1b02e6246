#include "limber/kernel/verlet/step.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "limber/kernel/collision/contacts.hpp"
#include "limber/kernel/collision/limb_contacts.hpp"
#include "limber/kernel/model/guarded_step.hpp"
#include "limber/kernel/relaxation/contact_relaxation.hpp"
#include "limber/kernel/relaxation/direct_projection.hpp"
#include "limber/kernel/relaxation/joint_trees.hpp"
#include "limber/kernel/relaxation/relaxation.hpp"
#include "limber/kernel/relaxation/tree_contacts.hpp"
#include "limber/kernel/sleeping/sleeping.hpp"
#include "limber/kernel/verlet/bodies.hpp"

namespace limber {
namespace {

// Fraction of the last step's displacement a particle keeps (its implicit velocity).
template <typename Scalar>
double velocity_retention(const VerletState<Scalar>& state, double dt) {
  const std::optional<double>& drag_factor = state.options.verlet.drag_factor;
  const double kept = drag_factor ? *drag_factor - 1.0 : std::exp(-state.settings.damping * dt);
  return kept * dt / state.previous_time_step;
}

// Verlet integration (thesis eq. 3.6): x' = x + k·(x − x*) + g·Δt², x* ← x. Pinned particles
// (w = 0) stay where they are.
template <typename Scalar>
void integrate(VerletState<Scalar>& state, double dt) {
  auto& p = state.particles;
  const Scalar k = static_cast<Scalar>(velocity_retention(state, dt));
  const Scalar dt2 = static_cast<Scalar>(dt * dt);
  const Scalar gx = state.gravity.x() * dt2, gy = state.gravity.y() * dt2, gz = state.gravity.z() * dt2;
  std::uint64_t integrated = 0;
  for (std::uint32_t island_index : state.awake_islands) {
    const Island& island = state.islands[island_index];
    for (std::uint32_t i = island.particle_begin; i < island.particle_end; ++i) {
      if (p.inverse_mass[i] == Scalar(0)) continue;
      const Scalar x = p.position_x[i], y = p.position_y[i], z = p.position_z[i];
      p.position_x[i] = x + k * (x - p.previous_x[i]) + gx;
      p.position_y[i] = y + k * (y - p.previous_y[i]) + gy;
      p.position_z[i] = z + k * (z - p.previous_z[i]) + gz;
      p.previous_x[i] = x, p.previous_y[i] = y, p.previous_z[i] = z;
    }
    integrated += island.particle_end - island.particle_begin;
  }
  // Applied forces: x += w·f·Δt² (cleared by step(), after its last substep).
  for (const auto& [i, force] : state.pending_forces) {
    const Scalar scale = p.inverse_mass[i] * dt2;
    p.position_x[i] += scale * static_cast<Scalar>(force.x());
    p.position_y[i] += scale * static_cast<Scalar>(force.y());
    p.position_z[i] += scale * static_cast<Scalar>(force.z());
  }
  state.counters.particles_integrated += integrated;
}

// Half of the rattle rule's velocity update: v += (h/2)·(g + w·f) for every awake movable
// particle (velocity Verlet's kick; Andersen 1983's first and last stage without the constraint
// forces, which the projections add).
template <typename Scalar>
void half_kick(VerletState<Scalar>& state, double h) {
  auto& p = state.particles;
  const Scalar half = static_cast<Scalar>(0.5 * h);
  const Scalar gx = state.gravity.x() * half, gy = state.gravity.y() * half, gz = state.gravity.z() * half;
  for (std::uint32_t island_index : state.awake_islands) {
    const Island& island = state.islands[island_index];
    for (std::uint32_t i = island.particle_begin; i < island.particle_end; ++i) {
      if (p.inverse_mass[i] == Scalar(0)) continue;
      p.velocity_x[i] += gx, p.velocity_y[i] += gy, p.velocity_z[i] += gz;
    }
  }
  for (const auto& [i, force] : state.pending_forces) {
    p.set_velocity(i, p.velocity(i) + (p.inverse_mass[i] * half) * force.template cast<Scalar>());
  }
}

// The rattle rule's start of a substep: damping, the first half kick, then the drift
// x ← x + h·v with the start positions kept as the previous ones (where relaxation takes the
// constraints' start gradients): x̃ = x₀ + h·v₀ + (h²/2)·a₀, second order (Verlet's
// x* = x₀ − v₀·Δt start is first order).
template <typename Scalar>
void kick_and_drift(VerletState<Scalar>& state, double h) {
  auto& p = state.particles;
  const std::optional<double>& drag_factor = state.options.verlet.drag_factor;
  const Scalar kept = static_cast<Scalar>(drag_factor ? *drag_factor - 1.0 : std::exp(-state.settings.damping * h));
  const Scalar step = static_cast<Scalar>(h);
  std::uint64_t integrated = 0;
  for (std::uint32_t island_index : state.awake_islands) {
    const Island& island = state.islands[island_index];
    for (std::uint32_t i = island.particle_begin; i < island.particle_end; ++i) {
      if (p.inverse_mass[i] == Scalar(0)) continue;
      p.velocity_x[i] *= kept, p.velocity_y[i] *= kept, p.velocity_z[i] *= kept;
    }
    integrated += island.particle_end - island.particle_begin;
  }
  half_kick(state, h);
  for (std::uint32_t island_index : state.awake_islands) {
    const Island& island = state.islands[island_index];
    for (std::uint32_t i = island.particle_begin; i < island.particle_end; ++i) {
      const Scalar x = p.position_x[i], y = p.position_y[i], z = p.position_z[i];
      p.previous_x[i] = x, p.previous_y[i] = y, p.previous_z[i] = z;
      if (p.inverse_mass[i] == Scalar(0)) continue;
      p.position_x[i] = x + step * p.velocity_x[i];
      p.position_y[i] = y + step * p.velocity_y[i];
      p.position_z[i] = z + step * p.velocity_z[i];
    }
  }
  state.counters.particles_integrated += integrated;
}

// A substep shorter than the ones before it would turn the relaxation's closing of the joint
// gaps they left, ε, into a velocity ε/h: a gap left by a step of 1/240 s closed in 10⁻⁷ s is a
// kick of 40 000·ε/Δt (the chain's 200 J became 13 000 J). So a substep of h within a time H
// after a longer step of H (state.correction_time: H = span − age > h) takes the velocity its
// relaxation makes, δ = x − x_predicted, as made over H, δ/H: closing ε, in one substep or
// several, then gives ε/H — what the step that left it would have given — and the substep's own
// constraint impulse, O(h), changes by O(h). Once a time H has passed, or at h ≥ H, the usual
// form runs (the same bits at a constant step).
//
// pbd: x* ← x₀ + (1 − h/H)·δ, so that (x − x*)/h = (x_predicted − x₀)/h + δ/H; the prediction
// is kept in the velocity arrays (pbd's velocity is implicit, so they are free).
template <typename Scalar>
void keep_prediction(VerletState<Scalar>& state) {
  auto& p = state.particles;
  for (std::uint32_t island_index : state.awake_islands) {
    const Island& island = state.islands[island_index];
    for (std::uint32_t i = island.particle_begin; i < island.particle_end; ++i) {
      p.velocity_x[i] = p.position_x[i], p.velocity_y[i] = p.position_y[i], p.velocity_z[i] = p.position_z[i];
    }
  }
}

template <typename Scalar>
void shortened_step_velocity(VerletState<Scalar>& state, double h, double longer) {
  auto& p = state.particles;
  const Scalar kept = static_cast<Scalar>(1.0 - h / longer);
  for (std::uint32_t island_index : state.awake_islands) {
    const Island& island = state.islands[island_index];
    for (std::uint32_t i = island.particle_begin; i < island.particle_end; ++i) {
      if (p.inverse_mass[i] == Scalar(0)) continue;
      p.previous_x[i] += kept * (p.position_x[i] - p.velocity_x[i]);
      p.previous_y[i] += kept * (p.position_y[i] - p.velocity_y[i]);
      p.previous_z[i] += kept * (p.position_z[i] - p.velocity_z[i]);
    }
  }
}

// The rattle rule after the position projections: v ← (x − x₀)/h, the constrained half-step
// velocity, then the second half kick. A shortened substep (`longer` > h) takes
// v ← v + (x − x₀ − h·v)/longer instead (shortened_step_velocity's reason).
template <typename Scalar>
void velocity_from_positions(VerletState<Scalar>& state, double h, double longer) {
  auto& p = state.particles;
  const Scalar inverse_step = static_cast<Scalar>(1.0 / h);
  const bool shortened = h < longer;
  const Scalar step = static_cast<Scalar>(h), inverse_longer = static_cast<Scalar>(1.0 / longer);
  for (std::uint32_t island_index : state.awake_islands) {
    const Island& island = state.islands[island_index];
    for (std::uint32_t i = island.particle_begin; i < island.particle_end; ++i) {
      if (p.inverse_mass[i] == Scalar(0)) continue;
      if (shortened) {  // the drift's own prediction, x₀ + h·v, rounded as it was
        p.velocity_x[i] += (p.position_x[i] - (p.previous_x[i] + step * p.velocity_x[i])) * inverse_longer;
        p.velocity_y[i] += (p.position_y[i] - (p.previous_y[i] + step * p.velocity_y[i])) * inverse_longer;
        p.velocity_z[i] += (p.position_z[i] - (p.previous_z[i] + step * p.velocity_z[i])) * inverse_longer;
        continue;
      }
      p.velocity_x[i] = (p.position_x[i] - p.previous_x[i]) * inverse_step;
      p.velocity_y[i] = (p.position_y[i] - p.previous_y[i]) * inverse_step;
      p.velocity_z[i] = (p.position_z[i] - p.previous_z[i]) * inverse_step;
    }
  }
  half_kick(state, h);
}

// Moves each kinematic target's pinned particle to where its path is at the end of substep
// `index` of `count` (the previous position stays where the substep began), with the matching
// velocity under the rattle rule.
template <typename Scalar>
void move_kinematic_particles(VerletState<Scalar>& state, int index, int count, double h) {
  auto& p = state.particles;
  for (const KinematicTarget& target : state.kinematic_targets) {
    const double along = double(index + 1) / count;
    const Eigen::Vector3d start = p.position(target.particle).template cast<double>();
    const Eigen::Vector3d end = target.start + along * (target.target - target.start);
    p.set_previous(target.particle, start.cast<Scalar>());
    p.set_position(target.particle, end.cast<Scalar>());
    if (uses_rattle(state)) p.set_velocity(target.particle, ((end - start) / h).cast<Scalar>());
  }
}

// The substep's contacts: those with the ground, the bounds and the ball, and the contact rows
// relaxation pushed (the rest are speculative).
template <typename Scalar>
int substep_contacts(const VerletState<Scalar>& state) {
  std::size_t count = state.plane_contacts.size() + state.ball_contacts.size();
  for (const auto lambda : state.plan.contact_batches.lambda) count += lambda > 0 ? 1 : 0;
  return static_cast<int>(count) + tree_contact_rows_pushed(state.plan.joint_trees);
}

// Whether the limbs have centre particles (LimbMasses::inertia), which project_limb_centres keeps
// on their axes.
template <typename Scalar>
bool has_limb_centres(const VerletState<Scalar>& state) {
  return state.limbs.size() > 0 && state.limbs.centre[0] != kNoCentre;
}

// The particles this step's contacts and limb-centre projections move (for the interleaved
// layouts, which keep the relaxation's positions outside state.particles).
template <typename Scalar>
void collect_contact_particles(VerletState<Scalar>& state) {
  state.contact_particles.clear();
  if (has_limb_centres(state)) {
    for (std::uint32_t k : state.awake_islands) {
      const Island& island = state.islands[k];
      for (std::uint32_t limb = island.limb_begin; limb < island.limb_end; ++limb) {
        state.contact_particles.push_back(state.limbs.head[limb]);
        state.contact_particles.push_back(state.limbs.centre[limb]);
        state.contact_particles.push_back(state.limbs.tail[limb]);
      }
    }
  }
  for (const PlaneContact& contact : state.plane_contacts) {
    state.contact_particles.push_back(state.features[contact.feature].particle);
    state.contact_particles.push_back(state.features[contact.feature].axis_partner);
  }
  for (const BallContact& contact : state.ball_contacts) {
    state.contact_particles.push_back(state.balls[contact.ball].particle);
    state.contact_particles.push_back(state.limbs.head[contact.limb]);
    state.contact_particles.push_back(state.limbs.tail[contact.limb]);
  }
  for (const ContactRow& row : state.contact_rows.rows) {
    for (std::uint32_t p : row.particle) {
      if (p != state.particles.null_particle()) state.contact_particles.push_back(p);
    }
  }
}

// Puts each limb's centre particle back on the midpoint of its head and tail. The distance
// constraints head–centre and centre–tail hold it there only to second order: three collinear
// particles give them gradients along the axis alone, so a sideways offset e of the centre
// violates them by ~e²/L and Gauss-Seidel pulls it back by ~e³/L² a sweep (a 1 m rod lying on
// the ground sagged 12 mm at 100 sweeps). The linear constraint C = x_c − (x_h + x_t)/2 = 0 has
// gradients E, −E/2, −E/2 and is solved in one projection, λ = C / (w_c + (w_h + w_t)/4),
// Δx_c = −w_c·λ, Δx_h = Δx_t = +w·λ/2: momentum and angular momentum are kept (the impulses
// −λ, λ/2, λ/2 sum to zero and their torque is −C × λ = 0). Run after every sweep, like the
// contacts. With the unweighted rule every movable particle counts w = 1. The constraint is
// linear, so its gradient is the same at the start and the end of a step: both projection rules
// project it alike, and the rattle rule's velocity stage projects its rate, v_c − (v_h + v_t)/2,
// by the same formula (`field` reads and writes positions or velocities). Returns the largest
// change, m or m/s.
template <typename Scalar, typename Field>
double project_limb_centres(VerletState<Scalar>& state, Field field) {
  auto& particles = state.particles;
  const bool weighted = state.options.rule == RelaxationRule::weighted;
  const auto inverse_mass = [&](std::uint32_t p) {
    const double w = particles.inverse_mass[p];
    return weighted || w == 0 ? w : 1.0;
  };
  double largest = 0;
  for (std::uint32_t k : state.awake_islands) {
    const Island& island = state.islands[k];
    for (std::uint32_t limb = island.limb_begin; limb < island.limb_end; ++limb) {
      const std::uint32_t head = state.limbs.head[limb], centre = state.limbs.centre[limb], tail = state.limbs.tail[limb];
      const double w_head = inverse_mass(head), w_centre = inverse_mass(centre), w_tail = inverse_mass(tail);
      const double denominator = w_centre + 0.25 * (w_head + w_tail);
      if (denominator <= 0) continue;
      const Eigen::Vector3d x_head = field.get(head).template cast<double>();
      const Eigen::Vector3d x_tail = field.get(tail).template cast<double>();
      const Eigen::Vector3d x_centre = field.get(centre).template cast<double>();
      const Eigen::Vector3d lambda = (x_centre - 0.5 * (x_head + x_tail)) / denominator;
      const Eigen::Vector3d delta_centre = -w_centre * lambda;
      field.set(centre, (x_centre + delta_centre).template cast<Scalar>());
      field.set(head, (x_head + 0.5 * w_head * lambda).template cast<Scalar>());
      field.set(tail, (x_tail + 0.5 * w_tail * lambda).template cast<Scalar>());
      largest = std::max({largest, delta_centre.norm(), 0.5 * std::max(w_head, w_tail) * lambda.norm()});
    }
  }
  return largest;
}

// The particles' positions or velocities, as project_limb_centres reads and writes them.
template <typename Scalar>
struct PositionField {
  ParticleBuffer<Scalar>& particles;
  auto get(std::uint32_t p) const { return particles.position(p); }
  void set(std::uint32_t p, const typename ParticleBuffer<Scalar>::Vector3& x) const { particles.set_position(p, x); }
};
template <typename Scalar>
struct VelocityField {
  ParticleBuffer<Scalar>& particles;
  auto get(std::uint32_t p) const { return particles.velocity(p); }
  void set(std::uint32_t p, const typename ParticleBuffer<Scalar>::Vector3& v) const { particles.set_velocity(p, v); }
};

// Stage 3 of a substep: sweeps over joints and links (or Newton steps), then long-range
// attachments, limb centres and contacts after each, until the iteration count, the tolerance
// or the wall-clock budget (`budget_us` for this substep) stops it. Fills `report`'s sweep
// count, last correction and stop.
template <typename Scalar>
void relax_positions(VerletState<Scalar>& state, double dt, double budget_us, StepReport& report) {
  const RelaxationSettings& relaxation = state.options.relaxation;
  const bool has_ball = !state.balls.empty(), has_planes = !state.planes.empty(), has_centres = has_limb_centres(state);
  const bool interleaved = state.plan.layout != ParticleLayout::soa;
  const auto start = std::chrono::steady_clock::now();
  begin_relaxation(state, dt);
  const bool has_rows = !state.contact_rows.empty();
  const bool copies = !state.plane_contacts.empty() || !state.ball_contacts.empty() || has_rows || has_centres;
  const bool direct = state.options.solver == RelaxationSolver::direct;
  const bool trees = state.plan.joint_trees.active();
  const int iterations = direct ? state.options.newton_iterations : relaxation.iterations;
  for (int iteration = 1; iteration <= iterations; ++iteration) {
    // The first sweep starts from the unconstrained prediction, far from the solution;
    // over-relaxing it overshoots (a chain at one sweep a step diverges at ω = 1.5).
    double largest = relaxation_sweep(state, iteration == 1 ? 1.0 : relaxation.over_relaxation);
    if (state.options.long_range_attachments) largest = std::max(largest, project_long_range_attachments(state));
    if (interleaved && copies) contact_particles_to_buffer(state);
    if (has_centres) largest = std::max(largest, project_limb_centres(state, PositionField<Scalar>{state.particles}));
    if (has_planes) largest = std::max(largest, project_plane_contacts(state, dt));
    if (has_ball) largest = std::max(largest, project_ball_contacts(state, dt));
    if (has_rows) largest = std::max(largest, contact_position_sweep(state));
    if (interleaved && copies) contact_particles_from_buffer(state);
    // Last, so every sweep leaves the tree joints closed (joint_trees.hpp); the contacts it
    // disturbs are the next sweep's.
    if (trees) largest = std::max(largest, project_joint_trees(state));
    report.iterations += 1;
    report.largest_correction = largest;
    report.stop = RelaxationStop::iterations;
    if (relaxation.tolerance > 0 && largest < relaxation.tolerance) {
      report.stop = RelaxationStop::tolerance;
      break;
    }
    if (budget_us > 0 && iteration < iterations) {
      const std::chrono::duration<double, std::micro> elapsed = std::chrono::steady_clock::now() - start;
      if (elapsed.count() >= budget_us) {
        report.stop = RelaxationStop::budget;
        break;
      }
    }
  }
  end_relaxation(state);
}

// Most sweeps the rattle rule's velocity stage runs in a substep where contacts act: a bound on
// the cost of a substep that does not converge (README.md, "Contacts under the rattle rule").
constexpr int kMaxContactVelocitySweeps = 32;

// The rattle rule's velocity stage: as many sweeps as the position stage ran (Newton steps: one
// exact solve each), each followed by the limb centres' rate and the contacts' restitution pass
// — Gauss-Seidel over every velocity row, the contacts as inequalities (contact_impulse), so
// joints and contacts agree on the velocities the substep ends with — until the velocity
// changes times the substep fall below the tolerance. Where a contact acts, the sweeps go on
// until no sweep changes a velocity by the resting speed (2|g|h) or more, at most
// kMaxContactVelocitySweeps: left unconverged, the contacts' last impulses break the joints'
// rates, the joints open gaps, and the gaps return the energy later (README.md, "Contacts under
// the rattle rule"). Compliant constraints (direct solver, α > 0) are springs, whose rate is
// free: they get the second half kick of their force instead (kick_compliant_constraints), then
// the contacts. Returns the velocity sweeps run.
template <typename Scalar>
int project_velocities(VerletState<Scalar>& state, double dt, int sweeps) {
  const bool contacts = !state.balls.empty() || !state.planes.empty();
  const bool rows = !state.contact_rows.empty();
  if (state.options.compliance > 0) {
    kick_compliant_constraints(state, dt);
    if (contacts) apply_restitution(state, dt);
    if (rows) apply_contact_row_restitution(state, dt);
    return 0;
  }
  const bool has_centres = has_limb_centres(state);
  const bool trees = state.plan.joint_trees.active();
  const double settled = resting_speed(state, dt);
  bool contact_acted = false;
  begin_velocity_projection(state);
  int sweep = 1;
  for (;; ++sweep) {
    double largest = velocity_sweep(state);
    if (trees) largest = std::max(largest, project_joint_tree_velocities(state));
    if (has_centres) largest = std::max(largest, project_limb_centres(state, VelocityField<Scalar>{state.particles}));
    double contact_change = 0;
    if (contacts) contact_change = apply_restitution(state, dt);
    if (rows) contact_change = std::max(contact_change, apply_contact_row_restitution(state, dt));
    contact_acted = contact_acted || contact_change > 0;
    largest = std::max(largest, contact_change);
    if (state.options.relaxation.tolerance > 0 && largest * dt < state.options.relaxation.tolerance) break;
    if (sweep >= sweeps && (!contact_acted || largest < settled || sweep >= kMaxContactVelocitySweeps)) break;
  }
  end_velocity_projection(state);
  return sweep;
}

// One substep of either rule (the whole step when relaxation.substeps is 1): the passes
// of step.hpp's list, each a lap of `clock` into the report's profile (StepProfile's stages).
template <typename Scalar>
StepReport substep(VerletState<Scalar>& state, double dt, double budget_us, int index, int count, StageClock& clock) {
  StepReport report;
  StepProfile& profile = report.profile;
  const bool rattle = uses_rattle(state);
  const bool has_ball = !state.balls.empty(), has_planes = !state.planes.empty();
  // > dt: a shortened substep (shortened_step_velocity).
  const double longer = std::max(dt, state.correction_time.span - state.correction_time.age);
  if (rattle) {
    kick_and_drift(state, dt);
  } else {
    integrate(state, dt);
    if (dt < longer) keep_prediction(state);
  }
  if (!state.kinematic_targets.empty()) move_kinematic_particles(state, index, count, dt);
  profile.integrate = clock.lap();
  if (has_ball) {
    detect_ball_contacts(state, dt);
    state.ball_touched = state.ball_touched || !state.ball_contacts.empty();
  }
  if (has_planes) detect_plane_contacts(state, dt);
  // The first substep's broadphase serves the step's substeps while no limb outruns it.
  const bool searched = state.collisions.active() && detect_limb_contacts(state, dt, count - index, index > 0);
  profile.detect = clock.lap();
  if (state.collisions.active()) build_contact_batches(state);
  if (state.plan.layout != ParticleLayout::soa) collect_contact_particles(state);
  profile.colour = clock.lap();
  if (!state.awake_islands.empty()) relax_positions(state, dt, budget_us, report);
  profile.relax = clock.lap();
  int velocity_sweeps = 0;
  if (rattle) {
    velocity_from_positions(state, dt, longer);
    if (!state.awake_islands.empty()) velocity_sweeps = project_velocities(state, dt, std::max(1, report.iterations));
    profile.velocity = clock.lap();
  } else {
    if (dt < longer) shortened_step_velocity(state, dt, longer);
    profile.velocity = clock.lap();
    if (has_ball || has_planes) apply_restitution(state, dt);
    if (!state.contact_rows.empty()) apply_contact_row_restitution(state, dt);
    profile.restitution = clock.lap();
  }
  report.contacts = substep_contacts(state);
  report.status = update_sleep(state, dt);
  report.substeps = 1;
  state.time += dt;
  state.previous_time_step = dt;
  if (longer == dt) {
    state.correction_time.span = dt, state.correction_time.age = 0;
  } else {
    state.correction_time.age += dt;
  }
  profile.sleep = clock.lap();
  if (state.options.profile) {
    const ContactRowSet& rows = state.contact_rows;
    profile.substeps = 1, profile.position_sweeps = report.iterations, profile.velocity_sweeps = velocity_sweeps;
    profile.contact_rows = static_cast<int>(rows.rows.size());
    profile.contact_colours = rows.empty() ? 0 : static_cast<int>(rows.colour_count);
    profile.candidate_pairs = searched ? static_cast<int>(state.collisions.candidate_pairs()) : 0;
    profile.limb_searches = searched ? 1 : 0;
    profile.contacts = report.contacts;
    const JointTreeCounts trees = joint_tree_counts(state);
    profile.tree_solves = trees.solves, profile.tree_newton_steps = trees.newton_steps, profile.tree_capped = trees.capped;
    profile.tree_factors = trees.factors, profile.tree_inverse_diagonals = trees.inverse_diagonals;
    profile.tree_substitutions = trees.substitutions, profile.tree_path_solves = trees.path_solves;
    profile.tree_lane_slots = trees.lane_slots;
    profile.tree_staging = trees.seconds.staging, profile.tree_elimination = trees.seconds.elimination;
    profile.tree_moves = trees.seconds.moves, profile.tree_contacts = trees.seconds.contacts;
  }
  return report;
}

// After a step that diverged: a pinned particle (w = 0) is moved only by a kinematic target,
// but a correction gone infinite moves it by 0·∞ = NaN; it goes back where it was, so that the
// bodies it holds can be teleported back and the World step on.
// The null particle (padded SIMD lanes point at it) goes back to the origin.
template <typename Scalar>
void restore_pinned_particles(VerletState<Scalar>& state) {
  auto& p = state.particles;
  for (std::uint32_t i = 0; i < p.size(); ++i) {
    if (p.inverse_mass[i] == Scalar(0) && !p.position(i).allFinite() && p.previous(i).allFinite()) p.set_position(i, p.previous(i));
  }
  const std::uint32_t null = p.null_particle();
  if (!p.position(null).allFinite() || !p.previous(null).allFinite()) {
    p.set_position(null, ParticleBuffer<Scalar>::Vector3::Zero()), p.set_previous(null, ParticleBuffer<Scalar>::Vector3::Zero());
  }
}

}  // namespace

template <typename Scalar>
StepReport step(VerletState<Scalar>& state, double dt) {
  return guarded_step(state, dt, [&](StepReport& report) {
    const int substeps = state.options.relaxation.substeps;
    const double h = dt / substeps, start_time = state.time;
    state.plan.fallbacks.value = 0;
    state.ball_touched = false;
    for (KinematicTarget& target : state.kinematic_targets) target.start = state.particles.position(target.particle).template cast<double>();
    StageClock clock(state.options.profile);
    for (int k = 0; k < substeps; ++k) {
      const StepReport part = substep(state, h, state.options.relaxation.budget_us / substeps, k, substeps, clock);
      report.profile += part.profile;
      report.iterations += part.iterations;
      report.largest_correction = part.largest_correction;
      report.stop = part.stop;
      report.contacts = std::max(report.contacts, part.contacts);
      report.status = part.status;
      report.substeps += 1;
      if (part.status != StepStatus::ok) break;
    }
    if (report.status == StepStatus::ok) state.time = start_time + dt;  // not n roundings of h
    if (report.status != StepStatus::ok) restore_pinned_particles(state);
    state.pending_forces.clear();
    state.kinematic_targets.clear();
    report.fallbacks = state.plan.fallbacks.value;
    transport_body_frames(state);  // the sticks' roll, carried onto their new axes
    report.profile.sleep += clock.lap();  // the step's bookkeeping after its substeps
  });
}

template <typename Scalar>
void apply_force(VerletState<Scalar>& state, int body, const Eigen::Vector3d& force) {
  const std::uint32_t limb = state.body_limb.at(static_cast<std::size_t>(body));
  const LimbBuffer& limbs = state.limbs;
  const double mass = limbs.head_mass[limb] + limbs.centre_mass[limb] + limbs.tail_mass[limb];
  state.pending_forces.emplace_back(limbs.head[limb], (limbs.head_mass[limb] / mass) * force);
  state.pending_forces.emplace_back(limbs.tail[limb], (limbs.tail_mass[limb] / mass) * force);
  if (limbs.centre[limb] != kNoCentre) {
    state.pending_forces.emplace_back(limbs.centre[limb], (limbs.centre_mass[limb] / mass) * force);
  }
  for (std::uint32_t k = 0; k < state.islands.size(); ++k) {
    const Island& island = state.islands[k];
    if (limb >= island.limb_begin && limb < island.limb_end) wake_island(state, k);
  }
}

template StepReport step<float>(VerletState<float>&, double);
template StepReport step<double>(VerletState<double>&, double);
template void apply_force<float>(VerletState<float>&, int, const Eigen::Vector3d&);
template void apply_force<double>(VerletState<double>&, int, const Eigen::Vector3d&);

}  // namespace limber
