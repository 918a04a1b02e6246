// The Lagrange-multiplier method (thesis 3.1.4, 3.4, 4.2.1): the multipliers are the joint
// forces, the joints stay closed, and energy and momentum are kept to the integrator's accuracy.
// (Joint types, gears and the tree solve against the sparse one: lagrange_joint_types_test.cpp.)

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "limber/kernel/lagrange/compile.hpp"
#include "limber/kernel/lagrange/multipliers.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/scene/generators.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

// The thesis's 5-link chain, the bottom link twice as heavy, hanging straight down at rest.
Model hanging_chain() {
  Model model = testing::make_chain({1, 1, 1, 1, 2}, 0.1, true, Vector3(0, 0, 1));
  for (std::size_t k = 0; k < model.bodies.size(); ++k) {
    model.bodies[k].axis = Vector3::UnitZ();
    model.bodies[k].position = Vector3(0, 0, 1 - (k + 0.5) * 0.1);
  }
  return model;
}

// A random tree of `links` links with random masses, lengths and velocities.
Model random_tree(std::size_t links, std::size_t branching, unsigned seed) {
  Model model = make_tree_model({.links = links, .branching = branching});
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (Body& body : model.bodies) {
    body.mass = 0.5 + 2 * std::abs(unit(random));
    body.linear_velocity = Vector3(unit(random), unit(random), unit(random));
    body.angular_velocity = 3 * Vector3(unit(random), unit(random), unit(random));
  }
  model.settings.sleep.enabled = false;
  return model;
}

TEST(LagrangeMultipliers, EachJointCarriesTheWeightBelowIt) {
  // At rest the multiplier of joint j is the force holding up every link below it: exactly
  // g·Σ m, straight up on the outboard side (λ, on the inboard side, points down).
  const Model model = hanging_chain();
  for (MultiplierSolver solver : {MultiplierSolver::tree, MultiplierSolver::sparse}) {
    LagrangeState state = compile_lagrange(model, {.solver = solver});
    RigidForces forces;
    forces.resize(state.bodies.size());
    accumulate_constrained_forces(state, state.bodies.state, forces);
    double carried = 0;
    for (std::size_t j = model.joints.size(); j-- > 0;) {
      carried += model.bodies[j].mass;
      EXPECT_NEAR(state.multipliers[j].z(), -9.81 * carried, 1e-10 * 9.81 * carried) << "joint " << j;
      EXPECT_LT(state.multipliers[j].head<2>().norm(), 1e-10);
    }
    // Every body is then in equilibrium: no acceleration.
    for (std::size_t b = 0; b < state.bodies.size(); ++b) {
      EXPECT_LT(forces.force[b].norm(), 1e-9) << b;
      EXPECT_LT(forces.torque[b].norm(), 1e-9) << b;
    }
  }
}

TEST(LagrangeMultipliers, ConstrainedAccelerationsKeepTheJointsClosed) {
  // J·u̇ = −J̇·u: the acceleration of every joint's anchor gap is zero.
  const Model model = random_tree(25, 2, 7);
  LagrangeState state = compile_lagrange(model, {.stabilization = Stabilization::projection});
  RigidForces forces;
  forces.resize(state.bodies.size());
  accumulate_constrained_forces(state, state.bodies.state, forces);
  // Finite difference of Ċ over a tiny step of the exact ODE (RK4).
  const double h = 1e-6;
  auto gap_rate = [&](const LagrangeState& s, std::size_t j) {
    const JointAnchors& joints = s.joints;
    const RigidBodyState& y = s.bodies.state;
    const std::int32_t i = joints.inboard[j], o = joints.outboard[j];
    const Eigen::Vector3d r_o = y.orientation[o] * joints.outboard_anchor[j];
    Eigen::Vector3d rate = -(s.bodies.linear_velocity(y, o) + s.bodies.angular_velocity(y, o).cross(r_o));
    if (i >= 0) rate += s.bodies.linear_velocity(y, i) + s.bodies.angular_velocity(y, i).cross(y.orientation[i] * joints.inboard_anchor[j]);
    return rate;
  };
  LagrangeState later = state;
  later.options.stabilization = Stabilization::projection;
  integrate_rigid_bodies(later.bodies, h, Integrator::rk4, later.scratch,
                         [&later](const RigidBodyState& y, RigidForces& f) { accumulate_constrained_forces(later, y, f); });
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    EXPECT_LT((gap_rate(later, j) - gap_rate(state, j)).norm() / h, 1e-4) << "joint " << j;
  }
}

