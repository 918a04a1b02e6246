// The dynamics of a kinematic tree in reduced coordinates (Featherstone, "Rigid Body Dynamics
// Algorithms", 2008):
//   forward_dynamics  v̇ = H⁻¹(τ − C)  by the articulated-body algorithm, O(n)   (Table 7.1)
//   inverse_dynamics  τ = H v̇ + C     by recursive Newton–Euler, O(n)        (Table 5.1)
//   bias_forces       C               the same with v̇ = 0
//   mass_matrix       H               by the composite-rigid-body algorithm  (Table 6.2)
// where H(q) is the joint-space inertia matrix and C(q, v) the bias forces (Coriolis,
// centrifugal and gravity). Coordinates, joint types and frames: articulated_tree.hpp; spatial
// vectors: spatial.hpp.
//
// Gravity g (a world-frame 3-vector, m/s², e.g. (0, 0, −9.81)) enters as Featherstone's
// fictitious base acceleration a₀ = (0, −g) (chapter 5): every body then feels its weight
// without a gravity term per body, and the body accelerations the algorithms propagate are the
// true ones plus a₀ (gravity subtracted). The joint accelerations v̇ are the true ones.
//
// Nothing here allocates once the workspace and the outputs have their sizes (the first call
// with a new tree sizes them). Inputs of the wrong size throw std::invalid_argument.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build
#include "limber/kernel/featherstone/articulated_tree.hpp"
#include "limber/kernel/featherstone/spatial.hpp"

namespace limber {

/// Per-body scratch shared by the algorithms below; sized by resize(tree) or by the first call.
/// Each algorithm documents which fields it leaves meaningful after it returns.
struct DynamicsWorkspace {
  std::vector<PluckerTransform> parent_to_body;     ///< ⁱX_λ(i) = X_J X_tree
  std::vector<PluckerTransform> world_to_body;      ///< ⁱX_0 (forward_kinematics)
  std::vector<SpatialVector> velocity;              ///< v_i, body coordinates
  std::vector<SpatialVector> bias_acceleration;     ///< c_i = v_i × v_J (c_J = 0 for these joints)
  std::vector<SpatialVector> acceleration;          ///< a_i + ⁱX_0 a₀ (ABA, RNEA; see gravity above)
  std::vector<SpatialVector> bias_force;            ///< ABA: p^A_i; RNEA: the joint force f_i
  std::vector<SpatialMatrix> articulated_inertia;   ///< ABA: I^A_i
  std::vector<SpatialInertia> composite_inertia;    ///< CRBA: the composite I^c_i, a rigid body's
  /// ABA's U_i = I^A_i S_i in the columns of body i's velocities (6 × nv).
  Eigen::Matrix<double, 6, Eigen::Dynamic> projected_inertia;
  /// ABA's D_i⁻¹ = (S_iᵀ U_i)⁻¹ (k_i × k_i) in the top rows of body i's velocity columns (6 × nv).
  Eigen::Matrix<double, 6, Eigen::Dynamic> joint_inertia_inverse;
  Eigen::VectorXd joint_bias;                       ///< ABA's u_i = τ_i − S_iᵀ p^A_i (nv)

