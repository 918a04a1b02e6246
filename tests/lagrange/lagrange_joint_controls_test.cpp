// Joint limits, friction and drives in the Lagrange method (kernel/lagrange/joint_controls.hpp):
// measured with the shared joint coordinates (kernel/model/joint_coordinates.hpp) — limits hold,
// friction decelerates at τ_f/I and then holds, a drive settles on its target with the damping
// ratio c/(2√(kI)) and stays stable when stiff; the tree and sparse solves agree; a step with
// control rows allocates nothing; what cannot be applied is refused by name.

// GCC 12 false positives inside Eigen's AVX-512 reductions over fixed-capacity vectors (a
// relative of bug 105593); must precede Eigen's headers.
#pragma GCC diagnostic ignored "-Warray-bounds"
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/lagrange/compile.hpp"
#include "limber/kernel/lagrange/constraints.hpp"
#include "limber/kernel/lagrange/multipliers.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "limber/kernel/model/joint_coordinates.hpp"
#include "tests/support/allocation_counter.hpp"
#include "tests/support/models.hpp"
#include "tests/support/oscillation.hpp"

namespace limber {
namespace {

constexpr double kPi = std::numbers::pi;

// One rod (cylinder, 1 kg, 1 m, radius 1 cm) whose head is held at the origin by `type`, lying
// along +x (so it falls about the y axis).
Model rod_on(JointType type, const Vector3& axis = Vector3::UnitY()) { return testing::rod_held_at_head(type, axis); }

// The rod's moment of inertia about an axis across it through its end, kg·m².
constexpr double kEndInertia = 1.0 / 3 + 0.01 * 0.01 / 4;

// Joint k's coordinates at the state's poses.
JointCoordinates coordinates(const LagrangeState& state, std::size_t k) {
  const Joint& joint = state.joint_controls.joints[k];
  const FramePose inboard = model_frame_pose(state, state.bodies.state, joint.inboard);
  const FramePose outboard = model_frame_pose(state, state.bodies.state, joint.outboard);
  return joint_coordinates(joint, state.joint_controls.frames[k], inboard, outboard);
}

double limit_excess(const LagrangeState& state, std::size_t k) {
  return limit_violation(state.joint_controls.joints[k], coordinates(state, k));
}

// The options every test runs: the default velocity-level step under both stabilizations, and
// RK4 at the acceleration level.
struct Case {
  LagrangeOptions options;
  const char* name;
};
const Case kCases[] = {
    {{}, "symplectic Euler, Baumgarte"},
    {{.stabilization = Stabilization::projection}, "symplectic Euler, projection"},
    {{.integrator = Integrator::rk4}, "RK4, Baumgarte"},
    {{.integrator = Integrator::rk4, .stabilization = Stabilization::projection}, "RK4, projection"},
};

// The largest tolerated excess past a limit, rad (or m): a velocity-level step reaches a limit
// speculatively (to first order in the step's rotation), the acceleration-level RK4 holds it once
// reached, and projection stabilization projects it back to rounding.
double tolerance(const Case& test, double dt) {
  if (test.options.stabilization == Stabilization::projection) return 1e-4;
  return dt > 0.01 ? 0.03 : 0.005;
}

TEST(LagrangeJointLimits, HingeRangeStopsAFallingPendulum) {
  // A rod hinged at its end (about y), released horizontally: it falls to +0.5 rad and is held
  // there, without passing the limit (no bounce: restitution 0).
  Model model = rod_on(JointType::revolute);
  model.joints[0].limits.range = Range{-0.5, 0.5};
  for (const Case& test : kCases) {
    for (const double dt : {1.0 / 60, 1.0 / 240}) {
      LagrangeState state = compile_lagrange(model, test.options);
      double worst = 0, largest = 0;
      for (int s = 0; s < static_cast<int>(2 / dt); ++s) {
        step(state, dt);
        worst = std::max(worst, limit_excess(state, 0));
        largest = std::max(largest, coordinates(state, 0).angle);
      }
      EXPECT_LT(worst, tolerance(test, dt)) << test.name << ", dt " << dt;
      EXPECT_GT(largest, 0.5 - 1e-6) << test.name << ", dt " << dt;  // it reached the limit
      EXPECT_NEAR(coordinates(state, 0).angle, 0.5, 1e-6) << test.name << ", dt " << dt;  // and rests on it
      EXPECT_LT(state.bodies.angular_velocity(state.bodies.state, 0).norm(), 1e-6) << test.name << ", dt " << dt;
      EXPECT_LT(state.last_report.constraint_error, 1e-6) << test.name << ", dt " << dt;
    }
  }
}

// A rod on a spherical joint, swing ≤ 0.6 rad about `cone` (unset: its axis at rest), twist in
// [−0.2, 0.2]: gravity swings it down (π/2 from rest), and it is thrown sideways and spun fast
// about its own axis (12 rad/s: 0.2 rad per 1/60 s step).
Model swinging_spherical_rod(std::optional<Vector3> cone) {
  Model model = rod_on(JointType::spherical);
  model.joints[0].limits.swing = 0.6;
  model.joints[0].limits.swing_axis = cone;
  model.joints[0].limits.twist = Range{-0.2, 0.2};
  model.bodies[0].angular_velocity = Vector3(-12, 0, 3);  // −x: about its own axis; z: sideways
  model.bodies[0].linear_velocity = Vector3(0, 1.5, 0);
  return model;
}

TEST(LagrangeJointLimits, SphericalSwingConeAndTwistRangeHold) {
  // The cone centred on the rest axis, and tilted 0.3 rad off it (the rest axis inside).
  const Vector3 tilted = Eigen::AngleAxisd(0.3, Vector3::UnitY()) * -Vector3::UnitX();
  for (const std::optional<Vector3>& cone : {std::optional<Vector3>(), std::optional<Vector3>(tilted)}) {
    for (const Case& test : kCases) {
      for (const double dt : {1.0 / 60, 1.0 / 240}) {
        // RK4 integrates the thin rod's spin (axial moment 5·10⁻⁵ kg·m²) explicitly: only at the small step.
        if (test.options.integrator == Integrator::rk4 && test.options.stabilization == Stabilization::baumgarte && dt > 0.01) continue;
        LagrangeState state = compile_lagrange(swinging_spherical_rod(cone), test.options);
        double swing = 0, twist = 0, largest_swing = 0;
        for (int s = 0; s < static_cast<int>(3 / dt); ++s) {
          step(state, dt);
          const JointCoordinates q = coordinates(state, 0);
          swing = std::max(swing, q.swing - 0.6);
          twist = std::max(twist, std::abs(q.twist) - 0.2);
          largest_swing = std::max(largest_swing, q.swing);
        }
        const std::string name = std::string(cone ? "tilted cone, " : "cone at rest, ") + test.name + ", dt " + std::to_string(dt);
        EXPECT_LT(swing, tolerance(test, dt)) << name;
        EXPECT_LT(twist, tolerance(test, dt)) << name;
        EXPECT_GT(largest_swing, 0.6 - 1e-3) << name;  // it did reach the cone
        EXPECT_LT(state.last_report.constraint_error, tolerance(test, dt)) << name;
      }
    }
  }
}

TEST(LagrangeJointLimits, PrismaticTravelHoldsASlidingBodyAtItsEnd) {
  // A vertical slide (down is +): the rod falls 0.25 m and stays at range.max.
  Model model = rod_on(JointType::prismatic, -Vector3::UnitZ());
  model.joints[0].limits.range = Range{-0.1, 0.25};
  for (const Case& test : kCases) {
    for (const double dt : {1.0 / 60, 1.0 / 240}) {
      LagrangeState state = compile_lagrange(model, test.options);
      double worst = 0;
      for (int s = 0; s < static_cast<int>(2 / dt); ++s) {
        step(state, dt);
        worst = std::max(worst, limit_excess(state, 0));
      }
      EXPECT_LT(worst, 1e-6) << test.name << ", dt " << dt;  // a slide is linear: every form holds it
      EXPECT_NEAR(coordinates(state, 0).slide, 0.25, 1e-9) << test.name << ", dt " << dt;
      EXPECT_LT(state.bodies.linear_velocity(state.bodies.state, 0).norm(), 1e-9) << test.name << ", dt " << dt;
    }
  }
}

TEST(LagrangeJointLimits, ALimitDoesNotHoldAwayFromIt) {
  // One-sided: a hinged rod resting on its limit is lifted off it by an upward push.
  Model model = rod_on(JointType::revolute);
  model.joints[0].limits.range = Range{-0.5, 0.0};  // horizontal is the upper limit: gravity presses on it
  for (const Case& test : kCases) {
    LagrangeState state = compile_lagrange(model, test.options);
    for (int s = 0; s < 60; ++s) step(state, 1.0 / 240);
    EXPECT_NEAR(coordinates(state, 0).angle, 0, 1e-6) << test.name;
    state.applied_torque[0] = Vector3(0, -10, 0);  // lifts (about −y), more than gravity's 4.9 N·m
    step(state, 1.0 / 240);
    EXPECT_LT(coordinates(state, 0).angle, -1e-4) << test.name;
  }
}

// The rod's angular velocity about the world y axis.
double spin(const LagrangeState& state) { return state.bodies.angular_velocity(state.bodies.state, 0).y(); }

TEST(LagrangeJointFriction, FrictionDeceleratesAtTorqueOverInertiaThenHolds) {
  // Gravity off, the rod spinning about y through its hinged end at 3 rad/s: friction τ_f
  // takes ω down at τ_f/I (a straight line), then holds it at 0. A spherical joint's friction
  // (a disc of radius τ_f) does the same to a spin about one axis.
  for (const JointType type : {JointType::revolute, JointType::spherical}) {
    Model model = rod_on(type);
    model.settings.gravity.setZero();
    const double friction = 0.5, start = 3;  // N·m, rad/s
    model.joints[0].friction = friction;
    model.bodies[0].angular_velocity = Vector3(0, start, 0);
    model.bodies[0].linear_velocity = Vector3(0, 0, -0.5 * start);
    const double deceleration = friction / kEndInertia, stop = start / deceleration;  // 1.5 rad/s², 2 s
    for (const Case& test : kCases) {
      const double dt = 1.0 / 240;
      const std::string name = std::string(joint_type_name(type)) + ", " + test.name;
      LagrangeState state = compile_lagrange(model, test.options);
      std::vector<double> speed;  // after each step
      for (int s = 0; s < static_cast<int>(3 / dt); ++s) {
        step(state, dt);
        speed.push_back(spin(state));
      }
      const auto at = [&](double t) { return speed[static_cast<std::size_t>(std::lround(t / dt)) - 1]; };
      // The mean deceleration over the first and the second half of the slide, within 2 %.
      EXPECT_NEAR((at(0.1) - at(0.9)) / 0.8, deceleration, 0.02 * deceleration) << name;
      EXPECT_NEAR((at(1.0) - at(1.8)) / 0.8, deceleration, 0.02 * deceleration) << name;
      for (std::size_t s = static_cast<std::size_t>((stop + 0.05) / dt); s < speed.size(); ++s) {
        ASSERT_LT(std::abs(speed[s]), 1e-9) << name << ", step " << s;  // stopped, and stays stopped
      }
    }
  }
}

TEST(LagrangeJointFriction, FrictionHoldsBelowItsBoundAndSlidesAbove) {
  // A hinged rod held horizontal against gravity's m·g·L/2 = 4.905 N·m by friction alone: 5 N·m
  // holds it still, 4 N·m lets it fall.
  for (const Case& test : kCases) {
    for (const double friction : {5.0, 4.0}) {
      Model model = rod_on(JointType::revolute);
      model.joints[0].friction = friction;
      LagrangeState state = compile_lagrange(model, test.options);
      for (int s = 0; s < 240; ++s) step(state, 1.0 / 240);
      const double angle = coordinates(state, 0).angle;
      if (friction > 4.905) EXPECT_LT(std::abs(angle), 1e-6) << test.name;
      else EXPECT_GT(angle, 0.05) << test.name;
    }
  }
}

TEST(LagrangeJointDrives, HingeDriveSettlesWithItsDampingRatio) {
  // Gravity off; a PD drive of k = 40 N·m/rad, c = 2ζ√(kI) with ζ = 0.2 pulls the rod (I about
  // its hinged end) from 0 to 0.3 rad: the logarithmic decrement of the overshoots gives ζ back.
  Model model = rod_on(JointType::revolute);
  model.settings.gravity.setZero();
  const double stiffness = 40, zeta = 0.2, target = 0.3;
  const double damping = 2 * zeta * std::sqrt(stiffness * kEndInertia);
  model.joints[0].drive = JointDrive{.stiffness = stiffness, .damping = damping, .target = target};
  for (const Case& test : kCases) {
    const double dt = 1e-3;
    LagrangeState state = compile_lagrange(model, test.options);
    std::vector<double> error;
    for (int s = 0; s < 4000; ++s) {
      step(state, dt);
      error.push_back(coordinates(state, 0).angle - target);
    }
    const std::vector<double> peaks = testing::maxima(error);
    ASSERT_GE(peaks.size(), 3u) << test.name;
    const double measured = testing::damping_ratio(peaks[0], peaks[1]);
    EXPECT_NEAR(measured, zeta, 0.1 * zeta) << test.name;
    EXPECT_LT(std::abs(error.back()), 1e-4) << test.name;  // settled (e^(−ζω·4 s) ≈ 10⁻⁴ of 0.3)
  }
}

TEST(LagrangeJointDrives, AStiffDriveStaysStableAtALargeStep) {
  // k·h²/I = 100 at h = 1/60 s, no damping: the implicit (compliant) row settles on the target
  // (an explicit PD step would multiply the error by ~100 per step).
  Model model = rod_on(JointType::revolute);
  model.settings.gravity.setZero();
  const double dt = 1.0 / 60, target = 0.3;
  model.joints[0].drive = JointDrive{.stiffness = 100 * kEndInertia / (dt * dt), .target = target};
  for (const Case& test : kCases) {
    LagrangeState state = compile_lagrange(model, test.options);
    double largest = 0;
    for (int s = 0; s < 120; ++s) {
      ASSERT_EQ(step(state, dt).status, StepStatus::ok) << test.name;
      largest = std::max(largest, std::abs(coordinates(state, 0).angle));
    }
    EXPECT_LT(largest, 1.05 * target) << test.name;
    EXPECT_NEAR(coordinates(state, 0).angle, target, 1e-6) << test.name;
  }
}

TEST(LagrangeJointDrives, PrismaticDriveHoldsAgainstGravity) {
  // A vertical slide (down is +) driven to 0.1 m: it settles where k·(target − x) carries m·g —
  // exactly with the velocity-level step; RK4, whose drive acts as an impulse before each step
  // while gravity acts through it, within that splitting's first-order error (k·h + c)·g·h/k.
  Model model = rod_on(JointType::prismatic, -Vector3::UnitZ());
  const double stiffness = 2000, damping = 60, g = 9.81, dt = 1.0 / 240;
  model.joints[0].drive = JointDrive{.stiffness = stiffness, .damping = damping, .target = 0.1};
  for (const Case& test : kCases) {
    LagrangeState state = compile_lagrange(model, test.options);
    for (int s = 0; s < 960; ++s) step(state, dt);
    const double bound = test.options.integrator == Integrator::rk4 ? (stiffness * dt + damping) * g * dt / stiffness : 1e-6;
    EXPECT_NEAR(coordinates(state, 0).slide, 0.1 + g / stiffness, bound) << test.name;
  }
}

TEST(LagrangeJointDrives, SphericalDriveTurnsTheLimbToItsTarget) {
  // Two rods in free fall (gravity off), tumbling; the second is driven relative to the first
  // to a target rotation given in world axes at rest (carried by the first rod).
  Model model = testing::make_chain({1, 2}, 0.5, false);
  model.settings.gravity.setZero();
  model.joints[0].drive = JointDrive{.stiffness = 20, .damping = 3, .target_rotation = Vector3(0.3, -0.5, 0.8)};
  model.bodies[0].angular_velocity = Vector3(0.5, 0, 1);
  for (const Case& test : kCases) {
    LagrangeState state = compile_lagrange(model, test.options);
    const Joint& joint = state.joint_controls.joints[0];
    const JointFrame& frame = state.joint_controls.frames[0];
    EXPECT_NEAR(drive_error(joint, frame, coordinates(state, 0)), Vector3(0.3, -0.5, 0.8).norm(), 1e-9);
    for (int s = 0; s < 2400; ++s) step(state, 1.0 / 240);
    EXPECT_LT(drive_error(joint, frame, coordinates(state, 0)), 1e-3) << test.name;
  }
}

TEST(LagrangeJointDrives, ADriveChangedBetweenStepsIsFollowed) {
  // The World writes a new drive into state.joint_controls between steps: the step reads it.
  Model model = rod_on(JointType::revolute);
  model.settings.gravity.setZero();
  model.joints[0].drive = JointDrive{.stiffness = 50, .damping = 10, .target = 0.3};
  LagrangeState state = compile_lagrange(model);
  for (int s = 0; s < 480; ++s) step(state, 1.0 / 240);
  EXPECT_NEAR(coordinates(state, 0).angle, 0.3, 1e-3);
  state.joint_controls.joints[0].drive->target = -0.4;
  for (int s = 0; s < 480; ++s) step(state, 1.0 / 240);
  EXPECT_NEAR(coordinates(state, 0).angle, -0.4, 1e-3);
}

// Two rods joined by `type` with every control it takes, the first pinned to the world by a
// spherical joint; a general pose and velocities.
Model controlled_pair(JointType type) {
  Model model = testing::make_chain({1, 2}, 0.5, true);
  Joint& joint = model.joints[1];
  joint.type = type;
  joint.axis = Vector3(0.3, 0.8, -0.2).normalized();
  if (type == JointType::spherical) {
    joint.limits.swing = 0.3;
    joint.limits.twist = Range{-0.1, 0.1};
    joint.drive = JointDrive{.stiffness = 5, .damping = 1, .target_rotation = Vector3(0.1, 0.2, 0)};
  } else {
    joint.limits.range = Range{-0.1, 0.1};
    joint.drive = JointDrive{.stiffness = 5, .damping = 1, .target = 0.2};
  }
  joint.friction = 0.3;
  model.bodies[0].angular_velocity = Vector3(0.3, -1, 2);
  model.bodies[1].angular_velocity = Vector3(-2, 1, 0.5);
  model.bodies[1].linear_velocity = Vector3(0.2, 0.1, -0.3);
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

TEST(LagrangeJointControls, RowRatesAreTheRatesOfTheMeasuredCoordinates) {
  // Each row's rate J·u is the time derivative of the coordinate joint_coordinates() measures
  // (hinge angle, slide, swing; the twist's times 1/cos(swing/2), |(a + a₀)/(1 + a·a₀)|), and
  // its J̇u the second derivative's velocity part: central differences along constant velocities.
  for (const JointType type : {JointType::revolute, JointType::prismatic, JointType::spherical}) {
    LagrangeState state = compile_lagrange(controlled_pair(type));
    RigidBodyState y = state.bodies.state;
    for (std::size_t b = 0; b < y.size(); ++b) {
      y.orientation[b] = (rotation_quaternion(Eigen::Vector3d(0.2, -0.3, 0.25) * (b + 1.0)) * y.orientation[b]).normalized();
    }
    const std::vector<Eigen::Vector3d> velocity = {Eigen::Vector3d(0.3, -0.2, 0.1), Eigen::Vector3d(-0.4, 0.5, 0.2)};
    const std::vector<Eigen::Vector3d> angular_velocity = {Eigen::Vector3d(0.7, -0.4, 1.1), Eigen::Vector3d(-1.3, 0.6, 0.9)};
    const auto measured = [&](const RigidBodyState& at) {
      JointControlSet set = state.controls;
      measure_joint_controls(state, state.joints, state.joint_controls, at, velocity, angular_velocity, set);
      state.bodies.state = at;
      return std::pair{set, coordinates(state, 1)};
    };
    const double h = 1e-5;
    const auto [set, q] = measured(y);
    const auto [set_before, q_before] = measured(moved(y, velocity, angular_velocity, -h));
    const auto [set_after, q_after] = measured(moved(y, velocity, angular_velocity, h));
    const auto derivative = [&](double before, double after) { return (after - before) / (2 * h); };
    const auto second = [&](double before, double at, double after) { return (after - 2 * at + before) / (h * h); };
    const ControlledJoint& joint = set.joints.at(0);
    const std::string name(joint_type_name(type));
    if (type == JointType::revolute) {
      const ControlRow& row = set.rows[0];
      EXPECT_NEAR(row.rate, derivative(q_before.angle, q_after.angle), 1e-7) << name;
      EXPECT_NEAR(row.velocity_product, second(q_before.angle, q.angle, q_after.angle), 1e-3) << name;
    } else if (type == JointType::prismatic) {
      const ControlRow& row = set.rows[0];
      EXPECT_NEAR(row.rate, derivative(q_before.slide, q_after.slide), 1e-7) << name;
      EXPECT_NEAR(row.velocity_product, second(q_before.slide, q.slide, q_after.slide), 1e-3) << name;
    } else {
      const ControlRow& swing = set.rows[joint.first_row + joint.swing_row];
      EXPECT_NEAR(swing.rate, derivative(q_before.swing, q_after.swing), 1e-7) << name;
      EXPECT_NEAR(swing.velocity_product, second(q_before.swing, q.swing, q_after.swing), 1e-3) << name;
      const ControlRow& twist = set.rows[joint.first_row + joint.twist_row];
      EXPECT_NEAR(twist.rate / std::cos(q.swing / 2), derivative(q_before.twist, q_after.twist), 1e-7) << name;
      EXPECT_NEAR(twist.velocity_product / std::cos(q.swing / 2), second(q_before.twist, q.twist, q_after.twist), 1e-3) << name;
    }
  }
}

TEST(LagrangeJointControls, TreeAndSparseSolversAgree) {
  // Every control on every type it takes, with limits reached: the two solves of the same rows
  // give the same motion.
  for (const JointType type : {JointType::revolute, JointType::prismatic, JointType::spherical}) {
    Model model = controlled_pair(type);
    for (const Integrator integrator : {Integrator::semi_implicit_euler, Integrator::rk4}) {
      LagrangeState tree = compile_lagrange(model, {.integrator = integrator, .solver = MultiplierSolver::tree});
      LagrangeState sparse = compile_lagrange(model, {.integrator = integrator, .solver = MultiplierSolver::sparse});
      ASSERT_TRUE(tree.uses_tree);
      ASSERT_FALSE(sparse.uses_tree);
      double engaged = 0;
      // 2.5 s: under RK4 the spherical joint's twist reaches its limit after 2 s (it stops 6·10⁻⁵ rad
      // short at 2 s since the limb's axial momentum is kept; rigid_integration.hpp).
      for (int s = 0; s < 600; ++s) {
        step(tree, 1.0 / 240), step(sparse, 1.0 / 240);
        for (const ControlRow& row : tree.controls.rows) engaged += row.mode == ControlMode::limit;
      }
      const RigidBodyState &a = tree.bodies.state, &b = sparse.bodies.state;
      for (std::size_t k = 0; k < a.size(); ++k) {
        EXPECT_LT((a.position[k] - b.position[k]).norm(), 1e-8) << joint_type_name(type) << ", body " << k;
        EXPECT_LT(a.orientation[k].angularDistance(b.orientation[k]), 1e-8) << joint_type_name(type) << ", body " << k;
      }
      EXPECT_GT(engaged, 0) << joint_type_name(type);  // the limits did act
    }
  }
}

TEST(LagrangeJointControls, AStepWithControlsAllocatesNothing) {
  for (const JointType type : {JointType::revolute, JointType::prismatic, JointType::spherical}) {
    for (const Case& test : kCases) {
      LagrangeState state = compile_lagrange(controlled_pair(type), test.options);
      ASSERT_TRUE(state.uses_tree);
      step(state, 1.0 / 240);
      const long before = testing::allocation_count();
      for (int s = 0; s < 480; ++s) step(state, 1.0 / 240);
      EXPECT_EQ(testing::allocation_count() - before, 0) << joint_type_name(type) << ", " << test.name;
    }
  }
}

TEST(LagrangeJointControls, WhatCannotBeAppliedIsRefusedByName) {
  // Validation refuses a drive on a universal joint and a twist range on a hinge, naming the field.
  Model model = rod_on(JointType::universal, Vector3::UnitY());
  model.joints[0].second_axis = Vector3::UnitZ();
  model.joints[0].drive = JointDrive{.stiffness = 1};
  try {
    compile_lagrange(model);
    ADD_FAILURE() << "compiled";
  } catch (const ModelError& error) {
    EXPECT_NE(std::string(error.what()).find("joints[0].drive"), std::string::npos) << error.what();
  }
  model = rod_on(JointType::revolute);
  model.joints[0].limits.twist = Range{-0.1, 0.1};
  try {
    compile_lagrange(model);
    ADD_FAILURE() << "compiled";
  } catch (const ModelError& error) {
    EXPECT_NE(std::string(error.what()).find("joints[0].limits.twist"), std::string::npos) << error.what();
  }
  // Friction on a universal joint is applied (its two free axes): it compiles with two control rows.
  model = rod_on(JointType::universal, Vector3::UnitY());
  model.joints[0].second_axis = Vector3::UnitZ();
  model.joints[0].friction = 0.1;
  EXPECT_EQ(compile_lagrange(model).constraints.rows[0].control_rows, 2);
}

}  // namespace
}  // namespace limber
