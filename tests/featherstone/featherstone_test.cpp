// Featherstone's algorithms in reduced coordinates (kernel/featherstone/): spatial algebra
// identities, the three dynamics algorithms against each other on random trees, the joint
// coordinates against their own derivatives, and the conservation laws an integrator should keep.
// The allocation functions are replaced in this program to count them (forward dynamics and
// stepping must allocate nothing once sized).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "limber/kernel/featherstone/articulated_tree.hpp"
#include "limber/kernel/featherstone/dynamics.hpp"
#include "limber/kernel/featherstone/integration.hpp"
#include "limber/kernel/featherstone/joint_space_factor.hpp"
#include "limber/kernel/featherstone/spatial.hpp"
#include "limber/kernel/model/model.hpp"
#include "tests/featherstone/random_trees.hpp"
#include "tests/support/allocation_counter.hpp"


namespace limber {
namespace {

using testing::random_inertia;
using testing::random_positions;
using testing::random_rotation;
using testing::random_tree;
using testing::random_tree_kinds;
using testing::random_vector;
using testing::uniform;
using testing::RandomTreeOptions;
using testing::uniform_vector;

const Eigen::Vector3d kGravity(0, 0, -9.81);

SpatialVector random_spatial(std::mt19937& rng) { return random_vector(rng, 6, 1); }

PluckerTransform random_transform(std::mt19937& rng) {
  return PluckerTransform::from_pose(random_rotation(rng).toRotationMatrix(), uniform_vector(rng, -1, 1));
}

double relative_error(const Eigen::VectorXd& value, const Eigen::VectorXd& reference) {
  return (value - reference).norm() / std::max(reference.norm(), 1e-300);
}

// --- Spatial algebra (chapter 2) -----------------------------------------------------------------

TEST(SpatialAlgebra, PluckerOperationsMatchTheirSixBySixMatrices) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    const PluckerTransform x = random_transform(rng), y = random_transform(rng);
    const SpatialVector m = random_spatial(rng), f = random_spatial(rng);
    const SpatialMatrix xm = x.motion_matrix();
    EXPECT_LT((x.apply_motion(m) - xm * m).norm(), 1e-14);
    EXPECT_LT((x.apply_force(f) - xm.inverse().transpose() * f).norm(), 1e-13);  // X* = X⁻ᵀ
    EXPECT_LT((x.force_matrix() - xm.inverse().transpose()).norm(), 1e-13);
    EXPECT_LT((x.transpose_apply_force(f) - xm.transpose() * f).norm(), 1e-14);
    EXPECT_LT((x.inverse_apply_motion(m) - xm.inverse() * m).norm(), 1e-13);
    EXPECT_LT((x.inverse().motion_matrix() - xm.inverse()).norm(), 1e-13);
    EXPECT_LT(((x * y).motion_matrix() - xm * y.motion_matrix()).norm(), 1e-13);
    const SpatialInertia body = random_inertia(rng);
    const SpatialMatrix inertia = body.matrix();
    EXPECT_LT((x.transpose_apply_inertia(inertia) - xm.transpose() * inertia * xm).norm(), 1e-13);
    EXPECT_LT((body.transformed_by(x).matrix() - xm.transpose() * inertia * xm).norm(), 1e-13);
  }
}

TEST(SpatialAlgebra, PowerIsTheSameInEveryFrame) {
  std::mt19937 rng(2);
  for (int trial = 0; trial < 20; ++trial) {
    const PluckerTransform x = random_transform(rng);
    const SpatialVector m = random_spatial(rng), f = random_spatial(rng);
    EXPECT_NEAR(x.apply_motion(m).dot(x.apply_force(f)), m.dot(f), 1e-13);
  }
}

