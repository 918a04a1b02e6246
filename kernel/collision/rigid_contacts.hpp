// Contacts of the rigid-body methods (every method on kernel/rigid/rigid_scene.hpp) (thesis 2.3–2.5): limbs and the ball against the ground
// and the bounds' walls, the ball against the limbs, and — through the collision world
// (kernel/geometry/limb_collisions.hpp) — limbs against limbs and limbs and the ball against the
// static colliders, answered with impulses.
//
// Detection runs after the bodies moved (the thesis's loop, figure 2.5: move, then collide; the
// Featherstone method under semi-implicit Euler runs it at the step's start instead, with
// RigidScene::speculative_time for speculative contacts, and remember_step_start after it, so the
// ball's path swept is the last step's):
// - a cylinder's end disk touches a plane at its lowest rim point, a capsule's end cap and the
//   ball at their lowest sphere point — up to two contacts per limb and plane;
// - each ball's candidate bodies come from the broadphase (BallCandidates,
//   kernel/geometry/broadphase.hpp: boxes about its path this step and the limbs' bounding spheres),
//   not from every body;
// - the ball against a limb: bounding spheres first, and the exact sphere–capsule or
//   sphere–cylinder closest point only when they overlap (the hierarchical test of 2.4);
// - continuous collision for each ball, first: a ball tested only where it overlaps after the
//   move passes through a limb thinner than its step's travel (4.4 m/s against a 4 cm limb at
//   Δt = 1/60 s, bench/collision.md). So its path over the step, from its centre at the step's start
//   (RigidScene::step_start_position, remember_step_start) to its centre now, is swept against
//   the limbs and the static colliders (time of impact, kernel/geometry/time_of_impact.hpp). At
//   its first touch of one that the overlap test will not answer — the ball passed through it,
//   grazed it between two steps, or ends deeper than half its radius in it or beyond its middle
//   (answer_at_touch) — the ball is moved back to that touch (1 µm inside, so the overlap test
//   finds the contact there, with the normal at the time of impact) and keeps its velocity: the
//   impulses answer the hit, and the ball gives up the rest of its step's travel (Box2D's
//   bullets and Bullet's CCD motion clamping do the same). Touches the overlap test answers
//   (the ball ends just inside, on the side it came from), resting and sliding contacts are as
//   before; a shape the ball already overlaps at the step's start by more than 1% of its radius
//   is the push-out's. Assumed: a limb holds still at its end-of-step pose through the step
//   (exact for a limb at rest; a limb swinging fast towards the ball meets it late or not at
//   all), and the planes are not swept (a half-space cannot be passed through).
// Response (kernel/collision/impulses.hpp, sequential_collision_impulse): sequential impulses with
// restitution (eq. 2.32–2.37, the full inertia tensor) and Coulomb friction, normal then
// tangent, which never gain energy; a few passes so touching contacts settle;
// approach speeds below 2|g|Δt bounce with e = 0 so resting contacts stay at rest. Then the
// remaining overlap is removed by a position change through the same effective mass (the
// contact point moves out by the depth, shared by inverse mass and inertia), at most the step's
// own approach plus Settings::contact_recovery_speed·Δt, so an initial overlap is not flung out.
#pragma once

#include "limber/kernel/rigid/rigid_scene.hpp"
#include "limber/kernel/threading/block_runner.hpp"

namespace limber {

/// Body b's Model shape as the rigid scene keeps it (RigidShapes; a ball's: a capsule of length 0).
Shape model_shape(const RigidScene& scene, std::size_t b);

/// Records every body's centre of mass in scene.step_start_position: the start of the path
/// detect_rigid_contacts sweeps the ball along. Every rigid method's step calls it first.
void remember_step_start(RigidScene& scene);

/// Finds the contacts of the awake bodies at the current state into scene.contacts (and with
/// scene.speculative_time the gaps they may close, with a negative depth), wakes the
/// islands the ball or an awake limb touches and sets scene.ball_touching. Limb–limb contacts
/// have a = the lower body index, b = the other, normal from b to a and restitution 0. First
/// moves the ball back along its path to where it hit a limb or a static collider (above);
/// returns whether it did, so a method keeping its own coordinates (Featherstone's q) takes the
/// ball's new position over. A scene with nothing to meet (no plane, no collision world, no
/// ball) finds nothing and leaves scene.limb_segments as they were. `runner`: threads for the
/// bodies' segments and reaches and the collision world's narrow phase (null: the calling
/// thread); the contacts are the same, in the same order, for any thread count.
bool detect_rigid_contacts(RigidScene& scene, BlockRunner* runner = nullptr);

/// A rigid method's step counts in report.profile (step_status.hpp, StepProfile): one substep,
/// report.contacts, and the broadphase pairs of the last detect_rigid_contacts. Called only when
/// the method's options ask for the profile.
inline void count_rigid_step(const RigidScene& scene, StepReport& report) {
  report.profile.substeps = 1, report.profile.contacts = report.contacts;
  report.profile.candidate_pairs = scene.collisions.active() ? static_cast<int>(scene.collisions.candidate_pairs()) : 0;
}

/// Impulses and position correction for scene.contacts; dt is the step's.
void resolve_rigid_contacts(RigidScene& scene, double dt);

}  // namespace limber
