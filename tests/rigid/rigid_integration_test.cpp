// Rigid-body integration (thesis 2.2): a torque-free body keeps its angular momentum exactly
// (the state carries L), and its motion converges at the integrator's order.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>

#include "limber/kernel/rigid/rigid_integration.hpp"

namespace limber {
namespace {

// An asymmetric body (principal moments 1, 2, 3 kg·m², turned off the world axes) spinning
// mostly about its unstable intermediate axis: the hardest free motion to integrate.
RigidBodyBuffer spinning_body() {
  RigidBodyBuffer bodies;
  bodies.resize(1);
  bodies.mass[0] = 2, bodies.inverse_mass[0] = 0.5;
  bodies.body_inertia[0] = Eigen::Vector3d(1, 2, 3).asDiagonal();
  bodies.body_inverse_inertia[0] = bodies.body_inertia[0].inverse();
  bodies.state.orientation[0] = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()));
  bodies.state.linear_momentum[0] = Eigen::Vector3d(0.2, 0, 0);
  const Eigen::Vector3d omega(0.1, 3, 0.2);
  bodies.state.angular_momentum[0] = bodies.world_inertia(bodies.state, 0) * omega;
  return bodies;
}

double rotational_energy(const RigidBodyBuffer& bodies) {
  return 0.5 * bodies.angular_velocity(bodies.state, 0).dot(bodies.state.angular_momentum[0]);
}

// The body after 1 s of free motion with step h.
RigidBodyBuffer spin(Integrator integrator, double h) {
  RigidBodyBuffer bodies = spinning_body();
  RigidIntegratorScratch scratch;
  scratch.resize(1);
  const int steps = static_cast<int>(std::lround(1.0 / h));
  for (int k = 0; k < steps; ++k) {
    integrate_rigid_bodies(bodies, h, integrator, scratch, [](const RigidBodyState&, RigidForces&) {});
  }
  EXPECT_NEAR(bodies.state.orientation[0].norm(), 1.0, 1e-14);
  return bodies;
}

// Angle between the orientation after 1 s and a converged reference (RK4, h = 1e-4), rad.
double orientation_error(Integrator integrator, double h) {
  static const Eigen::Quaterniond reference = spin(Integrator::rk4, 1e-4).state.orientation[0];
  return spin(integrator, h).state.orientation[0].angularDistance(reference);
}

double energy_error(Integrator integrator, double h) {
  return std::abs(rotational_energy(spin(integrator, h)) - rotational_energy(spinning_body()));
}

TEST(RigidIntegration, FreeBodyKeepsItsAngularMomentumExactly) {
  const Eigen::Vector3d start = spinning_body().state.angular_momentum[0];
  for (Integrator integrator : {Integrator::euler, Integrator::semi_implicit_euler, Integrator::rk2, Integrator::rk4}) {
    const Eigen::Vector3d end = spin(integrator, 1e-3).state.angular_momentum[0];
    EXPECT_LT((end - start).norm(), 1e-13 * start.norm()) << integrator_name(integrator);
  }
}

TEST(RigidIntegration, FreeBodyConvergesAtTheIntegratorsOrder) {
  // Halving h divides the orientation error by 2^order; the energy error shrinks with it.
  struct Case { Integrator integrator; int order; double h; };
  // Without torque the semi-implicit step is the free-rotation splitting alone: second order.
  for (const Case& c : {Case{Integrator::euler, 1, 1e-3}, Case{Integrator::semi_implicit_euler, 2, 4e-3},
                        Case{Integrator::rk2, 2, 4e-3}, Case{Integrator::rk4, 4, 2e-2}}) {
    const double coarse = orientation_error(c.integrator, c.h), fine = orientation_error(c.integrator, c.h / 2);
    EXPECT_NEAR(std::log2(coarse / fine), c.order, 0.3) << "integrator " << static_cast<int>(c.integrator) << ": errors " << coarse << ", " << fine;
    EXPECT_LT(energy_error(c.integrator, c.h / 2), energy_error(c.integrator, c.h));
    EXPECT_LT(energy_error(c.integrator, c.h / 2), 1e-2 * rotational_energy(spinning_body()));
  }
}

TEST(RigidIntegration, ThinSpinningRodStaysStableWithTheSemiImplicitStep) {
  // A thin rod (axial moment 10⁻³ of the transverse ones) tumbling and spinning with h·|ω| ≈ 0.5:
  // advancing q with ω = I⁻¹L explicitly spins it up without bound; the free-rotation flow
  // keeps its energy within a few per cent.
  RigidBodyBuffer bodies;
  bodies.resize(1);
  bodies.mass[0] = 1, bodies.inverse_mass[0] = 1;
  bodies.body_inertia[0] = Eigen::Vector3d(0.1, 0.1, 1e-4).asDiagonal();
  bodies.body_inverse_inertia[0] = bodies.body_inertia[0].inverse();
  bodies.state.angular_momentum[0] = bodies.world_inertia(bodies.state, 0) * Eigen::Vector3d(30, 10, 100);
  const double start = rotational_energy(bodies);
  RigidIntegratorScratch scratch;
  scratch.resize(1);
  double largest = start;
  for (int k = 0; k < 10000; ++k) {
    integrate_rigid_bodies(bodies, 5e-3, Integrator::semi_implicit_euler, scratch, [](const RigidBodyState&, RigidForces&) {});
    largest = std::max(largest, rotational_energy(bodies));
  }
  EXPECT_LT(largest, 1.05 * start);
}

