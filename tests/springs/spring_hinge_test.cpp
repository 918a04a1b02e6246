// Revolute joints (hinges) in the stiff-spring method: two zero-length springs at anchor ± ε·h
// (thesis 3.2.5's two shared points, kernel/springs/compile.hpp), with the hinge's range, friction
// and drive about its axis (kernel/springs/spring_forces.hpp). Measured with the shared joint
// coordinates (kernel/model/joint_coordinates.hpp).
#include <algorithm>
#include <cmath>
#include <iostream>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/model/joint_coordinates.hpp"
#include "limber/kernel/springs/compile.hpp"
#include "limber/kernel/springs/spring_forces.hpp"
#include "limber/kernel/springs/step.hpp"
#include "tests/support/models.hpp"
#include "tests/support/oscillation.hpp"

namespace limber {
namespace {

constexpr double kPi = std::numbers::pi;

// One rod (cylinder, 1 kg, 1 m, radius 5 cm) lying along +x whose head is hinged to the world at
// the origin about y: it swings in the xz plane, the hinge plane. ε = 1/4 m.
constexpr double kRadius = 0.05, kSpacing = 0.25;
constexpr double kEndInertia = 1.0 / 3 + kRadius * kRadius / 4;  // kg·m², across the rod through its end

Model rod_on_hinge() { return testing::rod_held_at_head(JointType::revolute, Vector3::UnitY(), kRadius); }

// The rod turning at ω about the hinge's anchor: its centre's velocity ω × (0.5, 0, 0).
void spin(Model& model, const Vector3& omega) {
  model.bodies[0].angular_velocity = omega;
  model.bodies[0].linear_velocity = omega.cross(Vector3(0.5, 0, 0));
}

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

// The rod's axis out of the hinge plane (xz), rad.
double off_plane(const SpringState& state) {
  const Eigen::Vector3d axis = pose(state, 0).orientation * Eigen::Vector3d::UnitZ();
  return std::asin(std::min(1.0, std::abs(axis.y())));
}

struct Case {
  SpringOptions options;
  const char* name;
  bool implicit() const { return options.integrator == Integrator::backward_euler; }
};
const Case kCases[] = {
    {{}, "symplectic Euler"},
    {{.integrator = Integrator::rk4}, "RK4"},
    {{.integrator = Integrator::backward_euler}, "backward Euler"},
};

// The explicit integrators' step on the 5 cm rod: the stiffest mode is its twist about its own
// axis against the hinge's springs, ω = √(2kε²/I_axial) = 1414 rad/s at k = 2·10⁴ N/m, damped
// at 2cε²/I_axial = 2000 /s by c = 20 N·s/m: symplectic Euler wants h below ~1 ms.
constexpr double kExplicitStep = 1.0 / 4000;

TEST(SpringHinge, IsTwoSpringsOnTheAxisAndTheGapIsTheAnchors) {
  const Model model = rod_on_hinge();
  const SpringState state = compile_springs(model);
  ASSERT_EQ(state.springs.size(), 1u);
  EXPECT_EQ(state.springs.count[0], 2);
  // ε·h in each frame: the world's y, and the rod's turned onto its principal axes.
  EXPECT_LT((state.springs.inboard_offset[0] - Eigen::Vector3d(0, kSpacing, 0)).norm(), 1e-12);
  EXPECT_LT((state.bodies.state.orientation[0] * state.springs.outboard_offset[0] - Eigen::Vector3d(0, kSpacing, 0)).norm(), 1e-12);
  // A spherical joint keeps its one spring at the anchors.
  const SpringState ball = compile_springs(testing::make_chain({1, 1}, 0.5, true));
  for (std::size_t s = 0; s < ball.springs.size(); ++s) EXPECT_EQ(ball.springs.count[s], 1);

  // Bent off its axis and pulled from its anchor: the observer's gap is the anchor's alone, and
  // the springs' energy is both springs'.
  SpringState bent = compile_springs(model);
  bent.bodies.state.orientation[0] = Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ())) * bent.bodies.state.orientation[0];
  bent.bodies.state.position[0] += Eigen::Vector3d(0.01, 0.02, 0);
  const Eigen::Vector3d anchor = joint_separation(bent.springs, bent.bodies.state, 0);
  EXPECT_GT(anchor.norm(), 0.01);
  EXPECT_DOUBLE_EQ(observe(bent).max_joint_gap, anchor.norm() / 1.0);
  double energy = 0;
  for (const double side : {1.0, -1.0}) {
    const Eigen::Vector3d outboard_point =
        bent.bodies.state.position[0] + bent.bodies.state.orientation[0] * (bent.springs.outboard_anchor[0] + side * bent.springs.outboard_offset[0]);
    energy += 0.5 * 2e4 * (Eigen::Vector3d(0, side * kSpacing, 0) - outboard_point).squaredNorm();
  }
  EXPECT_NEAR(spring_energy(bent), energy, 1e-12 * energy);
}

