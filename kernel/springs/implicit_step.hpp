// The implicit step of the stiff-spring method: linearized backward Euler over the whole system
// (thesis eq. 3.16–3.22, in the form of Baraff & Witkin 1998, "Large steps in cloth simulation",
// eq. 6), so the joints' springs can be as stiff as wanted at any time step.
//
// Unknowns: each body's velocity change Δu = (Δv, Δω), 6 per body. A spring between anchor
// points p_i = x_i + r_i and p_j = x_j + r_j (r the world lever) has the relative-velocity
// Jacobian J = [G_i, −G_j], G = [E, −[r]×] (3×6): ḋ = J u. Its force f = −k·d − c·ḋ acts as
// the generalized force Gᵀf on each body, so ∂f/∂q = −k JᵀJ and ∂f/∂u = −c JᵀJ (the lever terms
// −[r]× are the anchor points' rotation with their bodies). One step solves
//   (M + (h·c + h²·k) Σ JᵀJ) Δu = h·(f₀ − h·k Σ Jᵀ ḋ₀),   M = diag(m E, I_world),
// which is symmetric positive definite, so LDLᵀ or conjugate gradients apply; f₀ holds gravity,
// drag, the springs and the gyroscopic torque −ω × I ω. Then x += h·v₁, q ← exp(h·ω₁)·q, and
// L ← L₀ + h·τ (so a torque-free body keeps L exactly). Left out, as Baraff & Witkin leave out
// non-symmetric terms: the geometric stiffness (∂Gᵀ/∂θ)·f from the levers turning under a
// loaded spring, which is second order in the rotation and would make the matrix non-symmetric.
// As h → ∞ an undamped spring's end reaches its anchor in one step (eq. 3.25).
#pragma once

#include "limber/kernel/springs/spring_state.hpp"

namespace limber {

/// Builds the block pattern of A (one 6×6 block per body and per joint between two bodies, which
/// its springs share; lower triangle) and analyses it for LDLᵀ once. Called by compile_springs().
void prepare_implicit_system(SpringState& state);

/// One implicit step of h seconds over the awake bodies (sleeping islands' rows get Δu = 0).
/// Fills the report's linear-solver fields.
void implicit_step(SpringState& state, double h, StepReport& report);

}  // namespace limber
