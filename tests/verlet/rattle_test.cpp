// The rattle projection rule (SHAKE positions along the start-of-substep gradients, then the
// RATTLE velocity stage) and substeps: the physical facts they promise — second order where
// pbd is first, energy kept, momentum and angular momentum kept to rounding, the same bits on
// every path — and the safeguard that falls back to pbd.
#include <cmath>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/study/run_metrics.hpp"
#include "limber/kernel/study/workloads.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

using testing::load_shipped_scene;
using testing::make_chain;

constexpr double kGravity = 9.81;

// A simple pendulum: a massless rod of `length` with a 1 kg point mass at its tail, pinned at the
// origin, released at rest horizontally along +x; compiled with limb_masses "lumps" and a
// shared-particle joint (pendulum_options).
Model simple_pendulum(double length) {
  Model model;
  model.name = "simple pendulum";
  Body rod;
  rod.name = "rod";
  rod.shape = {ShapeType::capsule, length, 0.001};
  rod.point_masses = {PointMass{Vector3(0, 0, -0.5 * length), 1.0, 0}};
  rod.mass = 1.0;
  rod.position = Vector3(0.5 * length, 0, 0);
  rod.axis = -Vector3::UnitX();
  model.bodies.push_back(rod);
  model.joints.push_back(spherical_joint("pin", kWorld, 0, Vector3::Zero(), Vector3(0, 0, 0.5 * length)));
  model.settings.sleep.enabled = false;
  return model;
}

// Options under `projection` in `substeps` substeps of `iterations` sweeps, with the particle
// settings `verlet` (the scene's).
VerletOptions relaxation_options(ProjectionRule projection, int substeps, int iterations, VerletSettings verlet = {}) {
  VerletOptions options;
  options.relaxation.projection = projection;
  options.relaxation.substeps = substeps;
  options.relaxation.iterations = iterations;
  options.verlet = verlet;
  return options;
}

// The known answer: θ'' = −(g/L)·sin θ from θ = π/2 at rest (θ from −z towards +x), by RK4 at
// interval/2000 (≈10⁻⁵ s) — an independent one-line ODE, not one of limber's methods. The bob's
// position every `interval` s up to `duration`.
std::vector<Eigen::Vector3d> pendulum_reference(double length, double duration, double interval) {
  const long per_sample = 2000, samples = std::lround(duration / interval);
  const double h = interval / per_sample;
  double theta = std::numbers::pi / 2, omega = 0;
  const auto acceleration = [&](double angle) { return -kGravity / length * std::sin(angle); };
  std::vector<Eigen::Vector3d> out{Eigen::Vector3d(length * std::sin(theta), 0, -length * std::cos(theta))};
  for (long s = 0; s < samples; ++s) {
    for (long k = 0; k < per_sample; ++k) {
      const double k1t = omega, k1w = acceleration(theta);
      const double k2t = omega + 0.5 * h * k1w, k2w = acceleration(theta + 0.5 * h * k1t);
      const double k3t = omega + 0.5 * h * k2w, k3w = acceleration(theta + 0.5 * h * k2t);
      const double k4t = omega + h * k3w, k4w = acceleration(theta + h * k3t);
      theta += h / 6 * (k1t + 2 * k2t + 2 * k3t + k4t);
      omega += h / 6 * (k1w + 2 * k2w + 2 * k3w + k4w);
    }
    out.emplace_back(length * std::sin(theta), 0, -length * std::cos(theta));
  }
  return out;
}

// Largest distance of the bob from the reference over the samples, m, for frames of 1/60 s split
// into `substeps`, relaxed to convergence.
double pendulum_error(ProjectionRule projection, int substeps, const std::vector<Eigen::Vector3d>& reference) {
  Model model = simple_pendulum(0.5);
  model.settings.time_step = 1.0 / 60;
  VerletOptions options = relaxation_options(projection, substeps, 50, {.joints = ParticleJoints::shared_particle, .limb_masses = LimbMasses::lumps, .drag_factor = {}});
  options.relaxation.tolerance = 1e-15;
  VerletState<double> state = compile<double>(model, options);
  const std::uint32_t bob = state.limbs.tail[0];
  double largest = 0;
  for (std::size_t frame = 1; frame < reference.size(); ++frame) {
    EXPECT_EQ(step(state).status, StepStatus::ok);
    largest = std::max(largest, (state.particles.position(bob) - reference[frame]).norm());
  }
  return largest;
}

