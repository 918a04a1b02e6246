// The Lagrange method's joint types and its gear (kernel/lagrange/constraints.hpp): each
// constraint's Jacobian is the derivative of its error and J̇u the derivative of J·u; each joint
// type leaves exactly the motions it should; the tree and sparse solvers agree with every type;
// meshed gears keep their speed ratio and their energy.

// GCC 12 false positives inside Eigen's AVX-512 reductions over fixed-capacity vectors (a
// relative of bug 105593); must precede Eigen's headers.
#pragma GCC diagnostic ignored "-Warray-bounds"
#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "limber/kernel/lagrange/compile.hpp"
#include "limber/kernel/lagrange/constraints.hpp"
#include "limber/kernel/lagrange/multipliers.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/scene/generators.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

constexpr JointType kTypes[] = {JointType::spherical, JointType::revolute, JointType::prismatic, JointType::universal,
                                JointType::fixed};

// A random tree whose joints cycle through every type, with random axes, masses and velocities.
Model mixed_tree(std::size_t links, std::size_t branching, unsigned seed) {
  Model model = make_tree_model({.links = links, .branching = branching});
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(-1, 1);
  const auto direction = [&] { return Vector3(unit(random), unit(random), unit(random)).normalized(); };
  for (Body& body : model.bodies) {
    body.mass = 0.5 + 2 * std::abs(unit(random));
    body.linear_velocity = Vector3(unit(random), unit(random), unit(random));
    body.angular_velocity = 3 * Vector3(unit(random), unit(random), unit(random));
  }
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    Joint& joint = model.joints[j];
    joint.type = kTypes[(j + seed) % std::size(kTypes)];
    joint.axis = direction();
    joint.second_axis = joint.axis.cross(direction()).normalized();
  }
  model.settings.sleep.enabled = false;
  return model;
}

// The state moved along constant velocities for time t: x + t·v, exp(t·ω)·q.
RigidBodyState moved(const RigidBodyState& y, const std::vector<Eigen::Vector3d>& velocity,
                     const std::vector<Eigen::Vector3d>& angular_velocity, double t) {
  RigidBodyState out = y;
  for (std::size_t b = 0; b < velocity.size(); ++b) {
    out.position[b] += t * velocity[b];
    out.orientation[b] = (rotation_quaternion(t * angular_velocity[b]) * y.orientation[b]).normalized();
  }
  return out;
}

TEST(LagrangeConstraints, JacobianAndVelocityProductAreDerivativesOfTheError) {
  for (unsigned seed = 1; seed <= 6; ++seed) {
    const Model model = mixed_tree(12, 1 + seed % 3, seed);
    LagrangeState state = compile_lagrange(model);
    std::mt19937 random(seed);
    std::uniform_real_distribution<double> unit(-1, 1);
    // A general pose (every constraint violated a little) and general velocities.
    RigidBodyState y = state.bodies.state;
    std::vector<Eigen::Vector3d> velocity(y.size()), angular_velocity(y.size());
    for (std::size_t b = 0; b < y.size(); ++b) {
      y.position[b] += 0.02 * Eigen::Vector3d(unit(random), unit(random), unit(random));
      y.orientation[b] = (rotation_quaternion(0.1 * Eigen::Vector3d(unit(random), unit(random), unit(random))) * y.orientation[b]).normalized();
      velocity[b] = Eigen::Vector3d(unit(random), unit(random), unit(random));
      angular_velocity[b] = 2 * Eigen::Vector3d(unit(random), unit(random), unit(random));
    }
    const ConstraintSet& constraints = state.constraints;
    const double h = 1e-5;
    ConstraintGeometry at = state.geometry, before = state.geometry, after = state.geometry;
    update_constraint_geometry(constraints, state.joints, y, at);
    const RigidBodyState y_before = moved(y, velocity, angular_velocity, -h), y_after = moved(y, velocity, angular_velocity, h);
    update_constraint_geometry(constraints, state.joints, y_before, before);
    update_constraint_geometry(constraints, state.joints, y_after, after);
    for (std::size_t c = 0; c < constraints.joint_count; ++c) {
      const ConstraintVector rate = constraint_rate(constraints, at, velocity, angular_velocity, c);
      const ConstraintVector difference = (constraint_error(constraints, state.joints, y_after, c) -
                                           constraint_error(constraints, state.joints, y_before, c)) / (2 * h);
      EXPECT_LT((rate - difference).norm(), 1e-7 * (1 + rate.norm())) << "seed " << seed << ", joint " << c << " ("
                                                                       << joint_type_name(model.joints[c].type) << ")";
      const ConstraintVector product = velocity_product(constraints, state.joints, at, y, velocity, angular_velocity, c);
      const ConstraintVector rate_difference = (constraint_rate(constraints, after, velocity, angular_velocity, c) -
                                                constraint_rate(constraints, before, velocity, angular_velocity, c)) / (2 * h);
      EXPECT_LT((product - rate_difference).norm(), 1e-6 * (1 + product.norm())) << "seed " << seed << ", joint " << c << " ("
                                                                                  << joint_type_name(model.joints[c].type) << ")";
    }
  }
}

