// Joint limits, joint friction and joint drives in the Featherstone method
// (kernel/featherstone/joint_space_contacts.hpp): limits that hold (hinge, cone and twist, slide)
// with the joint held by the tree either way round, Coulomb friction that decelerates at τ_f/I and
// holds a load below it without creeping, drives whose damping ratio and period are the ones their
// stiffness and damping give and that stay stable far past an explicit PD's step, a spherical drive
// that reaches its target rotation, a drive changed between steps, and no allocation in a step.
// Every coordinate is measured from the rigid bodies with kernel/model/joint_coordinates.hpp.

// GCC 12 false positives inside Eigen's AVX-512 reductions over fixed-capacity vectors (a
// relative of bug 105593); must precede Eigen's headers.
#pragma GCC diagnostic ignored "-Warray-bounds"
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/featherstone/compile.hpp"
#include "limber/kernel/featherstone/integration.hpp"
#include "limber/kernel/featherstone/joint_space_contacts.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/model/joint_coordinates.hpp"
#include "tests/support/allocation_counter.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr Integrator kIntegrators[] = {Integrator::semi_implicit_euler, Integrator::rk4};

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", value);
  return text;
}

// Model body b's frame pose, from the rigid bodies (not the tree): the principal frame turned back
// to the Model's body frame, the centre of mass moved back to the shape's centre.
FramePose frame_pose(const FeatherstoneState& state, std::size_t b) {
  const RigidBodyState& y = state.bodies.state;
  FramePose pose;
  pose.orientation = (y.orientation[b] * state.shapes.principal_frame[b].conjugate()).normalized();
  pose.position = y.position[b] - pose.orientation * state.shapes.centre_offset[b];
  return pose;
}

JointCoordinates coordinates(const FeatherstoneState& state, std::size_t k) {
  const Joint& joint = state.joint_controls.joints[k];
  const FramePose inboard = joint.inboard == kWorld ? FramePose{} : frame_pose(state, static_cast<std::size_t>(joint.inboard));
  return joint_coordinates(joint, state.joint_controls.frames[k], inboard, frame_pose(state, static_cast<std::size_t>(joint.outboard)));
}

JointMeasures measures(const FeatherstoneState& state) {
  return measure_joints(state.joint_controls, [&](std::size_t b) { return frame_pose(state, b); });
}

// A capsule limb of `length` m (radius 0.05) and `mass` kg centred at `position` along `axis`.
Body limb(const std::string& name, double length, double mass, const Vector3& position, const Vector3& axis) {
  Body body;
  body.name = name;
  body.shape = {ShapeType::capsule, length, 0.05};
  body.mass = mass;
  body.position = position;
  body.axis = axis.normalized();
  return body;
}

Joint joint_of(JointType type, const std::string& name, int inboard, int outboard, const Vector3& inboard_anchor,
               const Vector3& outboard_anchor, const Vector3& axis = Vector3::UnitX()) {
  Joint joint = spherical_joint(name, inboard, outboard, inboard_anchor, outboard_anchor);
  joint.type = type;
  joint.axis = axis;
  return joint;
}

// A 1 m, 1 kg limb lying along +x from the pivot (0, 0, 1), on joint `type` about or along `axis`
// to the world: joint 0. Turned round (`reversed`): a small body is welded to the world at the
// pivot and the joint is the limb's (inboard) to it (outboard), so the tree's child is the Model's
// inboard body and the coordinate the joint measures turns the other way.
Model pivoted_limb(JointType type, const Vector3& axis, bool reversed) {
  Model model;
  model.name = "pivoted_limb";
  model.bodies.push_back(limb("limb", 1, 1, Vector3(0.5, 0, 1), Vector3::UnitX()));
  const Vector3 pivot(0, 0, 1), limb_tail(0, 0, -0.5);
  if (!reversed) {
    model.joints.push_back(joint_of(type, "pivot", kWorld, 0, pivot, limb_tail, axis));
    return model;
  }
  model.bodies.push_back(limb("mount", 0.1, 0.5, pivot, Vector3::UnitX()));  // its axis along the limb's
  model.joints.push_back(joint_of(type, "pivot", 0, 1, limb_tail, Vector3::Zero(), axis));
  model.joints.push_back(joint_of(JointType::fixed, "weld", kWorld, 1, pivot, Vector3::Zero()));
  return model;
}

// A limb whose inertia about its centre is diag(moments) (kg·m², body frame; z its axis), centred
// at the origin along +z, mass 2 kg, hinged (or balled) to the world at its centre, gravity off.
Model spinning_limb(JointType type, const Vector3& moments) {
  Model model;
  model.name = "spinning_limb";
  Body body = limb("rotor", 1, 2, Vector3::Zero(), Vector3::UnitZ());
  body.inertial = Inertial{Vector3::Zero(), moments.asDiagonal()};
  model.bodies.push_back(body);
  model.joints.push_back(joint_of(type, "axle", kWorld, 0, Vector3::Zero(), Vector3::Zero(), Vector3::UnitX()));
  model.settings.gravity.setZero();
  model.settings.sleep.enabled = false;
  return model;
}

