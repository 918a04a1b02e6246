// The explicit spring integrators' stability bound on a model (thesis 3.3, eq. 3.15), from the
// spring modes linearized about the model's initial pose (bench/reliability.md, "Stability stress").
//
// Linearize the spring method about the initial pose: u = the bodies' velocities (v, ω), 6 per
// body; each joint's separation d = p_inboard − p_outboard has velocity J u with J = [I, −[r_in]×]
// for the inboard body and −[I, −[r_out]×] for the outboard one (r: the anchor from the centre of
// mass, world). The springs f = −k·d − c·ḋ give M u̇ = −K x − C u with K = k Σ JᵀJ and
// C = c Σ JᵀJ = (c/k)·K: damping proportional to stiffness, so the modes of K φ = ω² M φ
// decouple, each ẍ + γ ẋ + ω² x = 0 with γ = (c/k)·ω². (Gravity's geometric stiffness,
// |tension|/L, is left out: 10² N/m beside k ≥ 10³ N/m for an equal-mass chain of 0.1 m links.)
//
// Forward Euler (the thesis's) multiplies each eigenvalue λ of a mode by z = 1 + hλ, so it is
// stable when |1 + hλ| ≤ 1 — eq. 3.15, h·k < 2 for ẏ = −k y, with k → −λ. For the damped mode,
// λ² + γλ + ω² = 0:
//   underdamped (γ < 2ω): |1 + hλ|² = 1 − hγ + h²ω² ≤ 1  ⇔  h ≤ γ/ω² = c/k, for every mode;
//   overdamped  (γ ≥ 2ω): both λ real, the fast one sets h·|λ_fast| ≤ 2,
//                         h ≤ 4/(γ + √(γ² − 4ω²)) (< c/k).
// (c = 0: never stable — undamped motion gains energy at every h, by a factor 1 + h²ω² a step.)
// Semi-implicit (symplectic) Euler, v' = v + h(−ω²x − γv), x' = x + h v', has the amplification
// polynomial z² − (2 − hγ − h²ω²) z + (1 − hγ); its roots are in the unit disc (Schur–Cohn)
// when h²ω² + 2hγ ≤ 4:  h ≤ √((c/k)² + 4/ω²) − c/k, the symplectic h·ω < 2 shortened by damping.
// The model's bound is the smallest over its modes.
#pragma once

#include <vector>

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/springs/spring_state.hpp"

namespace limber::study {

/// The spring-mode frequencies ω (rad/s) of `model` under springs of `stiffness` (N/m), from
/// K φ = ω² M φ at the initial pose; rigid motions (ω² ≤ 10⁻⁹ of the largest) left out. Dense:
/// O((6·bodies)³), for models of tens of bodies. Throws ModelError for an invalid model.
std::vector<double> spring_mode_frequencies(const Model& model, double stiffness);

/// The largest stable step (s) of `integrator` on a model whose spring modes are `frequencies`
/// (rad/s), with springs k (N/m) and c (N·s/m), by the bounds above. Infinity for the implicit
/// step (Integrator::backward_euler) and the Runge-Kutta ones, which this does not bound.
double predicted_largest_stable_step(Integrator integrator, const std::vector<double>& frequencies, double stiffness,
                                     double damping);

}  // namespace limber::study
