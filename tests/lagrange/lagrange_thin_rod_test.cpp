// Limbs of zero radius under the Lagrange method: their axial moment is 10⁻⁶ of the transverse
// one (kernel/rigid/rigid_scene.hpp), so ω_axial = L·a/I_axial magnifies any error in the world
// L or the axis a a million times. Nothing twists such a rod (every force acts on its axis), so
// its spin about its axis must stay what it was; the rods must stay finite, gain no energy and
// move as Featherstone's reduced coordinates move them (kernel/lagrange/README.md, "Thin limbs").

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/featherstone/compile.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/lagrange/compile.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/study/workloads.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

constexpr double kLength = 0.1;  // m, each rod
constexpr double kGravity = 9.81;
const Vector3 kPivot(0, 0, 1);

// One rod of zero radius, 1 kg, its head on a spherical joint at kPivot, tilted `tilt` rad from
// hanging and turning about the vertical at `spin` rad/s: a conical swing in 3-D.
Model conical_rod(double tilt, double spin) {
  Model model;
  model.name = "conical_rod";
  Body rod;
  rod.name = "rod";
  rod.shape = {ShapeType::cylinder, kLength, 0};
  rod.mass = 1;
  const Vector3 down(std::sin(tilt), 0, -std::cos(tilt));
  rod.axis = -down;  // head at the pivot
  rod.position = kPivot + 0.5 * kLength * down;
  rod.angular_velocity = Vector3(0, 0, spin);
  rod.linear_velocity = rod.angular_velocity.cross(rod.position - kPivot);
  model.bodies.push_back(rod);
  model.joints.push_back(spherical_joint("pin", kWorld, 0, kPivot, Vector3(0, 0, 0.5 * kLength)));
  model.settings.gravity = Vector3(0, 0, -kGravity);
  model.settings.sleep.enabled = false;
  return model;
}

// `links` rods of zero radius, 1 kg each, on spherical joints, the first pinned at kPivot, held out
// horizontally along (1, 1, 0)/√2 and released from rest. Off the world axes, rounding breaks
// the planar symmetry as it does in any scene (along x the axial components stay exactly 0).
Model horizontal_rod_chain(std::size_t links) {
  Model model = testing::make_chain(std::vector<double>(links, 1.0), kLength, true, kPivot);
  const Vector3 direction = Vector3(1, 1, 0).normalized();
  for (std::size_t k = 0; k < links; ++k) {
    model.bodies[k].shape = {ShapeType::cylinder, kLength, 0};
    model.bodies[k].axis = -direction;
    model.bodies[k].position = kPivot + (k + 0.5) * kLength * direction;
  }
  model.settings.gravity = Vector3(0, 0, -kGravity);
  return model;
}

// `links` rods of zero radius, 1 kg each, on spherical joints, the first pinned at kPivot, hanging
// and released from rest with link k tilted 0.15 rad off the vertical towards azimuth 1.3·k rad
// (the accuracy studies' small 3-D release, kernel/study/workloads.hpp): the links swing in
// different planes, regularly, and each link's swing reverses many times a second.
Model hanging_rod_chain(std::size_t links) {
  Model model = horizontal_rod_chain(links);
  Vector3 head = kPivot;
  for (std::size_t k = 0; k < links; ++k) {
    const double azimuth = 1.3 * static_cast<double>(k);
    const Vector3 down = Vector3(0.15 * std::cos(azimuth), 0.15 * std::sin(azimuth), -1).normalized();
    model.bodies[k].axis = -down;
    model.bodies[k].position = head + 0.5 * kLength * down;
    head += kLength * down;
  }
  return model;
}

// The energy the motion can trade: kinetic plus potential above every body's lowest possible
// centre (hanging straight down from the pivot), J. Gains are bounded as a fraction of it.
double swing_energy(const Model& model) {
  double energy = 0;
  for (std::size_t k = 0; k < model.bodies.size(); ++k) {
    const Body& body = model.bodies[k];
    const double lowest = kPivot.z() - (k + 0.5) * kLength;
    energy += body.mass * kGravity * (body.position.z() - lowest) + 0.5 * body.mass * body.linear_velocity.squaredNorm();
  }
  return energy;  // + the rotational energy, small beside it for these models (≤ a third of the translational)
}

// Body b's spin about its own axis (the axis of least inertia), rad/s.
double axial_spin(const LagrangeState& state, std::size_t b) {
  const RigidBodyState& y = state.bodies.state;
  const Eigen::Vector3d axis = y.orientation[b] * (state.shapes.principal_frame[b].conjugate() * Eigen::Vector3d::UnitZ());
  return state.bodies.angular_velocity(y, b).dot(axis);
}

// The tail of the last rod, m.
Eigen::Vector3d tip(const RigidScene& scene) {
  return world_point(scene, scene.bodies.size() - 1, Eigen::Vector3d(0, 0, -0.5 * kLength));
}

struct Setting {
  const char* name;
  LagrangeOptions options;
  double dt;
};
const LagrangeOptions kDefaults{};
const LagrangeOptions kRk4Projection{.integrator = Integrator::rk4, .stabilization = Stabilization::projection};