// The 5-link chain of chain.json released horizontally, stepped `steps` times; the largest
// joint error over the run, m.
double largest_error(const LagrangeOptions& options, int steps, double dt) {
  const Model model = testing::load_shipped_scene("chain.json");
  LagrangeState state = compile_lagrange(model, options);
  double largest = 0;
  for (int s = 0; s < steps; ++s) {
    const StepReport report = step(state, dt);
    EXPECT_EQ(report.status, StepStatus::ok);
    largest = std::max(largest, report.constraint_error);
  }
  return largest;
}

// Over 10⁴ steps (42 s) of the chaotic heavy-end chain, links 0.2 m long. Measured: projection
// 4.7·10⁻⁹ m, Baumgarte 5.8·10⁻³ m (symplectic Euler) and 3.2·10⁻⁴ m (RK4), at the end's whips.
TEST(LagrangeDrift, ProjectionHoldsTheJointsClosed) {
  EXPECT_LT(largest_error({.stabilization = Stabilization::projection}, 10000, 1.0 / 240), 1e-8);
}

TEST(LagrangeDrift, BaumgarteKeepsTheJointErrorBounded) {
  EXPECT_LT(largest_error({.integrator = Integrator::semi_implicit_euler, .stabilization = Stabilization::baumgarte},
                          10000, 1.0 / 240),
            1e-2);
  EXPECT_LT(largest_error({.integrator = Integrator::rk4, .stabilization = Stabilization::baumgarte}, 10000, 1.0 / 240), 1e-3);
}

// |energy change| over 1 s of the undamped pendulum chain with RK4 and step h, J.
double energy_drift(double h) {
  const Model model = testing::load_shipped_scene("chain.json");
  LagrangeState state = compile_lagrange(model, {.integrator = Integrator::rk4, .stabilization = Stabilization::baumgarte});
  const double start = observe(state).energy();
  for (int s = 0; s < std::lround(1.0 / h); ++s) step(state, h);
  return std::abs(observe(state).energy() - start);
}

TEST(LagrangeEnergy, PendulumChainKeepsItsEnergyWithRungeKutta) {
  const double coarse = energy_drift(1.0 / 240), fine = energy_drift(1.0 / 480);
  EXPECT_LT(fine, 1e-3);        // of about 200 J
  EXPECT_LT(fine, coarse / 4);  // at least second order (Baumgarte's terms are first order in C)
}

TEST(LagrangeMomentum, FreeTreeKeepsItsLinearMomentum) {
  Model model = random_tree(15, 2, 3);
  model.joints.erase(model.joints.begin());  // the pin: free-floating
  model.settings.gravity.setZero();
  for (Integrator integrator : {Integrator::semi_implicit_euler, Integrator::rk4}) {
    LagrangeState state = compile_lagrange(model, {.integrator = integrator});
    const Eigen::Vector3d start = observe(state).linear_momentum;
    for (int s = 0; s < 500; ++s) step(state, 1e-3);
    EXPECT_LT((observe(state).linear_momentum - start).norm(), 1e-9 * (1 + start.norm()));
  }
}

TEST(LagrangeGraphs, ALoopUsesTheSparseSolverAndTheTreeSolverRefusesIt) {
  Model model = testing::make_chain({1, 1, 1, 1}, 0.2, true);
  model.joints.push_back(spherical_joint("closing", 0, 3, Vector3(0, 0, 0.1), Vector3(0, 0, -0.1)));
  EXPECT_FALSE(compile_lagrange(model).uses_tree);
  try {
    compile_lagrange(model, {.solver = MultiplierSolver::tree});
    ADD_FAILURE() << "compiled";
  } catch (const ModelError& error) {
    EXPECT_NE(std::string(error.what()).find("'closing'"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace limber
