// Where the Verlet method puts a limb's mass (thesis 4.1; VerletSettings::limb_masses): the
// thesis's half at each end, or three particles that keep the limb's mass, centre of mass and
// transverse inertia — and the particle limb then swings like the rigid one.
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "limber/kernel/mass/mass_properties.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/study/workloads.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

using ::testing::HasSubstr;
using testing::make_chain;

using Kind = ParticleOrigin::Kind;

Model one_limb(const Shape& shape, double mass) {
  Model model;
  model.name = "one_limb";
  Body body;
  body.name = "rod";
  body.shape = shape;
  body.mass = mass;
  model.bodies.push_back(body);
  model.settings.sleep.enabled = false;
  return model;
}

// The particle method putting limbs' mass as `limb_masses`, joints as `joints`.
VerletOptions placed(LimbMasses limb_masses, ParticleJoints joints = ParticleJoints::zero_length_constraint) {
  VerletOptions options;
  options.verlet.limb_masses = limb_masses;
  options.verlet.joints = joints;
  return options;
}

Scene study_chain() { return study::heavy_end_chain(study::ChainRelease::arc); }

/// The particle of `state` that stands for `kind` of body `body`; fails the test if none.
template <typename Scalar>
std::uint32_t particle_of(const VerletState<Scalar>& state, Kind kind, std::uint32_t body = 0) {
  for (std::uint32_t p = 0; p < state.particle_origins.size(); ++p) {
    if (state.particle_origins[p].kind == kind && state.particle_origins[p].index == body) return p;
  }
  ADD_FAILURE() << "no particle of kind " << int(kind) << " for body " << body;
  return 0;
}

/// The mass properties of the particles `particles` (point masses, eq. 4.1), in the world frame.
MassProperties particle_mass_properties(const VerletState<double>& state, const std::vector<std::uint32_t>& particles) {
  std::vector<Eigen::Vector3d> positions;
  std::vector<double> masses;
  for (std::uint32_t p : particles) positions.push_back(state.particles.position(p)), masses.push_back(state.particle_mass[p]);
  return point_masses(positions, masses);
}

TEST(LimbMasses, UniformThinRodGetsOneSixthTwoThirdsOneSixth) {
  const double mass = 3.0;
  const VerletState<double> state = compile<double>(one_limb({ShapeType::cylinder, 0.8, 0.0}, mass), placed(LimbMasses::inertia));
  ASSERT_EQ(state.particles.size(), 3u);
  EXPECT_NEAR(state.particle_mass[particle_of(state, Kind::limb_head)], mass / 6, 1e-15 * mass);
  EXPECT_NEAR(state.particle_mass[particle_of(state, Kind::limb_centre)], 2 * mass / 3, 1e-15 * mass);
  EXPECT_NEAR(state.particle_mass[particle_of(state, Kind::limb_tail)], mass / 6, 1e-15 * mass);
  EXPECT_EQ(state.limbs.centre[0], particle_of(state, Kind::limb_centre));
  // The thesis's placement: two particles, half each, and no centre.
  const VerletState<double> ends = compile<double>(one_limb({ShapeType::cylinder, 0.8, 0.0}, mass), placed(LimbMasses::ends));
  ASSERT_EQ(ends.particles.size(), 2u);
  EXPECT_EQ(ends.particle_mass[0], mass / 2);
  EXPECT_EQ(ends.particle_mass[1], mass / 2);
  EXPECT_EQ(ends.limbs.centre[0], kNoCentre);
}