  /// Sizes every field for `tree` (allocates).
  void resize(const ArticulatedTree& tree);
  /// Whether the sizes match `tree` (body and velocity counts).
  bool fits(const ArticulatedTree& tree) const;
};

/// X_J(q) for body i's joint: joint frame → body frame, from the joint's slice of q (at
/// position_offset). Quaternions are normalized here, so they need not be exactly unit.
PluckerTransform joint_transform(const ArticulatedBody& body, const double* joint_positions);

/// Body poses: fills workspace.parent_to_body and world_to_body for positions q (nq).
void body_poses(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, DynamicsWorkspace& workspace);
/// The same for the bodies of `range` alone (the workspace sized for the tree), the same bits.
void body_poses(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, DynamicsWorkspace& workspace, BodyRange range);

/// Body poses and velocities: fills workspace.parent_to_body, world_to_body and velocity
/// (v_i, body coordinates). q: nq, v: nv.
void forward_kinematics(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                        const Eigen::Ref<const Eigen::VectorXd>& v, DynamicsWorkspace& workspace);
/// The same for the bodies of `range` alone (the workspace sized for the tree), the same bits.
void forward_kinematics(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                        const Eigen::Ref<const Eigen::VectorXd>& v, DynamicsWorkspace& workspace, BodyRange range);

/// The bodies' velocities and velocity-product accelerations alone (workspace.velocity and
/// bias_acceleration, v: nv) at the poses workspace already holds (body_poses or
/// forward_kinematics of the current q): forward_kinematics without recomputing the poses, the
/// same bits.
void body_velocities(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& v, DynamicsWorkspace& workspace);
/// The same for the bodies of `range` alone, the same bits.
void body_velocities(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& v, DynamicsWorkspace& workspace, BodyRange range);

/// The articulated-body algorithm (Table 7.1): the joint accelerations v̇ (nv, written to
/// `joint_accelerations`, resized) for positions q (nq), velocities v (nv), joint forces τ (nv;
/// N·m for revolute and spherical, N for prismatic, (n, f) in the child frame for floating) and
/// gravity g (world frame, m/s²). O(n); allocates nothing once sized. Leaves parent_to_body,
/// velocity, bias_acceleration and acceleration meaningful; the last is the true acceleration
/// plus the fictitious base acceleration a₀ = (0, −g), i.e. ⁱX_0 a₀ added, body coordinates.
void forward_dynamics(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& v, const Eigen::Ref<const Eigen::VectorXd>& joint_forces,
                      const Eigen::Vector3d& gravity, DynamicsWorkspace& workspace, Eigen::VectorXd& joint_accelerations);
/// The same for the bodies of `range` alone: v̇ on their coordinates (joint_accelerations of size
/// nv), the workspace's entries of their bodies and coordinates; the same bits.
void forward_dynamics(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& v, const Eigen::Ref<const Eigen::VectorXd>& joint_forces,
                      const Eigen::Vector3d& gravity, DynamicsWorkspace& workspace, Eigen::VectorXd& joint_accelerations, BodyRange range);

/// forward_dynamics of (H + diag(armature)) v̇ = τ − C: `armature` (nv, ≥ 0) is added to the
/// diagonal of each joint's D_i = S_iᵀ I^A_i S_i, which adds it to H's diagonal (a rotor's
/// reflected inertia; MuJoCo's joint armature). The implicit joint drives use it
/// (joint_controls.hpp): a drive's k·h² + c·h on the driven coordinates. The workspace's
/// projected_inertia and joint_inertia_inverse are then those of H + diag(armature).
void forward_dynamics(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& v, const Eigen::Ref<const Eigen::VectorXd>& joint_forces,
                      const Eigen::Ref<const Eigen::VectorXd>& armature, const Eigen::Vector3d& gravity,
                      DynamicsWorkspace& workspace, Eigen::VectorXd& joint_accelerations);

/// The same at the poses and velocities `kinematics` holds: forward_kinematics of the current q
/// and v (its parent_to_body, velocity and bias_acceleration; it may be `workspace` itself),
/// without finding them again, the same bits; `armature` nv values or null.
void forward_dynamics(const ArticulatedTree& tree, const DynamicsWorkspace& kinematics, const Eigen::Ref<const Eigen::VectorXd>& joint_forces,
                      const double* armature, const Eigen::Vector3d& gravity, DynamicsWorkspace& workspace,
                      Eigen::VectorXd& joint_accelerations);
/// The same for the bodies of `range` alone: v̇ on their coordinates (joint_accelerations of size
/// nv), the workspace's entries of their bodies and coordinates; the same bits.
void forward_dynamics(const ArticulatedTree& tree, const DynamicsWorkspace& kinematics, const Eigen::Ref<const Eigen::VectorXd>& joint_forces,
                      const double* armature, const Eigen::Vector3d& gravity, DynamicsWorkspace& workspace,
                      Eigen::VectorXd& joint_accelerations, BodyRange range);

/// Recursive Newton–Euler (Table 5.1): the joint forces τ (nv, written to `joint_forces`,
/// resized) that give accelerations v̇ (nv) at q, v under gravity g. With v̇ = 0 it is the bias
/// force C(q, v). O(n); allocates nothing once sized.
void inverse_dynamics(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& v, const Eigen::Ref<const Eigen::VectorXd>& joint_accelerations,
                      const Eigen::Vector3d& gravity, DynamicsWorkspace& workspace, Eigen::VectorXd& joint_forces);

/// The bias forces C(q, v) (nv: Coriolis, centrifugal and gravity; what inverse_dynamics gives for
/// v̇ = 0) on the coordinates of the bodies of `range`, written to `forces` (sized nv), at the
/// poses and velocities `kinematics` holds: forward_kinematics of the current q and v (its
/// parent_to_body, velocity and bias_acceleration on the range), which it does not find again
/// (MuJoCo's mj_rne on mj_kinematics' and mj_comVel's results). With H from mass_matrix,
/// H⁻¹(τ − C) is forward_dynamics' v̇ (MuJoCo's mj_rne, then mj_solveM). O(n); allocates nothing.
/// Leaves the workspace's acceleration and bias_force meaningful on the range; `kinematics` may
/// be `workspace` itself.
void bias_forces(const ArticulatedTree& tree, const DynamicsWorkspace& kinematics, const Eigen::Vector3d& gravity,
                 DynamicsWorkspace& workspace, Eigen::VectorXd& forces, BodyRange range);

/// The composite-rigid-body algorithm (Table 6.2): the joint-space inertia matrix H(q) (nv × nv,
/// symmetric positive definite, written to `joint_space_inertia`, resized), dense. O(n·depth) work.
void mass_matrix(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, DynamicsWorkspace& workspace,
                 Eigen::MatrixXd& joint_space_inertia);

class JointSpaceFactor;
/// The same H written into `factor`'s sparsity (joint_space_factor.hpp: only the entries on each
/// coordinate's path to the root, the rest being zero), ready for factor.factor(). O(n·depth);
/// allocates nothing once the workspace is sized. Throws std::invalid_argument when the factor
/// is not assigned to this tree's coordinates.
void mass_matrix(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, DynamicsWorkspace& workspace,
                 JointSpaceFactor& factor);
/// The same at the poses `poses` holds (its parent_to_body: body_poses or forward_kinematics of
/// the current q), without recomputing them; the same bits.
void mass_matrix(const ArticulatedTree& tree, const DynamicsWorkspace& poses, DynamicsWorkspace& workspace, JointSpaceFactor& factor);
/// The same for the coordinates of the bodies of `range` alone (the workspace sized for the
/// tree), the same bits.
void mass_matrix(const ArticulatedTree& tree, const DynamicsWorkspace& poses, DynamicsWorkspace& workspace, JointSpaceFactor& factor,
                 BodyRange range);

}  // namespace limber
