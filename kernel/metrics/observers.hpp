// Observers: what a step did to the physics — joint gap, stretch, centre of mass, momentum,
// energy, sleeping. Read-only over a state; every method will expose the same quantities.
#pragma once

#include <span>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/featherstone/featherstone_state.hpp"
#include "limber/kernel/lagrange/lagrange_state.hpp"
#include "limber/kernel/metrics/observation.hpp"
#include "limber/kernel/particles/verlet_state.hpp"
#include "limber/kernel/springs/spring_state.hpp"

namespace limber {

/// The particle method's observation: joint gaps between the particles or anchor points a joint
/// holds together, relative to its reference length; each limb's stretch; the particles' momentum,
/// kinetic energy from their velocities and gravity's potential energy.
template <typename Scalar>
Observation observe(const VerletState<Scalar>& state, ObservationScope scope = ObservationScope::full);

/// The same quantities for the stiff-spring method: joint gaps between the springs' anchor
/// points (relative to the same lengths as the Verlet method's), no stretch (limbs are rigid),
/// kinetic energy ½ m v² + ½ ω·L, and potential energy including the springs' ½ k |d|².
Observation observe(const SpringState& state, ObservationScope scope = ObservationScope::full);

/// The same for the Lagrange method: joint gaps |C| between the joints' anchor points.
Observation observe(const LagrangeState& state, ObservationScope scope = ObservationScope::full);

/// The same for the Featherstone method, from the rigid bodies it refreshes from (q, v): joint
/// gaps between the joints' world anchor points (a prismatic joint's along its slide not
/// counted), which reduced coordinates keep at 0 to rounding.
Observation observe(const FeatherstoneState& state, ObservationScope scope = ObservationScope::full);

/// Each Model body's limb as collision sees it now (head → tail and radius; kernel/geometry/
/// limb_collisions.hpp), then the ball's (head = tail = its centre) when there is one, into
/// `segments`: what LimbCollisions::deepest_penetration measures every
/// method with. The stiff-spring, Lagrange and Featherstone states share the rigid scene's.
/// A method's virtual links (its serial joints', scene/serial_links.hpp) are not the Model's
/// bodies and are left out.
template <typename Scalar>
void limb_segments(const VerletState<Scalar>& state, const Model& model, std::vector<LimbSegment>& segments);
void limb_segments(const RigidScene& scene, const Model& model, std::vector<LimbSegment>& segments);
/// Every limb the particle state has (its virtual links too), then the balls.
template <typename Scalar>
void limb_segments(const VerletState<Scalar>& state, std::vector<LimbSegment>& segments);

/// The deepest overlap of `segments` (limb_segments': the Model bodies' limbs, then the balls)
/// now, the same measure for every method: between limbs, and limbs and static geometry, by
/// `collisions` (a LimbCollisions of `model`: each limb as the capsule or cylinder around its
/// segment, the pairs it excludes left out); and below the ground, the deepest end sphere of a
/// capsule or end rim of a cylinder. The first of equal depths, in that order.
Penetration deepest_penetration(const Model& model, LimbCollisions& collisions, std::span<const LimbSegment> segments);

extern template Observation observe<float>(const VerletState<float>&, ObservationScope);
extern template Observation observe<double>(const VerletState<double>&, ObservationScope);

}  // namespace limber