TEST(SpatialAlgebra, ForceCrossProductIsMinusTheTransposedMotionCrossProduct) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    const SpatialVector m = random_spatial(rng), other = random_spatial(rng), f = random_spatial(rng);
    EXPECT_LT((cross_motion(m, other) - motion_cross_matrix(m) * other).norm(), 1e-15);
    EXPECT_LT((cross_force(m, f) - force_cross_matrix(m) * f).norm(), 1e-15);
    EXPECT_EQ((force_cross_matrix(m) + motion_cross_matrix(m).transpose()).norm(), 0.0);
    // Cross products transform like the vectors they make: X(m × m') = Xm × Xm'.
    const PluckerTransform x = random_transform(rng);
    EXPECT_LT((x.apply_motion(cross_motion(m, other)) - cross_motion(x.apply_motion(m), x.apply_motion(other))).norm(), 1e-13);
    EXPECT_LT((x.apply_force(cross_force(m, f)) - cross_force(x.apply_motion(m), x.apply_force(f))).norm(), 1e-13);
  }
}

TEST(SpatialAlgebra, SpatialInertiaGivesMomentumAndKineticEnergyOfTheCentreOfMass) {
  std::mt19937 rng(4);
  for (int trial = 0; trial < 20; ++trial) {
    const SpatialInertia inertia = random_inertia(rng);
    const SpatialVector v = random_spatial(rng);
    const Eigen::Vector3d omega = v.head<3>();
    const Eigen::Vector3d centre = inertia.centre_of_mass();
    const Eigen::Vector3d centre_velocity = v.tail<3>() + omega.cross(centre);
    const double expected_energy = 0.5 * inertia.mass * centre_velocity.squaredNorm() +
                                   0.5 * omega.dot(inertia.inertia_about_centre_of_mass() * omega);
    EXPECT_NEAR(0.5 * v.dot(inertia * v), expected_energy, 1e-14);
    EXPECT_LT(((inertia * v).tail<3>() - inertia.mass * centre_velocity).norm(), 1e-14);
    // Angular momentum about the origin = c × m v_c + I_c ω.
    const Eigen::Vector3d angular = centre.cross(inertia.mass * centre_velocity) + inertia.inertia_about_centre_of_mass() * omega;
    EXPECT_LT(((inertia * v).head<3>() - angular).norm(), 1e-14);
    EXPECT_LT((inertia.matrix() * v - inertia * v).norm(), 1e-14);
  }
}

// --- The tree --------------------------------------------------------------------------------------

ArticulatedBody valid_body(int parent) {
  ArticulatedBody body;
  body.name = "forearm";
  body.parent = parent;
  body.joint = ArticulatedJoint::revolute;
  body.joint_axis = Eigen::Vector3d::UnitY();
  body.inertia = SpatialInertia::from_mass_properties(1, Eigen::Vector3d(0.2, 0, 0), Eigen::Vector3d(0.01, 0.02, 0.02).asDiagonal());
  return body;
}

// The message of the ModelError that adding `body` as body 2 of a two-body chain throws.
std::string rejection(const ArticulatedBody& body) {
  ArticulatedTree tree;
  tree.add_body(valid_body(-1));
  tree.add_body(valid_body(0));
  try {
    tree.add_body(body);
  } catch (const ModelError& error) {
    return error.what();
  }
  return "accepted";
}

TEST(ArticulatedTree, ValidationNamesTheBodyAndTheProblem) {
  ArticulatedBody body = valid_body(1);
  EXPECT_EQ(rejection(body), "accepted");

  body = valid_body(2);
  EXPECT_EQ(rejection(body), "bodies[2] (\"forearm\").parent: must be -1 (the world) or an earlier body (< 2), got 2");
  body = valid_body(1), body.joint_axis = Eigen::Vector3d(0, 2, 0);
  EXPECT_EQ(rejection(body), "bodies[2] (\"forearm\").joint_axis: must be a unit vector, got length 2");
  body = valid_body(1), body.tree_transform.translation.y() = std::nan("");
  EXPECT_EQ(rejection(body), "bodies[2] (\"forearm\").tree_transform.translation[1]: must be a finite number, got nan");
  body = valid_body(1), body.tree_transform.rotation(0, 0) = 2;
  EXPECT_NE(rejection(body).find("bodies[2] (\"forearm\").tree_transform.rotation: must be a rotation matrix"), std::string::npos);
  body = valid_body(1), body.inertia.mass = -1;
  EXPECT_EQ(rejection(body), "bodies[2] (\"forearm\").inertia.mass: must be > 0, got -1");
  body = valid_body(1), body.inertia.rotational_inertia(2, 2) = -1;
  EXPECT_NE(rejection(body).find("bodies[2] (\"forearm\").inertia.rotational_inertia: must be positive definite"), std::string::npos);
  body = valid_body(1), body.inertia = SpatialInertia::from_mass_properties(1, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.01, 0.01, 1).asDiagonal());
  EXPECT_NE(rejection(body).find("break the triangle inequality"), std::string::npos);
  body = valid_body(1), body.name.clear(), body.inertia.mass = 0;
  EXPECT_EQ(rejection(body), "bodies[2].inertia.mass: must be > 0, got 0");
  // A spherical joint has no axis to check.
  body = valid_body(1), body.joint = ArticulatedJoint::spherical, body.joint_axis = Eigen::Vector3d::Zero();
  EXPECT_EQ(rejection(body), "accepted");
}

