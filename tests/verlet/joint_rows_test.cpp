// The particle method's joints beyond "two limb ends held together": hinges, universal and
// fixed joints, limits, friction, drives and anchors anywhere on a limb (kernel/particles/
// joint_rows.hpp). Each test asserts a physical property; the measures are the shared
// joint_coordinates() every method is measured with.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/model/joint_coordinates.hpp"
#include "limber/kernel/relaxation/joint_projection.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"

namespace limber {
namespace {

constexpr double kPi = std::numbers::pi;

// One capsule limb of `length` hanging from the world at its head by `joint` (its axis given,
// tail → head), gravity off unless asked.
Model hanging_limb(const Vector3& axis, JointType type, const Vector3& joint_axis, double length = 0.5) {
  Model model;
  Body body;
  body.name = "limb";
  body.shape = {ShapeType::capsule, length, 0.03};
  body.mass = 2;
  body.axis = axis.normalized();
  body.position = Vector3(0, 0, 1) - 0.5 * length * body.axis;
  model.bodies.push_back(body);
  Joint joint;
  joint.name = "joint";
  joint.type = type;
  joint.inboard = kWorld;
  joint.outboard = 0;
  joint.inboard_anchor = Vector3(0, 0, 1);
  joint.outboard_anchor = Vector3(0, 0, 0.5 * length);
  joint.axis = joint_axis;
  model.joints.push_back(joint);
  model.settings.time_step = 1.0 / 240;
  model.settings.sleep.enabled = false;
  model.settings.gravity.setZero();
  return model;
}

VerletOptions options_with(int iterations, ProjectionRule rule = ProjectionRule::pbd, int substeps = 1) {
  VerletOptions options;
  options.relaxation.iterations = iterations;
  options.relaxation.projection = rule;
  options.relaxation.substeps = substeps;
  return options;
}

template <typename Scalar>
Eigen::Vector3d position(const VerletState<Scalar>& state, std::uint32_t p) {
  return state.particles.position(p).template cast<double>();
}

// Body b's pose as the joint measures read it: its frame from the particles, its centre.
template <typename Scalar>
FramePose pose_of(const VerletState<Scalar>& state, std::size_t b) {
  const std::uint32_t limb = state.body_limb[b];
  const Eigen::Vector3d head = position(state, state.limbs.head[limb]), tail = position(state, state.limbs.tail[limb]);
  return {framed_orientation(state, b).value(), 0.5 * (head + tail)};
}

template <typename Scalar>
JointCoordinates coordinates(const VerletState<Scalar>& state, const Model& model, std::size_t k) {
  const Joint& joint = model.joints[k];
  const FramePose inboard = joint.inboard == kWorld ? FramePose{} : pose_of(state, static_cast<std::size_t>(joint.inboard));
  return joint_coordinates(joint, joint_frame(model, k), inboard, pose_of(state, static_cast<std::size_t>(joint.outboard)));
}

// Inertia of a particle limb about the world axis `axis` through `point`, kg·m².
template <typename Scalar>
double inertia_about(const VerletState<Scalar>& state, const Eigen::Vector3d& point, const Eigen::Vector3d& axis) {
  double inertia = 0;
  for (std::size_t p = 0; p < state.particles.size(); ++p) {
    if (state.particles.inverse_mass[p] == Scalar(0)) continue;
    inertia += state.particle_mass[p] * (position(state, static_cast<std::uint32_t>(p)) - point).cross(axis).squaredNorm();
  }
  return inertia;
}

template <typename Scalar>
class ParticleJointRows : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ParticleJointRows, Scalars);

TYPED_TEST(ParticleJointRows, AHingeKeepsItsAxis) {
  // A horizontal limb on a hinge about y, set spinning about z (out of the hinge's plane) and
  // falling under gravity: the hinge lets it turn about y only, so its axis stays in the x–z plane.
  Model model = hanging_limb(Vector3(-1, 0, 0), JointType::revolute, Vector3::UnitY());
  model.settings.gravity = Vector3(0, 0, -9.81);
  model.bodies[0].angular_velocity = Vector3(0, 0, 3);
  auto state = compile<TypeParam>(model, options_with(20));
  double out_of_plane = 0;
  for (int s = 0; s < 480; ++s) {
    ASSERT_EQ(step(state).status, StepStatus::ok);
    const Eigen::Vector3d axis = (position(state, state.limbs.head[0]) - position(state, state.limbs.tail[0])).normalized();
    // The start's spin is inconsistent with the hinge; the sweeps take it out over the first
    // steps (faster with more sweeps), then the axis stays in the plane.
    if (s >= 60) out_of_plane = std::max(out_of_plane, std::abs(axis.y()));
  }
  EXPECT_LT(out_of_plane, 1e-4) << "rad off the hinge's plane";
}

TYPED_TEST(ParticleJointRows, AHingeRangeHoldsThroughAFall) {
  // The limb starts horizontal (the hinge's zero) and falls; its range [-0.5, 0.5] rad stops it.
  for (const double dt : {1.0 / 60, 1.0 / 240}) {
    Model model = hanging_limb(Vector3(-1, 0, 0), JointType::revolute, Vector3::UnitY());
    model.settings.gravity = Vector3(0, 0, -9.81);
    model.settings.time_step = dt;
    model.joints[0].limits.range = Range{-0.5, 0.5};
    auto state = compile<TypeParam>(model, options_with(20));
    double past = 0, reached = 0;
    for (int s = 0; s < static_cast<int>(2 / dt); ++s) {
      ASSERT_EQ(step(state).status, StepStatus::ok);
      const JointCoordinates q = coordinates(state, model, 0);
      past = std::max(past, limit_violation(model.joints[0], q));
      reached = std::max(reached, std::abs(q.angle));
    }
    EXPECT_GT(reached, 0.45) << "it fell onto the limit";
    EXPECT_LT(past, 2e-3) << "rad past the range at dt " << dt;
  }
}

TEST(ParticleJoints, AHingedPendulumKeepsItsEnergyUnderTheRattleRule) {
  // A framed limb swinging on a hinge for 10 s at 1/60 s (8 substeps of 4 sweeps): the rattle
  // rule's energy error stays bounded (its velocity stage projects the hinge's rows too), where
  // the pbd rule drains it.
  const auto drift = [](ProjectionRule rule) {
    Model model = hanging_limb(Vector3(-1, 0, 0), JointType::revolute, Vector3::UnitY());
    model.settings.gravity = Vector3(0, 0, -9.81);
    model.settings.time_step = 1.0 / 60;
    auto state = compile<double>(model, options_with(4, rule, 8));
    const double start = observe(state).energy();
    double worst = 0;
    for (int s = 0; s < 600; ++s) {
      EXPECT_EQ(step(state).status, StepStatus::ok);
      worst = std::max(worst, std::abs(observe(state).energy() - start));
    }
    return worst / (2 * 9.81 * 0.5);  // of m·g·L
  };
  EXPECT_LT(drift(ProjectionRule::rattle), 1e-3);
  EXPECT_GT(drift(ProjectionRule::pbd), 0.1);
}

TYPED_TEST(ParticleJointRows, SwingAndTwistLimitsHoldASpinningLimb) {
  // A hanging limb thrown sideways and spun about its own axis: its axis stays inside the
  // 0.6 rad cone (centred on its rest axis, or tilted 0.3 rad off it) and its twist about the
  // cone's axis inside [-0.2, 0.2], as joint_coordinates measures them.
  const Vector3 tilted = Eigen::AngleAxisd(0.3, Vector3::UnitY()) * Vector3::UnitZ();
  for (const std::optional<Vector3>& cone : {std::optional<Vector3>(), std::optional<Vector3>(tilted)}) {
    Model model = hanging_limb(Vector3(0, 0, 1), JointType::spherical, Vector3::UnitX());
    model.settings.gravity = Vector3(0, 0, -9.81);
    model.bodies[0].angular_velocity = Vector3(8, 0, 10);
    model.joints[0].limits.swing = 0.6;
    model.joints[0].limits.swing_axis = cone;
    model.joints[0].limits.twist = Range{-0.2, 0.2};
    auto state = compile<TypeParam>(model, options_with(20));
    double past = 0, swing = 0, twist = 0;
    for (int s = 0; s < 480; ++s) {
      ASSERT_EQ(step(state).status, StepStatus::ok);
      const JointCoordinates q = coordinates(state, model, 0);
      past = std::max(past, limit_violation(model.joints[0], q));
      swing = std::max(swing, q.swing), twist = std::max(twist, std::abs(q.twist));
    }
    const char* name = cone ? "tilted cone" : "cone at rest";
    EXPECT_GT(swing, 0.55) << name << ": it reached the cone";
    EXPECT_GT(twist, 0.15) << name << ": it reached the twist limit";
    EXPECT_LT(past, 5e-3) << name << ": rad past a limit";
  }
}

TEST(ParticleJoints, FrictionInAHingeDeceleratesAtTorqueOverInertia) {
  // A limb spinning about a vertical hinge, gravity off. Joint friction τ_f takes angular speed
  // away at τ_f/I per second (Coulomb: constant torque), measured against the same limb
  // without friction so the method's own dissipation cancels, and then holds it still.
  const auto run = [](double friction, std::vector<double>& angle) {
    Model model = hanging_limb(Vector3(-1, 0, 0), JointType::revolute, Vector3::UnitZ());
    model.bodies[0].angular_velocity = Vector3(0, 0, 4);
    model.joints[0].friction = friction;
    auto state = compile<double>(model, options_with(4, ProjectionRule::rattle, 4));
    const double inertia = inertia_about(state, Vector3(0, 0, 1), Vector3::UnitZ());
    double unwrapped = 0, previous = 0;
    for (int s = 0; s < 480; ++s) {
      EXPECT_EQ(step(state).status, StepStatus::ok);
      const Eigen::Vector3d d = position(state, state.limbs.tail[0]) - Eigen::Vector3d(0, 0, 1);
      const double now = std::atan2(d.y(), d.x());
      unwrapped += std::remainder(now - previous, 2 * kPi), previous = now;
      angle.push_back(unwrapped);
    }
    return inertia;
  };
  std::vector<double> free, braked;
  const double friction = 0.6;
  const double inertia = run(0, free);
  run(friction, braked);
  const double dt = 1.0 / 240, deceleration = friction / inertia;  // rad/s²
  // The hinge keeps only part of the start's spin (the world anchor stops the head): the free
  // limb's steady rate is the speed friction has to take away.
  const double speed = (free.back() - free[free.size() / 2]) / ((free.size() - 1 - free.size() / 2) * dt);
  const double stop = speed / deceleration;
  ASSERT_LT(stop, 1.6) << "the test needs the limb to stop within the run";
  // Before it stops the lag grows as ½·(τ_f/I)·t².
  for (const double t : {0.25 * stop, 0.5 * stop, 0.9 * stop}) {
    const auto s = static_cast<std::size_t>(t / dt) - 1;
    const double lag = free[s] - braked[s];
    EXPECT_NEAR(lag, 0.5 * deceleration * t * t, 0.05 * 0.5 * deceleration * t * t) << "at t = " << t << " s";
  }
  // After it stops it stays.
  const auto still = static_cast<std::size_t>((stop + 0.1) / dt);
  EXPECT_NEAR(braked.back(), braked[still], 1e-3);
}

TEST(ParticleJoints, AHingeDriveSettlesWithTheStatedDampingRatio) {
  // A hinge drive (k, c) on a limb of inertia I about the hinge, gravity off: a damped
  // oscillator toward the target with ζ = c/(2√(kI)). The logarithmic decrement of successive
  // overshoots gives the measured ζ.
  Model model = hanging_limb(Vector3(-1, 0, 0), JointType::revolute, Vector3::UnitZ());
  model.settings.time_step = 1.0 / 1000;
  JointDrive drive;
  drive.stiffness = 40, drive.target = 0.3;
  model.joints[0].drive = drive;
  auto probe = compile<double>(model, options_with(10));
  const double inertia = inertia_about(probe, Vector3(0, 0, 1), Vector3::UnitZ());
  const double zeta = 0.2;
  model.joints[0].drive->damping = 2 * zeta * std::sqrt(drive.stiffness * inertia);
  auto state = compile<double>(model, options_with(10));
  std::vector<double> error;
  for (int s = 0; s < 4000; ++s) {
    ASSERT_EQ(step(state).status, StepStatus::ok);
    error.push_back(coordinates(state, model, 0).angle - drive.target);
  }
  std::vector<double> peaks;  // |error| at successive extrema
  for (std::size_t s = 1; s + 1 < error.size(); ++s) {
    if ((error[s] - error[s - 1]) * (error[s + 1] - error[s]) < 0) peaks.push_back(std::abs(error[s]));
  }
  ASSERT_GE(peaks.size(), 3u);
  const double decrement = std::log(peaks[0] / peaks[1]);  // half a period apart: πζ/√(1−ζ²)
  const double measured = decrement / std::sqrt(kPi * kPi + decrement * decrement);
  EXPECT_NEAR(measured, zeta, 0.1 * zeta);
  EXPECT_LT(std::abs(error.back()), 1e-3) << "rad from the target at the end";
}

TYPED_TEST(ParticleJointRows, AStiffDriveStaysStableAtLargeSteps) {
  // k·h²/I ≫ 1 at 1/60 s, which an explicit PD cannot take: the compliant row is implicit.
  Model model = hanging_limb(Vector3(-1, 0, 0), JointType::revolute, Vector3::UnitZ());
  model.settings.time_step = 1.0 / 60;
  JointDrive drive;
  drive.stiffness = 1e5, drive.damping = 10, drive.target = 0.5;
  model.joints[0].drive = drive;
  auto state = compile<TypeParam>(model, options_with(20));
  for (int s = 0; s < 120; ++s) ASSERT_EQ(step(state).status, StepStatus::ok);
  EXPECT_NEAR(coordinates(state, model, 0).angle, 0.5, 1e-2);
}

TEST(ParticleJoints, ASphericalDriveReachesItsTargetRotation) {
  Model model = hanging_limb(Vector3(0, 0, 1), JointType::spherical, Vector3::UnitX());
  JointDrive drive;
  drive.stiffness = 50, drive.damping = 5;
  drive.target_rotation = Vector3(0.4, -0.3, 0.2);
  model.joints[0].drive = drive;
  auto state = compile<double>(model, options_with(20));
  for (int s = 0; s < 960; ++s) ASSERT_EQ(step(state).status, StepStatus::ok);
  const JointFrame frame = joint_frame(model, 0);
  EXPECT_LT(drive_error(model.joints[0], frame, coordinates(state, model, 0)), 0.02) << "rad from the target";
}

// A torso with an arm hung from a point off its axis, below its top end (thesis 4.5.2's missing arms).
Model torso_and_arm() {
  Model model;
  Body torso;
  torso.name = "torso", torso.shape = {ShapeType::capsule, 0.4, 0.1}, torso.mass = 30, torso.position = Vector3(0, 0, 1);
  Body arm;
  arm.name = "arm", arm.shape = {ShapeType::capsule, 0.3, 0.04}, arm.mass = 3;
  const Vector3 shoulder = torso.to_world(Vector3(0, 0.15, 0.12));
  arm.axis = Vector3(0, 0, 1), arm.position = shoulder - Vector3(0, 0, 0.15);
  model.bodies = {torso, arm};
  Joint joint = spherical_joint("shoulder", 0, 1, Vector3(0, 0.15, 0.12), Vector3(0, 0, 0.15));
  model.joints.push_back(joint);
  model.settings.time_step = 1.0 / 240;
  model.settings.sleep.enabled = false;
  model.settings.gravity.setZero();
  return model;
}

TEST(ParticleJoints, AnArmAnchoredMidLimbKeepsItsAnchorAndTheMomentum) {
  Model model = torso_and_arm();
  std::mt19937 random(7);
  std::uniform_real_distribution<double> speed(-2, 2);
  for (Body& body : model.bodies) {
    body.linear_velocity = Vector3(speed(random), speed(random), speed(random));
    body.angular_velocity = 3 * Vector3(speed(random), speed(random), speed(random));
  }
  auto state = compile<double>(model, options_with(30));
  // The particles reproduce each limb's mass and centre of mass, frame particles included.
  for (std::size_t b = 0; b < 2; ++b) {
    double mass = 0;
    Eigen::Vector3d moment = Eigen::Vector3d::Zero();
    for (std::size_t p = 0; p < state.particles.size(); ++p) {
      if (state.particle_origins[p].kind == ParticleOrigin::Kind::world_pin || state.particle_origins[p].index != b) continue;
      mass += state.particle_mass[p], moment += state.particle_mass[p] * position(state, static_cast<std::uint32_t>(p));
    }
    EXPECT_NEAR(mass, model.bodies[b].mass, 1e-12);
    EXPECT_LT((moment / mass - model.bodies[b].position).norm(), 1e-12);
  }
  step(state);  // the first step makes the initial velocities ones the joint allows
  const Observation start = observe(state);
  double gap = 0;
  for (int s = 0; s < 2400; ++s) {
    ASSERT_EQ(step(state).status, StepStatus::ok);
    const FramePose torso = pose_of(state, 0);
    const Eigen::Vector3d shoulder = torso.position + torso.orientation * Eigen::Vector3d(0, 0.15, 0.12);
    const std::uint32_t arm = state.body_limb[1];
    gap = std::max(gap, (shoulder - position(state, state.limbs.head[arm])).norm());
  }
  EXPECT_LT(gap, 1e-3) << "m between the shoulder and the arm's head";
  // No gravity, no contacts: the weighted rows keep the linear momentum (Verlet's implicit
  // velocity) to rounding.
  EXPECT_LT((observe(state).linear_momentum - start.linear_momentum).norm(), 1e-9 * (1 + start.linear_momentum.norm()));
}

// Many small ragdoll-like chains (hinges, cones, twists, drives, friction, an off-axis anchor):
// enough rows for colours to be split across threads.
Model jointed_copies(int copies) {
  Model one = torso_and_arm();
  one.settings.gravity = Vector3(0, 0, -9.81);
  Body forearm;
  forearm.name = "forearm", forearm.shape = {ShapeType::capsule, 0.25, 0.03}, forearm.mass = 2;
  forearm.axis = Vector3(0, 0, 1);
  forearm.position = one.bodies[1].tail() - Vector3(0, 0, 0.125);
  one.bodies.push_back(forearm);
  Joint elbow;
  elbow.name = "elbow", elbow.type = JointType::revolute, elbow.inboard = 1, elbow.outboard = 2;
  elbow.inboard_anchor = Vector3(0, 0, -0.15), elbow.outboard_anchor = Vector3(0, 0, 0.125), elbow.axis = Vector3::UnitY();
  elbow.limits.range = Range{-2.4, 0};
  elbow.friction = 0.5;
  one.joints.push_back(elbow);
  one.joints[0].limits.swing = 1.2, one.joints[0].limits.twist = Range{-0.5, 0.5};
  JointDrive drive;
  drive.stiffness = 20, drive.damping = 2, drive.target_rotation = Vector3(0.5, 0, 0);
  one.joints[0].drive = drive;
  one.joints.push_back([] {
    Joint hold;
    hold.name = "hold", hold.type = JointType::fixed, hold.inboard = kWorld, hold.outboard = 0;
    hold.inboard_anchor = Vector3(0, 0, 1.2), hold.outboard_anchor = Vector3(0, 0, 0.2);
    return hold;
  }());
  Model model = one;
  model.bodies.clear(), model.joints.clear();
  for (int c = 0; c < copies; ++c) {
    std::string prefix = "c";  // appended, not "c" + std::string&&: GCC 12's -Wrestrict false positive (bug 105329)
    prefix.append(std::to_string(c)).append(".");
    append_model(model, one, prefix, Vector3(c % 40, c / 40, 0));
  }
  for (Body& body : model.bodies) body.angular_velocity = Vector3(1.5, -2, 0.7);
  return model;
}

template <typename Scalar>
std::vector<Scalar> run_positions(const Model& model, int threads, bool simd) {
  VerletOptions options = options_with(8);
  options.threads = threads, options.simd = simd, options.parallel_minimum_slots = 64;
  auto state = compile<Scalar>(model, options);
  for (int s = 0; s < 60; ++s) EXPECT_EQ(step(state).status, StepStatus::ok);
  return {state.particles.position_x.begin(), state.particles.position_x.end()};
}

TYPED_TEST(ParticleJointRows, JointRowsGiveTheSameBitsForOneOrTwoThreadsAndScalarOrSimd) {
  const Model model = jointed_copies(200);
  const auto one = run_positions<TypeParam>(model, 1, true);
  EXPECT_EQ(one, run_positions<TypeParam>(model, 2, true)) << "two threads";
  EXPECT_EQ(one, run_positions<TypeParam>(model, 1, false)) << "scalar lanes";
}

// The rows' angles use atan2_lanes, one polynomial for scalar and SIMD lanes: within 3 ulp of
// the exact angle (long double's atan2) in every quadrant and at every scale (the worst of these
// draws is about 2.1, next to tan(π/8), where the octant's reduction cancels), and each SIMD lane
// the bits of the scalar path.
TYPED_TEST(ParticleJointRows, TheRowsAtan2IsWithinThreeUlpAndTheSameInEveryLane) {
  using Scalar = TypeParam;
  using Simd = SimdLanes<Scalar>;
  using Bits = std::conditional_t<sizeof(Scalar) == 4, std::uint32_t, std::uint64_t>;
  std::mt19937 random(17);
  std::uniform_real_distribution<double> unit(-1, 1), scale(-6, 6);
  const auto ulp = [](Scalar angle) { return std::nextafter(std::abs(angle), Scalar(4)) - std::abs(angle); };
  double worst = 0;
  for (int trial = 0; trial < 20000 / static_cast<int>(Simd::size); ++trial) {
    alignas(64) Scalar ys[Simd::size], xs[Simd::size], lanes[Simd::size];
    for (std::size_t lane = 0; lane < Simd::size; ++lane) {
      const double size = std::pow(10.0, scale(random));
      ys[lane] = static_cast<Scalar>(size * unit(random)), xs[lane] = static_cast<Scalar>(size * unit(random));
    }
    if (trial == 0) ys[0] = 0, xs[0] = 1, ys[1] = 1, xs[1] = 0, ys[2] = 0, xs[2] = -1, ys[3] = -1, xs[3] = -1;  // the axes, a diagonal
    joint_projection::atan2_lanes<Simd>(Simd::load(ys), Simd::load(xs)).store_aligned(lanes);
    for (std::size_t lane = 0; lane < Simd::size; ++lane) {
      const Scalar angle = joint_projection::atan2_lanes<ScalarLanes<Scalar>>(ys[lane], xs[lane]);
      ASSERT_EQ(std::bit_cast<Bits>(lanes[lane]), std::bit_cast<Bits>(angle))
          << "lane " << lane << ": atan2(" << ys[lane] << ", " << xs[lane] << ")";
      const long double exact = std::atan2(static_cast<long double>(ys[lane]), static_cast<long double>(xs[lane]));
      const double error = static_cast<double>(std::abs(static_cast<long double>(angle) - exact) / ulp(static_cast<Scalar>(exact)));
      worst = std::max(worst, error);
      ASSERT_LE(error, 3.0) << "atan2(" << ys[lane] << ", " << xs[lane] << ") = " << angle << ", exact " << static_cast<double>(exact);
    }
  }
  this->RecordProperty("worst_ulp", std::to_string(worst));
}

// A limit's measure (joint_projection::measure) gives its angle and the axis B turns about to
// increase it, which the rows and the trees project along: it must be the angle's gradient with
// respect to B's rotation (A held), or a projection along it moves the joint off the path that
// closes the limit, and a joint pressed against its limit gains energy step after step. Checked
// against central differences at random frames, swung up to 2.5 rad, for every kind of limit.
TEST(ParticleJoints, EachLimitsAxisIsTheGradientOfItsAngle) {
  using Lanes = ScalarLanes<double>;
  using Vec = joint_projection::Vec3<double>;
  std::mt19937 random(17);
  std::uniform_real_distribution<double> draw(-1, 1);
  const auto unit = [&] { return Eigen::Vector3d(draw(random), draw(random), draw(random)).normalized(); };
  const auto vec = [](const Eigen::Vector3d& x) { return Vec{x.x(), x.y(), x.z()}; };
  JointRowBatches<double> batches;
  const std::size_t slot = batches.push(0);
  for (const JointRowKind kind : {JointRowKind::swing, JointRowKind::twist, JointRowKind::hinge}) {
    for (int trial = 0; trial < 200; ++trial) {
      // Directions in each side's frame coordinates: the limit's axis (the hinge's along A's u;
      // the cone's, which the twist is about, anywhere), a reference ⟂ it in A, one in B.
      const Eigen::Vector3d d1 = kind == JointRowKind::hinge ? Eigen::Vector3d::UnitZ() : unit();
      const Eigen::Vector3d r = unit();
      const Eigen::Vector3d d2 = (r - r.dot(d1) * d1).normalized();
      const Eigen::Vector3d e = Eigen::Vector3d(draw(random), draw(random), kind == JointRowKind::hinge ? 0.3 * draw(random) : 0).normalized();
      for (int k = 0; k < 3; ++k) batches.direction[k][slot] = d1[k], batches.direction[3 + k][slot] = d2[k], batches.direction[6 + k][slot] = e[k];
      const Eigen::Matrix3d a = Eigen::AngleAxisd(3 * draw(random), unit()).toRotationMatrix();
      const Eigen::Matrix3d b = Eigen::AngleAxisd(2.5 * std::abs(draw(random)), unit()).toRotationMatrix() * a;
      const auto angle = [&](const Eigen::Matrix3d& frame_b) {
        return joint_projection::measure<Lanes, double>(kind, batches, slot, vec(a.col(0)), vec(a.col(1)), vec(a.col(2)), vec(frame_b.col(0)),
                                                        vec(frame_b.col(1)), vec(frame_b.col(2)));
      };
      const joint_projection::Measure<double> measured = angle(b);
      const double step = 1e-6;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Matrix3d turn = Eigen::AngleAxisd(step, Eigen::Vector3d::Unit(k)).toRotationMatrix();
        const double plus = angle(turn * b).value, minus = angle(turn.transpose() * b).value;
        if (std::abs(plus - minus) > 1) continue;  // across the ±π cut of the angle
        const double axis[3] = {measured.axis.x, measured.axis.y, measured.axis.z};
        EXPECT_NEAR(axis[k], (plus - minus) / (2 * step), 1e-6) << "kind " << int(kind) << ", trial " << trial << ", component " << k;
      }
    }
  }
}

