// The particle method's contacts with other limbs and with static geometry, as contact rows
// (kernel/particles/contact_rows.hpp): found from the limbs' segments by the shared collision
// world (kernel/geometry/limb_collisions.hpp), projected in the coloured sweeps
// (kernel/relaxation/contact_relaxation.hpp), and given their restitution here, in the same
// velocity pass as the ground's and the ball's contacts (contacts.hpp).
//
// Detection runs on the predicted positions with a speculative margin: a pair is kept while its
// surfaces are closer than the margin — the most the two can close in the substep, twice the
// largest particle displacement, plus a slop — so a row holds C ≥ 0 before the limbs meet,
// and thin fast limbs do not pass through each other between detections. The margin is capped
// (0.5 m), so the ball is swept besides (continuous collision, kernel/geometry/time_of_impact.hpp):
// where its path from its previous position first touches static geometry that a search at its
// end would not answer (it passed through, or ends deep or beyond the middle: answer_at_touch),
// the search sees the ball there, so its row holds the surface it met at the normal it met it
// with (a plate thinner than the ball's travel is not passed, nor pushed out through its back).
//
// The broadphase runs at a step's first substep and keeps the pairs within the step's reach
// (each segment's motion in that substep times the step's substeps, and 1 cm more); the later
// substeps run the narrowphase on those pairs alone — the contacts a search would find, to the
// bit, as long as no segment has outrun its reach, and otherwise the substep searches again
// (LimbCollisions::find_kept_pairs). Box2D v3 also finds its pairs once a step; its contacts
// then keep their points through the substeps. Keeping the rows themselves (points, normals)
// through the step was tried and not kept: on the pile it diverged at 2 × 2, 4 × 2 and 16 × 2 and
// sank deeper (8 × 4: 5.2 cm against 8 mm).
#pragma once

#include "limber/kernel/particles/verlet_state.hpp"

namespace limber {

/// Finds the substep's limb–limb, limb–static and ball–static contacts into
/// state.contact_rows, waking a sleeping island an awake limb reaches. Nothing when the scene
/// has no collision beyond the ground, the bounds and the ball (LimbCollisions::active()).
/// A search with the broadphase keeps its pairs for `substeps_ahead` (≥ 1) substeps like this
/// one, its margins grown to match (1: for this one). `reuse_pairs` (a step's later substeps)
/// runs the narrowphase on the pairs kept instead, unless an island woke or fell asleep since
/// they were found or a segment outran them. Returns whether it searched.
template <typename Scalar>
bool detect_limb_contacts(VerletState<Scalar>& state, double dt, int substeps_ahead = 1, bool reuse_pairs = false);

/// The restitution pass over the contact rows (velocities, as apply_restitution in
/// contacts.hpp): a row still touching leaves with normal speed e·v (v its approach), 0 for
/// resting approaches; one pushed by relaxation also loses the push-out speed; under the rattle
/// rule each row is an inequality of the velocity stage (contact_impulse, contacts.hpp). Returns
/// the largest change of a row's normal speed, m/s.
template <typename Scalar>
double apply_contact_row_restitution(VerletState<Scalar>& state, double dt);

}  // namespace limber