TEST(SpringHinge, KeepsItsAxis) {
  // Gravity on; the rod swings about the hinge at 4 rad/s and is spun off the hinge plane at
  // w = 3 rad/s (about z). Off the axis the two springs hold it with 2kε² per radian (plus the
  // anchor's give), so the rod leaves the plane by about w·√(I_end/(2kε²)) (its kinetic energy
  // off the plane into that spring): 0.035 rad at k = 2·10⁴ N/m, 0.005 at 10⁶; allowed twice that.
  for (const double stiffness : {2e4, 1e6}) {
    Model model = rod_on_hinge();
    model.joints[0].stiffness = stiffness;
    model.joints[0].damping = 20;
    const double w = 3;
    spin(model, Vector3(0, 4, w));
    const double bound = 2 * w * std::sqrt(kEndInertia / (2 * stiffness * kSpacing * kSpacing));
    for (const Case& test : kCases) {
      if (stiffness > 1e5 && !test.implicit()) continue;
      const double dt = test.implicit() ? 1.0 / 480 : kExplicitStep;
      SpringState state = compile_springs(model, test.options);
      double largest = 0, swing = 0;
      for (int s = 0; s < static_cast<int>(2 / dt); ++s) {
        ASSERT_EQ(step(state, dt).status, StepStatus::ok) << test.name;
        largest = std::max(largest, off_plane(state));
        swing = std::max(swing, std::abs(coordinates(state, 0).angle));
      }
      EXPECT_LT(largest, bound) << test.name << ", k " << stiffness;
      EXPECT_GT(swing, 1.0) << test.name;  // it swung about its hinge
      std::cout << "[ hinge    ] " << test.name << ", k " << stiffness << ": off the plane by at most " << largest
                << " rad (bound " << bound << ")\n";
    }
  }
}

TEST(SpringHinge, TheImplicitStepHoldsAStiffHingeAtAFrameStep) {
  // k = 10⁶ N/m at 1/60 s, the rod spun off its plane: h²·k/m = 280 and h²·2kε²/I_axial =
  // 2.8·10⁴, stable because the backward-Euler matrix carries both springs of the pair with their
  // levers r ± ε·h (with the anchor's lever r for both instead, this diverges in its first steps).
  Model model = rod_on_hinge();
  model.joints[0].stiffness = 1e6;
  model.joints[0].damping = 20;
  spin(model, Vector3(0, 4, 3));
  SpringState state = compile_springs(model, {.integrator = Integrator::backward_euler});
  const double dt = 1.0 / 60;
  double largest = 0, gap = 0;
  for (int s = 0; s < 120; ++s) {
    ASSERT_EQ(step(state, dt).status, StepStatus::ok);
    largest = std::max(largest, off_plane(state));
    gap = std::max(gap, joint_separation(state.springs, state.bodies.state, 0).norm());
  }
  EXPECT_LT(largest, 0.01);
  EXPECT_LT(gap, 2.5e-3);  // m: 1.25 mm measured, the lag of a first-order step on the swinging rod
  EXPECT_GT(std::abs(coordinates(state, 0).angle), 0.1);  // it swings
}

