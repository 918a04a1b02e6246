// The stiff-spring method (thesis 3.3, 4.4.1): stability of its explicit and implicit
// integrators on one spring, the weight each joint's spring carries in a hanging chain, and the
// conservation laws the springs must keep.
#include <cmath>
#include <complex>

#include <gtest/gtest.h>

#include "limber/kernel/mass/mass_properties.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/springs/compile.hpp"
#include "limber/kernel/springs/spring_forces.hpp"
#include "limber/kernel/springs/step.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

constexpr double kMass = 2.0;  // kg

// One limb hanging from the world by a spring at its centre of mass (no lever, so no rotation):
// the mass-spring oscillator m ẍ = −k x − c ẋ, started 0.1 m from rest, no gravity.
Model single_spring() {
  Model model;
  model.name = "single_spring";
  Body body;
  body.name = "mass";
  body.shape = {ShapeType::capsule, 0.1, 0.02};
  body.mass = kMass;
  body.position = Vector3(0.1, 0, 0);
  model.bodies.push_back(body);
  model.joints.push_back(spherical_joint("spring", kWorld, 0, Vector3::Zero(), Vector3::Zero()));
  model.settings.gravity.setZero();
  model.settings.sleep.enabled = false;
  model.settings.divergence_speed = 1e300;
  return model;
}

// Largest |x| over `steps` steps, relative to the start.
double largest_excursion(const Model& model, SpringOptions options, double h, int steps) {
  SpringState state = compile_springs(model, options);
  double largest = 0;
  for (int k = 0; k < steps; ++k) {
    step(state, h);
    const double x = state.bodies.state.position[0].norm() / 0.1;
    if (!std::isfinite(x)) return INFINITY;
    largest = std::max(largest, x);
  }
  return largest;
}

// Forward Euler on ẏ = λ y multiplies y by 1 + hλ each step, so it is stable while |1 + hλ| ≤ 1
// for every eigenvalue λ (eq. 3.13–3.15: h·k < 2 for ẏ = −k y). The damped oscillator's
// eigenvalues are λ = (−c ± √(c² − 4km)) / 2m; this is the largest stable h.
double forward_euler_bound(double k, double c) {
  const std::complex<double> root = std::sqrt(std::complex<double>(c * c - 4 * k * kMass));
  double bound = INFINITY;
  for (const std::complex<double> lambda : {(-c + root) / (2 * kMass), (-c - root) / (2 * kMass)}) {
    bound = std::min(bound, -2 * lambda.real() / std::norm(lambda));  // |1 + hλ| = 1
  }
  return bound;
}

TEST(SpringStability, ForwardEulerIsStableExactlyBelowItsBound) {
  const Model model = single_spring();
  for (const double k : {1e2, 1e4, 1e6}) {
    for (const double damping_ratio : {0.05, 0.5, 2.0}) {
      const double c = damping_ratio * 2 * std::sqrt(k * kMass);
      const double bound = forward_euler_bound(k, c);
      const SpringOptions options{.integrator = Integrator::euler, .stiffness = k, .damping = c};
      // Enough steps for the unstable run's growth, |1 + hλ| per step, to reach 100×.
      double growth = 1;
      const std::complex<double> root = std::sqrt(std::complex<double>(c * c - 4 * k * kMass));
      for (const std::complex<double> lambda : {(-c + root) / (2 * kMass), (-c - root) / (2 * kMass)}) {
        growth = std::max(growth, std::abs(1.0 + 1.1 * bound * lambda));
      }
      const int steps = static_cast<int>(std::log(100.0) / std::log(growth)) + 10;
      EXPECT_LE(largest_excursion(model, options, 0.9 * bound, steps), 1.0 + 1e-9) << "k " << k << ", c " << c;
      EXPECT_GT(largest_excursion(model, options, 1.1 * bound, steps), 10.0) << "k " << k << ", c " << c;
    }
  }
}

TEST(SpringStability, UndampedForwardEulerAlwaysGainsEnergy) {
  // With c = 0 the eigenvalues ±iω give |1 + hλ| = √(1 + h²ω²) > 1 for every h: the thesis's
  // springs needed their damping.
  const SpringOptions options{.integrator = Integrator::euler, .stiffness = 1e3, .damping = 0.0};
  EXPECT_GT(largest_excursion(single_spring(), options, 1e-3, 20000), 1.1);
}

