// compile(Model, VerletOptions) -> VerletState: the Model as particles and distance constraints.
#pragma once

#include <string>

#include "kernel/model/model.hpp"
#include "kernel/verlet/verlet_state.hpp"

namespace limber {

/// Builds the Verlet state of `model` (thesis 3.2.5, 4.2.2):
/// - each limb becomes two particles, its head and tail (the ends of its axis), each carrying
///   half its mass, and a distance constraint of the limb's length between them;
/// - a spherical joint becomes a zero-length distance constraint between the inboard limb's
///   anchor particle and the outboard's, or one shared particle when
///   settings.verlet.joints == shared_particle; a joint to the world pins a particle (w = 0);
/// - initial velocities become previous positions, x(−Δt) = x(0) − v·Δt;
/// - particles are grouped by island (connected limbs) and ordered breadth-first from the
///   island's root (a limb held by the world, else its first limb), so constraints are swept
///   from the pinned end outwards; the ball is its own island;
/// - passes the scene does not need are left out: no contact features without a ground or
///   bounds, no ball contacts without a ball.
/// Throws ModelError when the model is invalid or names something the particle method cannot
/// represent (an anchor that is not an axis end point), naming the joint.
template <typename Scalar>
VerletState<Scalar> compile(const Model& model, const VerletOptions& options = {});

/// A particle's name for outputs: "<body>.head", "<body>.tail", "<joint>.pin" or "ball".
/// `model` is the one the state was compiled from.
std::string particle_name(const Model& model, const ParticleOrigin& origin);

extern template VerletState<float> compile<float>(const Model&, const VerletOptions&);
extern template VerletState<double> compile<double>(const Model&, const VerletOptions&);

}  // namespace limber
