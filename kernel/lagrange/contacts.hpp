// Contacts and limits of the Lagrange method solved through its joints: what a contact pushes
// moves the whole jointed body and opens no joint, and a push that would turn a joint past its
// limit is held by it.
//
// A row r — a contact's normal n or one of its tangents t at point p between bodies a and b, or a
// limit's nearer side — has a Jacobian G_r: [d; (p − c_a) × d] on a and its negative on b for a
// contact, the joint control row's (joint_controls.hpp), signed to point inside, for a limit. Its
// response, the velocity change of every body when a unit impulse acts along it with the joints'
// equality rows held (J·Δu = 0), is one substitution against the factor of [M Jᵀ; J 0]:
// Δu_r = (M⁻¹ − M⁻¹Jᵀ(JM⁻¹Jᵀ)⁻¹JM⁻¹) G_rᵀ, the Schur complement of the joint rows. The rows'
// Delassus matrix is W = G·[Δu_r], and projected Gauss-Seidel on it gives the impulses: λ ≥ 0 on
// a normal reaching its contact's bounce (restitution above the resting speed, else 0) and on a
// limit reaching at most its bound within the step (a limit past it stops); a contact's normal
// and tangents together by the step of kernel/numerics/contact_projection.hpp on its 3×3 block of
// W, friction in Coulomb's disc |λ_t| ≤ μ·λ_n opposing the slip it leaves (until this design each
// tangent took its own diagonal entry and their pair was clamped to the disc, which converges to
// a slip along −W_tt λ_t; the ragdoll stack now rests at every landing phase). The push-out solves the same rows for position changes: each
// normal out by its depth less the separation it may keep (the rule of every method,
// geometry.hpp), each limit past its bound back onto it, none pushed past. Rows of bodies in
// different islands (the bodies joints and gears join) share a substitution (their responses do
// not overlap), so a step costs a factor and about three substitutions per contact and one per
// limit of its most touched island, not per row of the scene. Drives and joint friction stay in the step's own solves.
// Before the move (semi-implicit Euler; step.cpp): the contacts are found at the step's start
// pose, speculative gaps included, and answered on the velocity-level step's velocities before
// the bodies move: a gap may close within the step and no more, a bounce leaves from where it is
// (contact_target_speed), and the push-out takes the start pose's overlap beyond twice
// kRestingSlop (push_out_before_move), as Featherstone's contacts before the move do.
// MuJoCo forms A = J M⁻¹ Jᵀ through its factor and solves contacts and limits on it alike
// (engine_solver.c); Featherstone's method takes the same contact step through its joint-space
// factor, warm-started (kernel/featherstone/joint_space_contacts.hpp).
#pragma once

#include "limber/kernel/lagrange/lagrange_state.hpp"

namespace limber {

/// Sizes state.contact_scratch for the scene at compile (after its islands): room for the rows
/// and responses of every contact the scene reserved.
void prepare_contacts_with_joints(LagrangeState& state);

/// Answers state.contacts (detect_rigid_contacts) and the joints' limits for a step of dt through
/// the joints: velocity impulses, then the push-out (positions). `before_move`: the contacts were
/// found at the step's start, speculative gaps included, and the bodies move after this
/// ("Before the move" above). Does nothing without contacts (the step's own solves hold the
/// limits then). Needs constraints (state.constraints.size() > 0); without them
/// resolve_rigid_contacts answers the same contacts body by body.
void resolve_contacts_with_joints(LagrangeState& state, double dt, bool before_move);

}  // namespace limber
