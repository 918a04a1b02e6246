// GCC 12 false positive inside Eigen's AVX-512 code (bug 105593); must precede Eigen's headers.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "limber/kernel/springs/spring_forces.hpp"

namespace limber {

SpringEnds spring_ends(const SpringState& state, const RigidBodyState& y, std::size_t s) {
  const SpringBuffer& springs = state.springs;
  SpringEnds ends;
  const std::int32_t inboard = springs.inboard[s], outboard = springs.outboard[s];
  ends.outboard_lever = y.orientation[outboard] * springs.outboard_anchor[s];
  const Eigen::Vector3d outboard_point = y.position[outboard] + ends.outboard_lever;
  const Eigen::Vector3d outboard_velocity = state.velocity[outboard] + state.angular_velocity[outboard].cross(ends.outboard_lever);
  Eigen::Vector3d inboard_point = springs.inboard_anchor[s], inboard_velocity = Eigen::Vector3d::Zero();
  if (inboard >= 0) {
    ends.inboard_lever = y.orientation[inboard] * springs.inboard_anchor[s];
    inboard_point = y.position[inboard] + ends.inboard_lever;
    inboard_velocity = state.velocity[inboard] + state.angular_velocity[inboard].cross(ends.inboard_lever);
  }
  ends.separation = inboard_point - outboard_point;
  ends.separation_rate = inboard_velocity - outboard_velocity;
  return ends;
}

void accumulate_forces(SpringState& state, const RigidBodyState& y, RigidForces& forces) {
  accumulate_applied_forces(state, y, forces);
  const SpringBuffer& springs = state.springs;
  for (std::size_t s = 0; s < springs.size(); ++s) {
    const std::int32_t inboard = springs.inboard[s], outboard = springs.outboard[s];
    if (state.islands[state.island_of_body[outboard]].sleeping) continue;  // both ends share an island
    const SpringEnds ends = spring_ends(state, y, s);
    const Eigen::Vector3d force = -springs.stiffness[s] * ends.separation - springs.damping[s] * ends.separation_rate;
    if (inboard >= 0) {
      forces.force[inboard] += force;
      forces.torque[inboard] += ends.inboard_lever.cross(force);
    }
    forces.force[outboard] -= force;
    forces.torque[outboard] -= ends.outboard_lever.cross(force);
  }
}

double spring_energy(const SpringState& state) {
  double energy = 0;
  for (std::size_t s = 0; s < state.springs.size(); ++s) {
    energy += 0.5 * state.springs.stiffness[s] * joint_separation(state.springs, state.bodies.state, s).squaredNorm();
  }
  return energy;
}

}  // namespace limber