TEST(SpringHinge, RangeHoldsAsStiffAsTheJoint) {
  // The rod is thrown up (−10 rad/s about y) against the range's min −0.5 rad, then falls under
  // gravity onto its max 0.6 rad. A limit is a spring ringing at the joint spring's √(k/m) (the
  // spherical limits' rule): reached at v ≤ 10 rad/s it gives way by about v/√(k/m), allowed
  // 2·v/√(k/m); at rest on the max (after 5 s: it bounces, with the limit's damping ratio 0.2),
  // gravity's torque over the limit's stiffness k·I/m (I = 1/12 kg·m², about the centre) presses
  // it in by 2.4·10⁻³ rad at k = 2·10⁴ N/m.
  for (const double stiffness : {2e4, 1e6}) {
    Model model = rod_on_hinge();
    model.joints[0].stiffness = stiffness;
    model.joints[0].damping = 0.2 * 2 * std::sqrt(stiffness);
    model.joints[0].limits.range = Range{-0.5, 0.6};
    spin(model, Vector3(0, -10, 0));
    const double give = 2 * 10 / std::sqrt(stiffness);
    for (const Case& test : kCases) {
      if (stiffness > 1e5 && !test.implicit()) continue;
      const double dt = test.implicit() ? (stiffness > 1e5 ? 1.0 / 2000 : 1.0 / 480) : kExplicitStep;
      SpringState state = compile_springs(model, test.options);
      double above = 0, below = 0;
      for (int s = 0; s < static_cast<int>(5 / dt); ++s) {
        ASSERT_EQ(step(state, dt).status, StepStatus::ok) << test.name;
        const double angle = coordinates(state, 0).angle;
        above = std::max(above, angle - 0.6), below = std::max(below, -0.5 - angle);
      }
      EXPECT_GT(below, 0) << test.name;  // it reached both ends
      EXPECT_GT(above, 0) << test.name;
      EXPECT_LT(below, give) << test.name << ", k " << stiffness;
      EXPECT_LT(above, give) << test.name << ", k " << stiffness;
      const double resting = coordinates(state, 0).angle - 0.6;
      EXPECT_GT(resting, 0) << test.name;  // it rests pressed onto the max
      EXPECT_LT(resting, 0.005) << test.name;
      EXPECT_LT(off_plane(state), 1e-3) << test.name;
      std::cout << "[ hinge    ] " << test.name << ", k " << stiffness << ": past min " << below << ", past max " << above
                << " rad (allowed " << give << "); at rest " << resting << "\n";
    }
  }
}

TEST(SpringHinge, FrictionDeceleratesAtTorqueOverInertiaThenHolds) {
  // Gravity off, the rod spinning about its hinge at 3 rad/s: friction τ_f takes it down at
  // τ_f/I_end, then holds it still.
  Model model = rod_on_hinge();
  model.settings.gravity.setZero();
  const double friction = 0.5, start = 3;
  model.joints[0].friction = friction;
  spin(model, Vector3(0, start, 0));
  const double deceleration = friction / kEndInertia, stop = start / deceleration;
  for (const Case& test : kCases) {
    const double dt = test.implicit() ? 1.0 / 480 : kExplicitStep;
    SpringState state = compile_springs(model, test.options);
    std::vector<double> speed;
    for (int s = 0; s < static_cast<int>(3 / dt); ++s) {
      ASSERT_EQ(step(state, dt).status, StepStatus::ok) << test.name;
      speed.push_back(state.bodies.angular_velocity(state.bodies.state, 0).y());
    }
    const auto at = [&](double t) { return speed[static_cast<std::size_t>(std::lround(t / dt)) - 1]; };
    EXPECT_NEAR((at(0.1) - at(0.9)) / 0.8, deceleration, 0.03 * deceleration) << test.name;
    EXPECT_NEAR((at(1.0) - at(1.8)) / 0.8, deceleration, 0.03 * deceleration) << test.name;
    for (std::size_t s = static_cast<std::size_t>((stop + 0.1) / dt); s < speed.size(); ++s) {
      ASSERT_LT(std::abs(speed[s]), 1e-4) << test.name << ", step " << s;
    }
    std::cout << "[ hinge    ] " << test.name << ": deceleration " << (at(0.1) - at(0.9)) / 0.8 << " rad/s² (τ_f/I "
              << deceleration << "), final " << speed.back() << " rad/s\n";
  }
}

