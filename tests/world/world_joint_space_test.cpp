// Joint space through the World (world.hpp, "Joint space"): coordinates set and read back bit
// for bit; M v̇ + C = τ for the accelerations the forward dynamics gives; the inverse dynamics of
// those returns τ; ½ vᵀ M v is the bodies' kinetic energy; springs and motors are the passive
// forces; a hinge's reaction is a falling rod's; the methods without joint coordinates refuse
// by name.
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "limber/kernel/world/world.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

World featherstone_humanoid() {
  WorldOptions options;
  options.method = Method::featherstone;
  Model model = testing::load_shipped_scene("ragdoll.json");
  model.settings.sleep.enabled = false;
  return World(model, options);
}

Eigen::VectorXd random_vector(Eigen::Index size, std::mt19937& random, double scale) {
  std::uniform_real_distribution<double> unit(-1, 1);
  Eigen::VectorXd v(size);
  for (Eigen::Index k = 0; k < size; ++k) v[k] = scale * unit(random);
  return v;
}

// The ragdoll at its pose with random rates (its positions include quaternions, which a random
// vector would not keep unit).
void set_random_state(World& world, std::mt19937& random) {
  const Eigen::VectorXd q = world.joint_positions();
  const Eigen::VectorXd v = random_vector(world.joint_velocities().size(), random, 1.5);
  world.set_joint_state(q, v);
}

TEST(WorldJointSpace, CoordinatesSetAreReadBackBitForBit) {
  World world = featherstone_humanoid();
  std::mt19937 random(3);
  const Eigen::VectorXd q = world.joint_positions();
  const Eigen::VectorXd v = random_vector(world.joint_velocities().size(), random, 2);
  world.set_joint_state(q, v);
  EXPECT_EQ(world.joint_positions(), q);
  EXPECT_EQ(world.joint_velocities(), v);
  EXPECT_EQ(static_cast<Eigen::Index>(world.joint_space_names().size()), v.size());
  EXPECT_THROW(world.set_joint_state(q, Eigen::VectorXd::Zero(v.size() + 1)), WorldError);
  EXPECT_EQ(world.joint_velocities(), v);  // nothing changed
}

TEST(WorldJointSpace, ForwardAndInverseDynamicsAgreeThroughTheMassMatrix) {
  World world = featherstone_humanoid();
  std::mt19937 random(5);
  for (int trial = 0; trial < 5; ++trial) {
    set_random_state(world, random);
    const Eigen::VectorXd tau = random_vector(world.joint_velocities().size(), random, 10);
    const Eigen::VectorXd acceleration = world.joint_accelerations(tau);
    const Eigen::MatrixXd mass = world.joint_mass_matrix();
    const Eigen::VectorXd bias = world.joint_bias_forces();
    EXPECT_LT((mass * acceleration + bias - tau).norm(), 1e-10 * (tau.norm() + bias.norm())) << "state " << trial;
    EXPECT_LT((world.inverse_dynamics(acceleration) - tau).norm(), 1e-10 * (tau.norm() + bias.norm())) << "state " << trial;
    EXPECT_LT((mass - mass.transpose()).norm(), 1e-12 * mass.norm());
  }
}

TEST(WorldJointSpace, HalfVMVIsTheBodiesKineticEnergy) {
  World world = featherstone_humanoid();  // no armature: the energy is the bodies' alone
  std::mt19937 random(9);
  set_random_state(world, random);
  const Eigen::VectorXd v = world.joint_velocities();
  const double from_matrix = 0.5 * v.dot(world.joint_mass_matrix() * v);
  EXPECT_NEAR(from_matrix, world.observe().kinetic_energy, 1e-10 * from_matrix);
}

TEST(WorldJointSpace, PassiveForcesAreTheSpringsAndTheMotors) {
  Model model = testing::rod_held_at_head(JointType::revolute, Eigen::Vector3d::UnitZ());
  model.joints[0].drive = JointDrive{.stiffness = 3, .damping = 0.5, .target = 0.2};
  model.actuators.push_back({.name = "motor", .joint = 0, .axis = 0, .gear = 4, .control_range = Range{-1, 1}});
  WorldOptions options;
  options.method = Method::featherstone;
  World world(model, options);
  Eigen::VectorXd q(1), v(1);
  q << 0.5, v << -2;
  world.set_joint_state(q, v);
  const double controls[] = {2};  // clamped to 1
  world.set_controls(controls);
  EXPECT_NEAR(world.joint_passive_forces()[0], 3 * (0.2 - 0.5) + 0.5 * 2 + 4 * 1, 1e-14);
  EXPECT_EQ(world.joint_space_names(), std::vector<std::string>{"hinge"});
}

// A rod (1 kg, 1 m) on a hinge at its end, released horizontal from rest: its centre falls at
// a = (L/2)·α, α = m g (L/2) / I, so the hinge holds it up with m (g − a), a quarter of its weight
// for a thin rod (I = m L²/3), and transmits no torque (nothing turns it about its centre but
// the hinge's force, and the torque is taken about the hinge).
TEST(WorldJointSpace, AHingedRodReleasedLevelHangsOnAQuarterOfItsWeight) {
  WorldOptions options;
  options.method = Method::featherstone;
  const double radius = 0.01;
  World world(testing::rod_held_at_head(JointType::revolute, Eigen::Vector3d::UnitY(), radius), options);
  const double g = -world.model().settings.gravity.z(), inertia = 1.0 / 3 + radius * radius / 4;  // about the hinge
  const Eigen::VectorXd acceleration = world.joint_accelerations(Eigen::VectorXd::Zero(1));
  const std::vector<JointReaction> reactions = world.joint_reactions(acceleration);
  ASSERT_EQ(reactions.size(), 1u);
  const Eigen::Vector3d expected(0, 0, g * (1 - 0.25 / inertia));
  EXPECT_LT((reactions[0].force - expected).norm(), 1e-12 * g) << reactions[0].force.transpose();
  EXPECT_LT(reactions[0].torque.norm(), 1e-12 * g) << reactions[0].torque.transpose();
  // At rest under its weight alone (v̇ = 0: held by a motor's torque), the hinge carries all of it.
  const std::vector<JointReaction> held = world.joint_reactions(Eigen::VectorXd::Zero(1));
  EXPECT_LT((held[0].force - Eigen::Vector3d(0, 0, g)).norm(), 1e-12 * g);
  EXPECT_LT((held[0].torque - Eigen::Vector3d(0, -g * 0.5, 0)).norm(), 1e-12 * g) << "the motor's torque m g L/2 about -y";
}

TEST(WorldJointSpace, MethodsWithoutJointCoordinatesRefuseByName) {
  WorldOptions options;
  options.method = Method::lagrange;
  World world(testing::load_shipped_scene("ragdoll.json"), options);
  try {
    world.joint_mass_matrix();
    FAIL() << "accepted";
  } catch (const WorldError& error) {
    EXPECT_EQ(std::string(error.what()), "joint_mass_matrix: the lagrange method has no joint coordinates (its bodies are maximal coordinates); featherstone has");
  }
  EXPECT_THROW(world.joint_reactions(Eigen::VectorXd::Zero(1)), WorldError);
}

}  // namespace
}  // namespace limber