TEST(Rattle, IsSecondOrderOnThePendulumWherePbdIsFirstOrder) {
  const std::vector<Eigen::Vector3d> reference = pendulum_reference(0.5, 1.0, 1.0 / 60);
  for (const ProjectionRule projection : {ProjectionRule::rattle, ProjectionRule::pbd}) {
    std::vector<double> errors;
    for (const int substeps : {8, 16, 32}) errors.push_back(pendulum_error(projection, substeps, reference));
    for (std::size_t k = 1; k < errors.size(); ++k) {
      const double ratio = errors[k - 1] / errors[k];  // per halving of the substep
      if (projection == ProjectionRule::rattle) {
        EXPECT_GT(ratio, 3.5) << "rattle: errors " << errors[k - 1] << " -> " << errors[k];
      } else {
        EXPECT_GT(ratio, 1.5) << "pbd: errors " << errors[k - 1] << " -> " << errors[k];
        EXPECT_LT(ratio, 2.5) << "pbd: errors " << errors[k - 1] << " -> " << errors[k];
      }
    }
  }
}

TEST(Rattle, IsSecondOrderOnTheThreeParticleDoublePendulum) {
  // Uniform rods as three particles (limb_masses "inertia": the limb centres' constraint and its
  // velocity stage too), against Featherstone with RK4 at 1/24000 s, over 0.5 s.
  const Scene model = study::double_pendulum();
  study::Method reference_method{.family = study::Family::featherstone, .time_step = 1.0 / 24000};
  study::Simulation reference(model, reference_method);
  const study::Trajectory expected = study::observe_run(reference, 0.5, 1.0 / 60).trajectory;
  std::vector<double> errors;
  for (const int substeps : {4, 8, 16}) {
    study::Method method{.family = study::Family::particles, .time_step = 1.0 / 60};
    method.verlet.solver = RelaxationSolver::direct;
    method.verlet.newton_iterations = 20;
    method.relaxation_tolerance = 1e-14;
    method.projection = ProjectionRule::rattle;
    method.substeps = substeps;
    method.limb_masses = LimbMasses::inertia;
    study::Simulation simulation(model, method);
    errors.push_back(study::trajectory_error(study::observe_run(simulation, 0.5, 1.0 / 60).trajectory, expected));
  }
  EXPECT_GT(errors[0] / errors[1], 3.5) << errors[0] << " -> " << errors[1];
  EXPECT_GT(errors[1] / errors[2], 3.5) << errors[1] << " -> " << errors[2];
}

TEST(Rattle, KeepsTheEnergyOfASwingingChainWherePbdLosesIt) {
  // The heavy-end chain released from its arc, 10 s in frames of 1/60 s, 128 substeps of 2
  // sweeps, no contacts: the energy error stays within 10⁻³ of m·g·ΣL at every step (what is
  // lost is the sweeps' unconverged residue, not the integrator); pbd's projection dissipates.
  const Scene chain = study::heavy_end_chain(study::ChainRelease::arc);
  const double scale = study::energy_scale(chain.model);
  for (const ProjectionRule projection : {ProjectionRule::rattle, ProjectionRule::pbd}) {
    Model model = chain.model;
    model.settings.time_step = 1.0 / 60;
    VerletState<double> state = compile<double>(model, relaxation_options(projection, 128, 2, chain.methods.verlet));
    const double start = observe(state).energy();
    double drift = 0;
    for (int s = 0; s < 10 * 60; ++s) {
      ASSERT_EQ(step(state).status, StepStatus::ok);
      drift = std::max(drift, std::abs(observe(state).energy() - start));
    }
    if (projection == ProjectionRule::rattle) {
      EXPECT_LT(drift, 1e-3 * scale);
    } else {
      EXPECT_GT(drift, 0.05 * scale) << "pbd is expected to dissipate";
    }
  }
}

