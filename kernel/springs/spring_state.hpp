// The mutable state of the stiff-spring method (thesis 3.3, 4.4.1): limbs as rigid bodies
// (layouts/bodies/rigid_body_buffer.hpp) whose spherical joints are stiff damped springs.
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

#include "kernel/collision/geometry.hpp"
#include "kernel/model/model.hpp"
#include "kernel/model/step_status.hpp"
#include "kernel/rigid/rigid_integration.hpp"
#include "layouts/bodies/rigid_body_buffer.hpp"

namespace limber {

/// How the spring method advances a step.
enum class SpringIntegrator : std::uint8_t {
  euler,                ///< explicit forward Euler (the thesis's): stable only for small h·k (eq. 3.15)
  semi_implicit_euler,  ///< explicit symplectic Euler: stable for h·ω < 2, ω² = k/m_effective
  rk2,                  ///< explicit midpoint Runge-Kutta
  rk4,                  ///< explicit classical Runge-Kutta
  backward_euler,       ///< implicit: one linearized backward-Euler solve over the whole system
                        ///< (eq. 3.16–3.22; Baraff & Witkin 1998), stable for every h·k
};

/// The sparse solver of the implicit step.
enum class SpringLinearSolver : std::uint8_t {
  ldlt,                ///< Eigen::SimplicialLDLT with an AMD ordering: exact, no fill on chains and trees, O(n)
  conjugate_gradient,  ///< Eigen::ConjugateGradient, Jacobi preconditioner, warm-started
};

/// Choices the spring method takes besides the Model.
struct SpringOptions {
  SpringIntegrator integrator = SpringIntegrator::semi_implicit_euler;
  SpringLinearSolver linear_solver = SpringLinearSolver::ldlt;
  std::optional<double> stiffness;  ///< N/m: overrides every joint's and the scene's
  std::optional<double> damping;    ///< N·s/m: likewise
  double solver_tolerance = 1e-10;  ///< conjugate gradient: relative residual
  /// Backward Euler: 1 is the linearized step (eq. 3.16–3.22); each further iteration is a
  /// Newton step on the nonlinear equations with the same matrix (implicit_step.hpp).
  int newton_iterations = 2;
  int contact_iterations = 8;       ///< passes of sequential impulses over the step's contacts
};

/// The springs, one per Model joint, one array per field. A world anchor has body −1 and its
/// anchor in world coordinates; a body anchor is in the rigid body's (principal) frame, relative
/// to its centre of mass (m).
struct SpringBuffer {
  std::vector<std::int32_t> inboard, outboard;
  std::vector<Eigen::Vector3d> inboard_anchor, outboard_anchor;
  std::vector<double> stiffness;         ///< k, N/m
  std::vector<double> damping;           ///< c, N·s/m
  std::vector<double> reference_length;  ///< what the joint gap is measured against (as the Verlet method's), m
  std::size_t size() const { return stiffness.size(); }
};

/// The limbs' geometry for contacts, per body (the ball is the last body when there is one).
struct RigidShapes {
  std::vector<ShapeType> shape;
  std::vector<double> length, radius;           ///< m (the ball: length 0, its radius)
  std::vector<Eigen::Vector3d> centre_offset;   ///< centre of mass in the Model's body frame (shape-centred), m
  /// Rotation from the rigid body's frame (its principal axes) to the Model's body frame: a
  /// Model body-frame point p is at x + q·principal_frame⁻¹·(p − centre_offset) in world.
  std::vector<Eigen::Quaterniond> principal_frame;
  std::vector<bool> is_ball;
};

/// Bodies joined by springs, simulated, put to sleep and woken together (thesis 4.5.3).
struct RigidIsland {
  std::vector<std::uint32_t> bodies;
  bool sleeping = false;
  double still_time = 0;  ///< s below the sleep threshold
};

/// A contact found this step: body `a` touches body `b` (−1: a plane, immovable), normal from b
/// to a, depth ≥ 0.
struct RigidContact {
  std::int32_t a = 0, b = -1;
  Eigen::Vector3d point = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::UnitZ();
  double depth = 0;
  double restitution = 0, friction = 0;
  double approach_speed = 0;  ///< normal speed towards each other before the impulses, m/s, ≥ 0
};

struct SpringStepReport {
  StepStatus status = StepStatus::ok;
  int contacts = 0;                 ///< found this step
  int linear_solver_iterations = 0; ///< conjugate gradient only
  double linear_solver_error = 0;   ///< its relative residual
};

/// The implicit step's system A Δu = b in block form: one 6×6 block per body (translation,
/// rotation) and per spring joining two bodies. The sparsity pattern is fixed at compile;
/// `block_value` locates each block's six columns in A's value array so a step refills A in
/// place.
struct ImplicitSystem {
  Eigen::SparseMatrix<double> matrix;              ///< A, 6n × 6n, lower triangle stored
  Eigen::VectorXd right_hand_side, solution;       ///< b (then the Newton residual), Δu (and the warm start)
  Eigen::VectorXd correction;                      ///< a Newton iteration's change of Δu
  std::vector<std::array<std::int64_t, 6>> diagonal_block;  ///< per body: offsets of its columns' first entries
  std::vector<std::array<std::int64_t, 6>> spring_block;    ///< per spring between bodies: block (max, min), −1 otherwise
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> ldlt;
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower> conjugate_gradient;
};

struct SpringState {
  RigidBodyBuffer bodies;
  RigidShapes shapes;
  SpringBuffer springs;
  std::vector<RigidIsland> islands;
  std::vector<std::uint32_t> island_of_body;
  std::vector<Plane> planes;
  std::int32_t ball = -1;  ///< body index of the ball, or −1
  double ball_restitution = 0;

  SpringOptions options;
  Settings settings;

  double time = 0;  ///< s
  std::vector<RigidContact> contacts;  ///< of the last step
  bool ball_touching = false;          ///< the ball had a contact with a limb in the last step
  RigidIntegratorScratch scratch;
  std::unique_ptr<ImplicitSystem> implicit;  ///< the backward-Euler integrator only (Eigen's solvers do not move)
  std::vector<Eigen::Vector3d> velocity, angular_velocity;  ///< scratch: v and ω of the state being evaluated, world
  std::vector<Eigen::Matrix3d> scratch_world_inertia;       ///< scratch for the implicit step
  SpringStepReport last_report;
};

}  // namespace limber
