// Joint limits, friction and drives in the stiff-spring method (kernel/springs/spring_forces.hpp):
// a limit is a one-sided angular spring as stiff as the joint's own, friction a regularized dry
// torque, a drive a PD torque (implicit in the backward-Euler step). Measured with the shared
// joint coordinates (kernel/model/joint_coordinates.hpp).
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/model/joint_coordinates.hpp"
#include "limber/kernel/springs/compile.hpp"
#include "limber/kernel/springs/step.hpp"
#include "tests/support/models.hpp"
#include "tests/support/oscillation.hpp"

namespace limber {
namespace {

constexpr double kPi = std::numbers::pi;

// One rod (cylinder, 1 kg, 1 m, radius 1 cm) whose head is held at the origin by a spherical
// joint, lying along +x.
Model rod_on_ball_joint() {
  Model model = testing::rod_held_at_head(JointType::spherical);
  model.joints[0].name = "ball";
  return model;
}

constexpr double kEndInertia = 1.0 / 3 + 0.01 * 0.01 / 4;  // kg·m², across the rod through its end

FramePose pose(const SpringState& state, int body) {
  if (body < 0) return {};
  const auto b = static_cast<std::size_t>(body);
  const Eigen::Quaterniond orientation = state.bodies.state.orientation[b] * state.shapes.principal_frame[b].conjugate();
  return {orientation, state.bodies.state.position[b] - orientation * state.shapes.centre_offset[b]};
}

JointCoordinates coordinates(const SpringState& state, std::size_t k) {
  const Joint& joint = state.joint_controls.joints[k];
  return joint_coordinates(joint, state.joint_controls.frames[k], pose(state, joint.inboard), pose(state, joint.outboard));
}

struct Case {
  SpringOptions options;
  const char* name;
};
const Case kCases[] = {
    {{}, "symplectic Euler"},
    {{.integrator = Integrator::rk4}, "RK4"},
    {{.integrator = Integrator::backward_euler}, "backward Euler"},
};

TEST(SpringJointLimits, SwingConeAndTwistRangeHoldAsStiffAsTheJoint) {
  // The rod swings down under gravity (π/2 from rest) and is thrown sideways and spun about its
  // axis at 12 rad/s, against a swing cone of 0.6 rad and twist range ±0.2 rad. A limit is a
  // spring ringing at the joint's √(k/m) for the limb's free turn (slower for the turn about the
  // held end, by √(I_centre/I_end) = 1/2 across a rod): reached at speed v, it gives way by about
  // 2·v/√(k/m) at most. The cone centred on the rest axis, and tilted 0.3 rad off it (the twist
  // is about the cone's axis).
  const Vector3 tilted = Eigen::AngleAxisd(0.3, Vector3::UnitZ()) * -Vector3::UnitX();
  for (const auto& [stiffness, cone] : {std::pair{2e4, std::optional<Vector3>()}, std::pair{1e6, std::optional<Vector3>()},
                                        std::pair{2e4, std::optional<Vector3>(tilted)}, std::pair{1e6, std::optional<Vector3>(tilted)}}) {
    Model model = rod_on_ball_joint();
    model.joints[0].stiffness = stiffness;
    model.joints[0].damping = 0.2 * 2 * std::sqrt(stiffness);
    model.joints[0].limits.swing = 0.6;
    model.joints[0].limits.swing_axis = cone;
    model.joints[0].limits.twist = Range{-0.2, 0.2};
    model.bodies[0].angular_velocity = Vector3(-12, 0, 3);
    model.bodies[0].linear_velocity = Vector3(0, 1.5, 0);
    const double give = 2 * 12 / std::sqrt(stiffness);  // the fastest approach (the spin)
    for (const Case& test : kCases) {
      const double dt = stiffness > 1e5 ? 1.0 / 2000 : 1.0 / 480;
      if (stiffness > 1e5 && test.options.integrator != Integrator::backward_euler) continue;
      SpringState state = compile_springs(model, test.options);
      double swing = 0, twist = 0, largest = 0;
      for (int s = 0; s < static_cast<int>(3 / dt); ++s) {
        ASSERT_EQ(step(state, dt).status, StepStatus::ok) << test.name;
        const JointCoordinates q = coordinates(state, 0);
        swing = std::max(swing, q.swing - 0.6);
        twist = std::max(twist, std::abs(q.twist) - 0.2);
        largest = std::max(largest, q.swing);
      }
      const std::string name = test.name + std::string(", k ") + std::to_string(stiffness) + (cone ? ", tilted cone" : "");
      EXPECT_LT(swing, give) << name;
      EXPECT_LT(twist, give) << name;
      EXPECT_GT(largest, 0.6) << name;  // it reached the cone
      // At rest it hangs on the cone's edge, pressed in by gravity's torque over the limit's stiffness.
      EXPECT_LT(coordinates(state, 0).swing - 0.6, 0.01) << name;
    }
  }
}

TEST(SpringJointFriction, FrictionDeceleratesAtTorqueOverInertiaThenHolds) {
  // Gravity off, the rod spinning about y through its held end at 3 rad/s: friction τ_f takes it
  // down at τ_f/I, then holds it still (its regularization: a damper below h·τ_f/I).
  Model model = rod_on_ball_joint();
  model.settings.gravity.setZero();
  const double friction = 0.5, start = 3;
  model.joints[0].friction = friction;
  model.bodies[0].angular_velocity = Vector3(0, start, 0);
  model.bodies[0].linear_velocity = Vector3(0, 0, -0.5 * start);
  const double deceleration = friction / kEndInertia, stop = start / deceleration;
  for (const Case& test : kCases) {
    const double dt = 1.0 / 480;
    SpringState state = compile_springs(model, test.options);
    std::vector<double> speed;
    for (int s = 0; s < static_cast<int>(3 / dt); ++s) {
      step(state, dt);
      speed.push_back(state.bodies.angular_velocity(state.bodies.state, 0).y());
    }
    const auto at = [&](double t) { return speed[static_cast<std::size_t>(std::lround(t / dt)) - 1]; };
    EXPECT_NEAR((at(0.1) - at(0.9)) / 0.8, deceleration, 0.03 * deceleration) << test.name;
    EXPECT_NEAR((at(1.0) - at(1.8)) / 0.8, deceleration, 0.03 * deceleration) << test.name;
    // Stopped: below τ_f·h/I it is brought to rest (through its inertia about the centre of
    // mass, so no overshoot), and it stays at rest.
    for (std::size_t s = static_cast<std::size_t>((stop + 0.1) / dt); s < speed.size(); ++s) {
      ASSERT_LT(std::abs(speed[s]), 1e-4) << test.name << ", step " << s;
    }
    EXPECT_LT(std::abs(speed.back()), 1e-9) << test.name;
  }
}

TEST(SpringJointDrives, DriveSettlesWithItsDampingRatio) {
  // Gravity off; a PD drive (k = 40 N·m/rad, ζ = 0.2 with I about the held end) turns the rod
  // 0.3 rad about y: the logarithmic decrement gives ζ back within 10 %, and it settles.
  Model model = rod_on_ball_joint();
  model.settings.gravity.setZero();
  const double stiffness = 40, zeta = 0.2, target = 0.3;
  model.joints[0].drive = JointDrive{.stiffness = stiffness, .damping = 2 * zeta * std::sqrt(stiffness * kEndInertia),
                                     .target_rotation = Vector3(0, target, 0)};
  for (const Case& test : kCases) {
    SpringState state = compile_springs(model, test.options);
    std::vector<double> angle;
    for (int s = 0; s < 4000; ++s) {
      step(state, 1e-3);
      angle.push_back(coordinates(state, 0).rotation.y() - target);
    }
    const std::vector<double> peaks = testing::maxima(angle);
    ASSERT_GE(peaks.size(), 3u) << test.name;
    const double measured = testing::damping_ratio(peaks[0], peaks[1]);
    EXPECT_NEAR(measured, zeta, 0.1 * zeta) << test.name;
    EXPECT_LT(std::abs(angle.back()), 1e-4) << test.name;
  }
}

TEST(SpringJointDrives, AStiffDriveIsStableInTheImplicitStep) {
  // k·h²/I = 100 at 1/60 s: the backward-Euler step carries the drive in its matrix and settles.
  Model model = rod_on_ball_joint();
  model.settings.gravity.setZero();
  const double dt = 1.0 / 60;
  model.joints[0].drive = JointDrive{.stiffness = 100 * kEndInertia / (dt * dt), .target_rotation = Vector3(0, 0.3, 0)};
  SpringState state = compile_springs(model, {.integrator = Integrator::backward_euler});
  double largest = 0;
  for (int s = 0; s < 120; ++s) {
    ASSERT_EQ(step(state, dt).status, StepStatus::ok);
    largest = std::max(largest, coordinates(state, 0).rotation.norm());
  }
  EXPECT_LT(largest, 0.3 * 1.05);
  EXPECT_NEAR(coordinates(state, 0).rotation.y(), 0.3, 1e-3);
}

TEST(SpringJointDrives, SphericalDriveTurnsTheLimbToItsTarget) {
  // Two rods in free fall (gravity off), tumbling; the second driven to a rotation given in
  // world axes at rest relative to the first. The explicit integrators apply the drive's
  // damping explicitly, stable while h·c·(1/I_o + 1/I_i) < 2 for the limbs' smallest moments
  // (about their axes): they get 8 cm thick rods; the implicit step takes the 1 cm ones.
  for (const Case& test : kCases) {
    Model model = testing::make_chain({1, 2}, 0.5, false);
    model.settings.gravity.setZero();
    model.joints[0].drive = JointDrive{.stiffness = 20, .damping = 3, .target_rotation = Vector3(0.3, -0.5, 0.8)};
    model.bodies[0].angular_velocity = Vector3(0.5, 0, 1);
    const bool implicit = test.options.integrator == Integrator::backward_euler;
    if (!implicit) {
      for (Body& body : model.bodies) body.shape.radius = 0.08;
    }
    SpringState state = compile_springs(model, test.options);
    for (int s = 0; s < 5000; ++s) step(state, implicit ? 1.0 / 480 : 1e-3);
    EXPECT_LT(drive_error(state.joint_controls.joints[0], state.joint_controls.frames[0], coordinates(state, 0)), 1e-3) << test.name;
  }
}

TEST(SpringJointControls, OtherJointTypesAreRefusedByName) {
  // The method takes spherical and revolute joints (spring_hinge_test.cpp): the others are
  // refused naming the joint and its type.
  for (const JointType type : {JointType::universal, JointType::prismatic, JointType::fixed}) {
    Model model = rod_on_ball_joint();
    model.joints[0].type = type;
    model.joints[0].axis = Vector3::UnitY();
    model.joints[0].second_axis = Vector3::UnitZ();
    const std::string name(joint_type_name(type));
    try {
      compile_springs(model);
      ADD_FAILURE() << name << " compiled";
    } catch (const ModelError& error) {
      EXPECT_NE(std::string(error.what()).find("joints[0] 'ball'"), std::string::npos) << error.what();
      EXPECT_NE(std::string(error.what()).find("does not support " + name + " joints"), std::string::npos) << error.what();
    }
  }
}

}  // namespace
}  // namespace limber