// Σ m·v and Σ m·x × v over the particles.
template <typename Scalar>
std::pair<Eigen::Vector3d, Eigen::Vector3d> momenta(const VerletState<Scalar>& state) {
  Eigen::Vector3d linear = Eigen::Vector3d::Zero(), angular = Eigen::Vector3d::Zero();
  for (std::uint32_t p = 0; p < state.particles.size(); ++p) {
    const Eigen::Vector3d v = particle_velocity(state, p), x = state.particles.position(p).template cast<double>();
    linear += state.particle_mass[p] * v;
    angular += state.particle_mass[p] * x.cross(v);
  }
  return {linear, angular};
}

TEST(Rattle, KeepsLinearAndAngularMomentumOfAFreeChainToRounding) {
  // A free chain of unequal masses, spinning and drifting without gravity, two sweeps a step (far
  // from converged): every projection's impulses are equal and opposite along a line through
  // both particles at the start of the step (or, in the velocity stage, at its end), so neither
  // momentum changes, converged or not.
  Model model = make_chain({1, 3, 0.5, 2, 1, 4}, 0.2, false);
  model.settings.gravity.setZero();
  model.settings.time_step = 1.0 / 60;
  const Vector3 centre(0.6, 0, 1), spin(0.5, 1.0, 6.0), drift(0.3, -0.2, 0.1);
  for (Body& body : model.bodies) {
    body.angular_velocity = spin;
    body.linear_velocity = drift + spin.cross(body.position - centre);
  }
  VerletState<double> state =
      compile<double>(model, relaxation_options(ProjectionRule::rattle, 1, 2, {.joints = ParticleJoints::shared_particle, .limb_masses = LimbMasses::ends, .drag_factor = {}}));
  const auto [linear, angular] = momenta(state);
  for (int s = 0; s < 600; ++s) ASSERT_EQ(step(state).status, StepStatus::ok);
  const auto [linear_after, angular_after] = momenta(state);
  EXPECT_LT((linear_after - linear).norm(), 1e-12 * linear.norm());
  EXPECT_LT((angular_after - angular).norm(), 1e-12 * angular.norm());
  EXPECT_GT(observe(state).max_link_stretch, 1e-6) << "two sweeps should leave the chain unconverged";
}

TEST(Rattle, ForcedFallbackIsCountedAndStaysFinite) {
  // Frames of 1/10 s in one substep: the chain's end links turn more than 60° a step, so their
  // start gradients no longer see the constraint; they must fall back to pbd, be counted, and
  // never produce a non-finite position.
  const Scene chain = study::heavy_end_chain(study::ChainRelease::arc);
  Model model = chain.model;
  model.settings.time_step = 0.1;
  for (const RelaxationSolver solver : {RelaxationSolver::gauss_seidel, RelaxationSolver::jacobi, RelaxationSolver::direct}) {
    VerletOptions options = relaxation_options(ProjectionRule::rattle, 1, 20, chain.methods.verlet);
    options.solver = solver;
    VerletState<double> state = compile<double>(model, options);
    std::uint64_t fallbacks = 0;
    for (int s = 0; s < 100; ++s) {
      const StepReport report = step(state);
      ASSERT_EQ(report.status, StepStatus::ok) << "solver " << int(solver);
      fallbacks += report.fallbacks;
    }
    EXPECT_GT(fallbacks, 0u) << "solver " << int(solver);
    for (std::uint32_t p = 0; p < state.particles.size(); ++p) ASSERT_TRUE(state.particles.position(p).allFinite());
  }
}

TEST(Substeps, PbdSubstepsAreSmallerStepsBitForBit) {
  // A step of Δt in n substeps is n steps of Δt/n: the same passes on the same numbers.
  Model model = load_shipped_scene("humanoid.json");
  model.settings.sleep.start_asleep = false;
  Model small = model;
  small.settings.time_step = model.settings.time_step / 4;
  VerletState<double> a = compile<double>(model, relaxation_options(ProjectionRule::pbd, 4, 10)),
                      b = compile<double>(small, relaxation_options(ProjectionRule::pbd, 1, 10));
  for (int s = 0; s < 100; ++s) {
    ASSERT_EQ(step(a).substeps, 4);
    for (int k = 0; k < 4; ++k) step(b);
  }
  EXPECT_TRUE(bitwise_equal(a.particles, b.particles));
}