TEST(SpringStability, SemiImplicitEulerIsStableExactlyBelowTwoOverOmega) {
  const Model model = single_spring();
  for (const double k : {1e2, 1e4, 1e6}) {
    const double bound = 2 / std::sqrt(k / kMass);  // h·ω < 2
    const SpringOptions options{.integrator = Integrator::semi_implicit_euler, .stiffness = k, .damping = 0.0};
    EXPECT_LT(largest_excursion(model, options, 0.95 * bound, 2000), 10.0) << "k " << k;
    EXPECT_GT(largest_excursion(model, options, 1.05 * bound, 2000), 1e3) << "k " << k;
  }
}

TEST(SpringStability, BackwardEulerIsStableForEveryStiffness) {
  const Model model = single_spring();
  const double h = 1e-2;
  for (const double factor : {1.0, 1e2, 1e4, 1e6}) {
    // k such that h is `factor` times the symplectic Euler bound, i.e. h·ω = 2·factor.
    const double omega = 2 * factor / h, k = omega * omega * kMass;
    for (SpringLinearSolver solver : {SpringLinearSolver::ldlt, SpringLinearSolver::conjugate_gradient}) {
      const SpringOptions options{.integrator = Integrator::backward_euler, .linear_solver = solver, .stiffness = k, .damping = 0.0};
      EXPECT_LE(largest_excursion(model, options, h, 500), 1.0 + 1e-9) << "h·ω = " << h * omega << ", solver " << static_cast<int>(solver);
    }
  }
}

TEST(SpringStability, BackwardEulerReachesTheAnchorInOneStepAsTheStepGrows) {  // eq. 3.25
  const Model model = single_spring();
  double previous = INFINITY;
  for (const double h : {1e-2, 1e0, 1e2}) {
    SpringState state = compile_springs(model, {.integrator = Integrator::backward_euler, .stiffness = 1e3, .damping = 0.0});
    step(state, h);
    const double remaining = state.bodies.state.position[0].norm() / 0.1;
    EXPECT_LT(remaining, previous) << "h " << h;
    previous = remaining;
  }
  EXPECT_LT(previous, 1e-6);
}

// The thesis's 5-link chain, the bottom link twice as heavy, hanging straight down.
Model hanging_chain() {
  Model model = testing::make_chain({1, 1, 1, 1, 2}, 0.1, true, Vector3(0, 0, 1));
  for (Body& body : model.bodies) body.axis = Vector3::UnitZ();
  for (std::size_t k = 0; k < model.bodies.size(); ++k) model.bodies[k].position = Vector3(0, 0, 1 - (k + 0.5) * 0.1);
  return model;
}

TEST(SpringChain, EachJointStretchesByTheWeightItCarries) {
  // At rest each spring holds the links below it: |d_i| = g Σ_{j ≥ i} m_j / k, so the top
  // joint opens most (the thesis's observation, 4.4.1).
  const Model model = hanging_chain();
  const double k = 2e4;
  for (Integrator integrator : {Integrator::semi_implicit_euler, Integrator::backward_euler}) {
    // c = 300 N·s/m damps the slowest mode (ω ≈ 33 rad/s) at (c/k)·ω²/2 ≈ 8 /s: at rest after 3 s.
    SpringState state = compile_springs(model, {.integrator = integrator, .stiffness = k, .damping = 300.0});
    for (int s = 0; s < 3000; ++s) ASSERT_EQ(step(state, 1e-3).status, StepStatus::ok);
    double carried = 0;
    for (std::size_t j = model.joints.size(); j-- > 0;) {
      carried += model.bodies[j].mass;
      const double gap = (joint_separation(state.springs, state.bodies.state, j)).norm();
      EXPECT_NEAR(gap, 9.81 * carried / k, 1e-3 * 9.81 * carried / k) << "joint " << j;
    }
  }
}