TEST(LimbMasses, ThreeParticlesKeepTheLimbsMassCentreOfMassAndTransverseInertia) {
  // Random cylinders, capsules and lumps on the axis, in random poses: the particles' own mass
  // properties (eq. 4.1) must be the limb's (body_mass_properties, moved to the world), except
  // for the spin about the axis, which points on the axis cannot carry.
  std::mt19937 random(41);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int trial = 0; trial < 60; ++trial) {
    const int kind = trial % 3;
    const double length = 0.1 + 2 * unit(random);
    Model model = one_limb({kind == 1 ? ShapeType::capsule : ShapeType::cylinder, length, 0.0}, 0.5 + 10 * unit(random));
    Body& body = model.bodies[0];
    if (kind == 0) body.shape.radius = 0.7 * length * unit(random);  // radius²/4 < length²/6 keeps m_centre > 0
    if (kind == 1) body.shape.radius = 0.3 * length * unit(random);
    if (kind == 2) {
      // Lumps near both ends and one anywhere, so the centre of mass stays between them.
      const double h = 0.5 * length;
      const double z[3] = {h * (0.5 + 0.5 * unit(random)), -h * (0.5 + 0.5 * unit(random)), h * (2 * unit(random) - 1)};
      body.mass = 0;
      for (double at : z) {
        const PointMass lump{Vector3(0, 0, at), 0.2 + unit(random), 0.1 * length * unit(random)};
        body.point_masses.push_back(lump);
        body.mass += lump.mass;
      }
    }
    body.axis = Vector3(unit(random) - 0.5, unit(random) - 0.5, unit(random) - 0.5).normalized();
    body.position = Vector3(unit(random), unit(random), unit(random));
    const VerletState<double> state = compile<double>(model, placed(LimbMasses::inertia));
    ASSERT_EQ(state.particles.size(), 3u);
    const MassProperties particles = particle_mass_properties(state, {0, 1, 2});
    const MassProperties own = body_mass_properties(body);
    const MassProperties limb = transformed(own, body.orientation(), body.position);
    const double scale = limb.mass * length * length;
    EXPECT_NEAR(particles.mass, limb.mass, 1e-12 * limb.mass) << "trial " << trial;
    EXPECT_NEAR(particles.mass, model.body_mass(), 1e-12 * limb.mass) << "trial " << trial;
    EXPECT_LT((particles.centre_of_mass - limb.centre_of_mass).norm(), 1e-12 * length) << "trial " << trial;
    const Eigen::Matrix3d spin = own.inertia(2, 2) * body.axis * body.axis.transpose();
    EXPECT_LT((particles.inertia - (limb.inertia - spin)).norm(), 1e-12 * scale) << "trial " << trial;
  }
}

// Period of a thin uniform rod of length L hung from its head by a joint to the world and
// released 5° from the vertical, from the zero crossings of its free end's horizontal offset.
double pendulum_period(LimbMasses limb_masses, ParticleJoints joints, double length) {
  const double angle = 5 * std::numbers::pi / 180;
  const Vector3 pivot(0, 0, 2);
  Model model = one_limb({ShapeType::cylinder, length, 0.0}, 2.0);
  Body& rod = model.bodies[0];
  rod.axis = Vector3(-std::sin(angle), 0, std::cos(angle));  // tail → head, up towards the pivot
  rod.position = pivot - 0.5 * length * rod.axis;
  model.joints.push_back(spherical_joint("pivot", kWorld, 0, pivot, Vector3(0, 0, 0.5 * length)));
  model.settings.time_step = 1.0 / 1000;
  VerletOptions options = placed(limb_masses, joints);
  options.relaxation.iterations = 50;
  VerletState<double> state = compile<double>(model, options);
  const std::uint32_t tail = state.limbs.tail[0];
  std::vector<double> crossings;
  double time = 0, previous = state.particles.position(tail).x();
  while (crossings.size() < 5 && time < 20) {
    EXPECT_EQ(step(state).status, StepStatus::ok);
    time += model.settings.time_step;
    const double x = state.particles.position(tail).x();
    if ((previous > 0) != (x > 0)) crossings.push_back(time - model.settings.time_step * x / (x - previous));
    previous = x;
  }
  EXPECT_EQ(crossings.size(), 5u);
  return (crossings.back() - crossings.front()) / 2;  // four half periods
}

TEST(LimbMasses, ThreeParticleRodSwingsLikeTheRigidPendulum) {
  // A rigid rod pinned at one end is a physical pendulum, T = 2π·sqrt(2L/(3g)) (I = m L²/3 about
  // the pivot). Half the mass at each end makes it a simple pendulum of length L, T = 2π·sqrt(L/g):
  // 22% slower. Three particles that keep the rod's inertia must swing like the rigid rod.
  const double length = 1.0, g = 9.81;
  const double rigid = 2 * std::numbers::pi * std::sqrt(2 * length / (3 * g));
  const double simple = 2 * std::numbers::pi * std::sqrt(length / g);
  for (const ParticleJoints joints : {ParticleJoints::zero_length_constraint, ParticleJoints::shared_particle}) {
    const double inertia = pendulum_period(LimbMasses::inertia, joints, length);
    const double ends = pendulum_period(LimbMasses::ends, joints, length);
    EXPECT_NEAR(inertia, rigid, 0.01 * rigid) << "joints " << int(joints);
    EXPECT_NEAR(ends, simple, 0.01 * simple) << "joints " << int(joints);
  }
}