// A measurement for RecordProperty, 3 significant digits.
std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", value);
  return text;
}

// What a run of `duration` s shows: the largest energy gain over the start (J), the largest change
// of any rod's axial spin (rad/s); fails the test at a step that is not ok or not finite. Records
// them, and the largest distance of the chain's end from Featherstone's RK4 at the same step over
// the first second (m), as properties named after `label` and the setting (--gtest_output=xml).
struct RunSummary {
  double largest_gain = 0, largest_spin_change = 0;
};
RunSummary run(const std::string& label, const Model& model, const Setting& setting, double duration) {
  LagrangeState state = compile_lagrange(model, setting.options);
  FeatherstoneState featherstone = compile_featherstone(model);
  const double start = observe(state).energy();
  std::vector<double> spin(model.bodies.size());
  for (std::size_t b = 0; b < spin.size(); ++b) spin[b] = axial_spin(state, b);
  RunSummary result;
  double largest_distance = 0;
  const int steps = static_cast<int>(std::lround(duration / setting.dt)), first_second = static_cast<int>(std::lround(1 / setting.dt));
  for (int s = 1; s <= steps; ++s) {
    const StepReport report = step(state, setting.dt);
    const double energy = observe(state).energy();
    if (report.status != StepStatus::ok || !std::isfinite(energy)) {
      ADD_FAILURE() << label << ", " << setting.name << ": step " << s << " (" << s * setting.dt << " s) status "
                    << static_cast<int>(report.status) << ", energy " << energy;
      return {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
    }
    result.largest_gain = std::max(result.largest_gain, energy - start);
    for (std::size_t b = 0; b < spin.size(); ++b) {
      result.largest_spin_change = std::max(result.largest_spin_change, std::abs(axial_spin(state, b) - spin[b]));
    }
    if (s <= first_second && step(featherstone, setting.dt).status == StepStatus::ok) {
      largest_distance = std::max(largest_distance, (tip(state) - tip(featherstone)).norm());
    }
  }
  const std::string name = label + ", " + setting.name + ": ";
  ::testing::Test::RecordProperty(name + "largest energy gain (J)", number(result.largest_gain));
  ::testing::Test::RecordProperty(name + "largest axial spin change (rad/s)", number(result.largest_spin_change));
  ::testing::Test::RecordProperty(name + "end from Featherstone over 1 s (m)", number(largest_distance));
  return result;
}

TEST(LagrangeThinRods, ConicalRodSwingsWithoutGainingEnergyOrSpin) {
  // Main diverged in 0.18 s (defaults) and 0.02 s (RK4 + projection) at 1/60 s. Nothing acts
  // about the rod's axis (the pin and gravity act on it), so Euler's equation for a symmetric
  // body keeps its axial spin (3·cos 0.5 = 2.6 rad/s here) constant: allowed to move by 1 %.
  const Model model = conical_rod(0.5, 3);
  const double budget = 0.01 * swing_energy(model);
  for (const Setting& setting : {Setting{"defaults, 1/60 s", kDefaults, 1.0 / 60},
                                 Setting{"RK4 + projection, 1/60 s", kRk4Projection, 1.0 / 60},
                                 Setting{"RK4 + projection, 1/240 s", kRk4Projection, 1.0 / 240}}) {
    const RunSummary result = run("conical rod", model, setting, 5);
    EXPECT_LT(result.largest_gain, budget) << setting.name;
    EXPECT_LT(result.largest_spin_change, 0.01 * 3 * std::cos(0.5)) << setting.name;
  }
}

TEST(LagrangeThinRods, RodChainsReleasedFromRestStayBounded) {
  // Main diverged within 0.3 s with either setting, two rods or five. The energy may fall (the
  // defaults' Baumgarte term and symplectic Euler damp the whip) but not rise by 1 % of what
  // the swing can trade.
  for (std::size_t links : {2u, 5u}) {
    const Model model = horizontal_rod_chain(links);
    const double budget = 0.01 * swing_energy(model);
    for (const Setting& setting : {Setting{"defaults, 1/60 s", kDefaults, 1.0 / 60},
                                   Setting{"defaults, 1/240 s", kDefaults, 1.0 / 240},
                                   Setting{"RK4 + projection, 1/240 s", kRk4Projection, 1.0 / 240},
                                   Setting{"RK4 + projection, 1/1000 s", kRk4Projection, 1.0 / 1000}}) {
      const std::string label = std::to_string(links) + " rods";
      EXPECT_LT(run(label, model, setting, 5).largest_gain, budget) << label << ", " << setting.name;
    }
  }
}

TEST(LagrangeThinRods, FiveRodChainFollowsFeatherstone) {
  // RK4 + projection at 1/240 s against Featherstone's RK4 at the same step, on one Model: both
  // fourth order, so over the first second (before the chain's whip makes the motion chaotic)
  // they must agree far better than the tip's travel (≈ 0.5 m). 1 cm, a tenth of a link, leaves
  // room for the two discretizations and nothing for a spinning or diverging rod.
  const Model model = horizontal_rod_chain(5);
  LagrangeState lagrange = compile_lagrange(model, kRk4Projection);
  FeatherstoneState featherstone = compile_featherstone(model);
  const double dt = 1.0 / 240;
  double largest = 0;
  for (int s = 1; s <= 240; ++s) {
    ASSERT_EQ(step(lagrange, dt).status, StepStatus::ok) << s;
    ASSERT_EQ(step(featherstone, dt).status, StepStatus::ok) << s;
    largest = std::max(largest, (tip(lagrange) - tip(featherstone)).norm());
  }
  EXPECT_LT(largest, 0.01);
  EXPECT_GT((tip(lagrange) - horizontal_rod_chain(5).bodies.back().tail()).norm(), 0.1);  // it did fall
}

// The chain's end (the last body's tail, kLength long) every 1/60 s over `duration` s under
// `state`'s method at step dt (a divisor of 1/60 s); fails the test at a step that is not ok.
template <typename State>
std::vector<Eigen::Vector3d> end_path(State state, double dt, double duration) {
  std::vector<Eigen::Vector3d> path;
  const int steps = static_cast<int>(std::lround(duration / dt)), every = static_cast<int>(std::lround(1 / (60 * dt)));
  for (int s = 1; s <= steps; ++s) {
    const StepStatus status = step(state, dt).status;
    if (status != StepStatus::ok) {
      ADD_FAILURE() << "step " << s << " at 1/" << std::lround(1 / dt) << " s: status " << static_cast<int>(status);
      break;
    }
    if (s % every == 0) path.push_back(tip(state));
  }
  return path;
}

// The largest distance between two paths sampled at the same times, m (infinite if one stopped).
double largest_distance(const std::vector<Eigen::Vector3d>& path, const std::vector<Eigen::Vector3d>& reference) {
  if (path.size() != reference.size()) return std::numeric_limits<double>::infinity();
  double largest = 0;
  for (std::size_t i = 0; i < path.size(); ++i) largest = std::max(largest, (path[i] - reference[i]).norm());
  return largest;
}

TEST(LagrangeThinRods, RungeKuttaWithProjectionConvergesAtItsOrder) {
  // RK4 and RK2 + projection on thin chains against Featherstone's RK4 at 1/9600 s (the same
  // bodies, with the same 10⁻⁶ floor on the axial moment): the chain's end over 2 s, at 1/240,
  // 1/480 and 1/960 s. Order p divides the error by 2^p per halving of Δt once the leading term
  // dominates (RK4: 14–16 here, RK2: 3.7–3.9); at least 2^(p − 0.5) is asked (RK4: 11.3), room
  // for what is left of the higher terms at 1/240 s and nothing for an order less. Turning q
  // inside the stages (e163403) gave RK4 21 then 3.3 on the rods and 9.3 then 4.9 on the point
  // masses (kernel/lagrange/README.md, "Thin limbs").
  const double duration = 2, reference_dt = 1.0 / 9600;
  struct Chain {
    const char* name;
    Model model;
  };
  const Chain chains[] = {{"rods", hanging_rod_chain(5)},
                          {"point masses", study::heavy_end_chain(study::ChainRelease::small_3d).model}};
  struct Method {
    const char* name;
    Integrator integrator;
    int order;
  };
  for (const Chain& chain : chains) {
    const std::vector<Eigen::Vector3d> reference = end_path(compile_featherstone(chain.model), reference_dt, duration);
    // The reference's own error: about 1/15 of its distance to the run at twice its step (RK4).
    const double reference_error = largest_distance(end_path(compile_featherstone(chain.model), 2 * reference_dt, duration), reference);
    for (const Method& method : {Method{"RK4", Integrator::rk4, 4}, Method{"RK2", Integrator::rk2, 2}}) {
      SCOPED_TRACE(std::string(chain.name) + ", " + method.name);
      const LagrangeOptions options{.integrator = method.integrator, .stabilization = Stabilization::projection};
      std::vector<double> errors;
      for (int steps_per_second : {240, 480, 960}) {
        const double error = largest_distance(end_path(compile_lagrange(chain.model, options), 1.0 / steps_per_second, duration), reference);
        RecordProperty(std::string(chain.name) + ", " + method.name + ": error at 1/" + std::to_string(steps_per_second) + " s (m)", number(error));
        errors.push_back(error);
      }
      EXPECT_LT(reference_error, 0.01 * errors.back());  // the reference does not blur the finest error
      for (std::size_t k = 1; k < errors.size(); ++k) {
        const double rate = std::log2(errors[k - 1] / errors[k]);
        RecordProperty(std::string(chain.name) + ", " + method.name + ": order from 1/" + std::to_string(240 << (k - 1)) + " s", number(rate));
        EXPECT_GE(rate, method.order - 0.5) << "errors " << errors[k - 1] << " m, " << errors[k] << " m";
      }
    }
  }
}

}  // namespace
}  // namespace limber