TEST(Substeps, ApplyForceActsOverTheWholeStep) {
  // A force applied before a step acts in every substep: a free particle pair (a limb) gains the
  // impulse F·Δt whatever the substep count and rule.
  for (const ProjectionRule projection : {ProjectionRule::pbd, ProjectionRule::rattle}) {
    for (const int substeps : {1, 5}) {
      Model model = make_chain({2.0}, 0.3, false);
      model.settings.gravity.setZero();
      model.settings.time_step = 0.01;
      VerletState<double> state = compile<double>(model, relaxation_options(projection, substeps, RelaxationSettings{}.iterations));
      apply_force(state, 0, Eigen::Vector3d(0, 0, 40));
      step(state);
      EXPECT_NEAR(observe(state).linear_momentum.z(), 40 * 0.01, 1e-12) << "substeps " << substeps;
    }
  }
}

TEST(Rattle, DirectSolverAndGaussSeidelReachTheSameSubsteps) {
  // Converged, both solve the same SHAKE equations: the trajectories agree to the tolerance.
  const Scene chain = study::heavy_end_chain(study::ChainRelease::small_3d);
  Model model = chain.model;
  model.settings.time_step = 1.0 / 60;
  VerletOptions gauss_seidel = relaxation_options(ProjectionRule::rattle, 8, 500, chain.methods.verlet);
  gauss_seidel.relaxation.tolerance = 1e-14;
  VerletOptions direct = gauss_seidel;
  direct.solver = RelaxationSolver::direct, direct.newton_iterations = 50;
  VerletState<double> a = compile<double>(model, gauss_seidel), b = compile<double>(model, direct);
  double largest = 0;
  for (int s = 0; s < 60; ++s) {
    step(a), step(b);
    for (std::uint32_t p = 0; p < a.particles.size(); ++p) largest = std::max(largest, (a.particles.position(p) - b.particles.position(p)).norm());
  }
  EXPECT_LT(largest, 1e-9);
}

TEST(Rattle, HumanoidIsKnockedOverAndFallsAsleep) {
  // Contacts (ground, ball), restitution and sleeping under the rattle rule.
  const Model model = load_shipped_scene("humanoid.json");
  VerletState<double> state = compile<double>(model, relaxation_options(ProjectionRule::rattle, 4, 10));
  const Eigen::Vector3d start = observe(state).body_centre_of_mass;
  for (int s = 0; s < 1200; ++s) ASSERT_EQ(step(state).status, StepStatus::ok);
  const Observation end = observe(state);
  EXPECT_TRUE(end.body_sleeping);
  EXPECT_LT(end.body_centre_of_mass.z(), 0.5 * start.z()) << "the body must have fallen";
  EXPECT_LT(end.max_joint_gap, 1e-3);
}

TEST(Rattle, FloatFollowsDouble) {
  // Velocity as state keeps float's rounding out of the velocity (pbd's (x − x*)/Δt divides it by
  // the substep): in float the chain never gains energy and ends within 1% of m·g·ΣL of double.
  const Scene chain = study::heavy_end_chain(study::ChainRelease::arc);
  Model model = chain.model;
  model.settings.time_step = 1.0 / 60;
  const VerletOptions options = relaxation_options(ProjectionRule::rattle, 64, 2, chain.methods.verlet);
  const double scale = study::energy_scale(model);
  VerletState<float> single = compile<float>(model, options);
  VerletState<double> twice = compile<double>(model, options);
  const double start = observe(single).energy();
  for (int s = 0; s < 10 * 60; ++s) {
    ASSERT_EQ(step(single).status, StepStatus::ok);
    step(twice);
    ASSERT_LT(observe(single).energy() - start, 1e-3 * scale) << "float gained energy at step " << s;
  }
  EXPECT_NEAR(observe(single).energy(), observe(twice).energy(), 1e-2 * scale);
}

}  // namespace
}  // namespace limber
