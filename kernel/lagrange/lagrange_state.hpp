// The mutable state of the Lagrange-multiplier method (thesis 3.1.4, 3.1.7, 3.4, 4.2.1): limbs as
// rigid bodies in maximal coordinates (kernel/rigid/rigid_scene.hpp) whose joints are
// constraint equations; constraint forces are computed *before* a joint opens, from the
// constraint Jacobian. Built by compile_lagrange() (compile.hpp); stepped by step() (step.hpp).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include "limber/kernel/collision/contact_memory.hpp"
#include "limber/kernel/lagrange/constraints.hpp"
#include "limber/kernel/lagrange/joint_controls.hpp"
#include "limber/kernel/model/joint_coordinates.hpp"
#include "limber/kernel/model/options.hpp"
#include "limber/kernel/scene/serial_links.hpp"
#include "limber/kernel/numerics/tree_elimination.hpp"
#include "limber/kernel/rigid/rigid_integration.hpp"
#include "limber/kernel/rigid/rigid_scene.hpp"

namespace limber {


/// Scratch of resolve_contacts_with_joints (contacts.hpp), kept so a step allocates nothing
/// once it has seen its largest contact set.
struct JointContactScratch {
  /// A unilateral row G·x ≥ target with impulse λ ≥ 0 (a contact's normal, a limit's side), or a
  /// friction row (a contact's two tangents follow its normal, |λ_t| ≤ μ·λ_n).
  enum class Kind : std::uint8_t { normal, tangent, limit };
  struct Row {
    Kind kind = Kind::normal;
    std::uint32_t contact = 0;     ///< index into RigidScene::contacts (normal, tangent)
    std::int32_t a = 0, b = -1;    ///< its bodies (b −1: the world)
    Eigen::Matrix<double, 6, 1> jacobian_a = Eigen::Matrix<double, 6, 1>::Zero(), jacobian_b = Eigen::Matrix<double, 6, 1>::Zero();
    double gap = 0;                ///< a limit's distance inside its bound (rad or m, < 0 past it)
    std::uint32_t batch = 0;       ///< the solve that measured its response
    double mobility = 0;           ///< W_rr: its rate per unit impulse through the joints
    /// A contact's normal row with friction: W of its three rows (normal, t₁, t₂), the contact's
    /// collision matrix through the joints (kernel/numerics/contact_projection.hpp).
    Eigen::Matrix3d contact_block = Eigen::Matrix3d::Zero();
    double target = 0;             ///< the rate (or displacement) it is solved to reach
    double impulse = 0;            ///< λ_r
  };
  std::vector<Row> rows;
  /// Per island (RigidScene::islands: the bodies joints and gears join): the first batch it has
  /// not used. Rows of different islands share a batch: their responses do not overlap.
  std::vector<std::uint32_t> next_batch;
  std::vector<Eigen::Matrix<double, 6, 1>> responses;  ///< per batch, per body (batch·bodies + body): Δu
  std::vector<Eigen::Matrix<double, 6, 1>> velocity, displacement;  ///< per body: (v, ω), (Δx, Δθ)
  ContactMemory memory;  ///< the last step's contact impulses: this step's warm start
};

struct LagrangeState : RigidScene {
  JointAnchors joints;        ///< the Model's joints' anchors
  ConstraintSet constraints;  ///< the joints' rows, then the gears'
  /// The Model's joints and frames, read every step for their limits, friction and drives (so a
  /// drive's target, gains or a joint's friction may change between steps: World::set_joint_drive
  /// writes joint_controls.joints[k].drive). Which joints have control rows is fixed at compile:
  /// a drive, limit or friction given later to a joint compiled without them is not applied.
  JointControls joint_controls;
  JointControlSet controls;  ///< the controlled joints' rows (joint_controls.hpp)
  JointServos servos;        ///< the servos for the next step (apply_actuator), per joint; zeroed after it
  /// Where motors act (Model::actuators; empty without them), serial joints through their
  /// virtual links (scene/serial_links.hpp).
  CoordinateAxes coordinate_axes;
  LagrangeOptions options;
  bool uses_tree = true;  ///< the solver chosen at compile (tree, or sparse for graphs with loops)
  RigidIntegratorScratch scratch;
  /// Baraff's elimination of [M Jᵀ; J 0] over bodies (6×6 blocks) and constraints, when they
  /// form a tree (kernel/numerics/tree_elimination.hpp).
  TreeElimination<double, 6> tree;
  /// Multipliers of the last evaluation, per constraint (its rows). A joint's point rows are the
  /// force on the inboard body at its anchor, N; angular rows are torques, N·m.
  std::vector<ConstraintVector> multipliers;
  double time_step = 0;  ///< Δt of the step under way (Baumgarte's default frequency needs it)
  // Scratch for the solves, sized at compile.
  std::vector<Eigen::Matrix<double, 6, 1>> body_rhs, accelerations;
  std::vector<ConstraintVector> constraint_rhs;
  std::vector<ConstraintVector> projection_multipliers;  ///< the projections' own multipliers (scratch)
  /// Per constraint, each row's compliance A (the solve's J·x + A·λ = c): 0 for its equations; a
  /// control row's is set by its mode (1 when off, its drive's when soft).
  std::vector<ConstraintVector> compliance;
  std::vector<Eigen::Matrix<double, 6, 1>> control_body_rhs;  ///< scratch: body_rhs with sliding friction
  std::vector<Eigen::Matrix<double, 6, 1>> stage_change;      ///< scratch: the impulse pass's x₂ (step.cpp)
  /// The geometry of the state being solved, computed once per evaluation (update_geometry):
  /// the constraints' levers and Jacobian blocks and each body's world inertia tensor.
  ConstraintGeometry geometry;
  std::vector<Eigen::Matrix3d> world_inertia;
  JointContactScratch contact_scratch;
  StepReport last_report;
};

}  // namespace limber