TEST(SpringChain, FreeFloatingSpringsKeepLinearMomentum) {
  Model model = testing::make_chain({1, 3, 0.5, 2}, 0.2, false);
  model.settings.gravity.setZero();
  for (std::size_t k = 0; k < model.bodies.size(); ++k) {
    model.bodies[k].linear_velocity = Vector3(0.3 * k, -0.2, 0.1 * k * k);
    model.bodies[k].angular_velocity = Vector3(1, -2.0 * k, 0.5);
  }
  for (Integrator integrator : {Integrator::euler, Integrator::semi_implicit_euler, Integrator::rk4,
                                      Integrator::backward_euler}) {
    SpringState state = compile_springs(model, {.integrator = integrator, .stiffness = 1e3, .damping = 1.0});
    const Eigen::Vector3d start = observe(state).linear_momentum;
    for (int s = 0; s < 500; ++s) step(state, 1e-3);
    EXPECT_LT((observe(state).linear_momentum - start).norm(), 1e-11 * (1 + start.norm())) << integrator_name(integrator);
  }
}

TEST(SpringChain, UndampedSpringsKeepEnergyWithRungeKutta) {
  Model model = testing::make_chain({1, 1, 1, 2}, 0.2, true);
  model.settings.damping = 0;
  SpringState state = compile_springs(model, {.integrator = Integrator::rk4, .stiffness = 1e3, .damping = 0.0});
  const double start = observe(state).energy();
  for (int s = 0; s < 2000; ++s) step(state, 5e-4);
  EXPECT_NEAR(observe(state).energy(), start, 1e-6 * std::abs(start) + 1e-6);
}

}  // namespace
}  // namespace limber

namespace limber {
namespace {

Model ball_over_ground(double restitution) {
  Model model;
  model.name = "ball_drop";
  model.ground = Ground{0.0, 0.0, 0.5};
  model.balls = {Ball{0.1, 2.0, restitution, Vector3(0, 0, 1.1), Vector3::Zero()}};
  model.settings.sleep.enabled = false;
  return model;
}

TEST(SpringContacts, BallLeavesTheGroundWithItsRestitution) {  // eq. 2.32
  for (const double restitution : {0.2, 0.5, 0.9}) {
    SpringState state = compile_springs(ball_over_ground(restitution), {.integrator = Integrator::semi_implicit_euler});
    double impact_speed = 0, rebound_speed = 0;
    for (int s = 0; s < 600 && rebound_speed == 0; ++s) {
      const double before = state.bodies.state.linear_momentum[0].z() / 2.0;
      step(state, 1e-3);
      const double after = state.bodies.state.linear_momentum[0].z() / 2.0;
      if (before < 0 && after > 0) impact_speed = -before, rebound_speed = after;
    }
    ASSERT_GT(impact_speed, 4.0);
    EXPECT_NEAR(rebound_speed / impact_speed, restitution, 0.01) << "e " << restitution;
  }
}

TEST(SpringContacts, LimbLyingOnTheGroundStaysAtRest) {
  for (ShapeType shape : {ShapeType::cylinder, ShapeType::capsule}) {
    Model model;
    model.name = "lying_limb";
    model.ground = Ground{0.0, 0.3, 0.8};
    Body body;
    body.name = "limb";
    body.shape = {shape, 0.4, 0.05};
    body.mass = 3;
    body.axis = Vector3(1, 0, 0);
    body.position = Vector3(0, 0, 0.05);
    model.bodies.push_back(body);
    model.settings.sleep.enabled = false;
    for (Integrator integrator : {Integrator::semi_implicit_euler, Integrator::backward_euler}) {
      SpringState state = compile_springs(model, {.integrator = integrator});
      const double start = observe(state).energy();
      for (int s = 0; s < 1000; ++s) ASSERT_EQ(step(state, 1.0 / 240).status, StepStatus::ok);
      const Observation end = observe(state);
      EXPECT_LT(std::abs(end.body_centre_of_mass.z() - 0.05), 2e-3) << "sinks or lifts";
      EXPECT_LT((end.body_centre_of_mass.head<2>()).norm(), 1e-3) << "slides";
      EXPECT_LT(end.energy(), start + 1e-3) << "gains energy";
    }
  }
}

}  // namespace
}  // namespace limber