TEST(LagrangeConstraints, TreeAndSparseSolversAgreeWithEveryJointType) {
  for (unsigned seed = 1; seed <= 8; ++seed) {
    const Model model = mixed_tree(4 + 6 * seed, 1 + seed % 3, seed);
    LagrangeState tree = compile_lagrange(model, {.solver = MultiplierSolver::tree});
    LagrangeState sparse = compile_lagrange(model, {.solver = MultiplierSolver::sparse});
    RigidForces forces_tree, forces_sparse;
    forces_tree.resize(tree.bodies.size()), forces_sparse.resize(sparse.bodies.size());
    accumulate_constrained_forces(tree, tree.bodies.state, forces_tree);
    accumulate_constrained_forces(sparse, sparse.bodies.state, forces_sparse);
    double scale = 0;
    for (const auto& lambda : sparse.multipliers) scale = std::max(scale, lambda.norm());
    for (std::size_t c = 0; c < tree.constraints.size(); ++c) {
      EXPECT_LT((tree.multipliers[c] - sparse.multipliers[c]).norm(), 1e-9 * scale) << "seed " << seed << ", joint " << c;
    }
  }
}

// One rod of `length` m (radius 1 mm, 1 kg) hanging from the world by `type` at its head,
// lying along +x from the anchor at the origin.
Model rod_on(JointType type, const Vector3& axis, double length = 1) {
  Model model;
  model.name = "rod";
  Body rod;
  rod.name = "rod";
  rod.shape = {ShapeType::cylinder, length, 0.001};
  rod.mass = 1;
  rod.axis = -Vector3::UnitX();  // head at the anchor
  rod.position = Vector3(0.5 * length, 0, 0);
  model.bodies.push_back(rod);
  Joint joint = spherical_joint("joint", kWorld, 0, Vector3::Zero(), Vector3(0, 0, 0.5 * length));
  joint.type = type;
  joint.axis = axis;
  model.joints.push_back(joint);
  model.settings.sleep.enabled = false;
  return model;
}

TEST(LagrangeJointTypes, HingedRodSwingsInItsPlaneWithTheExactSpeedAtTheBottom) {
  // A rod hinged about y at its end, released horizontally: it stays in the x–z plane, turns
  // only about y, and passes the bottom with ω² = 3g/L·(1 + O(r²/L²)) (energy: ½·(mL²/3)·ω² = mgL/2).
  const double length = 1, g = 9.81;
  const Model model = rod_on(JointType::revolute, Vector3::UnitY(), length);
  LagrangeState state = compile_lagrange(model, {.integrator = Integrator::rk4, .stabilization = Stabilization::projection});
  const double dt = 1e-3;
  double fastest = 0;
  for (int s = 0; s < 1000; ++s) {
    step(state, dt);
    const Eigen::Vector3d omega = state.bodies.angular_velocity(state.bodies.state, 0);
    EXPECT_LT(omega.cross(Eigen::Vector3d::UnitY()).norm(), 1e-7 * (1 + omega.norm())) << s;
    EXPECT_LT(std::abs(state.bodies.state.position[0].y()), 1e-9) << s;
    fastest = std::max(fastest, omega.norm());
  }
  const double inertia = length * length / 3 + 0.001 * 0.001 / 4;  // about the end, per kg
  EXPECT_NEAR(fastest, std::sqrt(g * length / inertia), 1e-3 * std::sqrt(3 * g / length));
  EXPECT_LT(state.last_report.constraint_error, 1e-9);
  EXPECT_LT(state.last_report.angular_error, 1e-9);
}

