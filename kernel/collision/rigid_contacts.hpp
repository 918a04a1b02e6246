// Contacts of the rigid-body methods (every method on kernel/rigid/rigid_scene.hpp) (thesis 2.3–2.5): limbs and the ball against the ground
// and the bounds' walls, the ball against the limbs, and — through the collision world
// (kernel/geometry/limb_collisions.hpp) — limbs against limbs and limbs and the ball against the
// static colliders, answered with impulses.
//
// Detection runs after the bodies moved (the thesis's loop, figure 2.5: move, then collide):
// - a cylinder's end disk touches a plane at its lowest rim point, a capsule's end cap and the
//   ball at their lowest sphere point — up to two contacts per limb and plane;
// - the ball against a limb: bounding spheres first, and the exact sphere–capsule or
//   sphere–cylinder closest point only when they overlap (the hierarchical test of 2.4).
// Response (kernel/collision/impulses.hpp, sequential_collision_impulse): sequential impulses with
// restitution (eq. 2.32–2.37, the full inertia tensor) and Coulomb friction, normal then
// tangent, which never gain energy; a few passes so touching contacts settle;
// approach speeds below 2|g|Δt bounce with e = 0 so resting contacts stay at rest. Then the
// remaining overlap is removed by a position change through the same effective mass (the
// contact point moves out by the depth, shared by inverse mass and inertia), at most the step's
// own approach plus Settings::contact_recovery_speed·Δt, so an initial overlap is not flung out.
#pragma once

#include "limber/kernel/rigid/rigid_scene.hpp"

namespace limber {

/// Finds the contacts of the awake bodies at the current state into scene.contacts, wakes the
/// islands the ball or an awake limb touches and sets scene.ball_touching. Limb–limb contacts
/// have a = the lower body index, b = the other, normal from b to a and restitution 0.
void detect_rigid_contacts(RigidScene& scene);

/// Impulses and position correction for scene.contacts; dt is the step's.
void resolve_rigid_contacts(RigidScene& scene, double dt);

}  // namespace limber