namespace limber {
namespace {

// One uniform rod hanging from the world at its head, released 5° from vertical.
Model hanging_rod() {
  Model model;
  model.name = "rod_pendulum";
  Body rod;
  rod.name = "rod";
  rod.shape = {ShapeType::capsule, 1.0, 0.01};
  rod.mass = 1;
  const double angle = 5 * 3.14159265358979 / 180;
  rod.axis = Vector3(-std::sin(angle), 0, std::cos(angle));  // tail → head points up to the pivot
  rod.position = Vector3(0, 0, 2) - 0.5 * rod.axis;
  model.bodies.push_back(rod);
  model.joints.push_back(spherical_joint("pivot", kWorld, 0, Vector3(0, 0, 2), Vector3(0, 0, 0.5)));
  model.settings.sleep.enabled = false;
  model.settings.time_step = 1e-3;
  return model;
}

// Period from the first two upward zero crossings of the centre of mass's x, s.
template <typename Advance, typename CentreX>
double period(Advance&& advance, CentreX&& centre_x, double dt) {
  double previous = centre_x(), time = 0, first = -1;
  for (int s = 0; s < 10000; ++s) {
    advance();
    time += dt;
    const double x = centre_x();
    if (previous < 0 && x >= 0) {
      const double crossing = time - dt * x / (x - previous);
      if (first >= 0) return crossing - first;
      first = crossing;
    }
    previous = x;
  }
  return INFINITY;
}

TEST(SpringAgreement, RigidRodOnAStiffSpringSwingsLikeThePhysicalPendulumAndTheInertiaParticles) {
  // The rigid-body and particle models of one limb agree: the rod on a stiff spring, and the
  // Verlet rod whose three particles keep its inertia (LimbMasses::inertia), both swing with the
  // physical pendulum's period 2π √(I_pivot / (m g L/2)), I_pivot from body_mass_properties
  // (the capsule's caps add 0.7 % to m L²/3).
  const Model model = hanging_rod();
  const MassProperties rod = body_mass_properties(model.bodies[0]);
  const double inertia_about_pivot = rod.inertia(0, 0) + rod.mass * 0.25;
  // The 5° amplitude lengthens the period by θ²/16.
  const double amplitude = 5 * 3.14159265358979 / 180;
  const double expected = 2 * 3.14159265358979 * std::sqrt(inertia_about_pivot / (9.81 * 0.5)) * (1 + amplitude * amplitude / 16);

  SpringState springs = compile_springs(model, {.integrator = Integrator::backward_euler, .stiffness = 1e7, .damping = 0.0});
  const double spring_period = period([&] { step(springs, 1e-3); }, [&] { return observe(springs).body_centre_of_mass.x(); }, 1e-3);
  EXPECT_NEAR(spring_period, expected, 1e-3 * expected);

  VerletOptions options;
  options.verlet.limb_masses = LimbMasses::inertia;
  options.relaxation.iterations = 50;
  VerletState<double> verlet = compile<double>(model, options);
  const double verlet_period = period([&] { step(verlet); }, [&] { return observe(verlet).body_centre_of_mass.x(); }, 1e-3);
  EXPECT_NEAR(verlet_period, spring_period, 1e-3 * expected);
}

}  // namespace
}  // namespace limber

namespace limber {
namespace {

TEST(SpringDrag, DragActsInTheLimbsOwnFrame) {  // thesis 2.1.5, 2.1.6
  // A free limb lying along x, no gravity, drag only across its axis: moving along its axis it
  // keeps its speed; moving across it, its speed decays as exp(−c t / m).
  for (const bool along : {true, false}) {
    Model model;
    model.name = "drag";
    Body body;
    body.name = "limb";
    body.shape = {ShapeType::capsule, 0.5, 0.02};
    body.mass = 2;
    body.axis = Vector3::UnitX();
    body.linear_velocity = along ? Vector3(3, 0, 0) : Vector3(0, 3, 0);
    model.bodies.push_back(body);
    model.settings.gravity.setZero();
    model.settings.sleep.enabled = false;
    model.settings.drag.linear = Vector3(4, 4, 0);  // N·s/m across the axis (body x, y), none along it (z)
    SpringState state = compile_springs(model, {.integrator = Integrator::rk4});
    for (int s = 0; s < 1000; ++s) step(state, 1e-3);
    const double speed = state.bodies.state.linear_momentum[0].norm() / 2;
    EXPECT_NEAR(speed, along ? 3.0 : 3.0 * std::exp(-4.0 * 1.0 / 2.0), 1e-6) << (along ? "along" : "across");
  }
}

}  // namespace
}  // namespace limber