// --- Limits --------------------------------------------------------------------------------------

TEST(FeatherstoneJointLimits, HingeRangeStopsAFallingLimbAtItsLimit) {
  // The limb starts horizontal; about +y it falls toward +angle and would swing through ±π/2.
  for (const bool reversed : {false, true}) {
    for (const Integrator integrator : kIntegrators) {
      Model model = pivoted_limb(JointType::revolute, Vector3::UnitY(), reversed);
      Model free = model;
      model.joints[0].limits.range = Range{-0.5, 0.5};
      FeatherstoneState state = compile_featherstone(model, {.integrator = integrator});
      FeatherstoneState unlimited = compile_featherstone(free, {.integrator = integrator});
      double worst = 0, widest = 0, widest_free = 0;
      for (int s = 0; s < 480; ++s) {  // 2 s at 1/240 s
        ASSERT_EQ(step(state).status, StepStatus::ok);
        step(unlimited);
        const double angle = coordinates(state, 0).angle;
        worst = std::max(worst, limit_violation(model.joints[0], coordinates(state, 0)));
        widest = std::max(widest, std::abs(angle));
        widest_free = std::max(widest_free, std::abs(coordinates(unlimited, 0).angle));
      }
      const std::string label = std::string(reversed ? "turned round, " : "") + integrator_name(integrator);
      EXPECT_LT(worst, 0.01) << label;                 // never more than 0.01 rad past 0.5 rad
      EXPECT_GT(widest, 0.49) << label;                // it did reach the limit
      EXPECT_GT(widest_free, 1.2) << label;            // which is what held it
      EXPECT_NEAR(std::abs(coordinates(state, 0).angle), 0.5, 0.01) << label;  // and rests on it
      RecordProperty("largest_violation_rad_" + std::string(reversed ? "reversed_" : "") + integrator_name(integrator), number(worst));
    }
  }
}

TEST(FeatherstoneJointLimits, ConeAndTwistHoldASpunLimbThrownOutOfTheCone) {
  // A ball joint at the limb's tail, cone of 0.6 rad about its rest axis (+x) or tilted 0.3 rad
  // off it, twist ±0.2 rad about the cone's axis. Gravity pulls it π/2 out of the cone; it is
  // also thrown sideways and spun about its own axis. At 1/60 s the spin (48 rad/s) makes the
  // step take substeps.
  struct Case {
    double dt, spin, tolerance;
  };
  const Vector3 tilted = Eigen::AngleAxisd(0.3, Vector3::UnitZ()) * Vector3::UnitX();
  for (const Case c : {Case{1.0 / 240, 12, 0.01}, Case{1.0 / 60, 48, 0.03}}) {
    for (const Integrator integrator : kIntegrators) {
      for (const int variant : {0, 1, 2}) {  // the cone at rest; turned round; the cone tilted
        const bool reversed = variant == 1;
        Model model = pivoted_limb(JointType::spherical, Vector3::UnitX(), reversed);
        model.bodies[0].angular_velocity = Vector3(0, 0, 3) + c.spin * Vector3::UnitX();  // sideways and spinning
        model.bodies[0].linear_velocity = Vector3(0, 1.5, 0);
        model.joints[0].limits.swing = 0.6;
        if (variant == 2) model.joints[0].limits.swing_axis = tilted;
        model.joints[0].limits.twist = Range{-0.2, 0.2};
        model.settings.sleep.enabled = false;
        FeatherstoneState state = compile_featherstone(model, {.integrator = integrator});
        double worst_swing = 0, worst_twist = 0, widest_swing = 0, widest_twist = 0;
        const int steps = static_cast<int>(std::lround(3 / c.dt));
        for (int s = 0; s < steps; ++s) {
          ASSERT_EQ(step(state, c.dt).status, StepStatus::ok);
          const JointCoordinates q = coordinates(state, 0);
          worst_swing = std::max(worst_swing, q.swing - 0.6);
          worst_twist = std::max(worst_twist, std::abs(q.twist) - 0.2);
          widest_swing = std::max(widest_swing, q.swing);
          widest_twist = std::max(widest_twist, std::abs(q.twist));
        }
        const std::string label = "dt " + number(c.dt) + ", " + integrator_name(integrator) + (reversed ? ", turned round" : variant == 2 ? ", tilted cone" : "");
        EXPECT_LT(worst_swing, c.tolerance) << label;
        EXPECT_LT(worst_twist, c.tolerance) << label;
        EXPECT_GT(widest_swing, 0.59) << label;  // both limits were reached
        EXPECT_GT(widest_twist, 0.19) << label;
        RecordProperty("swing_twist_violation_rad_" + number(c.dt) + "_" + integrator_name(integrator) + (reversed ? "_reversed" : variant == 2 ? "_tilted" : ""),
                       number(worst_swing) + " " + number(worst_twist));
      }
    }
  }
}