TEST(ArticulatedTree, EachJointOwnsAContiguousSliceOfQAndV) {
  ArticulatedTree tree;
  const ArticulatedJoint types[] = {ArticulatedJoint::floating, ArticulatedJoint::revolute, ArticulatedJoint::spherical, ArticulatedJoint::fixed, ArticulatedJoint::prismatic};
  for (int i = 0; i < 5; ++i) {
    ArticulatedBody body = valid_body(i - 1);
    body.joint = types[i];
    tree.add_body(body);
  }
  EXPECT_EQ(tree.position_count(), 7 + 1 + 4 + 0 + 1);
  EXPECT_EQ(tree.velocity_count(), 6 + 1 + 3 + 0 + 1);
  const int position_offsets[] = {0, 7, 8, 12, 12}, velocity_offsets[] = {0, 6, 7, 10, 10};
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(tree.position_offset(i), position_offsets[i]);
    EXPECT_EQ(tree.velocity_offset(i), velocity_offsets[i]);
  }
  Eigen::VectorXd neutral(13);
  neutral << 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0;
  EXPECT_EQ(tree.neutral_positions(), neutral);
  // At the neutral positions every joint frame is its child's body frame.
  for (int i = 0; i < 5; ++i) {
    const PluckerTransform x = joint_transform(tree.body(i), neutral.data() + tree.position_offset(i));
    EXPECT_EQ(x.rotation, Eigen::Matrix3d::Identity());
    EXPECT_EQ(x.translation, Eigen::Vector3d::Zero());
  }
}

// --- Dynamics on random trees ----------------------------------------------------------------------

TEST(Dynamics, ArticulatedBodyAlgorithmSolvesTheMassMatrixEquation) {
  std::mt19937 rng(10);
  DynamicsWorkspace workspace;
  Eigen::VectorXd accelerations, bias, no_acceleration;
  Eigen::MatrixXd inertia;
  int trees = 0;
  for (const RandomTreeOptions& kind : random_tree_kinds()) {
    for (int trial = 0; trial < 10; ++trial, ++trees) {
      const ArticulatedTree tree = random_tree(rng, kind);
      if (tree.velocity_count() == 0) continue;  // a fixed single body
      const Eigen::VectorXd q = random_positions(rng, tree);
      const Eigen::VectorXd v = random_vector(rng, tree.velocity_count(), 2);
      const Eigen::VectorXd tau = random_vector(rng, tree.velocity_count(), 5);
      forward_dynamics(tree, q, v, tau, kGravity, workspace, accelerations);
      mass_matrix(tree, q, workspace, inertia);
      no_acceleration.setZero(tree.velocity_count());
      inverse_dynamics(tree, q, v, no_acceleration, kGravity, workspace, bias);  // C(q, v)
      EXPECT_LT((inertia - inertia.transpose()).norm(), 1e-14 * inertia.norm());
      const Eigen::LLT<Eigen::MatrixXd> factor(inertia);
      ASSERT_EQ(factor.info(), Eigen::Success) << "H is not positive definite";
      const Eigen::VectorXd reference = factor.solve(tau - bias);
      EXPECT_LT(relative_error(accelerations, reference), 1e-9) << "tree " << trees << ", " << tree.body_count() << " bodies";
    }
  }
}

