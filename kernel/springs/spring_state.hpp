// The mutable state of the stiff-spring method (thesis 3.3, 4.4.1): limbs as rigid bodies
// (layouts/bodies/rigid_body_buffer.hpp) whose spherical and revolute joints are stiff damped
// springs (one at a ball joint's anchor, two on a hinge's axis).
// Built by compile_springs() (compile.hpp) from the same Model as every other method; stepped by
// step() (step.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <Eigen/IterativeLinearSolvers>

#include "limber/kernel/model/joint_coordinates.hpp"
#include "limber/kernel/model/method_settings.hpp"
#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/options.hpp"
#include "limber/kernel/model/step_status.hpp"
#include "limber/kernel/numerics/integrator.hpp"
#include "limber/kernel/rigid/rigid_integration.hpp"
#include "limber/kernel/rigid/rigid_scene.hpp"
#include "limber/kernel/scene/serial_links.hpp"
#include "limber/layouts/bodies/rigid_body_buffer.hpp"

namespace limber {


/// The joints' springs, one entry per Model joint: its anchors (JointAnchors: what the joint gap
/// is measured at), and one array per field. A spherical joint is one zero-length spring between
/// its anchors; a revolute joint two, between the points anchor ± offset of each body (the
/// thesis's hinge, 3.2.5: two links sharing two points, the axis through both), each with the
/// joint's k and c.
struct SpringBuffer : JointAnchors {
  std::vector<double> stiffness;  ///< k, N/m, of each of the joint's springs
  std::vector<double> damping;    ///< c, N·s/m, likewise
  /// ε·h: the hinge axis h times the half-spacing ε of a revolute joint's two springs, in the
  /// inboard body's frame (world for a joint to the world) and the outboard's (as the anchors);
  /// zero for one spring at the anchor. ε is a quarter of the shorter limb (compile.hpp).
  std::vector<Eigen::Vector3d> inboard_offset, outboard_offset;
  std::vector<std::uint8_t> count;  ///< springs of the joint: 1, or 2 for a revolute joint
};

/// The `e`-th spring of joint s (e < count[s]) as the sign of its offset: 0 for a joint's single
/// spring at its anchors, +1 and −1 for a hinge's pair.
inline int spring_side(const SpringBuffer& springs, std::size_t s, int e) { return springs.count[s] == 1 ? 0 : 1 - 2 * e; }

/// The implicit step's system A Δu = b in block form: one 6×6 block per body (translation,
/// rotation) and per spring joining two bodies. The sparsity pattern is fixed at compile;
/// `block_value` locates each block's six columns in A's value array so a step refills A in
/// place.
struct ImplicitSystem {
  Eigen::SparseMatrix<double> matrix;              ///< A, 6n × 6n, lower triangle stored
  Eigen::VectorXd right_hand_side, solution;       ///< b (then the Newton residual), Δu (and the warm start)
  Eigen::VectorXd correction;                      ///< a Newton iteration's change of Δu
  std::vector<std::array<std::int64_t, 6>> diagonal_block;  ///< per body: offsets of its columns' first entries
  std::vector<std::array<std::int64_t, 6>> spring_block;    ///< per joint between bodies (its springs'): block (max, min), −1 otherwise
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt;
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower> conjugate_gradient;
};

/// The spring method's state: the rigid scene (kernel/rigid/rigid_scene.hpp) and its springs.
struct SpringState : RigidScene {
  SpringBuffer springs;
  /// The Model's joints and frames, read every step for their limits, friction and drives (so a
  /// drive may change between steps: World::set_joint_drive writes joint_controls.joints[k].drive).
  JointControls joint_controls;
  std::vector<std::uint32_t> controlled_joints;  ///< joints with a limit, friction or drive
  CoordinateAxes coordinate_axes;  ///< where motors act (Model::actuators; empty without them)
  SpringOptions options;
  double time_step = 0;  ///< Δt of the step under way (friction's regularization reads it)
  RigidIntegratorScratch scratch;
  std::unique_ptr<ImplicitSystem> implicit;  ///< the backward-Euler integrator only (Eigen's solvers do not move)
  std::vector<Eigen::Matrix3d> scratch_world_inertia;  ///< scratch for the implicit step
  StepReport last_report;
};

}  // namespace limber
