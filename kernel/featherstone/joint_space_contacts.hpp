// Contacts of the Featherstone method, answered through the joint-space inertia: the impulsive
// form of the equations of motion, H·Δv = Jᵀι (Featherstone 2008, chapter 11, impact), solved by
// the articulated-body algorithm instead of forming H — an impulse on one link moves the whole
// tree, at O(n) (Mirtich 1996, "Impulse-based dynamic simulation of rigid body systems", PhD
// thesis, Berkeley, which also measures an articulated body's collision matrix with test
// impulses; Kokkevis 2004, "Practical physics for articulated characters", GDC).
//
// The contacts are found on the rigid bodies the state keeps beside (q, v)
// (detect_rigid_contacts, kernel/collision/rigid_contacts.hpp): body a touches body b (b: a
// plane, or another body) at p with normal n from b to a. Their response:
//
// Impulse response. A world impulse J at p on tree body i is a spatial impulse
// f = (E((p − r) × J), E J) in the body's frame (E: world → body rotation, r: the body's origin).
// Its generalized impulse τ = Jᵀ f (nv) is what propagating f to the root collects,
// τ_k = S_kᵀ f on every joint k between i and the root; the joint velocities change by
// Δv = H⁻¹ τ. Neither H nor Jᵀ is formed: Δv is the articulated-body algorithm (Table 7.1) run
// with v = 0, g = 0, τ = 0 and f as an external force — its bias terms vanish, so its inward
// pass is p_i = −f_i, u_i = −S_iᵀ p_i, p_λ += λX_i*(p_i + U_i D_i⁻¹ u_i) and its outward pass
// Δv_i = D_i⁻¹(u_i − U_iᵀ ⁱX_λ Δa_λ), Δa_i = ⁱX_λ Δa_λ + S_i Δv_i gives every body's spatial
// velocity change Δa_i as well. The articulated inertias I^A, U, D⁻¹ depend on q only: computed
// once per step (one ABA with v = 0), each impulse then costs O(bodies of its island).
//
// Per contact, its collision matrix K (3×3, world: the change of the relative velocity
// v_a(p) − v_b(p) per unit impulse +J on a and −J on b) is measured once per step with three
// unit impulses: K = J_c H⁻¹ J_cᵀ for the contact's three rows J_c, symmetric positive
// semi-definite; its normal-normal entry is the contact's effective inverse mass
// 1/(J_n H⁻¹ J_nᵀ).
//
// Impulses. Sequential impulses as in the rigid methods (rigid_contacts.hpp; Catto 2005), a
// fixed number of passes (RigidScene::contact_iterations): in each pass, a contact approaching
// (v_n = n·(v_a(p) − v_b(p)) < 0) gets the normal impulse j_n = −(1 + e)·v_n / (nᵀKn) — Newton's
// restitution on the approach it has at that moment, e set to 0 for contacts that approached
// slower than 2|g|Δt before the first pass (resting contacts stay at rest) — and then, along the
// direction t of the sliding velocity that leaves, the impulse that stops sliding,
// −(t·v)/(tᵀKt), clamped to Coulomb's μ·j_n. Each is an impulse along one direction of at most
// (1 + e) times the one that stops motion along it, which changes the kinetic energy ½vᵀHv by
// −(s − s²/2)(d·v)²/(dᵀKd) ≤ 0, s ∈ [0, 2]: never adds energy.
//
// Penetration. Then a position pass through the same effective masses pushes overlaps out: each
// contact's target is its depth, at most the step's approach plus
// Settings::contact_recovery_speed·Δt (an initial overlap is not flung out); projected
// Gauss–Seidel over the contacts on the linearized map from a joint-space displacement
// δ = H⁻¹Jᵀλ (λ ≥ 0, accumulated per contact) to the contact points' motion, the same passes;
// then q ← q ⊕ δ (displace_positions). No velocity bias (Baumgarte) is added; but v holds
// relative velocities in the child frames the push-out turned, so v is re-projected: the
// velocities that keep every body's motion in its own frame as closely as the joints allow at
// the new pose, in the kinetic-energy metric, v = H⁻¹ Σ J_iᵀ I_i v_i (one inward pass and one
// ABA): an H-orthogonal projection, which never adds kinetic energy — keeping v instead would
// swing a limb's fast spin about its axis onto its neighbours. The rigid bodies are refreshed.
#pragma once

#include <vector>

#include "limber/kernel/featherstone/featherstone_state.hpp"

namespace limber {

/// Impulses, then push-out, for state.contacts (found by detect_rigid_contacts on the refreshed
/// rigid bodies); dt is the step's. Leaves (q, v), state.kinematics and the rigid bodies
/// consistent. Allocates nothing.
void resolve_joint_space_contacts(FeatherstoneState& state, double dt);

/// Applies only the impulses of resolve_joint_space_contacts (no push-out) and refreshes the
/// rigid bodies: for tests of the impulses' energy.
void apply_joint_space_impulses(FeatherstoneState& state, double dt);

/// τ = Σ J_iᵀ f_i: the joint forces (nv) equivalent to spatial forces f_i on the tree bodies
/// (body coordinates, at the body's origin; `body_forces`, one per tree body, consumed: zeroed),
/// by the inward pass of recursive Newton–Euler (Table 5.1): τ_i = S_iᵀ f_i, f_λ += λX_i* f_i.
/// Reads state.kinematics.parent_to_body.
void joint_forces_of_body_forces(const FeatherstoneState& state, std::vector<SpatialVector>& body_forces,
                                 Eigen::VectorXd& joint_forces);

}  // namespace limber