// A forest of `count` random trees (floating, branching, chains) in one ArticulatedTree, and each
// tree's body range: the islands of the Featherstone method.
ArticulatedTree random_forest(std::mt19937& rng, int count, std::vector<BodyRange>& ranges) {
  ArticulatedTree forest;
  const std::vector<RandomTreeOptions> kinds = random_tree_kinds();
  for (int t = 0; t < count; ++t) {
    const ArticulatedTree tree = random_tree(rng, kinds[static_cast<std::size_t>(t) % kinds.size()]);
    const int first = forest.body_count();
    for (ArticulatedBody body : tree.bodies()) {
      if (body.parent >= 0) body.parent += first;
      forest.add_body(body);
    }
    ranges.push_back({first, forest.body_count()});
  }
  return forest;
}

TEST(Dynamics, EachIslandAloneGivesTheBitsOfTheWholeForest) {
  // The range overloads (kinematics, ABA, CRBA into the factor, both integrators) on each tree of
  // a forest give exactly what the whole-forest call gives on its bodies and coordinates.
  std::mt19937 rng(31);
  std::vector<BodyRange> ranges;
  const ArticulatedTree forest = random_forest(rng, 5, ranges);
  const Eigen::VectorXd q = random_positions(rng, forest);
  const Eigen::VectorXd v = random_vector(rng, forest.velocity_count(), 2);
  const Eigen::VectorXd tau = random_vector(rng, forest.velocity_count(), 5);
  DynamicsWorkspace whole, apart;
  whole.resize(forest), apart.resize(forest);
  forward_kinematics(forest, q, v, whole);
  for (const BodyRange range : ranges) forward_kinematics(forest, q, v, apart, range);
  for (int i = 0; i < forest.body_count(); ++i) {
    const auto index = static_cast<std::size_t>(i);
    EXPECT_TRUE(whole.velocity[index] == apart.velocity[index]) << "body " << i;
    EXPECT_TRUE(whole.world_to_body[index].rotation == apart.world_to_body[index].rotation) << "body " << i;
  }
  Eigen::VectorXd whole_acceleration, apart_acceleration = Eigen::VectorXd::Zero(forest.velocity_count());
  forward_dynamics(forest, whole, tau, nullptr, kGravity, whole, whole_acceleration);
  for (const BodyRange range : ranges) forward_dynamics(forest, apart, tau, nullptr, kGravity, apart, apart_acceleration, range);
  EXPECT_TRUE(whole_acceleration == apart_acceleration);
  JointSpaceFactor whole_factor, apart_factor;
  whole_factor.assign(forest), apart_factor.assign(forest);
  mass_matrix(forest, whole, whole, whole_factor);
  EXPECT_LT(whole_factor.factor(), 0);
  for (const BodyRange range : ranges) {
    mass_matrix(forest, apart, apart, apart_factor, range);
    const auto [first, last] = forest.velocity_span(range);
    EXPECT_LT(apart_factor.factor(first, last), 0);
  }
  for (int i = 0; i < forest.velocity_count(); ++i) EXPECT_EQ(whole_factor.pivot(i), apart_factor.pivot(i)) << "coordinate " << i;
  for (const Integrator integrator : {Integrator::semi_implicit_euler, Integrator::rk4}) {
    FeatherstoneIntegratorWorkspace whole_steps, apart_steps;
    whole_steps.resize(forest), apart_steps.resize(forest);
    Eigen::VectorXd whole_q = q, whole_v = v, apart_q = q, apart_v = v;
    for (int s = 0; s < 3; ++s) {
      integrate(forest, whole_q, whole_v, tau, kGravity, 0.01, integrator, whole_steps);
      for (const BodyRange range : ranges) integrate(forest, apart_q, apart_v, tau, kGravity, 0.01, integrator, apart_steps, nullptr, range);
    }
    EXPECT_TRUE(whole_q == apart_q) << integrator_name(integrator);
    EXPECT_TRUE(whole_v == apart_v) << integrator_name(integrator);
  }
}