// A limb of zero radius as the rigid scene makes it: axial moment 10⁻⁶ of the transverse ones,
// tumbling at 5 rad/s with a spin of `spin` rad/s about its axis, turned off the world axes.
RigidBodyBuffer thin_rod(double spin) {
  RigidBodyBuffer bodies;
  bodies.resize(1);
  bodies.mass[0] = 1, bodies.inverse_mass[0] = 1;
  bodies.body_inertia[0] = Eigen::Vector3d(1e-3, 1e-3, 1e-9).asDiagonal();
  bodies.body_inverse_inertia[0] = bodies.body_inertia[0].inverse();
  bodies.state.orientation[0] = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized()));
  const Eigen::Vector3d omega = bodies.state.orientation[0] * Eigen::Vector3d(4, 3, spin);  // world
  bodies.state.angular_momentum[0] = bodies.world_inertia(bodies.state, 0) * omega;
  return bodies;
}

TEST(RigidIntegration, SymmetricLimbTurnsExactlyWithTheSemiImplicitStepAtAnyStep) {
  // A symmetric body's free motion is a turn about L by |L|·t/I₁ and about its own axis by
  // L_z·t·(1/I_z − 1/I₁) (Landau & Lifshitz §33). The free-rotation flow must give it at a step
  // where the axial turn is 200 rad (h·ω_z): splitting about the three axes turned the axis itself.
  const RigidBodyBuffer start = thin_rod(2000);
  const Eigen::Vector3d momentum = start.state.angular_momentum[0];
  const double transverse = 1e-3, axial_moment = 1e-9, time = 1.0;
  const double axial = (start.state.orientation[0].conjugate() * momentum).z();
  const Eigen::Quaterniond about_momentum(Eigen::AngleAxisd(momentum.norm() * time / transverse, momentum.normalized()));
  const double axial_turn = axial * time * (1 / axial_moment - 1 / transverse);
  const Eigen::Quaterniond about_axis(Eigen::AngleAxisd(axial_turn, Eigen::Vector3d::UnitZ()));
  const Eigen::Quaterniond exact = about_momentum * start.state.orientation[0] * about_axis;
  RigidBodyBuffer bodies = start;
  RigidIntegratorScratch scratch;
  scratch.resize(1);
  for (int k = 0; k < 10; ++k) {
    integrate_rigid_bodies(bodies, 0.1, Integrator::semi_implicit_euler, scratch, [](const RigidBodyState&, RigidForces&) {});
  }
  // The axial turn (2000 rad over the run) loses digits to rounding; the axis must not.
  const Eigen::Vector3d axis = bodies.state.orientation[0] * Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d exact_axis = exact * Eigen::Vector3d::UnitZ();
  EXPECT_LT((axis - exact_axis).norm(), 1e-9);
  EXPECT_NEAR(momentum.dot(axis), axial, 1e-12 * momentum.norm());
}

TEST(RigidIntegration, RungeKuttaKeepsAThinLimbsAxialMomentum) {
  // The world L and q advance apart; L·a (the momentum about the limb's axis) must still stay as
  // it started, or ω_axial = L·a/I_z, 10⁶ times its error, spins the limb up until it diverges.
  for (Integrator integrator : {Integrator::rk2, Integrator::rk4}) {
    RigidBodyBuffer bodies = thin_rod(2);
    const Eigen::Vector3d momentum = bodies.state.angular_momentum[0];
    const double axial = (bodies.state.orientation[0].conjugate() * momentum).z();
    RigidIntegratorScratch scratch;
    scratch.resize(1);
    for (int k = 0; k < 1000; ++k) {
      integrate_rigid_bodies(bodies, 1e-3, integrator, scratch, [](const RigidBodyState&, RigidForces&) {});
    }
    const Eigen::Vector3d axis = bodies.state.orientation[0] * Eigen::Vector3d::UnitZ();
    EXPECT_NEAR(momentum.dot(axis), axial, 1e-3 * std::abs(axial)) << integrator_name(integrator);
    EXPECT_LT((bodies.state.angular_momentum[0] - momentum).norm(), 1e-13 * momentum.norm()) << integrator_name(integrator);
  }
}

TEST(RigidIntegration, ConstantForceGivesTheParabolaExactlyWithRungeKutta) {
  for (Integrator integrator : {Integrator::rk2, Integrator::rk4}) {
    RigidBodyBuffer bodies = spinning_body();
    const Eigen::Vector3d x0 = bodies.state.position[0], v0 = bodies.linear_velocity(bodies.state, 0), g(0, 0, -9.81);
    RigidIntegratorScratch scratch;
    scratch.resize(1);
    for (int k = 0; k < 100; ++k) {
      integrate_rigid_bodies(bodies, 0.01, integrator, scratch,
                             [&](const RigidBodyState&, RigidForces& forces) { forces.force[0] += bodies.mass[0] * g; });
    }
    const Eigen::Vector3d exact = x0 + v0 + 0.5 * g;
    EXPECT_LT((bodies.state.position[0] - exact).norm(), 1e-12);
  }
}

}  // namespace
}  // namespace limber