TEST(ParticleJoints, WhatParticlesCannotRepresentIsRefusedByName) {
  Model prismatic = hanging_limb(Vector3(0, 0, 1), JointType::prismatic, Vector3::UnitZ());
  EXPECT_THROW(
      {
        try {
          compile<double>(prismatic, options_with(4));
        } catch (const ModelError& error) {
          EXPECT_NE(std::string(error.what()).find("joints[0] 'joint'"), std::string::npos) << error.what();
          throw;
        }
      },
      ModelError);
  Model hinge = hanging_limb(Vector3(0, 0, 1), JointType::revolute, Vector3::UnitX());
  VerletOptions shared = options_with(4);
  shared.verlet.joints = limber::ParticleJoints::shared_particle;
  EXPECT_THROW(compile<double>(hinge, shared), ModelError);
  VerletOptions jacobi = options_with(4);
  jacobi.solver = RelaxationSolver::jacobi;
  EXPECT_THROW(compile<double>(hinge, jacobi), std::invalid_argument);
  VerletOptions unweighted = options_with(4);
  unweighted.rule = RelaxationRule::unweighted;
  EXPECT_THROW(compile<double>(hinge, unweighted), std::invalid_argument);
  // Two off-axis anchors on one limb out of one plane through its axis.
  Model torso = torso_and_arm();
  torso.bodies.push_back(torso.bodies[1]);
  torso.bodies.back().name = "other_arm";
  torso.joints.push_back(spherical_joint("other", 0, 2, Vector3(0.15, 0.0, 0.12), Vector3(0, 0, 0.15)));
  torso.bodies.back().position = torso.bodies[0].to_world(Vector3(0.15, 0, 0.12)) - Vector3(0, 0, 0.15);
  EXPECT_THROW(compile<double>(torso, options_with(4)), ModelError);
}

}  // namespace
}  // namespace limber
