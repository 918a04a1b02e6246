// Impulse response of colliding rigid bodies, with restitution and Coulomb friction (thesis 2.5).
//
// Two bodies a and b touch at a point p with unit normal n pointing from b towards a. An impulse
// j (N·s) applied at p, +j to a and −j to b, changes their velocities instantly:
//   Δv_a = w_a j,   Δω_a = I_a⁻¹ (r_a × j),   r_a = p − c_a   (and the opposite for b),
// with w = 1/m and I⁻¹ the world-frame inverse inertia tensor. The relative velocity of the two
// material points at p, v_rel = v_a(p) − v_b(p), then changes by K j, where K is the collision
// matrix (Mirtich, "Impulse-based dynamic simulation of rigid body systems", PhD thesis,
// Berkeley 1996), [r]× the cross-product matrix ([r]× x = r × x):
//   K = (w_a + w_b) E − [r_a]× I_a⁻¹ [r_a]× − [r_b]× I_b⁻¹ [r_b]×.
// Baraff ("Rigid body simulation II — nonpenetration constraints", SIGGRAPH course notes 1997,
// section 8, colliding contact) uses only its normal-normal entry.
// K is symmetric positive semi-definite, and positive definite when either inverse mass is
// positive. Along the normal it is the thesis's denominator of eq. 2.37:
//   nᵀ K n = 1/m1 + 1/m2 + ((I1⁻¹(r1×n))×r1 + (I2⁻¹(r2×n))×r2)·n,
// written with the inertia tensor where the thesis divides by a scalar I.
//
// Restitution (thesis eq. 2.32) is Newton's: the normal relative velocity after impact is −e
// times the one before, e in [0, 1] (0: the bodies stay in contact, 1: elastic). Friction is
// Coulomb's, applied to the impulse: the tangential impulse is at most μ times the normal one.
// Units: kg, m, s. An immovable body (the ground, a wall) has zero inverse mass and inertia; a
// body turning about a fixed pivot has zero inverse mass, its pivot as `centre_of_mass` and its
// inverse inertia about the pivot.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// The state of a rigid body an impulse acts on, all in the world frame.
struct ImpulseBody {
  double inverse_mass = 0;                                        ///< 1/kg; 0 for an immovable body
  Eigen::Matrix3d inverse_inertia = Eigen::Matrix3d::Zero();      ///< about the centre of mass, 1/(kg·m²)
  Eigen::Vector3d centre_of_mass = Eigen::Vector3d::Zero();       ///< m
  Eigen::Vector3d linear_velocity = Eigen::Vector3d::Zero();      ///< of the centre of mass, m/s
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();     ///< rad/s
};

/// World-frame inverse inertia tensor R I_body⁻¹ Rᵀ (1/(kg·m²)) of a body whose body-frame
/// inertia tensor (about its centre of mass, kg·m², symmetric positive definite; see
/// kernel/mass/mass_properties.hpp) is `body_inertia` and whose orientation (body → world) is
/// `orientation` (normalized here). The body-frame tensor is constant, so its inverse can be
/// computed once and only rotated as the body turns (Baraff, "Rigid body simulation I", 1997).
/// Throws std::invalid_argument if `body_inertia` is not positive definite.
Eigen::Matrix3d world_inverse_inertia(const Eigen::Matrix3d& body_inertia, const Eigen::Quaterniond& orientation);

/// Velocity (m/s) of the body's material point at world `point`: v + ω × (point − c).
Eigen::Vector3d velocity_at(const ImpulseBody& body, const Eigen::Vector3d& point);

/// Collision matrix K (1/kg: m/s per N·s): the change of the relative velocity
/// v_a(p) − v_b(p) caused by an impulse j at `point`, +j on a and −j on b, is K j. See the
/// header comment; nᵀKn is the thesis's denominator of eq. 2.37.
Eigen::Matrix3d collision_matrix(const ImpulseBody& a, const ImpulseBody& b, const Eigen::Vector3d& point);

/// The thesis's linear-only impulse (eq. 2.33, 2.34), bodies treated as particles:
///   J = −(1 + e) (v1 − v2)·n / (1/m1 + 1/m2),   returned as J·n (N·s, +on a, −on b),
/// v the centre-of-mass velocities, n unit from b to a. Zero when the centres separate
/// ((v1 − v2)·n ≥ 0) or both bodies are immovable. It equals collision_impulse without friction
/// when the impact is central (r parallel to n) or the inertia is infinite (I⁻¹ = 0).
Eigen::Vector3d linear_collision_impulse(const ImpulseBody& a, const ImpulseBody& b, const Eigen::Vector3d& normal,
                                         double restitution);

/// The impulse of one collision: `impulse` is applied +impulse to a and −impulse to b.
struct CollisionImpulse {
  Eigen::Vector3d impulse = Eigen::Vector3d::Zero();  ///< N·s
  double normal_impulse = 0;                           ///< impulse·n, N·s (≥ 0)
  bool sliding = false;  ///< true when friction was bounded by the Coulomb cone (the bodies slide)
};

