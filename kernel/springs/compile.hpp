// compile_springs(Model, SpringOptions) -> SpringState: the Model as rigid bodies and springs.
#pragma once

#include "kernel/model/model.hpp"
#include "kernel/springs/spring_state.hpp"

namespace limber {

/// Builds the stiff-spring state of `model` (thesis 4.4.1):
/// - each limb becomes a rigid body at its centre of mass, with the mass properties of
///   body_mass_properties() (kernel/mass/): uniform over its shape, or its point masses; its
///   frame is on its principal axes (diagonal inertia), and principal moments below 10⁻⁶ of the
///   largest (a limb of zero radius about its axis) are raised to that floor;
/// - each spherical joint becomes a zero-length spring with damping between its inboard and
///   outboard anchors (a world anchor stays fixed), k and c from `options`, else the joint's,
///   else Settings::springs;
/// - the ball becomes a solid sphere body; bodies joined by springs form islands, which start
///   asleep when the scene asks (Settings::sleep.start_asleep) and they are at rest;
/// - the implicit integrator's sparse pattern is built and analysed once (AMD ordering).
/// Throws ModelError when the model is invalid.
SpringState compile_springs(const Model& model, const SpringOptions& options = {});

/// World position of Model body `body`'s body-frame point `local_point` (Model frame: the
/// shape's centre), m.
Eigen::Vector3d world_point(const SpringState& state, std::size_t body, const Eigen::Vector3d& local_point);

}  // namespace limber
