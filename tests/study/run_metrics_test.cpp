// The study's measures (kernel/study/) on cases with known answers, and the fact the Pareto study
// rests on: every method simulates the same body model, so its trajectory converges to the
// reference as Δt falls — except the thesis's particle masses, a different body.
#include <cmath>
#include <limits>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/study/run_metrics.hpp"
#include "tests/support/models.hpp"

namespace limber::study {
namespace {

Method featherstone_rk4(double dt) { return {.series = "featherstone rk4", .family = Family::featherstone, .time_step = dt}; }

Model hanging_chain() {
  return make_chain_model({.links = 6, .link_length = 0.2, .link_mass = 1, .end_mass_ratio = 3, .anchor = {0, 0, 2},
                           .direction = {0, 0, -1}});
}

TEST(StudyMetrics, RestingChainUnderFeatherstoneHasNoGapNoDriftAndDoesNotMove) {
  const Model model = hanging_chain();
  Simulation simulation(model, featherstone_rk4(1.0 / 240));
  const ObservedRun run = observe_run(simulation, 1.0, 0.05);
  EXPECT_EQ(run.errors.status, StepStatus::ok);
  EXPECT_EQ(run.errors.steps, 240);
  EXPECT_LT(run.errors.max_joint_gap, 1e-12);
  EXPECT_LT(run.errors.relative_energy_drift(), 1e-12);
  ASSERT_EQ(run.trajectory.samples.size(), 21u);  // t = 0, 0.05, …, 1
  Trajectory at_rest = run.trajectory;
  for (auto& sample : at_rest.samples) sample = run.trajectory.samples.front();
  EXPECT_LT(trajectory_error(run.trajectory, at_rest), 1e-12);
}

// A free, non-spinning body's flight under gravity is a quadratic in t, which RK4 integrates
// exactly: the energy measure must then report no drift, whatever the step, while kinetic and
// potential energy exchange tens of joules. (Spinning, Featherstone's body-frame velocity turns
// and RK4 is no longer exact.)
TEST(StudyMetrics, FreeBodyEnergyIsExactUnderRungeKutta) {
  Model model = testing::make_chain({2.0}, 0.3, /*pinned=*/false);
  model.bodies[0].linear_velocity = Vector3(3, -1, 8);
  for (const Method& method : {featherstone_rk4(1.0 / 30),
                               Method{.series = "lagrange rk4", .family = Family::lagrange, .time_step = 1.0 / 30,
                                      .lagrange = {.integrator = Integrator::rk4}}}) {
    Simulation simulation(model, method);
    const Observation start = simulation.observe();
    const ObservedRun run = observe_run(simulation, 1.0);
    EXPECT_GT(std::abs(simulation.observe().kinetic_energy - start.kinetic_energy), 10) << method.series;
    EXPECT_LT(run.errors.energy_drift, 1e-9 * start.kinetic_energy) << method.series;
  }
}

TEST(StudyMetrics, EnergyScaleIsWeightTimesLength) {
  const Model model = hanging_chain();  // 5 × 1 kg + 3 kg, 6 × 0.2 m
  EXPECT_NEAR(energy_scale(model), 8 * 9.81 * 1.2, 1e-12);
}

Trajectory line(double offset, int samples) {
  Trajectory trajectory{.sample_interval = 0.1, .samples = {}};
  for (int k = 0; k < samples; ++k) trajectory.samples.push_back({Eigen::Vector3d(k, offset, 0), Eigen::Vector3d(k, 0, offset)});
  return trajectory;
}

TEST(StudyMetrics, TrajectoryErrorIsTheLargestRmsDistance) {
  EXPECT_DOUBLE_EQ(trajectory_error(line(0.25, 5), line(0, 5)), 0.25);  // both points 0.25 m off: RMS 0.25
  Trajectory partly = line(0, 5);
  partly.samples[3][0].y() = 0.4;  // one of two points 0.4 m off at one sample: RMS 0.4/√2
  EXPECT_DOUBLE_EQ(trajectory_error(partly, line(0, 5)), 0.4 / std::sqrt(2.0));
}

TEST(StudyMetrics, MaxPointErrorIsTheWorstPointAtItsWorstMoment) {
  EXPECT_DOUBLE_EQ(max_point_error(line(0.25, 5), line(0, 5)), 0.25);
  Trajectory partly = line(0, 5);
  partly.samples[3][0].y() = 0.4;  // one point 0.4 m off at one sample
  EXPECT_DOUBLE_EQ(max_point_error(partly, line(0, 5)), 0.4);
  Trajectory broken = line(0, 5);
  broken.samples[2][1].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(max_point_error(broken, line(0, 5)), std::numeric_limits<double>::infinity());
  EXPECT_EQ(max_point_error(line(0, 3), line(0, 5)), std::numeric_limits<double>::infinity());
}

TEST(StudyMetrics, TrajectoryErrorOfAStoppedOrNonFiniteRunIsInfinite) {
  EXPECT_EQ(trajectory_error(line(0, 3), line(0, 5)), std::numeric_limits<double>::infinity());
  Trajectory broken = line(0, 5);
  broken.samples[2][1].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(trajectory_error(broken, line(0, 5)), std::numeric_limits<double>::infinity());
  Trajectory coarser = line(0, 5);
  coarser.sample_interval = 0.2;
  EXPECT_THROW(trajectory_error(coarser, line(0, 5)), std::invalid_argument);
}

TEST(StudyMetrics, SampleIntervalMustBeWholeSteps) {
  Simulation simulation(hanging_chain(), featherstone_rk4(1.0 / 240));
  EXPECT_THROW(observe_run(simulation, 0.1, 0.011), std::invalid_argument);
}

TEST(StudyMetrics, ErrorMeterAveragesGapsOverStepsAndCarriesNonFiniteEnergy) {
  Observation start;
  start.potential_energy = 10;
  ErrorMeter meter(start, 5.0);
  Observation a = start, b = start;
  a.rms_joint_gap = 3e-3, a.max_joint_gap = 4e-3, a.kinetic_energy = 1;
  b.rms_joint_gap = 4e-3, b.max_joint_gap = 5e-3, b.potential_energy = 8;
  meter.add(a);
  meter.add(b);
  RunErrors errors = meter.result();
  EXPECT_DOUBLE_EQ(errors.rms_joint_gap, std::sqrt((9e-6 + 16e-6) / 2));
  EXPECT_DOUBLE_EQ(errors.max_joint_gap, 5e-3);
  EXPECT_DOUBLE_EQ(errors.energy_drift, 2);  // b lost 2 J
  EXPECT_DOUBLE_EQ(errors.energy_gain, 1);   // a gained 1 J
  EXPECT_DOUBLE_EQ(errors.relative_energy_gain(), 0.2);
  b.kinetic_energy = std::numeric_limits<double>::quiet_NaN();
  meter.add(b);
  EXPECT_EQ(meter.result().energy_gain, std::numeric_limits<double>::infinity());
  EXPECT_EQ(classify(meter.result()), Stability::non_finite);
}

// The verdict flags each measure past its bound, says where and when, and nothing within; a
// stopped run is its stopping step's status. The bounds the scene does not give come from the
// Model: its thinnest limb's radius, and an energy gain of 1% (1 scale with a motor).
TEST(StudyMetrics, TheVerdictFlagsEachMeasurePastItsToleranceAndNothingWithin) {
  Model model = hanging_chain();
  model.ground = Ground{};
  Observation start;
  const VerdictBounds bounds = verdict_bounds(model, start);
  double thinnest = 1e9;
  for (const Body& body : model.bodies) thinnest = std::min(thinnest, body.shape.radius);
  EXPECT_EQ(bounds.penetration, thinnest);
  EXPECT_EQ(bounds.energy_gain, 0.01);
  EXPECT_EQ(bounds.joint_gap, model.settings.tolerances.joint_gap);

  RunErrors within;
  within.max_joint_gap = 0.99 * bounds.joint_gap, within.max_limit_violation = 0.99 * bounds.limit;
  within.deepest_penetration = {0.99 * bounds.penetration, 2, -1, -1};
  within.energy_gain = 0.99 * bounds.energy_gain * bounds.energy_scale;
  EXPECT_EQ(verdict(within, model, bounds).status, "ok");
  EXPECT_EQ(verdict(within, model, bounds).text, "ok");

  RunErrors deep = within;
  deep.deepest_penetration.depth = 2 * bounds.penetration, deep.penetration_time = 0.5;
  const Verdict sunk = verdict(deep, model, bounds);
  EXPECT_EQ(sunk.status, "inaccurate");
  EXPECT_THAT(sunk.text, ::testing::HasSubstr(model.bodies[2].name + " into the ground at t = 0.500 s"));
  RunErrors others = within;
  others.max_link_stretch = 2 * bounds.joint_gap, others.max_limit_violation = 2 * bounds.limit;
  others.energy_gain = 2 * bounds.energy_gain * bounds.energy_scale;
  const Verdict three = verdict(others, model, bounds);
  EXPECT_THAT(three.text, ::testing::StartsWith("inaccurate: joints open (or links stretched) by "));
  EXPECT_THAT(three.text, ::testing::HasSubstr("; a limit passed by "));
  EXPECT_THAT(three.text, ::testing::HasSubstr("; energy gained "));
  RunErrors open = within;
  open.max_joint_gap = 2 * bounds.joint_gap, open.widest_joint = 1, open.joint_gap_time = 0.25;
  EXPECT_THAT(verdict(open, model, bounds).text,
              ::testing::StartsWith("inaccurate: joint '" + model.joints[1].name + "' open by "));
  RunErrors stopped = others;
  stopped.status = StepStatus::diverged_speed;
  EXPECT_EQ(verdict(stopped, model, bounds).status, "diverged_speed");

  model.actuators.push_back(Actuator{});
  EXPECT_EQ(verdict_bounds(model, start).energy_gain, 1.0);
  model.settings.tolerances.energy_gain = 0.5, model.settings.tolerances.penetration = 0.001;
  EXPECT_EQ(verdict_bounds(model, start).energy_gain, 0.5);
  EXPECT_EQ(verdict_bounds(model, start).penetration, 0.001);

  // A box's thickness is its smallest half-extent (it has no radius): a board 2 mm thick, its
  // 1 mm half below the chain's 2 mm radius, bounds the default penetration as a limb's radius does.
  model.settings.tolerances.penetration.reset();
  Body board = model.bodies[0];
  board.name = "board", board.shape = Shape{};
  board.shape.type = ShapeType::box, board.shape.half_extents = Vector3(0.3, 0.2, 0.001);
  model.bodies.push_back(board);
  EXPECT_EQ(verdict_bounds(model, start).penetration, 0.001);
}

// The double pendulum of uniform rods, released horizontally, compared over 0.5 s with
// Featherstone RK4 at a tiny step.
double pendulum_trajectory_error(const Method& method) {
  const Model model = make_chain_model({.links = 2, .link_length = 0.5, .link_mass = 1, .anchor = {0, 0, 1}});
  Simulation reference(model, featherstone_rk4(1.0 / 8000));
  const Trajectory expected = observe_run(reference, 0.5, 0.05).trajectory;
  Simulation simulation(model, method);
  return trajectory_error(observe_run(simulation, 0.5, 0.05).trajectory, expected);
}

Method verlet_direct(double dt, LimbMasses masses) {
  Method method{.series = "verlet direct", .family = Family::particles, .time_step = dt};
  method.verlet.solver = RelaxationSolver::direct;
  method.verlet.newton_iterations = 5;
  method.limb_masses = masses;
  return method;
}

TEST(StudyMetrics, EveryMethodConvergesToTheReferenceOnTheSameBodyModel) {
  for (const auto& make : {+[](double dt) { return verlet_direct(dt, LimbMasses::inertia); },
                           +[](double dt) { return Method{.series = "lagrange", .family = Family::lagrange, .time_step = dt,
                                                          .lagrange = {.stabilization = Stabilization::projection}}; },
                           +[](double dt) { return Method{.series = "featherstone semi-implicit", .family = Family::featherstone,
                                                          .time_step = dt,
                                                          .featherstone = {.integrator = Integrator::semi_implicit_euler}}; }}) {
    const double coarse = pendulum_trajectory_error(make(1.0 / 200)), fine = pendulum_trajectory_error(make(1.0 / 800));
    // At least first order: a quarter of the step leaves at most ~a quarter of the error (0.4 allows for noise).
    EXPECT_LT(fine, 0.4 * coarse) << make(1).series << ": " << coarse << " m at 1/200 s, " << fine << " m at 1/800 s";
  }
}

TEST(StudyMetrics, TheThesisParticleMassesAreADifferentBody) {
  // Half of each rod's mass at each end: 3× a uniform rod's moment of inertia about its centre
  // (thesis 4.1). The trajectory error then stops falling with the step.
  const double coarse = pendulum_trajectory_error(verlet_direct(1.0 / 200, LimbMasses::ends));
  const double fine = pendulum_trajectory_error(verlet_direct(1.0 / 800, LimbMasses::ends));
  EXPECT_GT(fine, 0.7 * coarse);
  EXPECT_GT(fine, 10 * pendulum_trajectory_error(verlet_direct(1.0 / 800, LimbMasses::inertia)));
}

}  // namespace
}  // namespace limber::study
