// GCC 12 false positive inside Eigen's AVX-512 code (bug 105593); must precede Eigen's headers.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "kernel/springs/spring_forces.hpp"

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
  body_velocities(state, y);
  const Settings& settings = state.settings;
  const RigidBodyBuffer& bodies = state.bodies;
  const bool drag = !settings.drag.linear.isZero(0) || !settings.drag.angular.isZero(0);
  for (const RigidIsland& island : state.islands) {
    if (island.sleeping) continue;
    for (std::uint32_t b : island.bodies) {
      forces.force[b] += bodies.mass[b] * settings.gravity;
      if (settings.damping > 0) {
        forces.force[b] -= settings.damping * bodies.mass[b] * state.velocity[b];
        forces.torque[b] -= settings.damping * y.angular_momentum[b];
      }
      if (drag) {
        // The Model's body frame (z: the limb's axis), not the principal frame.
        const Eigen::Matrix3d rotation = (y.orientation[b] * state.shapes.principal_frame[b].conjugate()).toRotationMatrix();
        forces.force[b] -= rotation * settings.drag.linear.cwiseProduct(rotation.transpose() * state.velocity[b]);
        forces.torque[b] -= rotation * settings.drag.angular.cwiseProduct(rotation.transpose() * state.angular_velocity[b]);
      }
    }
  }
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

Eigen::Vector3d spring_separation(const SpringState& state, const RigidBodyState& y, std::size_t s) {
  const SpringBuffer& springs = state.springs;
  const std::int32_t inboard = springs.inboard[s], outboard = springs.outboard[s];
  const Eigen::Vector3d outboard_point = y.position[outboard] + y.orientation[outboard] * springs.outboard_anchor[s];
  const Eigen::Vector3d inboard_point =
      inboard >= 0 ? Eigen::Vector3d(y.position[inboard] + y.orientation[inboard] * springs.inboard_anchor[s]) : springs.inboard_anchor[s];
  return inboard_point - outboard_point;
}

double spring_energy(const SpringState& state) {
  double energy = 0;
  for (std::size_t s = 0; s < state.springs.size(); ++s) {
    energy += 0.5 * state.springs.stiffness[s] * spring_separation(state, state.bodies.state, s).squaredNorm();
  }
  return energy;
}

}  // namespace limber