TEST(LagrangeJointTypes, PrismaticJointSlidesWithoutTurning) {
  // On a slide tilted 30° below horizontal the rod accelerates at g·sin 30° along it and keeps
  // its orientation, whatever it is spun with.
  const Vector3 axis(std::cos(std::numbers::pi / 6), 0, -std::sin(std::numbers::pi / 6));
  Model model = rod_on(JointType::prismatic, axis);
  model.bodies[0].angular_velocity = Vector3(0.3, -1, 2);  // projected away
  LagrangeState state = compile_lagrange(model, {.integrator = Integrator::rk4, .stabilization = Stabilization::projection});
  const Eigen::Quaterniond start_orientation = state.bodies.state.orientation[0];
  const Eigen::Vector3d start = state.bodies.state.position[0];
  const double dt = 1e-3, duration = 0.5;
  for (int s = 0; s < 500; ++s) step(state, dt);
  const Eigen::Vector3d travelled = state.bodies.state.position[0] - start;
  EXPECT_NEAR(travelled.dot(axis), 0.5 * 9.81 * 0.5 * duration * duration, 1e-6);
  EXPECT_LT(travelled.cross(axis).norm(), 1e-9);
  EXPECT_LT(start_orientation.angularDistance(state.bodies.state.orientation[0]), 1e-9);
}

TEST(LagrangeJointTypes, UniversalJointAllowsNoTwist) {
  // A rod hanging from a Cardan joint (axes x and y, both across the rod): spinning it about its
  // own axis (z) is impossible, swinging is not; the two axes stay perpendicular.
  Model model = rod_on(JointType::universal, Vector3::UnitX());
  model.joints[0].second_axis = Vector3::UnitY();
  model.bodies[0].axis = Vector3::UnitZ();  // hanging below the anchor, head up
  model.bodies[0].position = Vector3(0, 0, -0.5);
  model.bodies[0].angular_velocity = Vector3(1, 0.5, 4);  // the 4 rad/s of twist are removed
  LagrangeState state = compile_lagrange(model, {.stabilization = Stabilization::projection});
  for (int s = 0; s < 2000; ++s) {
    step(state, 1.0 / 240);
    const RigidBodyState& y = state.bodies.state;
    // The twist axis is perpendicular to both joint axes: the world x and the rod's own y.
    const Eigen::Vector3d second = y.orientation[0] * state.constraints.rows[0].outboard_direction[0];
    const Eigen::Vector3d twist_axis = Eigen::Vector3d::UnitX().cross(second).normalized();
    EXPECT_LT(std::abs(state.bodies.angular_velocity(y, 0).dot(twist_axis)), 1e-8) << s;
    EXPECT_LT(state.last_report.angular_error, 1e-9) << s;
  }
}

TEST(LagrangeJointTypes, FixedJointsWeldLimbs) {
  // A rod welded to the world does not fall; two rods welded to each other and hung from a
  // spherical joint swing as one rigid body (their relative pose never changes).
  LagrangeState welded = compile_lagrange(rod_on(JointType::fixed, Vector3::UnitX()));
  const RigidBodyState start = welded.bodies.state;
  for (int s = 0; s < 480; ++s) step(welded, 1.0 / 240);
  EXPECT_LT((welded.bodies.state.position[0] - start.position[0]).norm(), 1e-9);
  EXPECT_LT(welded.bodies.state.orientation[0].angularDistance(start.orientation[0]), 1e-9);

  Model pair = testing::make_chain({1, 2}, 0.5, true);
  pair.joints[1].type = JointType::fixed;
  pair.bodies[1].angular_velocity = Vector3(0, 0, 3);  // a bend is removed at the first step
  LagrangeState state = compile_lagrange(pair, {.stabilization = Stabilization::projection});
  const Eigen::Quaterniond relative = state.bodies.state.orientation[0].conjugate() * state.bodies.state.orientation[1];
  for (int s = 0; s < 960; ++s) step(state, 1.0 / 240);
  const RigidBodyState& y = state.bodies.state;
  EXPECT_LT((y.orientation[0].conjugate() * y.orientation[1]).angularDistance(relative), 1e-8);
  EXPECT_LT(state.last_report.constraint_error, 1e-9);
  EXPECT_GT(state.bodies.angular_velocity(y, 0).norm(), 0.1);  // it did swing
}