TEST(SpringHinge, DriveSettlesWithItsDampingRatio) {
  // Gravity off; a PD drive (k = 40 N·m/rad, ζ = 0.2 with I about the hinge) turns the rod to
  // 0.3 rad about its hinge: the logarithmic decrement gives ζ back within 10 %, and it settles.
  Model model = rod_on_hinge();
  model.settings.gravity.setZero();
  const double stiffness = 40, zeta = 0.2, target = 0.3;
  model.joints[0].drive = JointDrive{.stiffness = stiffness, .damping = 2 * zeta * std::sqrt(stiffness * kEndInertia), .target = target};
  for (const Case& test : kCases) {
    const double dt = test.implicit() ? 1e-3 : kExplicitStep;
    SpringState state = compile_springs(model, test.options);
    std::vector<double> angle;
    for (int s = 0; s < static_cast<int>(4 / dt); ++s) {
      ASSERT_EQ(step(state, dt).status, StepStatus::ok) << test.name;
      angle.push_back(coordinates(state, 0).angle - target);
    }
    const std::vector<double> peaks = testing::maxima(angle);
    ASSERT_GE(peaks.size(), 3u) << test.name;
    const double measured = testing::damping_ratio(peaks[0], peaks[1]);
    EXPECT_NEAR(measured, zeta, 0.1 * zeta) << test.name;
    EXPECT_LT(std::abs(angle.back()), 1e-4) << test.name;
    std::cout << "[ hinge    ] " << test.name << ": damping ratio " << measured << " (drive's " << zeta << ")\n";
  }
}

TEST(SpringHinge, AStiffDriveIsStableInTheImplicitStep) {
  // k·h²/I = 100 at 1/60 s about the hinge: backward Euler carries the drive in its matrix.
  Model model = rod_on_hinge();
  model.settings.gravity.setZero();
  const double dt = 1.0 / 60;
  model.joints[0].drive = JointDrive{.stiffness = 100 * kEndInertia / (dt * dt), .target = -0.3};
  SpringState state = compile_springs(model, {.integrator = Integrator::backward_euler});
  double largest = 0;
  for (int s = 0; s < 120; ++s) {
    ASSERT_EQ(step(state, dt).status, StepStatus::ok);
    largest = std::max(largest, std::abs(coordinates(state, 0).angle));
  }
  EXPECT_LT(largest, 0.3 * 1.05);
  EXPECT_NEAR(coordinates(state, 0).angle, -0.3, 1e-3);
}

TEST(SpringHinge, DriveBetweenTwoFreeLimbs) {
  // Two rods in free fall (gravity off), tumbling, hinged about y at their shared end; the
  // second driven to 0.7 rad: it gets there, about the hinge alone (the springs keep the axis).
  for (const Case& test : kCases) {
    Model model = testing::make_chain({1, 2}, 0.5, false);
    model.settings.gravity.setZero();
    for (Body& body : model.bodies) body.shape.radius = kRadius;
    model.joints[0].type = JointType::revolute;
    model.joints[0].axis = Vector3::UnitY();
    model.joints[0].drive = JointDrive{.stiffness = 20, .damping = 3, .target = 0.7};
    model.bodies[0].angular_velocity = Vector3(0.5, 0, 1);
    SpringState state = compile_springs(model, test.options);
    const double dt = test.implicit() ? 1.0 / 480 : kExplicitStep;
    for (int s = 0; s < static_cast<int>(5 / dt); ++s) ASSERT_EQ(step(state, dt).status, StepStatus::ok) << test.name;
    const JointCoordinates q = coordinates(state, 0);
    EXPECT_NEAR(q.angle, 0.7, 1e-3) << test.name;
    EXPECT_NEAR(q.rotation.norm(), 0.7, 2e-3) << test.name;  // nothing but the hinge's turn
  }
}

