#include "kernel/verlet/step.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "kernel/collision/contacts.hpp"
#include "kernel/numerics/flush_denormals.hpp"
#include "kernel/relaxation/relaxation.hpp"
#include "kernel/sleeping/sleeping.hpp"

namespace limber {
namespace {

// Fraction of the last step's displacement a particle keeps (its implicit velocity).
template <typename Scalar>
double velocity_retention(const VerletState<Scalar>& state, double dt) {
  const Settings& settings = state.settings;
  const double kept = settings.verlet.drag_factor ? *settings.verlet.drag_factor - 1.0
                                                  : std::exp(-settings.damping * dt);
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
  // Applied forces: x += w·f·Δt².
  for (const auto& [i, force] : state.pending_forces) {
    const Scalar scale = p.inverse_mass[i] * dt2;
    p.position_x[i] += scale * static_cast<Scalar>(force.x());
    p.position_y[i] += scale * static_cast<Scalar>(force.y());
    p.position_z[i] += scale * static_cast<Scalar>(force.z());
  }
  state.pending_forces.clear();
  state.counters.particles_integrated += integrated;
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
    state.contact_particles.push_back(static_cast<std::uint32_t>(state.ball_particle));
    state.contact_particles.push_back(state.limbs.head[contact.limb]);
    state.contact_particles.push_back(state.limbs.tail[contact.limb]);
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
// contacts. With the unweighted rule every movable particle counts w = 1. Returns the largest
// displacement, m.
template <typename Scalar>
double project_limb_centres(VerletState<Scalar>& state) {
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
      const Eigen::Vector3d x_head = particles.position(head).template cast<double>();
      const Eigen::Vector3d x_tail = particles.position(tail).template cast<double>();
      const Eigen::Vector3d x_centre = particles.position(centre).template cast<double>();
      const Eigen::Vector3d lambda = (x_centre - 0.5 * (x_head + x_tail)) / denominator;
      const Eigen::Vector3d delta_centre = -w_centre * lambda;
      particles.set_position(centre, (x_centre + delta_centre).template cast<Scalar>());
      particles.set_position(head, (x_head + 0.5 * w_head * lambda).template cast<Scalar>());
      particles.set_position(tail, (x_tail + 0.5 * w_tail * lambda).template cast<Scalar>());
      largest = std::max({largest, delta_centre.norm(), 0.5 * std::max(w_head, w_tail) * lambda.norm()});
    }
  }
  return largest;
}

}  // namespace

template <typename Scalar>
StepReport step(VerletState<Scalar>& state, double dt) {
  StepReport report;
  if (!valid_time_step(dt)) {
    report.status = StepStatus::invalid_time_step;
    return state.last_report = report;
  }
  const FlushDenormals flush_denormals;
  const bool has_ball = state.ball_particle >= 0;
  const bool has_planes = !state.planes.empty();
  const bool has_centres = has_limb_centres(state);

  integrate(state, dt);
  if (has_ball) detect_ball_contacts(state, dt);
  if (has_planes) detect_plane_contacts(state, dt);
  const bool interleaved = state.plan.layout != ParticleLayout::soa;
  if (interleaved) collect_contact_particles(state);

  const RelaxationSettings& relaxation = state.settings.relaxation;
  const auto start = std::chrono::steady_clock::now();
  if (!state.awake_islands.empty()) {
    begin_relaxation(state, dt);
    const bool copies = !state.plane_contacts.empty() || !state.ball_contacts.empty() || has_centres;
    const bool direct = state.options.solver == RelaxationSolver::direct;
    const int iterations = direct ? state.options.newton_iterations : relaxation.iterations;
    for (int iteration = 1; iteration <= iterations; ++iteration) {
      // The first sweep starts from the unconstrained prediction, far from the solution;
      // over-relaxing it overshoots (a chain at one sweep a step diverges at ω = 1.5).
      double largest = relaxation_sweep(state, iteration == 1 ? 1.0 : relaxation.over_relaxation);
      if (state.options.long_range_attachments) largest = std::max(largest, project_long_range_attachments(state));
      if (interleaved && copies) contact_particles_to_buffer(state);
      if (has_centres) largest = std::max(largest, project_limb_centres(state));
      if (has_planes) largest = std::max(largest, project_plane_contacts(state, dt));
      if (has_ball) largest = std::max(largest, project_ball_contacts(state, dt));
      if (interleaved && copies) contact_particles_from_buffer(state);
      report.iterations = iteration;
      report.largest_correction = largest;
      report.stop = RelaxationStop::iterations;
      if (relaxation.tolerance > 0 && largest < relaxation.tolerance) {
        report.stop = RelaxationStop::tolerance;
        break;
      }
      if (relaxation.budget_us > 0 && iteration < iterations) {
        const std::chrono::duration<double, std::micro> elapsed = std::chrono::steady_clock::now() - start;
        if (elapsed.count() >= relaxation.budget_us) {
          report.stop = RelaxationStop::budget;
          break;
        }
      }
    }
    end_relaxation(state);
  }
  if (has_ball || has_planes) apply_restitution(state, dt);

  report.status = update_sleep(state, dt);
  state.time += dt;
  state.previous_time_step = dt;
  return state.last_report = report;
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
