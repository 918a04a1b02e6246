#include "limber/kernel/metrics/divergence.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "limber/kernel/geometry/bounding_volumes.hpp"

namespace limber {

DivergenceBounds divergence_bounds(const Model& model, const Observation& start) {
  // The scene's extent: the diagonal of the box around its limbs and balls at the start.
  Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::max()), high = -low;
  double mass = 0;
  for (const Body& body : model.bodies) {
    const BoundingSphere sphere = limb_sphere(body.shape, body.position, body.orientation());
    low = low.cwiseMin((sphere.centre.array() - sphere.radius).matrix());
    high = high.cwiseMax((sphere.centre.array() + sphere.radius).matrix());
    mass += body.mass;
  }
  for (const Ball& ball : model.balls) {
    low = low.cwiseMin((ball.position.array() - ball.radius).matrix());
    high = high.cwiseMax((ball.position.array() + ball.radius).matrix());
    mass += ball.mass;
  }
  const double extent = mass > 0 ? std::max((high - low).norm(), 1.0) : 1.0;
  DivergenceBounds bounds;
  bounds.start_energy = start.energy();
  bounds.energy_scale = std::max(mass * model.settings.gravity.norm() * extent + start.kinetic_energy, 1.0);
  return bounds;
}

StepStatus check_divergence(const Observation& now, const DivergenceBounds& bounds) {
  const bool finite = std::isfinite(now.kinetic_energy) && std::isfinite(now.potential_energy) && now.linear_momentum.allFinite() &&
                      now.body_centre_of_mass.allFinite() && std::isfinite(now.max_joint_gap) &&
                      std::isfinite(now.max_link_stretch);
  if (!finite) return StepStatus::diverged_non_finite;
  if (now.energy() - bounds.start_energy > kDivergenceEnergyFactor * bounds.energy_scale) return StepStatus::diverged_energy;
  // A particle limb's length is a constraint like a joint's: stretched by a whole link, it has come apart too.
  if (std::max(now.max_joint_gap, now.max_link_stretch) > kDivergenceJointGap) return StepStatus::diverged_joint_gap;
  return StepStatus::ok;
}

}  // namespace limber
