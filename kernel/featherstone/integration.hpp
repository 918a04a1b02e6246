// Time integration of a kinematic tree's state (q, v), and the observers the tests use (energy,
// momentum).
//
// Positions live on a manifold: a spherical or floating joint's orientation is a unit
// quaternion, which must be advanced by rotations, never by adding to its coefficients. Both
// integrators therefore move q by `displace_positions`, q ⊕ δ, with δ a tangent vector of size
// nv laid out like v:
//   revolute, prismatic   q + δ
//   spherical             q ⊗ exp(δ/2): δ is a rotation vector (axis · angle, rad) in the child
//                         frame, exp(δ/2) = (cos(|δ|/2), sin(|δ|/2) δ/|δ|)
//   floating              (θ, d): p + R(q) d, then the quaternion as spherical by θ; d is a
//                         translation in the child frame at q, m
// so q ⊕ h·v is one step with the velocity v held constant in the child frame (body-frame ω,
// as in q ← q ⊗ exp(h ω/2)). Quaternions are renormalized after every step.
//
// RK4 is combined in the tangent space at the step's start q₀ (Munthe-Kaas 1998, "Runge–Kutta
// methods on Lie groups"): each stage s sits at q₀ ⊕ Θ_s and contributes the rate of Θ, not of
// the quaternion: Θ̇ = J_r⁻¹(θ) ω for a rotation (J_r the right Jacobian of SO(3)) and
// ḋ = exp(θ) v for a floating joint's translation; q₁ = q₀ ⊕ h·Σ b_s Θ̇_s. This keeps the
// classical method's order 4 on the rotations.
#pragma once

#include <cstdint>

#include <Eigen/Core>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build
#include "limber/kernel/featherstone/articulated_tree.hpp"
#include "limber/kernel/featherstone/dynamics.hpp"
#include "limber/kernel/numerics/integrator.hpp"

namespace limber {

/// Scratch for `integrate`, sized by resize(tree) or by the first call.
struct FeatherstoneIntegratorWorkspace {
  DynamicsWorkspace dynamics;
  Eigen::VectorXd start_positions, stage_positions;                // nq
  Eigen::VectorXd start_velocities, stage_velocities, stage_rate;  // nv
  Eigen::VectorXd stage_displacement, accelerations;              // nv
  Eigen::VectorXd acceleration_sum, displacement_rate_sum;        // nv

  void resize(const ArticulatedTree& tree);
  bool fits(const ArticulatedTree& tree) const;
};

/// out = q ⊕ displacement (see above). q, out: nq (out may be q itself); displacement: nv.
void displace_positions(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                        const Eigen::Ref<const Eigen::VectorXd>& displacement, Eigen::Ref<Eigen::VectorXd> out);
/// The same on the coordinates of the bodies of `range` alone.
void displace_positions(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                        const Eigen::Ref<const Eigen::VectorXd>& displacement, Eigen::Ref<Eigen::VectorXd> out, BodyRange range);

/// Advances (q, v) by h seconds under constant joint forces τ (nv) and gravity g (world frame,
/// m/s²) with forward_dynamics. Allocates nothing once the workspace is sized. Implements
/// semi_implicit_euler (v ← v + h v̇(q, v); q ← q ⊕ h v with the new v; order 1; a floating
/// joint's translation in world-fixed axes: semi_implicit_velocity) and rk4
/// (stages combined in the tangent space; order 4); compile refuses the others. `kinematics`,
/// when given, holds forward_kinematics of (q, v) (poses, body velocities and bias
/// accelerations), which the first stage then does not find again: the same bits.
void integrate(const ArticulatedTree& tree, Eigen::VectorXd& q, Eigen::VectorXd& v,
               const Eigen::Ref<const Eigen::VectorXd>& joint_forces, const Eigen::Vector3d& gravity, double h,
               Integrator integrator, FeatherstoneIntegratorWorkspace& workspace, const DynamicsWorkspace* kinematics = nullptr);
/// The same for the bodies of `range` alone (their coordinates of q and v; the workspace sized
/// for the tree), the same bits.
void integrate(const ArticulatedTree& tree, Eigen::VectorXd& q, Eigen::VectorXd& v,
               const Eigen::Ref<const Eigen::VectorXd>& joint_forces, const Eigen::Vector3d& gravity, double h,
               Integrator integrator, FeatherstoneIntegratorWorkspace& workspace, const DynamicsWorkspace* kinematics, BodyRange range);

/// Semi-implicit Euler's velocity update alone, v ← v + h v̇(q, v) (semi_implicit_velocity;
/// integrate's first half; q is not moved), on the bodies of `range` (their coordinates of v;
/// the workspace sized for the tree): the velocity a step solves its constraints on before the positions move with it
/// (kernel/featherstone/step.hpp). `kinematics` as for integrate.
void accelerate(const ArticulatedTree& tree, const Eigen::VectorXd& q, Eigen::VectorXd& v,
                const Eigen::Ref<const Eigen::VectorXd>& joint_forces, const Eigen::Vector3d& gravity, double h,
                FeatherstoneIntegratorWorkspace& workspace, const DynamicsWorkspace* kinematics, BodyRange range);

/// Semi-implicit Euler's velocity update from accelerations v̇ (nv: forward_dynamics', or the
/// joint-space factor's) on the bodies of `range`: v ← v + h·v̇, but a floating joint's linear
/// velocity takes its origin's classical acceleration v̇ + ω × v in the axes its frame has at the
/// step's start. Its v̇ is the spatial acceleration in its turning frame, whose −ω × v term,
/// explicit, scales the velocity by √(1 + (hω)²) a step: a body spinning at 40 rad/s in flight
/// at 1/200 s gained 2 % of its speed a step, e⁴ of its kinetic energy a second (humanoid100.xml
/// diverged). With the world-fixed axes the translation is integrated as a free particle's, and
/// semi_implicit_move carries the velocity into the turned frame.
void semi_implicit_velocity(const ArticulatedTree& tree, Eigen::VectorXd& v, const Eigen::VectorXd& accelerations, double h,
                            BodyRange range);

/// Semi-implicit Euler's move on the bodies of `range`: q ← q ⊕ h·v, then each floating joint's
/// velocity in its turned frame, v ← exp(θ)ᵀ v (θ = h·ω, its turn): the world velocity it had,
/// kept. Other joints' velocities are relative to frames that turn with their parents: unchanged.
/// `displacement` (nv) is scratch, h·v on the range's coordinates afterwards.
void semi_implicit_move(const ArticulatedTree& tree, Eigen::VectorXd& q, Eigen::VectorXd& v, double h, Eigen::VectorXd& displacement,
                        BodyRange range);

/// T = ½ vᵀHv = Σ ½ v_iᵀ I_i v_i + armature_energy: the bodies' and the rotors', J.
double kinetic_energy(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& v, DynamicsWorkspace& workspace);
/// Σ ½ a_k v_k²: the kinetic energy of the armature (the rotors' reflected inertia a_k on
/// revolute or prismatic coordinate k, which no body holds), J.
double armature_energy(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& v);

/// V = −Σ m_i g·c_i, c_i the world position of body i's centre of mass; J (zero at the world
/// origin).
double potential_energy(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Vector3d& gravity,
                        DynamicsWorkspace& workspace);

/// The tree's total spatial momentum Σ ⁰X_i* I_i v_i: (angular momentum about the world origin,
/// linear momentum), world frame; kg·m²/s and kg·m/s.
SpatialVector spatial_momentum(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                               const Eigen::Ref<const Eigen::VectorXd>& v, DynamicsWorkspace& workspace);

}  // namespace limber