/// Impulse response with Newton restitution and Coulomb friction at `point` (m), `normal` unit
/// from b towards a, `restitution` e in [0, 1], `friction` μ ≥ 0 (throws std::invalid_argument
/// otherwise). With v_rel = v_a(p) − v_b(p) and v_n = v_rel·n:
/// - v_n ≥ 0 (separating or resting without approach): no impulse.
/// - Sticking is tried first: the impulse j solving K j = −v_rel − e v_n n leaves no tangential
///   relative velocity and a normal one of −e v_n. It is kept if |j_t| ≤ μ j_n
///   (j_n = j·n, j_t = j − j_n n): inside the friction cone.
/// - Otherwise the bodies slide: j = j_n (n − μ t), t the unit direction of the pre-impact
///   tangential relative velocity (when that is zero, t = −j_t/|j_t| from the sticking impulse,
///   so friction still acts along the impulse that would have stopped the sliding), with
///   j_n = −(1 + e) v_n / (nᵀ K (n − μ t)) so that the normal relative velocity is still −e v_n.
/// This is the algebraic Coulomb impulse (Mirtich & Canny, "Impulse-based simulation of rigid
/// bodies", 1995; Stewart, "Rigid-body dynamics with friction and impact", SIAM Review 2000): one
/// linear solve, with the sliding direction frozen at its pre-impact value instead of followed
/// through the impact as Mirtich's thesis integrates it.
/// Energy: without friction it never gains kinetic energy for e ≤ 1, and neither does it when K
/// does not couple normal and tangent (nᵀK t = 0: central impacts) and is isotropic in the
/// tangent plane (spheres). With friction and coupling it can GAIN energy, and does often:
/// - sticking gains ½ j_t·v_t when the tangential impulse has a component along the sliding
///   velocity (possible through the off-diagonal nᵀK t);
/// - sliding gains without bound when nᵀK(n − μt) is small but positive: j_n = −(1+e)v_n / that
///   grows as it nears 0, and the frozen friction direction then drives the tangential velocity
///   far past zero.
/// Measured over 10⁵ random impacts each (random masses, inertia tensors, velocities and contact
/// points, e uniform in [0, 1]): free-body pairs gained energy in 0.4 % of impacts at μ = 0.1 and
/// 3–4 % at μ = 0.5–3; a body against immovable ground in 0.6 % and 5–10 %; the worst cases
/// multiplied the kinetic energy by 10⁴ or more (a one-off measurement; the test suite checks only
/// that gains occur). Use μ = 0, or an integrating (Mirtich) or complementarity (Stewart–Trinkle)
/// model, where that matters.
/// Where nᵀK(n − μt) ≤ 0 (no sliding impulse reaches −e v_n: the impulsive form of Painlevé's
/// paradox) the sticking impulse is returned, or the frictionless one if sticking is not reachable.
/// Returns zero when no impulse can change the normal relative velocity (nᵀKn = 0: both bodies
/// immovable, or pinned so that p cannot move along n).
CollisionImpulse collision_impulse(const ImpulseBody& a, const ImpulseBody& b, const Eigen::Vector3d& point,
                                   const Eigen::Vector3d& normal, double restitution, double friction);

/// The same contact answered one direction at a time, as sequential-impulse solvers do (Catto,
/// "Iterative dynamics with temporal coherence", GDC 2005): first the normal impulse
/// j_n = −(1+e)·v_n / (nᵀK n) (eq. 2.37), then, along the direction t of the sliding velocity
/// that remains, the impulse that stops sliding, −(t·v)/(tᵀK t), clamped to μ·j_n. Each is an
/// impulse along one direction of at most (1+e) times what stops motion along it, which changes
/// the kinetic energy by −(s − s²/2)(d·v)²/(dᵀK d) ≤ 0 for s ∈ [0, 2]: unlike the coupled model
/// above, it never gains energy, at any μ. The price: when K couples n and t (an off-centre
/// contact), the friction impulse slightly changes the normal velocity it follows. Used by the
/// rigid-body methods' contacts (kernel/collision/rigid_contacts.hpp). Same conventions and returns as
/// collision_impulse.
CollisionImpulse sequential_collision_impulse(const ImpulseBody& a, const ImpulseBody& b, const Eigen::Vector3d& point,
                                              const Eigen::Vector3d& normal, double restitution, double friction);

/// Applies impulse j (N·s) at world `point` to `body`: v += w j, ω += I⁻¹ ((point − c) × j).
/// For a collision, apply +impulse to a and −impulse to b.
void apply_impulse(ImpulseBody& body, const Eigen::Vector3d& point, const Eigen::Vector3d& impulse);

}  // namespace limber