TEST(LimbMasses, RodLyingOnItsEndsStaysStraightAndFallsAsleep) {
  // Its ends touch the ground; the centre, two thirds of the mass, is held only by the limb. The
  // collinear constraints alone would let it sag (they resist a sideways offset e only by ~e²/L);
  // the centre projection keeps the rod straight, so it comes to rest as fast as a two-particle one.
  for (const LimbMasses limb_masses : {LimbMasses::ends, LimbMasses::inertia}) {
    Model model = one_limb({ShapeType::cylinder, 1.0, 0.02}, 2.0);
    model.bodies[0].axis = Vector3::UnitX();
    model.bodies[0].position = Vector3(0, 0, 0.1);
    model.ground = Ground{0, 0.0, 0.6};
    model.settings.sleep.enabled = true;
    VerletState<double> state = compile<double>(model, placed(limb_masses));
    int steps = 0;
    for (; !state.islands[0].sleeping && steps < 240 * 3; ++steps) ASSERT_EQ(step(state).status, StepStatus::ok);
    ASSERT_TRUE(state.islands[0].sleeping) << "limb_masses " << int(limb_masses);
    EXPECT_LT(steps, 240) << "limb_masses " << int(limb_masses) << ": a dropped rod comes to rest within a second";
    const Eigen::Vector3d head = state.particles.position(state.limbs.head[0]);
    const Eigen::Vector3d tail = state.particles.position(state.limbs.tail[0]);
    EXPECT_NEAR(head.z(), 0.02, 1e-6);
    EXPECT_NEAR(tail.z(), 0.02, 1e-6);
    if (limb_masses == LimbMasses::inertia) {
      const Eigen::Vector3d centre = state.particles.position(state.limbs.centre[0]);
      EXPECT_LT((centre - 0.5 * (head + tail)).norm(), 1e-9);
    }
  }
}

TEST(LimbMasses, RodDroppedFlatBouncesWithTheGroundsRestitution) {
  // Restitution 0.5: the rod must leave the ground at half its impact speed. An impulse given to
  // the ends alone would move only their third of the mass (it bounced at 0.05 of the speed).
  // Under either projection rule (rattle: restitution is part of its velocity stage).
  const double restitution = 0.5;
  for (const auto& [limb_masses, projection] : {std::pair{LimbMasses::ends, ProjectionRule::pbd}, std::pair{LimbMasses::inertia, ProjectionRule::pbd},
                                                std::pair{LimbMasses::ends, ProjectionRule::rattle}, std::pair{LimbMasses::inertia, ProjectionRule::rattle}}) {
    Model model = one_limb({ShapeType::cylinder, 1.0, 0.02}, 2.0);
    model.bodies[0].axis = Vector3::UnitY();
    model.bodies[0].position = Vector3(0, 0, 0.5);
    model.ground = Ground{0, restitution, 0.0};
    model.settings.time_step = 1.0 / 1000;
    VerletOptions options = placed(limb_masses);
    options.relaxation.projection = projection;
    VerletState<double> state = compile<double>(model, options);
    double impact = 0, rebound = 0;
    for (int s = 0; s < 600; ++s) {
      ASSERT_EQ(step(state).status, StepStatus::ok);
      const double speed = observe(state).linear_momentum.z() / model.body_mass();
      impact = std::min(impact, speed);
      rebound = std::max(rebound, speed);
    }
    ASSERT_LT(impact, -2.5) << "the rod must have fallen onto the ground";
    EXPECT_NEAR(rebound / -impact, restitution, 0.02) << "limb_masses " << int(limb_masses) << " projection " << int(projection);
  }
}

// Speed of an elastic ball of mass `ball_mass` after striking, at 3 m/s, a free thin rod of mass
// 2 kg and length 1 m at `height` above the rod's centre, with no gravity.
double ball_speed_after_strike(LimbMasses limb_masses, double ball_mass, double height, ProjectionRule projection) {
  Model model = one_limb({ShapeType::cylinder, 1.0, 0.01}, 2.0);
  VerletOptions options = placed(limb_masses);
  options.relaxation.projection = projection;
  model.bodies[0].position = Vector3(0, 0, 1);
  model.balls = {Ball{0.05, ball_mass, 1.0, Vector3(0.2, 0, 1 + height), Vector3(-3, 0, 0)}};
  model.settings.gravity.setZero();
  model.settings.time_step = 1.0 / 1000;
  VerletState<double> state = compile<double>(model, options);
  const Eigen::Vector3d momentum = observe(state).linear_momentum;
  for (int s = 0; s < 200; ++s) EXPECT_EQ(step(state).status, StepStatus::ok);
  EXPECT_LT((observe(state).linear_momentum - momentum).norm(), 1e-9 * momentum.norm());
  return particle_velocity(state, state.balls.front().particle).x();
}