TEST(FeatherstoneJointLimits, SlideRangeHoldsAFallingBodyAtItsMaximum) {
  for (const bool reversed : {false, true}) {
    for (const Integrator integrator : kIntegrators) {
      // A vertical limb sliding along −z (down) from its pivot, travel [−0.1, 0.3] m.
      Model model;
      model.bodies.push_back(limb("slider", 0.5, 2, Vector3(0, 0, 0.75), Vector3::UnitZ()));
      const Vector3 pivot(0, 0, 1), down = -Vector3::UnitZ();
      if (!reversed) {
        model.joints.push_back(joint_of(JointType::prismatic, "rail", kWorld, 0, pivot, Vector3(0, 0, 0.25), down));
      } else {
        model.bodies.push_back(limb("mount", 0.1, 0.5, pivot, Vector3::UnitZ()));
        model.joints.push_back(joint_of(JointType::prismatic, "rail", 0, 1, Vector3(0, 0, 0.25), Vector3::Zero(), down));
        model.joints.push_back(joint_of(JointType::fixed, "weld", kWorld, 1, pivot, Vector3::Zero()));
      }
      model.joints[0].limits.range = reversed ? Range{-0.3, 0.1} : Range{-0.1, 0.3};
      model.settings.sleep.enabled = false;
      FeatherstoneState state = compile_featherstone(model, {.integrator = integrator});
      double worst = 0;
      for (int s = 0; s < 480; ++s) {
        ASSERT_EQ(step(state).status, StepStatus::ok);
        worst = std::max(worst, limit_violation(model.joints[0], coordinates(state, 0)));
      }
      const std::string label = std::string(reversed ? "turned round, " : "") + integrator_name(integrator);
      EXPECT_LT(worst, 0.002) << label;  // m; free, it would have fallen 19.6 m
      EXPECT_NEAR(coordinates(state, 0).slide, reversed ? -0.3 : 0.3, 0.002) << label;
      EXPECT_LT(state.bodies.linear_velocity(state.bodies.state, 0).norm(), 1e-3) << label;  // resting on the stop
    }
  }
}

TEST(FeatherstoneJointLimits, LimbRestingOnItsLimitFallsAsleepThere) {
  Model model = pivoted_limb(JointType::revolute, Vector3::UnitY(), false);
  model.joints[0].limits.range = Range{-0.5, 0.5};
  model.joints[0].friction = 0.05;  // settles the bounce-free rest sooner
  FeatherstoneState state = compile_featherstone(model);
  for (int s = 0; s < 960; ++s) ASSERT_EQ(step(state).status, StepStatus::ok);
  EXPECT_TRUE(state.islands[0].sleeping);
  EXPECT_NEAR(coordinates(state, 0).angle, 0.5, 0.005);
}

// --- Friction ------------------------------------------------------------------------------------

TEST(FeatherstoneJointFriction, SpinningLimbDeceleratesAtFrictionOverInertiaThenStaysStopped) {
  // Hinged at its centre about body x, I = 0.2 kg·m²; τ_f = 0.5 N·m: 2.5 rad/s² from 5 rad/s,
  // stopped at 2 s.
  const double inertia = 0.2, friction = 0.5, start = 5;
  for (const Integrator integrator : kIntegrators) {
    Model model = spinning_limb(JointType::revolute, Vector3(inertia, inertia, 0.01));
    model.joints[0].friction = friction;
    model.bodies[0].angular_velocity = Vector3(start, 0, 0);
    FeatherstoneState state = compile_featherstone(model, {.integrator = integrator});
    const double dt = 1.0 / 240;
    std::vector<double> time, speed;
    for (int s = 1; s <= 720; ++s) {
      ASSERT_EQ(step(state, dt).status, StepStatus::ok);
      time.push_back(s * dt);
      speed.push_back(state.bodies.angular_velocity(state.bodies.state, 0).x());
    }
    // Least-squares slope over 0.2–1.6 s.
    double st = 0, sw = 0, stt = 0, stw = 0, n = 0;
    for (std::size_t i = 0; i < time.size(); ++i) {
      if (time[i] < 0.2 || time[i] > 1.6) continue;
      st += time[i], sw += speed[i], stt += time[i] * time[i], stw += time[i] * speed[i], n += 1;
    }
    const double slope = (n * stw - st * sw) / (n * stt - st * st);
    EXPECT_NEAR(slope, -friction / inertia, 0.03 * friction / inertia) << integrator_name(integrator);
    RecordProperty(std::string("deceleration_rad_s2_") + integrator_name(integrator), number(-slope));
    // Stopped by 2.05 s, and stays stopped: no reversal, no creep.
    const double angle_stopped = coordinates(state, 0).angle;
    for (std::size_t i = 0; i < time.size(); ++i) {
      if (time[i] > 2.05) {
        EXPECT_LT(std::abs(speed[i]), 1e-9) << integrator_name(integrator) << " at " << time[i];
      }
      EXPECT_GT(speed[i], -1e-9) << integrator_name(integrator);
    }
    for (int s = 0; s < 240; ++s) step(state, dt);
    EXPECT_NEAR(coordinates(state, 0).angle, angle_stopped, 1e-12);
  }
}