TEST(Dynamics, InverseDynamicsUndoesForwardDynamics) {
  std::mt19937 rng(11);
  DynamicsWorkspace workspace;
  Eigen::VectorXd accelerations, forces;
  for (const RandomTreeOptions& kind : random_tree_kinds()) {
    for (int trial = 0; trial < 10; ++trial) {
      const ArticulatedTree tree = random_tree(rng, kind);
      if (tree.velocity_count() == 0) continue;
      const Eigen::VectorXd q = random_positions(rng, tree);
      const Eigen::VectorXd v = random_vector(rng, tree.velocity_count(), 2);
      const Eigen::VectorXd tau = random_vector(rng, tree.velocity_count(), 5);
      forward_dynamics(tree, q, v, tau, kGravity, workspace, accelerations);
      inverse_dynamics(tree, q, v, accelerations, kGravity, workspace, forces);
      EXPECT_LT(relative_error(forces, tau), 1e-9);
    }
  }
}

TEST(Dynamics, MassMatrixGivesTheKineticEnergy) {
  // T = ½ vᵀHv, with the armature (a rotor's reflected inertia on a revolute or prismatic
  // coordinate, in H's diagonal) in every other tree.
  std::mt19937 rng(12);
  DynamicsWorkspace workspace;
  Eigen::MatrixXd inertia;
  for (int trial = 0; trial < 20; ++trial) {
    const ArticulatedTree random = random_tree(rng, {.bodies = 9, .branching = true, .floating_base = trial % 2 == 0});
    ArticulatedTree tree;
    for (int i = 0; i < random.body_count(); ++i) {
      ArticulatedBody body = random.body(i);
      const bool one_axis = body.joint == ArticulatedJoint::revolute || body.joint == ArticulatedJoint::prismatic;
      if (one_axis && trial % 4 < 2) body.armature = uniform(rng, 0.1, 1);
      tree.add_body(body);
    }
    const Eigen::VectorXd q = random_positions(rng, tree);
    const Eigen::VectorXd v = random_vector(rng, tree.velocity_count(), 2);
    mass_matrix(tree, q, workspace, inertia);
    const double energy = kinetic_energy(tree, q, v, workspace);
    EXPECT_NEAR(0.5 * v.dot(inertia * v), energy, 1e-12 * energy);
  }
}

// The world-frame spatial velocity of each body, (ω, velocity of the body origin) in body
// coordinates, by central differences of its pose along q ⊕ εv.
TEST(Dynamics, JointVelocitiesAreTheRatesOfTheJointPositions) {
  std::mt19937 rng(13);
  DynamicsWorkspace at, before, after;
  const double epsilon = 1e-6;
  for (int trial = 0; trial < 10; ++trial) {
    const ArticulatedTree tree = random_tree(rng, {.bodies = 8, .branching = true, .floating_base = trial % 2 == 0});
    const Eigen::VectorXd q = random_positions(rng, tree);
    const Eigen::VectorXd v = random_vector(rng, tree.velocity_count(), 2);
    Eigen::VectorXd q_before(q.size()), q_after(q.size());
    displace_positions(tree, q, -epsilon * v, q_before);
    displace_positions(tree, q, epsilon * v, q_after);
    forward_kinematics(tree, q, v, at);
    body_poses(tree, q_before, before);
    body_poses(tree, q_after, after);
    for (int i = 0; i < tree.body_count(); ++i) {
      const auto b = static_cast<std::size_t>(i);
      // Body-to-world rotation R = Eᵀ and the origin p; Rᵀ Ṙ = [ω]×, v_O = Rᵀ ṗ.
      const Eigen::Matrix3d rotation = at.world_to_body[b].rotation.transpose();
      const Eigen::Matrix3d rotation_rate =
          (after.world_to_body[b].rotation.transpose() - before.world_to_body[b].rotation.transpose()) / (2 * epsilon);
      const Eigen::Matrix3d omega_cross = rotation.transpose() * rotation_rate;
      const Eigen::Vector3d omega(omega_cross(2, 1), omega_cross(0, 2), omega_cross(1, 0));
      const Eigen::Vector3d origin_velocity =
          rotation.transpose() * (after.world_to_body[b].translation - before.world_to_body[b].translation) / (2 * epsilon);
      EXPECT_LT((omega - at.velocity[b].head<3>()).norm(), 1e-7) << "body " << i;
      EXPECT_LT((origin_velocity - at.velocity[b].tail<3>()).norm(), 1e-7) << "body " << i;
    }
  }
}

