// The contact rows' part of relaxation (kernel/particles/contact_rows.hpp): coloured every
// substep as contacts come and go, batched by colour, and swept after the distance constraints
// and the joint rows in every sweep — colour after colour, SIMD lanes and threads inside a
// colour, the overflow last — on the SoA particle arrays. Internal to kernel/relaxation.
//
// The colouring is Box2D v3's constraint graph rebuilt each substep: each row, in the rows'
// order (detection's, which is deterministic), takes the lowest colour that moves none of its
// movable particles yet; static and pinned particles never block a colour. A row no colour
// takes goes to the overflow. The rows are coloured among themselves, not with the joints: a
// sweep runs the distance colours, the joint colours, then the contact colours.
#pragma once

#include "limber/kernel/particles/verlet_state.hpp"

namespace limber {

/// Colours state.contact_rows and fills the plan's contact batches (λ and friction zeroed), with
/// what the sweeps would otherwise gather every time: the shares w_k c_k, the effective masses
/// and the start points at the substep's start positions (so call it after the prediction, as
/// step() does, and before the sweeps). Allocates only when the rows outgrow every earlier
/// substep's.
template <typename Scalar>
void build_contact_batches(VerletState<Scalar>& state);

/// One sweep of every contact row (positions). Returns the largest displacement, m.
template <typename Scalar>
double contact_position_sweep(VerletState<Scalar>& state);

}  // namespace limber