TEST(SpringHinge, TheArmedRagdollRunsUnderTheImplicitStepWithItsKneesInRange) {
  // tools/scenes/ragdoll.json (hinged knees and elbows with ranges, friction on every joint, the
  // default springs k = 2·10⁴ N/m) at its own Δt = 1/240 s for 2 s: the ball knocks it over onto
  // its back and its knees fold to their 2.356 rad stop. A range is a limit spring ringing at the
  // joint spring's √(k/m) (m the reduced mass of thigh and shin, 10.2 kg: 44 rad/s), so a knee
  // reaching it at v rad/s gives about v/√(k/m), and the test allows 2·v/√(k/m) for the fastest
  // knee (the spherical limits' rule, spring_joint_controls_test.cpp). The elbows are printed, not
  // held to it: the torso lands on the arms and bends them backwards under its weight, which the
  // light arms' limit springs (about 100 N·m/rad) cannot hold (kernel/springs/README.md).
  const Scene scene = load_scene_file(LIMBER_SOURCE_DIR "/tools/scenes/ragdoll.json");
  const SpringOptions options{.integrator = Integrator::backward_euler, .defaults = scene.methods.springs};
  SpringState state = compile_springs(scene.model, options);
  const double dt = scene.model.settings.time_step;
  double knee_excess = 0, knee_rate = 0, knee_bend = 0, elbow_excess = 0, gap = 0;
  bool woke = false;
  for (int s = 0; s < static_cast<int>(std::lround(2 / dt)); ++s) {
    ASSERT_EQ(step(state, dt).status, StepStatus::ok) << "step " << s;
    const Observation observation = observe(state);
    gap = std::max(gap, observation.max_joint_gap);
    woke = woke || !observation.body_sleeping;
    for (std::size_t k = 0; k < scene.model.joints.size(); ++k) {
      const Joint& joint = scene.model.joints[k];
      if (joint.type != JointType::revolute) continue;
      const double angle = coordinates(state, k).angle;
      const double excess = std::max(joint.limits.range->min - angle, angle - joint.limits.range->max);
      if (joint.name.find("tibia") == std::string::npos) {
        elbow_excess = std::max(elbow_excess, excess);
        continue;
      }
      knee_excess = std::max(knee_excess, excess), knee_bend = std::max(knee_bend, angle);
      const auto o = static_cast<std::size_t>(joint.outboard), i = static_cast<std::size_t>(joint.inboard);
      const Eigen::Vector3d axis = pose(state, joint.inboard).orientation * state.joint_controls.frames[k].axis;
      const Eigen::Vector3d relative = state.bodies.angular_velocity(state.bodies.state, o) - state.bodies.angular_velocity(state.bodies.state, i);
      knee_rate = std::max(knee_rate, std::abs(axis.dot(relative)));
    }
  }
  const double thigh = scene.model.bodies[5].mass, shin = scene.model.bodies[7].mass;
  const double ringing = std::sqrt(scene.methods.springs.stiffness * (1 / thigh + 1 / shin));
  EXPECT_TRUE(woke);                 // the ball hit it
  EXPECT_GT(knee_bend, 2.0);         // its knees folded
  EXPECT_LT(knee_excess, 2 * knee_rate / ringing);
  std::cout << "[ ragdoll  ] springs-implicit at 1/240 s: knees past their range by at most " << knee_excess
            << " rad (allowed 2·" << knee_rate << " rad/s / " << ringing << " /s = " << 2 * knee_rate / ringing
            << "), elbows by " << elbow_excess << " rad; largest joint gap " << gap << "\n";
}

}  // namespace
}  // namespace limber