TEST(Dynamics, AFreeBodyFallsWithGravity) {
  std::mt19937 rng(14);
  const ArticulatedTree tree = random_tree(rng, {.bodies = 1, .floating_base = true});
  const Eigen::VectorXd q = random_positions(rng, tree);
  DynamicsWorkspace workspace;
  Eigen::VectorXd accelerations;
  forward_dynamics(tree, q, Eigen::VectorXd::Zero(6), Eigen::VectorXd::Zero(6), kGravity, workspace, accelerations);
  // At rest: no angular acceleration, and the origin accelerates at g (child coordinates).
  const Eigen::Matrix3d body_to_world = Eigen::Quaterniond(q[3], q[4], q[5], q[6]).toRotationMatrix();
  EXPECT_LT(accelerations.head<3>().norm(), 1e-12);
  EXPECT_LT((body_to_world * accelerations.tail<3>() - kGravity).norm(), 1e-12);
}

TEST(Dynamics, ForwardDynamicsAndSteppingAllocateNothingOnceSized) {
  std::mt19937 rng(15);
  const ArticulatedTree tree = random_tree(rng, {.bodies = 30, .branching = true, .floating_base = true});
  Eigen::VectorXd q = random_positions(rng, tree);
  Eigen::VectorXd v = random_vector(rng, tree.velocity_count(), 1);
  const Eigen::VectorXd tau = random_vector(rng, tree.velocity_count(), 1);
  DynamicsWorkspace workspace;
  FeatherstoneIntegratorWorkspace stepper;
  Eigen::VectorXd accelerations, forces;
  forward_dynamics(tree, q, v, tau, kGravity, workspace, accelerations);  // sizes
  inverse_dynamics(tree, q, v, accelerations, kGravity, workspace, forces);
  integrate(tree, q, v, tau, kGravity, 1e-3, Integrator::rk4, stepper);
  const long before = testing::allocation_count();
  for (int step = 0; step < 10; ++step) {
    forward_dynamics(tree, q, v, tau, kGravity, workspace, accelerations);
    inverse_dynamics(tree, q, v, accelerations, kGravity, workspace, forces);
    integrate(tree, q, v, tau, kGravity, 1e-3, Integrator::rk4, stepper);
    integrate(tree, q, v, tau, kGravity, 1e-3, Integrator::semi_implicit_euler, stepper);
  }
  EXPECT_EQ(testing::allocation_count() - before, 0);
}

// --- Conservation under integration ---------------------------------------------------------------

// A pendulum chain hanging from the world (or, with `floating_root`, from a free body): `links`
// bodies of 1 kg, 0.6 m apart along −z, each a slender box (0.03, 0.03, 0.002 kg·m² about its
// centre of mass, 0.3 m below its joint); revolute joints about y (a planar chain) or spherical
// joints. Starts at rest at joint angles ~`amplitude` rad (spherical joints also spinning at
// ~`spin` rad/s); `q`, `v` receive the start.
struct PendulumStart {
  double amplitude = 0.3, spin = 0;
  bool floating_root = false;
};
ArticulatedTree pendulum_chain(int links, ArticulatedJoint joint, const PendulumStart& start, Eigen::VectorXd& q, Eigen::VectorXd& v) {
  ArticulatedTree tree;
  const SpatialInertia link = SpatialInertia::from_mass_properties(1, Eigen::Vector3d(0, 0, -0.3), Eigen::Vector3d(0.03, 0.03, 0.002).asDiagonal());
  if (start.floating_root) {
    ArticulatedBody root;
    root.joint = ArticulatedJoint::floating;
    root.inertia = SpatialInertia::from_mass_properties(2, Eigen::Vector3d::Zero(), Eigen::Vector3d(0.02, 0.03, 0.04).asDiagonal());
    tree.add_body(root);
  }
  for (int i = 0; i < links; ++i) {
    ArticulatedBody body;
    body.parent = tree.body_count() - 1;
    body.joint = joint;
    body.joint_axis = Eigen::Vector3d::UnitY();
    if (body.parent >= 0 && !(start.floating_root && i == 0)) body.tree_transform.translation = Eigen::Vector3d(0, 0, -0.6);
    body.inertia = link;
    tree.add_body(body);
  }
  q = tree.neutral_positions();
  v = Eigen::VectorXd::Zero(tree.velocity_count());
  const int first = start.floating_root ? 1 : 0;
  for (int i = 0; i < links; ++i) {
    const int p = tree.position_offset(first + i), d = tree.velocity_offset(first + i);
    if (joint == ArticulatedJoint::revolute) {
      q[p] = i == 0 ? start.amplitude : -0.5 * start.amplitude * i;
    } else {
      const Eigen::Quaterniond turn(Eigen::AngleAxisd(start.amplitude * (1 + 0.5 * i), Eigen::Vector3d(0.3, 1, 0.2 * i).normalized()));
      q.segment<4>(p) << turn.w(), turn.x(), turn.y(), turn.z();
      v.segment<3>(d) = start.spin * Eigen::Vector3d(1.0, 0.3 * i, -0.5);
    }
  }
  if (start.floating_root) v.head<6>() << 0.3, -0.2, 0.5, 0.1, 0.2, 1.0;
  return tree;
}