TEST(FeatherstoneJointFriction, HoldsALoadBelowItAndSlipsAboveWithoutCreeping) {
  // The horizontal limb's weight pulls with m·g·L/2 = 4.905 N·m about the pivot.
  const double weight_torque = 1 * 9.81 * 0.5;
  for (const Integrator integrator : kIntegrators) {
    for (const double friction : {1.1 * weight_torque, 0.5 * weight_torque}) {
      Model model = pivoted_limb(JointType::revolute, Vector3::UnitY(), false);
      model.joints[0].friction = friction;
      model.settings.sleep.enabled = false;
      FeatherstoneState state = compile_featherstone(model, {.integrator = integrator});
      for (int s = 0; s < 240; ++s) ASSERT_EQ(step(state).status, StepStatus::ok);
      const double angle = coordinates(state, 0).angle;
      if (friction > weight_torque) {
        // Held, not creeping: a creep would move it h²·α ≈ 2.6·10⁻⁴ rad a step; what is left is
        // round-off at the penalty's conditioning, kPenalty·ε of the held velocity (~10⁻¹⁴ rad a step).
        EXPECT_LT(std::abs(angle), 1e-10) << integrator_name(integrator);
      } else {
        // Slips under the net torque m·g·L/2·cos θ − τ_f: past 0.3 rad within a second.
        EXPECT_GT(angle, 0.3) << integrator_name(integrator);
      }
    }
  }
}

TEST(FeatherstoneJointFriction, HoldsAChainWhoseJointsCoupleWithoutCreeping) {
  // Three 1 kg, 0.5 m links on ball joints, pinned horizontal: the pin must hold 22 N·m, the next
  // joints 9.8 and 2.5 N·m, each through the others. 30 N·m of friction in each holds them all.
  for (const Integrator integrator : kIntegrators) {
    Model model = testing::make_chain({1, 1, 1}, 0.5, /*pinned=*/true);
    for (Joint& joint : model.joints) joint.friction = 30;
    model.settings.sleep.enabled = false;
    FeatherstoneState state = compile_featherstone(model, {.integrator = integrator});
    for (int s = 0; s < 240; ++s) ASSERT_EQ(step(state).status, StepStatus::ok);
    for (std::size_t k = 0; k < model.joints.size(); ++k) {
      EXPECT_LT(coordinates(state, k).rotation.norm(), 1e-9) << integrator_name(integrator) << " joint " << k;
    }
  }
}

TEST(FeatherstoneJointFriction, BallJointFrictionSlowsTheRelativeSpinAlongItsDirection) {
  // A ball joint at the centre of a rotor with I = 0.2 about every axis: |ω| falls at τ_f/I
  // whatever its direction, and the direction is kept (the impulse is clamped by its norm).
  Model model = spinning_limb(JointType::spherical, Vector3(0.2, 0.2, 0.2));
  model.joints[0].friction = 0.5;
  const Vector3 start(3, -2, 1);
  model.bodies[0].angular_velocity = start;
  FeatherstoneState state = compile_featherstone(model);
  for (int s = 0; s < 240; ++s) ASSERT_EQ(step(state).status, StepStatus::ok);  // 1 s
  const Vector3 omega = state.bodies.angular_velocity(state.bodies.state, 0);
  EXPECT_NEAR(omega.norm(), start.norm() - 2.5, 0.02 * 2.5);
  EXPECT_GT(omega.normalized().dot(start.normalized()), 1 - 1e-9);
}

// --- Drives --------------------------------------------------------------------------------------

// Successive positive peaks of e(t).
std::vector<std::pair<double, double>> peaks(const std::vector<double>& e, double dt) {
  std::vector<std::pair<double, double>> out;
  for (std::size_t i = 1; i + 1 < e.size(); ++i) {
    if (e[i] > 0 && e[i] > e[i - 1] && e[i] >= e[i + 1]) out.emplace_back(i * dt, e[i]);
  }
  return out;
}