TEST(LimbMasses, BallBouncesOffTheRodAsOffTheRigidRod) {
  // An elastic hit at distance s from a free rod's centre meets the effective mass
  // 1/(1/m + s²/I); the ball leaves at v·(M − m_eff)/(M + m_eff). Three particles keep I, so
  // they must give the rigid rod's answer; half the mass at each end has I three times too
  // large, and near an end the ball meets a heavier rod.
  const double rod_mass = 2.0, ball_mass = 1.0, speed = -3.0;
  const MassProperties rod = solid_cylinder(rod_mass, 0.01, 1.0);
  const auto rigid_answer = [&](double s, double inertia) {
    const double effective = 1 / (1 / rod_mass + s * s / inertia);
    return speed * (ball_mass - effective) / (ball_mass + effective);
  };
  for (const ProjectionRule projection : {ProjectionRule::pbd, ProjectionRule::rattle}) {
    for (const double height : {0.0, 0.4}) {
      const double inertia = ball_speed_after_strike(LimbMasses::inertia, ball_mass, height, projection);
      EXPECT_NEAR(inertia, rigid_answer(height, rod.inertia(0, 0)), 0.01 * std::abs(speed))
          << "at " << height << " m, projection " << int(projection);
      const double ends = ball_speed_after_strike(LimbMasses::ends, ball_mass, height, projection);
      EXPECT_NEAR(ends, rigid_answer(height, rod_mass * 0.25), 0.01 * std::abs(speed))
          << "at " << height << " m, projection " << int(projection);
    }
  }
}

TEST(LimbMasses, ForceMovesAnUnevenLimbWithoutTurningIt) {
  // apply_force acts at the limb's centre of mass: every particle gets the same acceleration.
  // A limb whose lumps put its centre of mass 0.16 m towards the head must not start to turn
  // (pushed at its middle, as half at each end would be, it would).
  Model model = one_limb({ShapeType::cylinder, 1.0, 0.02}, 0.0);
  Body& limb = model.bodies[0];
  limb.point_masses = {{Vector3(0, 0, 0.45), 2.0, 0.0}, {Vector3(0, 0, -0.3), 1.0, 0.0}, {Vector3(0, 0, 0.05), 1.0, 0.1}};
  limb.mass = 4.0;
  model.settings.gravity.setZero();
  VerletState<double> state = compile<double>(model, placed(LimbMasses::inertia));
  ASSERT_GT(body_mass_properties(limb).centre_of_mass.z(), 0.15);
  const Eigen::Vector3d force(0, 40, 0);
  apply_force(state, 0, force);
  step(state);
  for (int s = 0; s < 100; ++s) ASSERT_EQ(step(state).status, StepStatus::ok);
  const double dt = model.settings.time_step;
  EXPECT_LT((observe(state).linear_momentum - force * dt).norm(), 1e-9 * force.norm() * dt);
  const Eigen::Vector3d axis =
      (state.particles.position(state.limbs.head[0]) - state.particles.position(state.limbs.tail[0])).normalized();
  EXPECT_LT((axis - Vector3::UnitZ()).norm(), 1e-9) << "the limb turned";
}

template <typename Scalar>
class ThreeParticleChains : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ThreeParticleChains, Scalars);