double total_energy(const ArticulatedTree& tree, const Eigen::VectorXd& q, const Eigen::VectorXd& v, DynamicsWorkspace& workspace) {
  return kinetic_energy(tree, q, v, workspace) + potential_energy(tree, q, kGravity, workspace);
}

struct EnergyDrift {
  double largest = 0;        ///< max |E(t) − E(0)| over the run, J
  double largest_early = 0;  ///< the same over the first tenth of the run, J
};

// |E(t) − E(0)| of a pendulum chain over `duration` seconds with step h.
EnergyDrift energy_drift(int links, ArticulatedJoint joint, const PendulumStart& start, Integrator integrator, double h,
                         double duration) {
  Eigen::VectorXd q, v;
  const ArticulatedTree tree = pendulum_chain(links, joint, start, q, v);
  const Eigen::VectorXd no_forces = Eigen::VectorXd::Zero(tree.velocity_count());
  FeatherstoneIntegratorWorkspace stepper;
  DynamicsWorkspace observer;
  const double initial = total_energy(tree, q, v, observer);
  EnergyDrift drift;
  const long steps = std::lround(duration / h);
  for (long s = 0; s < steps; ++s) {
    integrate(tree, q, v, no_forces, kGravity, h, integrator, stepper);
    drift.largest = std::max(drift.largest, std::abs(total_energy(tree, q, v, observer) - initial));
    if (s < steps / 10) drift.largest_early = drift.largest;
  }
  return drift;
}

// Energy scale of a chain: every link's weight times the chain's length, J.
double energy_scale(int links) { return links * 9.81 * 0.6 * links; }

TEST(Integration, RungeKuttaEnergyErrorShrinksSixteenfoldWhenTheStepHalves) {
  for (const ArticulatedJoint joint : {ArticulatedJoint::revolute, ArticulatedJoint::spherical}) {
    const PendulumStart start{.amplitude = 0.3, .spin = 1};
    const double coarse = energy_drift(3, joint, start, Integrator::rk4, 1.0 / 100, 5).largest;
    const double fine = energy_drift(3, joint, start, Integrator::rk4, 1.0 / 200, 5).largest;
    EXPECT_GT(coarse / fine, 8) << articulated_joint_name(joint) << ": drift " << coarse << " J, then " << fine << " J";
    EXPECT_LT(coarse, 1e-6 * energy_scale(3)) << articulated_joint_name(joint);
  }
}

// With a constant joint-space inertia (one revolute pendulum) semi-implicit Euler is symplectic:
// over 10⁵ steps of 1 ms its energy error oscillates, O(h), and never outgrows the first 10 s.
TEST(Integration, SemiImplicitEulerKeepsAPendulumsEnergyBounded) {
  const EnergyDrift drift = energy_drift(1, ArticulatedJoint::revolute, {.amplitude = 0.5}, Integrator::semi_implicit_euler, 1e-3, 100);
  EXPECT_LT(drift.largest, 1e-3 * energy_scale(1));
  EXPECT_LE(drift.largest, 1.1 * drift.largest_early);
}

