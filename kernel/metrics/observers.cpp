#include "kernel/metrics/observers.hpp"

#include <algorithm>
#include <cmath>

namespace limber {

template <typename Scalar>
Observation observe(const VerletState<Scalar>& state) {
  Observation out;
  out.time = state.time;
  const auto& particles = state.particles;
  auto position = [&](std::uint32_t p) { return particles.position(p).template cast<double>().eval(); };

  double gap_squares = 0;
  for (const auto& [c, reference] : state.joint_constraints) {
    const double gap = (position(state.constraints.particle_i[c]) - position(state.constraints.particle_j[c])).norm() / reference;
    out.max_joint_gap = std::max(out.max_joint_gap, gap);
    gap_squares += gap * gap;
  }
  if (!state.joint_constraints.empty()) out.rms_joint_gap = std::sqrt(gap_squares / state.joint_constraints.size());

  for (std::size_t limb = 0; limb < state.limbs.size(); ++limb) {
    const std::uint32_t c = state.limbs.link_constraint[limb];
    const double rest = state.constraints.rest_length[c];
    const double length = (position(state.constraints.particle_i[c]) - position(state.constraints.particle_j[c])).norm();
    out.max_link_stretch = std::max(out.max_link_stretch, std::abs(length - rest) / rest);
  }

  const Eigen::Vector3d gravity = state.gravity.template cast<double>();
  const double dt = state.previous_time_step;
  double body_mass = 0;
  for (std::uint32_t p = 0; p < particles.size(); ++p) {
    const double mass = state.particle_mass[p];
    const Eigen::Vector3d x = position(p);
    const Eigen::Vector3d velocity = (x - particles.previous(p).template cast<double>()) / dt;
    out.linear_momentum += mass * velocity;
    out.kinetic_energy += 0.5 * mass * velocity.squaredNorm();
    out.potential_energy -= mass * gravity.dot(x);
    if (static_cast<std::int64_t>(p) != state.ball_particle) {
      out.body_centre_of_mass += mass * x;
      body_mass += mass;
    }
  }
  if (body_mass > 0) out.body_centre_of_mass /= body_mass;

  out.islands = static_cast<int>(state.islands.size());
  out.body_sleeping = true;
  for (std::size_t k = 0; k < state.islands.size(); ++k) {
    out.islands_sleeping += state.islands[k].sleeping;
    if (static_cast<std::int64_t>(k) != state.ball_island) out.body_sleeping = out.body_sleeping && state.islands[k].sleeping;
  }
  return out;
}

template Observation observe<float>(const VerletState<float>&);
template Observation observe<double>(const VerletState<double>&);

}  // namespace limber