// Two disks on axles along y (revolute joints to the world), meshed with `ratio`; the first
// carries a 1 kg lump off its axle, so gravity turns it and, through the gear, the second.
Model geared_disks(double ratio) {
  Model model;
  model.name = "gears";
  for (int k = 0; k < 2; ++k) {
    Body disk;
    disk.name = k == 0 ? "large" : "small";
    const double radius = k == 0 ? 0.2 : 0.1;
    disk.shape = {ShapeType::cylinder, 0.02, radius};
    disk.axis = Vector3::UnitY();
    disk.position = Vector3(k == 0 ? 0 : 0.3, 0, 1);
    disk.mass = k == 0 ? 3 : 1;
    if (k == 0) {  // the disk's own mass at its centre, plus the lump on its rim (body frame: z is the axle)
      disk.point_masses = {{Vector3::Zero(), 2, radius}, {Vector3(radius, 0, 0), 1, 0}};
    }
    model.bodies.push_back(disk);
    Joint axle = spherical_joint(std::string("axle_") + disk.name, kWorld, k, disk.position, Vector3::Zero());
    axle.type = JointType::revolute;
    axle.axis = Vector3::UnitY();
    model.joints.push_back(axle);
  }
  model.gears.push_back({.name = "mesh", .first = 0, .second = 1, .first_axis = Vector3::UnitY(),
                         .second_axis = Vector3::UnitY(), .ratio = ratio});
  model.settings.sleep.enabled = false;
  return model;
}

TEST(LagrangeGears, MeshedGearsKeepTheirSpeedRatio) {
  const double ratio = -2;  // the small gear (half the radius) turns twice as fast, the other way
  for (Integrator integrator : {Integrator::semi_implicit_euler, Integrator::rk4}) {
    LagrangeState state = compile_lagrange(geared_disks(ratio), {.integrator = integrator});
    EXPECT_FALSE(state.uses_tree);  // the gear closes a loop through the world
    for (int s = 0; s < 480; ++s) {
      step(state, 1.0 / 240);
      const RigidBodyState& y = state.bodies.state;
      const double first = state.bodies.angular_velocity(y, 0).y(), second = state.bodies.angular_velocity(y, 1).y();
      // The velocity-level step holds J·u = 0 exactly; RK4 at the acceleration level drifts by
      // its truncation error only.
      const double bound = integrator == Integrator::semi_implicit_euler ? 1e-9 : 1e-5;
      EXPECT_NEAR(second, ratio * first, bound * (1 + std::abs(second))) << s;
    }
    EXPECT_GT(std::abs(state.bodies.angular_velocity(state.bodies.state, 0).y()), 1);  // it turned
  }
}

TEST(LagrangeGears, IdealGearsDoNoWork) {
  // Energy is conserved (to RK4's accuracy): the gear's force only passes power from one disk to the other.
  LagrangeState state = compile_lagrange(geared_disks(-2), {.integrator = Integrator::rk4});
  const double start = observe(state).energy();
  for (int s = 0; s < 1000; ++s) step(state, 1e-3);
  EXPECT_LT(std::abs(observe(state).energy() - start), 1e-4 * 9.81 * 0.2);  // of the lump's mg·r
}

TEST(LagrangeGears, TheTreeSolverRefusesAGearThatClosesALoop) {
  try {
    compile_lagrange(geared_disks(-2), {.solver = MultiplierSolver::tree});
    ADD_FAILURE() << "compiled";
  } catch (const ModelError& error) {
    // The loop is axle, gear, axle through the world; the message names the constraint that closed it.
    EXPECT_NE(std::string(error.what()).find("closes a loop"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace limber