// For a chain the method as specified (v ← v + h v̇, then q ← q ⊕ h v) is not symplectic: the
// joint-space inertia depends on q, and the gyroscopic forces of spherical joints are taken
// explicitly. Its energy error then drifts, about linearly in t and in h (a first-order method's
// secular error): the drift halves with the step, and over 10⁵ steps of 1 ms at these moderate
// swings it stays below 2% of the chain's energy scale.
TEST(Integration, SemiImplicitEulerEnergyDriftOfAChainIsFirstOrder) {
  for (const ArticulatedJoint joint : {ArticulatedJoint::revolute, ArticulatedJoint::spherical}) {
    const PendulumStart start = joint == ArticulatedJoint::revolute ? PendulumStart{.amplitude = 0.3} : PendulumStart{.amplitude = 0.2, .spin = 0.5};
    const double coarse = energy_drift(3, joint, start, Integrator::semi_implicit_euler, 2e-3, 20).largest;
    const double fine = energy_drift(3, joint, start, Integrator::semi_implicit_euler, 1e-3, 20).largest;
    EXPECT_GT(coarse / fine, 1.6) << articulated_joint_name(joint);
    EXPECT_LT(coarse / fine, 2.5) << articulated_joint_name(joint);
    const double long_run = energy_drift(3, joint, start, Integrator::semi_implicit_euler, 1e-3, 100).largest;
    EXPECT_LT(long_run, 0.02 * energy_scale(3)) << articulated_joint_name(joint);
  }
}

TEST(Integration, QuaternionsStayUnitOverAHundredThousandSteps) {
  for (const Integrator integrator : {Integrator::semi_implicit_euler, Integrator::rk4}) {
    Eigen::VectorXd q, v;
    const ArticulatedTree tree = pendulum_chain(3, ArticulatedJoint::spherical, {.amplitude = 0.2, .spin = 0.5, .floating_root = true}, q, v);
    const Eigen::VectorXd no_forces = Eigen::VectorXd::Zero(tree.velocity_count());
    FeatherstoneIntegratorWorkspace stepper;
    double worst = 0;
    for (int step = 0; step < 100000; ++step) {
      integrate(tree, q, v, no_forces, kGravity, 1e-3, integrator, stepper);
      for (int i = 0; i < tree.body_count(); ++i) {
        const int start = tree.position_offset(i) + (tree.body(i).joint == ArticulatedJoint::floating ? 3 : 0);
        worst = std::max(worst, std::abs(q.segment<4>(start).norm() - 1));
      }
    }
    EXPECT_LT(worst, 1e-12) << integrator_name(integrator);
    EXPECT_TRUE(v.allFinite() && q.allFinite()) << integrator_name(integrator);
  }
}

// A floating tree in zero gravity with no joint forces: nothing outside acts on it, so its
// total spatial momentum (world frame, about the world origin) stays put. RK4 keeps it to its
// truncation error; the energy too.
TEST(Integration, AFreeFloatingTreeKeepsItsSpatialMomentum) {
  std::mt19937 rng(21);
  for (int trial = 0; trial < 4; ++trial) {
    const ArticulatedTree tree = random_tree(rng, {.bodies = trial == 0 ? 1 : 6, .branching = true, .floating_base = true});
    Eigen::VectorXd q = random_positions(rng, tree);
    Eigen::VectorXd v = random_vector(rng, tree.velocity_count(), 2);
    const Eigen::VectorXd no_forces = Eigen::VectorXd::Zero(tree.velocity_count());
    const Eigen::Vector3d no_gravity = Eigen::Vector3d::Zero();
    FeatherstoneIntegratorWorkspace stepper;
    DynamicsWorkspace observer;
    const SpatialVector start = spatial_momentum(tree, q, v, observer);
    const double start_energy = kinetic_energy(tree, q, v, observer);
    for (int step = 0; step < 1000; ++step) integrate(tree, q, v, no_forces, no_gravity, 1e-3, Integrator::rk4, stepper);
    const SpatialVector end = spatial_momentum(tree, q, v, observer);
    EXPECT_LT((end - start).norm(), 1e-9 * start.norm()) << "trial " << trial;
    EXPECT_NEAR(kinetic_energy(tree, q, v, observer), start_energy, 1e-9 * start_energy) << "trial " << trial;
  }
}

}  // namespace
}  // namespace limber