TEST(FeatherstoneJointDrives, HingeDriveSettlesWithTheDampingRatioAndPeriodOfItsGains) {
  // I = 0.2 kg·m² about the hinge, k = 20 N·m/rad (ω_n = 10 rad/s), ζ = 0.2: c = 2ζ√(kI) = 0.8.
  const double inertia = 0.2, stiffness = 20, zeta = 0.2, target = 0.3, dt = 1e-3;
  const double damping = 2 * zeta * std::sqrt(stiffness * inertia);
  for (const bool reversed : {false, true}) {
    for (const Integrator integrator : kIntegrators) {
      Model model = spinning_limb(JointType::revolute, Vector3(inertia, inertia, 0.01));
      if (reversed) {  // the hinge is the rotor's (inboard) to a mount welded to the world
        model.bodies.push_back(limb("mount", 0.1, 0.5, Vector3(0, 0, -1), Vector3::UnitZ()));
        model.joints[0] = joint_of(JointType::revolute, "axle", 0, 1, Vector3::Zero(), Vector3(0, 0, 1), Vector3::UnitX());
        model.joints.push_back(joint_of(JointType::fixed, "weld", kWorld, 1, Vector3(0, 0, -1), Vector3::Zero()));
      }
      model.joints[0].drive = JointDrive{.stiffness = stiffness, .damping = damping, .target = target};
      FeatherstoneState state = compile_featherstone(model, {.integrator = integrator});
      std::vector<double> error;
      for (int s = 0; s < 4000; ++s) {
        ASSERT_EQ(step(state, dt).status, StepStatus::ok);
        error.push_back(coordinates(state, 0).angle - target);
      }
      const std::string label = std::string(reversed ? "turned round, " : "") + integrator_name(integrator);
      const auto found = peaks(error, dt);
      ASSERT_GE(found.size(), 3u) << label;
      double decrement = 0;
      for (int i = 0; i < 2; ++i) decrement += std::log(found[i].second / found[i + 1].second) / 2;
      const double measured_zeta = decrement / std::sqrt(4 * kPi * kPi + decrement * decrement);
      EXPECT_NEAR(measured_zeta, zeta, 0.1 * zeta) << label;
      const double period = (found[2].first - found[0].first) / 2;
      const double expected_period = 2 * kPi / (std::sqrt(stiffness / inertia) * std::sqrt(1 - zeta * zeta));
      EXPECT_NEAR(period, expected_period, 0.03 * expected_period) << label;
      EXPECT_LT(std::abs(error.back()), 1e-4) << label;  // settled on the target
      EXPECT_LT(measures(state).drive_error, 1e-4) << label;
      RecordProperty("damping_ratio_" + std::string(reversed ? "reversed_" : "") + integrator_name(integrator), number(measured_zeta));
    }
  }
}

TEST(FeatherstoneJointDrives, StiffDriveStaysStableFarPastAnExplicitStep) {
  // k·h²/I = 1e5 / 3600 / 0.2 ≈ 140 at 1/60 s: an explicit PD diverges above ~4.
  const double inertia = 0.2, stiffness = 1e5, target = 0.3, dt = 1.0 / 60;
  for (const Integrator integrator : kIntegrators) {
    for (const double damping : {0.0, 50.0}) {
      Model model = spinning_limb(JointType::revolute, Vector3(inertia, inertia, 0.01));
      model.joints[0].drive = JointDrive{.stiffness = stiffness, .damping = damping, .target = target};
      FeatherstoneState state = compile_featherstone(model, {.integrator = integrator});
      double farthest = 0;
      for (int s = 0; s < 120; ++s) {
        ASSERT_EQ(step(state, dt).status, StepStatus::ok);
        farthest = std::max(farthest, std::abs(coordinates(state, 0).angle - target));
      }
      EXPECT_LE(farthest, target + 1e-9) << integrator_name(integrator);  // never farther than it started
      EXPECT_LT(std::abs(coordinates(state, 0).angle - target), 1e-3) << integrator_name(integrator);
    }
  }
}

