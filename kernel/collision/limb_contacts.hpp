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
#pragma once

#include "limber/kernel/particles/verlet_state.hpp"

namespace limber {

/// Finds the substep's limb–limb, limb–static and ball–static contacts into
/// state.contact_rows, waking a sleeping island an awake limb reaches. Nothing when the scene
/// has no collision beyond the ground, the bounds and the ball (LimbCollisions::active()).
template <typename Scalar>
void detect_limb_contacts(VerletState<Scalar>& state, double dt);

/// The restitution pass over the contact rows (velocities, as apply_restitution in
/// contacts.hpp): a row still touching leaves with normal speed e·v (v its approach), 0 for
/// resting approaches; one pushed by relaxation also loses the push-out speed; under the rattle
/// rule each row is an inequality of the velocity stage (contact_impulse, contacts.hpp). Returns
/// the largest change of a row's normal speed, m/s.
template <typename Scalar>
double apply_contact_row_restitution(VerletState<Scalar>& state, double dt);

}  // namespace limber