TYPED_TEST(ThreeParticleChains, WorkInBothJointModesEveryOrderingAndLayout) {
  // Five links with centres: the particles carry exactly the links' mass; renumbering and the
  // interleaved layouts change where particles are stored, not one bit of where they go; the
  // joints hold and every centre stays on its link's axis.
  for (const ParticleJoints joints : {ParticleJoints::zero_length_constraint, ParticleJoints::shared_particle}) {
    Model model = make_chain({1.0, 1.0, 1.0, 1.0, 2.0}, 0.2, true);
    const auto run = [&](ParticleOrder ordering, ParticleLayout layout,
                         RelaxationSolver solver = RelaxationSolver::gauss_seidel) {
      VerletOptions options = placed(LimbMasses::inertia, joints);
      options.ordering = ordering, options.layout = layout, options.solver = solver;
      options.threads = 2, options.parallel_minimum_slots = 1;
      VerletState<TypeParam> state = compile<TypeParam>(model, options);
      double mass = 0;
      for (double m : state.particle_mass) mass += m;
      EXPECT_NEAR(mass, model.body_mass(), 1e-12 * mass);
      for (int s = 0; s < 240; ++s) EXPECT_EQ(step(state).status, StepStatus::ok);
      return state;
    };
    const auto by_origin = [](const VerletState<TypeParam>& state) {
      std::map<std::pair<int, std::uint32_t>, Eigen::Matrix<TypeParam, 3, 1>> positions;
      for (std::size_t p = 0; p < state.particles.size(); ++p) {
        positions[{int(state.particle_origins[p].kind), state.particle_origins[p].index}] = state.particles.position(p);
      }
      return positions;
    };
    const VerletState<TypeParam> reference = run(ParticleOrder::breadth_first, ParticleLayout::soa);
    EXPECT_EQ(reference.particles.size(), joints == ParticleJoints::shared_particle ? 11u : 16u);
    const auto expected = by_origin(reference);
    for (const ParticleOrder ordering :
         {ParticleOrder::depth_parity, ParticleOrder::reverse_cuthill_mckee, ParticleOrder::shuffled}) {
      EXPECT_EQ(by_origin(run(ordering, ParticleLayout::soa)), expected) << "ordering " << int(ordering);
    }
    for (const ParticleLayout layout : {ParticleLayout::aos, ParticleLayout::aosoa}) {
      EXPECT_EQ(by_origin(run(ParticleOrder::depth_parity, layout)), expected) << "layout " << int(layout);
    }
    EXPECT_EQ(by_origin(run(ParticleOrder::shuffled, ParticleLayout::aos, RelaxationSolver::jacobi)),
              by_origin(run(ParticleOrder::breadth_first, ParticleLayout::soa, RelaxationSolver::jacobi)));
    const Observation observation = observe(reference);
    const double tolerance = std::is_same_v<TypeParam, float> ? 1e-5 : 1e-9;
    EXPECT_LT(observation.max_joint_gap, 1e-3);
    EXPECT_LT(observation.max_link_stretch, 1e-3);
    for (std::size_t limb = 0; limb < reference.limbs.size(); ++limb) {
      const auto position = [&](std::uint32_t p) { return reference.particles.position(p).template cast<double>().eval(); };
      const Eigen::Vector3d midpoint = 0.5 * (position(reference.limbs.head[limb]) + position(reference.limbs.tail[limb]));
      EXPECT_LT((position(reference.limbs.centre[limb]) - midpoint).norm(), tolerance) << "limb " << limb;
    }
    EXPECT_GT((observation.body_centre_of_mass - Vector3(0.5, 0, 1)).norm(), 0.1) << "the chain must have swung";
  }
}

TEST(LimbMasses, LimbsThreeAxisParticlesCannotCarryAreRefusedByName) {
  // Each is fine with half the mass at each end; with three particles on the axis each needs a
  // negative mass or a centre of mass off the axis, and compile must say which body and why.
  const auto refusal = [](const Body& bad) {
    Model model = one_limb({ShapeType::cylinder, 1.0, 0.02}, 1.0);
    model.bodies.push_back(bad);
    try {
      compile<double>(model, placed(LimbMasses::inertia));
    } catch (const ModelError& error) {
      EXPECT_NO_THROW(compile<double>(model, placed(LimbMasses::ends)));
      return std::string(error.what());
    }
    ADD_FAILURE() << "compiled";
    return std::string();
  };
  Body disc;
  disc.name = "disc";
  disc.shape = {ShapeType::cylinder, 0.1, 0.1};  // radius²/4 = 0.0025 > length²/6 = 0.0017
  disc.mass = 1.0;
  const std::string wide = refusal(disc);
  EXPECT_THAT(wide, HasSubstr("bodies[1] 'disc': limb_masses \"inertia\" needs"));
  EXPECT_THAT(wide, HasSubstr("too wide"));
  EXPECT_THAT(wide, HasSubstr("use limb_masses \"ends\""));
  EXPECT_EQ(wide.find('\n'), std::string::npos);

  Body lumps = disc;
  lumps.name = "lumps";
  lumps.shape = {ShapeType::capsule, 1.0, 0.05};
  lumps.point_masses = {{Vector3(0.01, 0, 0.4), 1.0, 0.0}, {Vector3(0, 0, -0.4), 1.0, 0.0}};
  lumps.mass = 2.0;
  EXPECT_THAT(refusal(lumps), HasSubstr("bodies[1] 'lumps': limb_masses \"inertia\" needs the centre of mass on the limb's axis"));
  lumps.point_masses = {{Vector3(0, 0, 0.9), 2.0, 0.0}};  // beyond the head
  EXPECT_THAT(refusal(lumps), HasSubstr("too wide"));
  lumps.point_masses = {{Vector3(0, 0, 0.2), 2.0, 0.0}};  // all at one point: no tail mass
  EXPECT_THAT(refusal(lumps), HasSubstr("too concentrated"));
  lumps.point_masses = {{Vector3(0, 0, 0), 2.0, 0.0}};  // all at the centre: nothing at the ends
  EXPECT_THAT(refusal(lumps), HasSubstr("bodies[1] 'lumps'"));
}