TEST(FeatherstoneJointDrives, APendulumDrivenIntoItsLimitMakesNoEnergyAtMujocosStep) {
  // The limb falls from horizontal onto its 0.5 rad limit while a stiff drive pulls it toward
  // 1 rad, past the limit, at MuJoCo's default step of 0.005 s: k·h²/I = 30 and c·h/I = 6 (I =
  // 1/3 kg·m² about the pivot), where an explicit PD diverges. The limit holds against the drive
  // through H + h·G, the drive's own armature. Energy — kinetic, gravity's and the drive's
  // spring ½·k·(θ − θ*)² — never rises past its start (semi-implicit Euler: never from one step to
  // the next, backward Euler's on the drive), and the limb comes to rest on its limit.
  const double inertia = 1.0 / 3, dt = 0.005, target = 1;
  const double stiffness = 30 * inertia / (dt * dt), damping = 6 * inertia / dt;
  for (const bool reversed : {false, true}) {
    for (const Integrator integrator : kIntegrators) {
      Model model = pivoted_limb(JointType::revolute, Vector3::UnitY(), reversed);
      model.joints[0].limits.range = Range{-0.5, 0.5};
      model.joints[0].drive = JointDrive{.stiffness = stiffness, .damping = damping, .target = target};
      model.settings.sleep.enabled = false;
      FeatherstoneState state = compile_featherstone(model, {.integrator = integrator});
      const auto energy = [&] {
        const Observation o = observe(state);
        const double stretch = coordinates(state, 0).angle - target;
        return o.kinetic_energy + o.potential_energy + 0.5 * stiffness * stretch * stretch;
      };
      const std::string label = std::string(reversed ? "turned round, " : "") + integrator_name(integrator);
      const double start = energy();
      double last = start, worst = 0;
      for (int s = 0; s < 400; ++s) {  // 2 s
        ASSERT_EQ(step(state, dt).status, StepStatus::ok) << label << ", step " << s;
        const double now = energy();
        ASSERT_LE(now, start) << label << ", step " << s << ": energy made";
        if (integrator == Integrator::semi_implicit_euler) ASSERT_LE(now, last + 1e-9 * start) << label << ", step " << s;
        last = now;
        worst = std::max(worst, limit_violation(model.joints[0], coordinates(state, 0)));
      }
      EXPECT_LT(worst, 0.01) << label;  // rad: as the falling limb without a drive (above)
      EXPECT_NEAR(coordinates(state, 0).angle, 0.5, 0.01) << label;
      EXPECT_LT(std::abs(state.v[0]), 1e-6) << label << ": at rest";
    }
  }
}

TEST(FeatherstoneJointDrives, UnderSemiImplicitEulerTheDrivesDynamicsAreTheStepsOwn) {
  // The step takes the stable PD's predicted velocity as semi-implicit Euler's (step.cpp): it must
  // be what the integrator gives under the forces the drives hold, to round-off. A ball joint
  // driven toward a turn, spinning and under gravity (so Coriolis and gravity terms are in v̇).
  Model model = pivoted_limb(JointType::spherical, Vector3::UnitX(), /*reversed=*/false);
  model.settings.sleep.enabled = false;
  model.bodies[0].angular_velocity = Vector3(4, 1, 0);
  JointDrive drive;
  drive.stiffness = 30, drive.damping = 3;
  drive.target_rotation = 0.8 * Vector3(1, -1, 2).normalized();
  model.joints[0].drive = drive;
  FeatherstoneState state = compile_featherstone(model, {.integrator = Integrator::semi_implicit_euler});
  const double dt = 1.0 / 240;
  double largest = 0, speed = 0;
  for (int s = 0; s < 240; ++s) {
    FeatherstoneState integrated = state;
    ASSERT_TRUE(joint_control_forces(integrated, integrated.joint_forces, dt));
    integrate(integrated.tree, integrated.q, integrated.v, integrated.controls.forces, integrated.settings.gravity, dt,
              Integrator::semi_implicit_euler, integrated.integration);
    ASSERT_EQ(step(state, dt).status, StepStatus::ok);
    largest = std::max({largest, (state.v - integrated.v).lpNorm<Eigen::Infinity>(), (state.q - integrated.q).lpNorm<Eigen::Infinity>()});
    speed = std::max(speed, state.v.lpNorm<Eigen::Infinity>());
  }
  EXPECT_GT(speed, 1.0);  // it moves
  EXPECT_LT(largest, 1e-12 * speed);
  RecordProperty("largest_difference", number(largest));
}

