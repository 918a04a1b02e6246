// The multipliers of the Lagrange method: the constraint forces that keep every joint closed.
//
// Each constraint c has rows C_c with velocity Jacobian blocks J_c,b (rows × 6) on the bodies it
// joins (kernel/lagrange/constraints.hpp; thesis figure 3.5: each joint touches only the blocks of
// its two bodies). With u̇ = M⁻¹(F + Jᵀλ) the joints stay closed when
//   J M⁻¹ Jᵀ λ = −(J M⁻¹ F + J̇u) − 2ω_b·Ċ − ω_b²·C          (thesis 3.1.4; Baumgarte terms optional)
// F holds the applied forces and, on the rotational rows, the gyroscopic torque −ω × Iω. Solved
// either by Baraff's tree-ordered factorization of [M Jᵀ; J 0] (kernel/numerics/tree_elimination.hpp;
// linear time) or, for graphs with loops, by Eigen's sparse LDLᵀ of J M⁻¹ Jᵀ. Both take a
// compliance A per row (J u̇ + A λ = c): 0 for the joints' equations, set per mode for their
// control rows (limits, friction, drives: joint_controls.hpp).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "limber/kernel/lagrange/lagrange_state.hpp"

namespace limber {

/// Orders the body–constraint graph for the tree solver (breadth-first from each component's
/// joint to the world, else its lowest body; eliminated in reverse) and sets state.uses_tree:
/// false when the constraints close a loop — between bodies (a gear between two axled wheels
/// does), or through the world by a second world joint in one component — (the sparse path then
/// serves) or when options ask for the sparse path. Throws ModelError when options.solver is
/// `tree` and a constraint closes a loop, naming it.
void prepare_multiplier_solver(LagrangeState& state, const Model& model);

/// Computes state.geometry (the constraints' levers and Jacobian blocks) and world_inertia for
/// state y: what the solves below read. Call it whenever y changed. Also measures the joints'
/// control rows (measure_joint_controls, with state.velocity and angular_velocity: fill them for
/// y first where rates matter) and leaves every control row off (zero Jacobian row, compliance 1),
/// so a solve that does not set them (solve_constrained alone) ignores them.
void update_geometry(LagrangeState& state, const RigidBodyState& y);

/// What the unknowns x of a solve with control rows are, and so what each row asks (s the
/// side of a row's nearer limit, w its rate, gap its distance inside the limit, w₀ the rate
/// before a change).
enum class ControlLevel : std::uint8_t {
  /// x = u₁, the velocities after the velocity-level step of dt. A limit engages at s·w ≥ −gap/dt
  /// (speculative: reached, not crossed, within the step) or, past it, s·w ≥ −ω_b·gap; a drive
  /// is compliant (A = 1/(dt·(k·dt + c))); friction holds up to f·dt, else slides at it.
  velocity,
  /// x = Δu, a velocity change, with the rows of `velocity` on the rates w₀ + J·Δu: the impulse
  /// pass before an acceleration-level step.
  velocity_change,
  /// x = Δu over an acceleration-level step as its stages treat the rows (to first order): limits
  /// at or past their bounds (or engaged by the impulse pass) s·J·Δu ≥ 0, friction that held in
  /// the impulse pass keeps the rate (up to f·dt), no drive.
  stage_change,
  /// x = u̇, an acceleration-level stage. Limits as in stage_change: s·C̈ ≥ −2ω_b·s·Ċ − ω_b²·gap;
  /// held friction C̈ = 0 up to f; no drive.
  acceleration,
  /// x = Δu, a velocity projection: a limit at or past its bound ends with s·w ≥ 0 (a stop, no
  /// bounce); nothing else.
  velocity_stop,
  /// x = Δq, a position projection: a violated limit is pushed back onto its bound, and no
  /// limit is pushed past it (s·(gap + J·Δq) ≥ 0 on every limit row).
  position,
};

/// Sets every control row's problem for a solve at `level` (state.controls measured at its state).
void set_control_problem(LagrangeState& state, ControlLevel level, double dt, double frequency);

/// solve_constrained with the control rows in the modes of an active-set loop: a limit row joins
/// when its bound would be violated and leaves when its multiplier pulls (beyond what friction
/// holds), friction sticks until the multipliers holding it exceed its bound (then slides at the
/// bound, along the direction of the sticking multipliers), a drive is a compliant row. At most
/// kMaxControlIterations solves. state.constraint_rhs holds the equality rows' right-hand sides.
void solve_with_controls(LagrangeState& state, const RigidBodyState& y, const std::vector<Eigen::Matrix<double, 6, 1>>& body_rhs,
                         std::vector<Eigen::Matrix<double, 6, 1>>& x);
inline constexpr int kMaxControlIterations = 10;





/// The augmented solve at state y (update_geometry(state, y) must have run): given per-body
/// right-hand sides (force, torque; 6 per body) and per-constraint right-hand sides c (its rows),
/// finds body accelerations u̇ = M⁻¹(F + Jᵀλ) and the multipliers λ with J u̇ = c. Sleeping
/// islands get u̇ = 0. Writes `accelerations` (6 per body) and state.multipliers.
void solve_constrained(LagrangeState& state, const RigidBodyState& y, const std::vector<Eigen::Matrix<double, 6, 1>>& body_rhs,
                       const std::vector<ConstraintVector>& constraint_rhs, std::vector<Eigen::Matrix<double, 6, 1>>& accelerations);

/// Factors the augmented system at state.geometry (update_geometry) for solve_factored: Baraff's
/// tree factor, kept in state.tree until the next solve (the sparse path keeps nothing).
void factor_constrained(LagrangeState& state);
/// solve_constrained against factor_constrained's factor: the same result, without factoring
/// again on the tree path (a substitution, O(bodies)); the sparse path solves in full.
void solve_factored(LagrangeState& state, const RigidBodyState& y, const std::vector<Eigen::Matrix<double, 6, 1>>& body_rhs,
                    const std::vector<ConstraintVector>& constraint_rhs, std::vector<Eigen::Matrix<double, 6, 1>>& accelerations);
/// ω_b of Baumgarte stabilization for a step of dt (0 under projection), 1/s.
double baumgarte_frequency(const LagrangeState& state, double dt);

/// Adds scale·Jᵀλ (state.multipliers, at the geometry last computed) to `forces`.
void add_constraint_forces(LagrangeState& state, RigidForces& forces, double scale);

/// Adds gravity, drag and the constraint forces Jᵀλ at state y to `forces` (the accumulate
/// function of the rigid integrators), with Baumgarte terms when stabilization asks for them.
void accumulate_constrained_forces(LagrangeState& state, const RigidBodyState& y, RigidForces& forces);

}  // namespace limber