TEST(LimbMasses, LumpsAtTheEndsAreExactlyTheChainsPointMasses) {
  // The accuracy studies' chain: five rods whose mass is point masses at their ends. With lumps
  // and shared particles the particle method holds exactly the point-mass system: 1, 1, 1, 1 and
  // 2 kg at the joints and the free end, and the pin.
  const VerletState<double> state = compile<double>(study_chain().model, testing::with_scene_settings(study_chain()));
  ASSERT_EQ(state.particles.size(), 6u);
  std::vector<double> free_masses;
  for (std::uint32_t p = 0; p < state.particles.size(); ++p) {
    if (state.particles.inverse_mass[p] == 0) {
      EXPECT_LT(state.particles.position(p).norm(), 1e-15) << "only the pin is held";
      continue;
    }
    free_masses.push_back(state.particle_mass[p]);
    EXPECT_NEAR(state.particles.inverse_mass[p], 1 / state.particle_mass[p], 1e-15);
  }
  EXPECT_THAT(free_masses, ::testing::UnorderedElementsAre(1.0, 1.0, 1.0, 1.0, 2.0));
}

TEST(LimbMasses, LumpsShareEachPointMassByTheLeverRule) {
  // A lump a quarter of the way from the tail puts 1/4 of its mass on the head, 3/4 on the tail:
  // the pair keeps its mass and centre of mass.
  Model model = one_limb({ShapeType::capsule, 1.0, 0.01}, 4.0);
  model.bodies[0].point_masses = {{Vector3(0, 0, -0.25), 4.0, 0.0}};
  const VerletState<double> state = compile<double>(model, placed(LimbMasses::lumps));
  EXPECT_DOUBLE_EQ(state.particle_mass[particle_of(state, Kind::limb_head)], 1.0);
  EXPECT_DOUBLE_EQ(state.particle_mass[particle_of(state, Kind::limb_tail)], 3.0);
}

TEST(LimbMasses, WhatLumpsCannotCarryIsRefusedByName) {
  const auto refusal = [](const Model& model, ParticleJoints joints = ParticleJoints::zero_length_constraint) {
    try {
      compile<double>(model, placed(LimbMasses::lumps, joints));
    } catch (const ModelError& error) {
      return std::string(error.what());
    }
    ADD_FAILURE() << "compiled";
    return std::string();
  };
  Model model = one_limb({ShapeType::capsule, 1.0, 0.01}, 2.0);
  EXPECT_THAT(refusal(model), HasSubstr("bodies[0] 'rod': limb_masses \"lumps\" needs point_masses on every body"));
  model.bodies[0].point_masses = {{Vector3(0, 0.1, 0.5), 2.0, 0.0}};
  EXPECT_THAT(refusal(model), HasSubstr("bodies[0] 'rod': limb_masses \"lumps\" needs every point mass on the limb's axis"));
  model.bodies[0].point_masses = {{Vector3(0, 0, 0.7), 2.0, 0.0}};
  EXPECT_THAT(refusal(model), HasSubstr("between the limb's ends"));
  // All the mass at the head leaves the tail a particle without mass, which only a shared or
  // pinned particle may be.
  model.bodies[0].point_masses = {{Vector3(0, 0, 0.5), 2.0, 0.0}};
  EXPECT_THAT(refusal(model), HasSubstr("bodies[0] 'rod': limb_masses \"lumps\" leaves its tail without mass"));
  Model chain = study_chain().model;
  chain.bodies[0].point_masses.pop_back();  // link_0 only at the pin
  chain.bodies[0].point_masses.push_back({Vector3(0, 0, 0.05), 0.5, 0.0});
  chain.bodies[0].mass = 1.0;
  EXPECT_THAT(refusal(chain), HasSubstr("'link_0': limb_masses \"lumps\" leaves its tail without mass"));
}

}  // namespace
}  // namespace limber