TEST(FeatherstoneJointDrives, BallJointDriveReachesItsTargetRotation) {
  for (const Integrator integrator : kIntegrators) {
    for (const bool reversed : {false, true}) {
      // A limb on a ball joint at its tail, driven (critically damped for I ≈ 0.34 kg·m²) to a turn
      // of 0.8 rad about (1, −1, 2), gravity off, spinning at the start.
      Model model = pivoted_limb(JointType::spherical, Vector3::UnitX(), reversed);
      model.settings.gravity.setZero();
      model.settings.sleep.enabled = false;
      model.bodies[0].angular_velocity = Vector3(4, 1, 0);
      JointDrive drive;
      drive.stiffness = 30, drive.damping = 2 * std::sqrt(30 * 0.34);
      drive.target_rotation = 0.8 * Vector3(1, -1, 2).normalized();
      model.joints[0].drive = drive;
      FeatherstoneState state = compile_featherstone(model, {.integrator = integrator});
      const double start_error = measures(state).drive_error;
      for (int s = 0; s < 960; ++s) ASSERT_EQ(step(state).status, StepStatus::ok);  // 4 s
      EXPECT_GT(start_error, 0.79) << integrator_name(integrator);
      EXPECT_LT(measures(state).drive_error, 1e-3) << integrator_name(integrator);
      // The deviation (inboard frame) is the target turn itself, given in world axes at rest.
      const Vector3 turn = state.joint_controls.frames[0].inboard_rest * coordinates(state, 0).rotation;
      EXPECT_LT((turn - drive.target_rotation).norm(), 1e-3) << integrator_name(integrator);
    }
  }
}

TEST(FeatherstoneJointDrives, DriveIsReadFromTheStateEveryStep) {
  // What World::set_joint_drive does: write state.joint_controls.joints[k].drive between steps.
  Model model = spinning_limb(JointType::revolute, Vector3(0.2, 0.2, 0.01));
  model.joints[0].drive = JointDrive{.stiffness = 20, .damping = 4, .target = 0.3};
  FeatherstoneState state = compile_featherstone(model);
  for (int s = 0; s < 480; ++s) step(state);
  EXPECT_NEAR(coordinates(state, 0).angle, 0.3, 1e-3);
  state.joint_controls.joints[0].drive->target = -0.4;
  for (int s = 0; s < 480; ++s) step(state);
  EXPECT_NEAR(coordinates(state, 0).angle, -0.4, 1e-3);
  // A velocity motor (k = 0): turns at its target velocity.
  state.joint_controls.joints[0].drive = JointDrive{.stiffness = 0, .damping = 50, .target_velocity = 2};
  for (int s = 0; s < 240; ++s) step(state);
  EXPECT_NEAR(state.bodies.angular_velocity(state.bodies.state, 0).x(), 2, 1e-3);
}

// --- Everything at once --------------------------------------------------------------------------

TEST(FeatherstoneJointControls, HumanoidWithLimitsFrictionAndDrivesStepsWithoutAllocating) {
  for (const Integrator integrator : kIntegrators) {
    Model model = testing::load_shipped_scene("humanoid.json");
    for (Joint& joint : model.joints) {
      joint.limits.swing = 0.8;
      joint.limits.twist = Range{-0.3, 0.3};
      joint.friction = 0.2;
      joint.drive = JointDrive{.stiffness = 2, .damping = 0.2};
    }
    FeatherstoneState state = compile_featherstone(model, {.integrator = integrator});
    step(state);
    const long before = testing::allocation_count();
    int contacts = 0;
    double worst = 0;
    // The ball hits, the body falls. Semi-implicit Euler only the first 0.5 s: from ~0.6 s its
    // explicit gyroscopic terms wind the spinning head up until it diverges near 0.8 s, controls
    // or not (featherstone_state.hpp).
    const int steps = integrator == Integrator::rk4 ? 480 : 120;
    for (int s = 0; s < steps; ++s) {
      const StepReport report = step(state);
      ASSERT_EQ(report.status, StepStatus::ok) << integrator_name(integrator) << " step " << s;
      contacts += report.contacts;
      worst = std::max(worst, measures(state).limit_violation);
    }
    EXPECT_EQ(testing::allocation_count() - before, 0) << integrator_name(integrator);
    EXPECT_GT(contacts, 0);
    EXPECT_LT(worst, 0.02) << integrator_name(integrator);  // rad, every joint at every step
    RecordProperty(std::string("humanoid_largest_violation_rad_") + integrator_name(integrator), number(worst));
  }
}

TEST(FeatherstoneJointControls, AppliesLimitsFrictionAndDrivesAndRefusesWhatItCannotHold) {
  Model model = pivoted_limb(JointType::revolute, Vector3::UnitY(), false);
  model.joints[0].limits.range = Range{-0.5, 0.5};
  model.joints[0].friction = 0.1;
  model.joints[0].drive = JointDrive{.stiffness = 1, .damping = 0.1};
  EXPECT_NO_THROW(compile_featherstone(model));
  // A universal joint (limited or not) is refused by name: reduced coordinates here have none.
  Model cardan = pivoted_limb(JointType::universal, Vector3::UnitY(), false);
  cardan.joints[0].second_axis = Vector3::UnitZ();
  cardan.joints[0].friction = 0.1;
  try {
    compile_featherstone(cardan);
    ADD_FAILURE() << "a universal joint was accepted";
  } catch (const ModelError& error) {
    EXPECT_NE(std::string(error.what()).find("joints[0] 'pivot'"), std::string::npos) << error.what();
  }
  // A limit the joint's type does not have is refused by name (validation).
  Model wrong = pivoted_limb(JointType::revolute, Vector3::UnitY(), false);
  wrong.joints[0].limits.swing = 0.5;
  try {
    compile_featherstone(wrong);
    ADD_FAILURE() << "a swing limit on a hinge was accepted";
  } catch (const ModelError& error) {
    EXPECT_NE(std::string(error.what()).find("joints[0]"), std::string::npos) << error.what();
  }
}

