// compile(Model, VerletOptions) -> VerletState: the Model as particles and distance constraints.
#pragma once

#include <string>

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/particles/verlet_state.hpp"

namespace limber {

/// Builds the Verlet state of `model` (thesis 3.2.5, 4.2.2):
/// - each limb becomes two particles, its head and tail (the ends of its axis), joined by a
///   distance constraint of the limb's length (its link constraint). Where its mass goes is
///   options.verlet.limb_masses (thesis 4.1):
///   - ends: half at each end, the thesis's program, whatever the limb's point masses; the
///     particle limb has the right mass and centre (for a uniform limb) but a uniform rod's
///     transverse inertia m·L²/4 instead of m·L²/12, so it swings like a simple pendulum;
///   - inertia: a third particle at the limb's centre, joined to the head and the tail by
///     distance constraints of length L/2, and masses m_tail, m_centre, m_head at z = −L/2, 0,
///     +L/2 that reproduce the limb's mass, centre of mass along the axis and inertia about a
///     transverse axis (body_mass_properties, kernel/mass/mass_properties.hpp; the mean of
///     I_xx and I_yy when they differ): a uniform rod gets m/6, 2m/3, m/6. This is the placement
///     that honours Body::point_masses. Three collinear particles hold the centre on the axis
///     only to second order, so step() also projects it onto the midpoint of head and tail after
///     every sweep (step.hpp). The centre is never a joint anchor and has no contact feature:
///     contacts push the ends, and the centre follows (collision/contacts.hpp);
///   - lumps: each of the body's point masses goes to the head and the tail by the lever rule,
///     so lumps at the ends are represented exactly (a chain of point masses on massless rods,
///     with shared-particle joints); a lump's own radius is not represented;
/// - a spherical joint becomes a zero-length distance constraint between the inboard limb's
///   anchor particle and the outboard's, or one shared particle when
///   options.verlet.joints == shared_particle; a joint to the world pins a particle (w = 0);
/// - initial velocities become previous positions, x(−Δt) = x(0) − v·Δt, and, under the rattle
///   projection rule, the particles' velocities (the rule is fixed at compile: the state is (x, v));
/// - particles are grouped by island (connected limbs); constraints run breadth-first from the
///   island's root (a limb held by the world, else its first limb), so they are swept from the
///   pinned end outwards, and the particles are then numbered in VerletOptions::ordering
///   (depth parity by default); each ball is its own island;
/// - passes the scene does not need are left out: no contact features without a ground or
///   bounds, no ball contacts without a ball.
/// Throws ModelError when the model is invalid or names something the particle method cannot
/// represent: an anchor that is not an axis end point (naming the joint); with limb_masses
/// inertia, a limb whose centre of mass is off its axis, or whose transverse inertia three
/// positive masses on its axis cannot give — a cylinder with radius²/4 ≥ length²/6, mass beyond
/// an end or all at one point (naming the body; "ends" represents every limb); with lumps, a body
/// without point masses, a lump off the axis or beyond an end, or an end left without mass that
/// no joint shares with a massive particle or pins (naming the body).
template <typename Scalar>
VerletState<Scalar> compile(const Model& model, const VerletOptions& options = {});

/// A particle's name for outputs: "<body>.head", "<body>.tail", "<body>.centre", "<joint>.pin"
/// or a ball's (ball_name, model.hpp).
/// `model` is the one the state's indices count: for a Model with serial joints, its expansion
/// (expand_serial_joints, serial_links.hpp), whose virtual links follow the Model's bodies.
std::string particle_name(const Model& model, const ParticleOrigin& origin);

extern template VerletState<float> compile<float>(const Model&, const VerletOptions&);
extern template VerletState<double> compile<double>(const Model&, const VerletOptions&);

}  // namespace limber
