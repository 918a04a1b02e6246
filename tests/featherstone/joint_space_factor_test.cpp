// The joint-space inertia's LᵀDL factor in its tree's sparsity (kernel/featherstone/
// joint_space_factor.hpp) against dense Eigen on random trees: it reproduces H, solves as a dense
// Cholesky does, fills nothing in, and its Delassus matrix is J H⁻¹ Jᵀ.
#include <algorithm>
#include <random>
#include <set>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "limber/kernel/featherstone/dynamics.hpp"
#include "limber/kernel/featherstone/joint_space_factor.hpp"
#include "tests/featherstone/random_trees.hpp"

namespace limber {
namespace {

using testing::random_positions;
using testing::random_tree;
using testing::random_tree_kinds;
using testing::random_vector;
using testing::RandomTreeOptions;

// Whether coordinate j is i or on i's path to the root.
bool on_path(const std::vector<int>& parent, int i, int j) {
  for (int k = i; k >= 0; k = parent[static_cast<std::size_t>(k)]) {
    if (k == j) return true;
  }
  return false;
}

// Calls check(rng, tree, H, its factor) for ten random trees of each kind with any coordinates,
// H at random positions.
template <typename Check>
void for_random_inertias(unsigned seed, Check&& check) {
  std::mt19937 rng(seed);
  DynamicsWorkspace workspace;
  Eigen::MatrixXd h;
  for (const RandomTreeOptions& kind : random_tree_kinds()) {
    for (int trial = 0; trial < 10; ++trial) {
      const ArticulatedTree tree = random_tree(rng, kind);
      if (tree.velocity_count() == 0) continue;  // a fixed single body
      mass_matrix(tree, random_positions(rng, tree), workspace, h);
      JointSpaceFactor factor;
      factor.assign(tree);
      factor.factor(h);
      check(rng, tree, h, factor);
    }
  }
}

TEST(JointSpaceFactor, EachCoordinatesParentIsTheOneBeforeItOnItsPathToTheRoot) {
  // world ─floating─ 0 ─fixed─ 1 ─spherical─ 2 ─revolute─ 3;  0 ─prismatic─ 4
  ArticulatedTree tree;
  const auto add = [&](int parent, ArticulatedJoint joint) {
    ArticulatedBody body;
    body.parent = parent, body.joint = joint;
    body.inertia = SpatialInertia::from_mass_properties(1, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity() * 0.1);
    tree.add_body(body);
  };
  add(-1, ArticulatedJoint::floating), add(0, ArticulatedJoint::fixed), add(1, ArticulatedJoint::spherical);
  add(2, ArticulatedJoint::revolute), add(0, ArticulatedJoint::prismatic);
  // Coordinates: 0–5 the base, 6–8 the ball (through the fixed joint to the base's last), 9 the hinge, 10 the slide.
  EXPECT_EQ(dof_parents(tree), (std::vector<int>{-1, 0, 1, 2, 3, 4, 5, 6, 7, 8, 5}));
}

TEST(JointSpaceFactor, ReproducesTheInertiaAndFillsNothingIn) {
  for_random_inertias(40, [](std::mt19937&, const ArticulatedTree& tree, const Eigen::MatrixXd& h, const JointSpaceFactor& factor) {
    const int n = factor.size();
    const std::vector<int> parent = dof_parents(tree);
    Eigen::MatrixXd l = Eigen::MatrixXd::Identity(n, n);
    Eigen::VectorXd d(n);
    for (int i = 0; i < n; ++i) {
      d[i] = factor.pivot(i);
      EXPECT_GT(d[i], 0);
      for (int j = 0; j < i; ++j) {
        l(i, j) = factor.lower(i, j);
        // H is zero off the paths to the root (the composite-rigid-body algorithm's structure)…
        if (!on_path(parent, i, j)) {
          EXPECT_EQ(h(i, j), 0.0) << i << ", " << j;
        }
      }
    }
    // …and LᵀDL, with L only on the paths, is H whole.
    const Eigen::MatrixXd rebuilt = l.transpose() * d.asDiagonal() * l;
    EXPECT_LT((rebuilt - h).norm(), 1e-13 * h.norm()) << tree.body_count() << " bodies";
  });
}

TEST(JointSpaceFactor, SolvesAsADenseCholeskyDoes) {
  for_random_inertias(41, [](std::mt19937& rng, const ArticulatedTree& tree, const Eigen::MatrixXd& h, const JointSpaceFactor& factor) {
    const Eigen::VectorXd b = random_vector(rng, factor.size(), 5);
    Eigen::VectorXd x = b;
    factor.solve(x);
    // Backward stable as a Cholesky is (the residual at rounding), and as close to its answer as
    // H's condition number lets two backward-stable solves be (a chain of 15 random bodies
    // reaches κ ~ 10⁹).
    EXPECT_LT((h * x - b).norm(), 1e-13 * h.norm() * x.norm()) << tree.body_count() << " bodies";
    const Eigen::VectorXd reference = h.llt().solve(b);
    const Eigen::VectorXd eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(h, Eigen::EigenvaluesOnly).eigenvalues();
    const double condition = eigenvalues.maxCoeff() / eigenvalues.minCoeff();
    EXPECT_LT((x - reference).norm(), 1e-14 * condition * reference.norm()) << tree.body_count() << " bodies, condition " << condition;
  });
}

TEST(JointSpaceFactor, DelassusMatrixIsTheRowsInverseInertia) {
  for_random_inertias(42, [](std::mt19937& rng, const ArticulatedTree& tree, const Eigen::MatrixXd& h, const JointSpaceFactor& factor) {
    const int n = factor.size();
    // Rows that touch a few coordinates, as contacts and limits do, and a dense one.
    Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(5, n);
    for (int r = 0; r < 4; ++r) jacobian(r, std::uniform_int_distribution<int>(0, n - 1)(rng)) = 1 + r;
    jacobian.row(4) = random_vector(rng, n, 1).transpose();
    Eigen::MatrixXd a, half;
    factor.delassus(jacobian, a, half);
    const Eigen::MatrixXd reference = jacobian * h.llt().solve(jacobian.transpose());
    EXPECT_LT((a - a.transpose()).norm(), 1e-15 * a.norm());
    // To rounding, as far as H's conditioning lets a dense solve agree (as above).
    const Eigen::VectorXd eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(h, Eigen::EigenvaluesOnly).eigenvalues();
    const double condition = eigenvalues.maxCoeff() / eigenvalues.minCoeff();
    EXPECT_LT((a - reference).norm(), std::max(1e-12, 1e-14 * condition) * reference.norm()) << tree.body_count() << " bodies";
  });
}

TEST(JointSpaceFactor, ARowsHalfSolveTouchesOnlyItsPathToTheRoot) {
  for_random_inertias(43, [](std::mt19937& rng, const ArticulatedTree& tree, const Eigen::MatrixXd&, const JointSpaceFactor& factor) {
    const std::vector<int> parent = dof_parents(tree);
    const int n = factor.size();
    const int loaded = std::uniform_int_distribution<int>(0, n - 1)(rng);
    Eigen::VectorXd y = Eigen::VectorXd::Zero(n);
    y[loaded] = 1;
    factor.solve_transposed_lower(y);
    for (int i = 0; i < n; ++i) {
      if (!on_path(parent, loaded, i)) {
        EXPECT_EQ(y[i], 0.0) << "coordinate " << i << " is off " << loaded << "'s path";
      }
    }
    EXPECT_EQ(y[loaded], 1.0);
  });
}

TEST(JointSpaceFactor, TheSparseMassMatrixIsTheDenseOnesEntriesAndSolvesAsTheArticulatedBodyAlgorithm) {
  // The contacts' responses went through the articulated-body algorithm with v = 0, g = 0 (its
  // impulse response is H⁻¹τ); now through the factor of H written straight into its sparsity.
  std::mt19937 rng(44);
  DynamicsWorkspace workspace, sparse_workspace;
  Eigen::MatrixXd h;
  Eigen::VectorXd accelerations;
  for (const RandomTreeOptions& kind : random_tree_kinds()) {
    for (int trial = 0; trial < 10; ++trial) {
      const ArticulatedTree tree = random_tree(rng, kind);
      if (tree.velocity_count() == 0) continue;
      const Eigen::VectorXd q = random_positions(rng, tree);
      mass_matrix(tree, q, workspace, h);
      JointSpaceFactor dense, sparse;
      dense.assign(tree), sparse.assign(tree);
      dense.factor(h);
      mass_matrix(tree, q, sparse_workspace, sparse);
      sparse.factor();
      const int n = dense.size();
      for (int i = 0; i < n; ++i) {
        EXPECT_EQ(sparse.pivot(i), dense.pivot(i));
        for (int j = 0; j < i; ++j) EXPECT_EQ(sparse.lower(i, j), dense.lower(i, j));
      }
      const Eigen::VectorXd tau = random_vector(rng, n, 5);
      Eigen::VectorXd x = tau;
      sparse.solve(x);
      forward_dynamics(tree, q, Eigen::VectorXd::Zero(n), tau, Eigen::Vector3d::Zero(), workspace, accelerations);
      EXPECT_LT((x - accelerations).norm(), 1e-10 * accelerations.norm()) << tree.body_count() << " bodies";
    }
  }
}

TEST(JointSpaceFactor, TheBiasForcesThroughTheFactorGiveTheArticulatedBodyAlgorithmsAccelerations) {
  // Before the move a touched island's velocity update is (H + diag(a))⁻¹(τ − C): the mass matrix
  // and the bias forces by recursive Newton–Euler at the poses and velocities the step holds
  // (forward_kinematics', which the step keeps between steps), then the factor's solve —
  // MuJoCo's way, where the articulated-body algorithm (with the drives' armature a on its D_i)
  // gave it.
  std::mt19937 rng(49);
  DynamicsWorkspace poses, workspace, articulated;
  Eigen::VectorXd bias, accelerations, expected, reference;
  for (const RandomTreeOptions& kind : random_tree_kinds()) {
    for (int trial = 0; trial < 10; ++trial) {
      const ArticulatedTree tree = random_tree(rng, kind);
      const int n = tree.velocity_count();
      if (n == 0) continue;
      const Eigen::VectorXd q = random_positions(rng, tree), v = random_vector(rng, n, 3), tau = random_vector(rng, n, 5);
      const Eigen::VectorXd armature = random_vector(rng, n, 1).cwiseAbs();
      const Eigen::Vector3d gravity = random_vector(rng, 3, 10);
      poses.resize(tree), workspace.resize(tree);
      forward_kinematics(tree, q, v, poses);
      JointSpaceFactor factor;
      factor.assign(tree);
      mass_matrix(tree, poses, workspace, factor);
      for (int i = 0; i < n; ++i) factor.add_inertia(i, i, armature[i]);
      ASSERT_LT(factor.factor(), 0);
      bias.setZero(n);
      bias_forces(tree, poses, gravity, workspace, bias, tree.all_bodies());
      inverse_dynamics(tree, q, v, Eigen::VectorXd::Zero(n), gravity, articulated, reference);
      EXPECT_LT((bias - reference).norm(), 1e-12 * (reference.norm() + 1)) << tree.body_count() << " bodies";
      accelerations = tau - bias;
      factor.solve(accelerations);
      forward_dynamics(tree, q, v, tau, armature, gravity, articulated, expected);
      EXPECT_LT((accelerations - expected).norm(), 1e-10 * (expected.norm() + 1)) << tree.body_count() << " bodies";
    }
  }
}

TEST(JointSpaceFactor, ASubtreesRangeFactorsAndSolvesAsTheWholeTree) {
  // Two trees side by side (islands): each one's coordinates factored and solved alone give the
  // bits of the whole.
  std::mt19937 rng(45);
  ArticulatedTree tree = random_tree(rng, {.bodies = 6, .branching = true, .floating_base = true});
  const int first_count = tree.velocity_count();
  const ArticulatedTree second = random_tree(rng, {.bodies = 5, .branching = true});
  const int shift = tree.body_count();
  for (ArticulatedBody body : second.bodies()) {
    if (body.parent >= 0) body.parent += shift;
    tree.add_body(body);
  }
  DynamicsWorkspace workspace;
  JointSpaceFactor whole, parts;
  whole.assign(tree), parts.assign(tree);
  const Eigen::VectorXd q = random_positions(rng, tree);
  mass_matrix(tree, q, workspace, whole);
  parts = whole;
  whole.factor();
  parts.factor(first_count, parts.size());
  parts.factor(0, first_count);
  const Eigen::VectorXd b = random_vector(rng, whole.size(), 1);
  Eigen::VectorXd x = b, y = b;
  whole.solve(x);
  parts.solve(y, first_count, parts.size());
  parts.solve(y, 0, first_count);
  EXPECT_EQ(x, y);
}

TEST(JointSpaceFactor, HalfRowsOnAPathGiveTheDelassusBlockAndTheSolve) {
  // The contacts' way (joint_space_contacts.cpp): Y = L⁻ᵀ Jᵀ on the loaded coordinates' paths,
  // K = Yᵀ D⁻¹ Y, and a motion L⁻¹ D⁻¹ Y ι, against the dense Delassus block and solve.
  for_random_inertias(46, [](std::mt19937& rng, const ArticulatedTree& tree, const Eigen::MatrixXd&, const JointSpaceFactor& factor) {
    const int n = factor.size();
    const int loaded = std::uniform_int_distribution<int>(0, n - 1)(rng);
    std::vector<int> path;
    for (int k = loaded; k >= 0; k = factor.parent(k)) path.push_back(k);  // descending
    Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(3, n);
    for (const int k : path) jacobian.col(k) = random_vector(rng, 3, 1);
    Eigen::Matrix<double, Eigen::Dynamic, 3> y = jacobian.transpose();
    factor.solve_transposed_lower(y, path);
    Eigen::Matrix3d k_half = Eigen::Matrix3d::Zero();
    for (const int k : path) k_half += y.row(k).transpose() * y.row(k) / factor.pivot(k);
    Eigen::MatrixXd a, half;
    factor.delassus(jacobian, a, half);
    EXPECT_LT((k_half - a).norm(), 1e-12 * a.norm()) << tree.body_count() << " bodies";
    const Eigen::Vector3d impulse = random_vector(rng, 3, 1);
    Eigen::VectorXd motion = Eigen::VectorXd::Zero(n), reference = jacobian.transpose() * impulse;
    for (const int k : path) motion[k] = y.row(k).dot(impulse) / factor.pivot(k);
    factor.solve_lower(motion);
    factor.solve(reference);
    EXPECT_LT((motion - reference).norm(), 1e-12 * reference.norm());
  });
}

TEST(JointSpaceFactor, RefusesParentsOutOfOrderAndAnInertiaThatIsNotPositiveDefinite) {
  JointSpaceFactor factor;
  EXPECT_THROW(factor.assign({-1, 1}), std::invalid_argument);
  EXPECT_THROW(factor.assign({-1, -2}), std::invalid_argument);
  factor.assign({-1, 0});
  EXPECT_THROW(factor.factor(Eigen::MatrixXd::Identity(3, 3)), std::invalid_argument);
  EXPECT_THROW(factor.set_inertia(0, 1, 1.0), std::invalid_argument);  // 1 is not on 0's path
  Eigen::Matrix2d singular;
  singular << 1, 1, 1, 1;  // a second coordinate that moves nothing the first does not
  factor.set_inertia(0, 0, 1), factor.set_inertia(1, 1, 1), factor.set_inertia(1, 0, 1);
  EXPECT_EQ(factor.factor(), 0);  // the step's form: says which coordinate, throws nothing
  try {
    factor.factor(singular);
    FAIL() << "a singular H was factored";
  } catch (const std::domain_error& error) {
    EXPECT_NE(std::string(error.what()).find("coordinate 0"), std::string::npos) << error.what();
  }
}

TEST(JointSpaceFactor, TheStepsReusedPosesGiveTheSameBits) {
  // The step forms H, the bodies' velocities and the articulated-body pass from poses it already
  // holds (mass_matrix, body_velocities and forward_dynamics from a workspace): they must be what
  // the same calls from q give, bit for bit.
  std::mt19937 rng(44);
  for (const RandomTreeOptions& kind : random_tree_kinds()) {
    const ArticulatedTree tree = random_tree(rng, kind);
    if (tree.velocity_count() == 0) continue;
    const Eigen::VectorXd q = random_positions(rng, tree), v = random_vector(rng, tree.velocity_count(), 2.0);
    DynamicsWorkspace from_q, poses, composite;
    forward_kinematics(tree, q, v, from_q);
    body_poses(tree, q, poses);
    body_velocities(tree, v, poses);
    for (int i = 0; i < tree.body_count(); ++i) {
      EXPECT_EQ(poses.velocity[static_cast<std::size_t>(i)], from_q.velocity[static_cast<std::size_t>(i)]) << "body " << i;
    }
    JointSpaceFactor h_from_q, h_from_poses;
    h_from_q.assign(tree), h_from_poses.assign(tree);
    mass_matrix(tree, q, composite, h_from_q);
    mass_matrix(tree, poses, composite, h_from_poses);
    ASSERT_LT(h_from_q.factor(), 0);
    ASSERT_LT(h_from_poses.factor(), 0);
    for (int i = 0; i < h_from_q.size(); ++i) EXPECT_EQ(h_from_q.pivot(i), h_from_poses.pivot(i)) << "coordinate " << i;
    const Eigen::VectorXd tau = random_vector(rng, tree.velocity_count(), 5.0), armature = random_vector(rng, tree.velocity_count(), 1.0).cwiseAbs();
    const Eigen::Vector3d gravity(0, 0, -9.81);
    Eigen::VectorXd from_q_acceleration, from_poses_acceleration;
    DynamicsWorkspace articulated;
    forward_dynamics(tree, q, v, tau, armature, gravity, articulated, from_q_acceleration);
    forward_dynamics(tree, poses, tau, armature.data(), gravity, articulated, from_poses_acceleration);
    EXPECT_EQ(from_q_acceleration, from_poses_acceleration);
  }
}

}  // namespace
}  // namespace limber