// --- Armature ------------------------------------------------------------------------------------

TEST(FeatherstoneArmature, APendulumsObservedEnergyHoldsTheRotorsToo) {
  // A limb swinging on a hinge whose armature is half its own inertia about the pivot: the
  // observed kinetic energy counts the rotor's ½ a θ̇², so the total holds under RK4 (without it,
  // a third of the kinetic energy would be missing at the bottom of the swing).
  Model model = pivoted_limb(JointType::revolute, Vector3::UnitY(), false);
  model.joints[0].armature = 1.0 / 6;  // the limb's m l²/3 = 1/3 kg·m² about the pivot
  model.settings.sleep.enabled = false;
  FeatherstoneState state = compile_featherstone(model, {.integrator = Integrator::rk4});
  const auto total = [&] {
    const Observation o = observe(state);
    return o.kinetic_energy + o.potential_energy;
  };
  const double start = total();
  double worst = 0, fastest = 0;
  for (int s = 0; s < 480; ++s) {
    step(state);
    worst = std::max(worst, std::abs(total() - start));
    fastest = std::max(fastest, observe(state).kinetic_energy);
  }
  EXPECT_GT(fastest, 4);                // J: it fell 0.5 m with its 1 kg
  EXPECT_LT(worst, 1e-4 * fastest);     // RK4 at 1/240 s
}

TEST(FeatherstoneArmature, AnArmTurningOnFrictionlessGroundKeepsItsSpinThroughThePushOuts) {
  // A mast turning about the vertical on a hinge with armature (a rotor's reflected inertia), and
  // an arm hinged to it that droops onto frictionless ground: its tip sinks under gravity each
  // step and the push-out lifts it. Nothing turns the system about the vertical (gravity and the
  // ground's forces are vertical), so its spin stays — the armature's momentum included, which
  // the push-out's re-projection must keep: leaving it out slows the spin by about a/(a + I) at
  // every push-out.
  for (const Integrator integrator : kIntegrators) {
    Model model;
    model.bodies.push_back(limb("mast", 0.2, 1, Vector3(0, 0, 0.5), Vector3::UnitZ()));
    model.bodies.push_back(limb("arm", 1, 1, Vector3(0.5, 0, 0.5), Vector3::UnitX()));
    model.joints.push_back(joint_of(JointType::revolute, "turn", kWorld, 0, Vector3(0, 0, 0.5), Vector3::Zero(), Vector3::UnitZ()));
    model.joints.push_back(joint_of(JointType::revolute, "droop", 0, 1, Vector3::Zero(), Vector3(0, 0, -0.5), Vector3::UnitY()));
    model.joints[0].armature = 0.25;  // about the arm's own inertia about the vertical
    model.ground = Ground{0, 0, 0};
    model.settings.sleep.enabled = false;
    FeatherstoneState state = compile_featherstone(model, {.integrator = integrator});
    const int turn = state.tree_joint[0].offset;
    state.v[turn] = 1;  // rad/s
    refresh_rigid_bodies(state);
    // The angular momentum about the vertical through the pivot, kg·m²/s: the bodies' and the
    // rotor's, a·(its turn rate).
    const auto spin = [&] {
      const RigidBodyState& y = state.bodies.state;
      double momentum = model.joints[0].armature * state.v[turn];
      for (std::size_t b = 0; b < 2; ++b) momentum += (y.angular_momentum[b] + y.position[b].cross(y.linear_momentum[b])).z();
      return momentum;
    };
    const double start = spin();
    int touching = 0;
    for (int s = 0; s < 720; ++s) {  // the arm falls onto the ground, then slides round on it
      ASSERT_EQ(step(state).status, StepStatus::ok);
      if (s >= 240) touching += static_cast<int>(!state.contacts.empty());
    }
    EXPECT_EQ(touching, 480) << integrator_name(integrator);
    // Within the integrators' own drift over the 3 s (semi-implicit Euler loses 4 %, RK4's
    // push-outs add 2 %); with the armature's momentum left out the spin stops within 0.5 s.
    EXPECT_NEAR(spin() / start, 1, 0.05) << integrator_name(integrator);
  }
}

}  // namespace
}  // namespace limber
