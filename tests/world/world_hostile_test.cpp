// The World under calls an engine should not make: time steps too small to take, orientations
// that are not rotations, handles of another World, a body blown up to infinity. Each is refused
// with a WorldError or a status, and nothing else in the World is harmed.
#include <cfloat>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "limber/kernel/world/world_internals.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

using ::testing::HasSubstr;
using testing::make_chain;

const Method kMethods[] = {Method::particles, Method::springs, Method::lagrange, Method::featherstone};

std::string name(Method method) { return std::string(method_name(method)); }

WorldOptions options_for(Method method, bool single_precision = false) {
  WorldOptions options;
  options.method = method;
  options.single_precision = single_precision;
  return options;
}

// Every body's pose, as bits to compare.
std::vector<double> pose_bits(const World& world) {
  std::vector<double> bits;
  for (const BodyId body : world.bodies()) {
    const Pose pose = world.pose(body);
    bits.insert(bits.end(), {pose.position.x(), pose.position.y(), pose.position.z(), pose.orientation.w(), pose.orientation.x(),
                             pose.orientation.y(), pose.orientation.z()});
  }
  return bits;
}

// A step too small to take — zero, subnormal, the smallest normal double, below the stated
// minimum — is refused as invalid_time_step and changes nothing; the World steps on after it.
TEST(WorldHostile, TimeStepsTooSmallToTakeAreRefusedAndChangeNothing) {
  const Model model = make_chain({1, 1, 2}, 0.2, true);
  const double too_small[] = {0.0, std::numeric_limits<double>::denorm_min(), 1e-320, DBL_MIN, 1e-200, 0.5 * kMinimumTimeStep};
  for (const Method method : kMethods) {
    World world(model, options_for(method));
    for (int k = 0; k < 10; ++k) world.step(1.0 / 240);
    const std::vector<double> before = pose_bits(world);
    const double time = world.time();
    for (const double dt : too_small) {
      EXPECT_EQ(world.step(dt), StepStatus::invalid_time_step) << name(method) << " dt " << dt;
      EXPECT_EQ(pose_bits(world), before) << name(method) << " dt " << dt;
      EXPECT_EQ(world.time(), time) << name(method);
    }
    EXPECT_EQ(world.step(kMinimumTimeStep), StepStatus::ok) << name(method);
    for (int k = 0; k < 10; ++k) EXPECT_EQ(world.step(1.0 / 240), StepStatus::ok) << name(method);
  }
}

// The methods' configurations the short-step property runs: each method with chain.json's
// settings, the particle method under both projection rules and in float.
struct Configuration {
  std::string label;
  WorldOptions options;
  double tolerance;  // of the energy, J: what stepping h later legitimately changes, and rounding
};

std::vector<Configuration> short_step_configurations(const Scene& scene) {
  std::vector<Configuration> configurations;
  for (const Method method : kMethods) configurations.push_back({name(method), world_options(method, scene.methods), 0.01});
  WorldOptions pbd = world_options(Method::particles, scene.methods);
  pbd.particles.relaxation.projection = ProjectionRule::pbd;
  configurations.push_back({"particles pbd", pbd, 0.01});
  WorldOptions thesis;  // one pbd step of the default sweeps: the thesis's form
  configurations.push_back({"particles pbd, 1 substep", thesis, 0.01});
  for (Configuration& configuration : std::vector<Configuration>(configurations.begin(), configurations.begin() + 1)) {
    configuration.options.single_precision = true;
    configuration.label += " float";
    configuration.tolerance = 0.5;  // float: 2.5·10⁻³ of the chain's 200 J
    configurations.push_back(configuration);
  }
  return configurations;
}

// A step of any length a method takes gives a right answer: among steps of 1/240 s, one much
// shorter step (10⁻³ … 10⁻⁹ s) changes the energy no more than stepping that much later does.
// Position-based steps used to turn the joint gaps the last long step left into velocity
// gap/h: one step of 10⁻⁷ s took chain.json from 200 J to 13 000 J, and Lagrange's Baumgarte
// term from 200 J to 6·10⁶ J at 10⁻⁷ s.
TEST(WorldHostile, AShortStepAmongLongOnesKeepsTheEnergy) {
  const Scene scene = testing::shipped_scene("chain.json");
  for (const Configuration& configuration : short_step_configurations(scene)) {
    World reference(scene.model, configuration.options);
    for (int k = 0; k < 240; ++k) ASSERT_EQ(reference.step(1.0 / 240), StepStatus::ok) << configuration.label;
    const double before = reference.observe().energy();
    for (const double h : {1e-3, 1e-5, 1e-7, 1e-9}) {
      World world(scene.model, configuration.options);
      for (int k = 0; k < 120; ++k) world.step(1.0 / 240);
      const double minimum = std::visit([](const auto& state) { return minimum_time_step(state); }, world.internals().state);
      if (h < minimum) {
        EXPECT_EQ(world.step(h), StepStatus::invalid_time_step) << configuration.label << " h " << h;
      } else {
        EXPECT_EQ(world.step(h), StepStatus::ok) << configuration.label << " h " << h;
      }
      for (int k = 120; k < 240; ++k) ASSERT_EQ(world.step(1.0 / 240), StepStatus::ok) << configuration.label << " h " << h;
      EXPECT_NEAR(world.observe().energy(), before, configuration.tolerance) << configuration.label << " h " << h;
    }
  }
}

// An orientation that is no rotation — zero, not a number, infinite, far from unit length — is
// refused by teleport, naming it, and the body stays where it was.
TEST(WorldHostile, TeleportRefusesAnOrientationThatIsNotARotation) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const Eigen::Quaterniond bad[] = {Eigen::Quaterniond(0, 0, 0, 0), Eigen::Quaterniond(nan, 0, 0, 0), Eigen::Quaterniond(1, inf, 0, 0),
                                    Eigen::Quaterniond(2, 0, 0, 0), Eigen::Quaterniond(1e-9, 0, 0, 0)};
  Model model = make_chain({1}, 0.3, false);
  model.settings.gravity.setZero();
  for (const Method method : kMethods) {
    World world(model, options_for(method));
    const BodyId limb = world.body("link_0");
    const std::vector<double> before = pose_bits(world);
    for (const Eigen::Quaterniond& orientation : bad) {
      try {
        world.teleport(limb, Pose{Eigen::Vector3d(0, 0, 2), orientation}, Motion{});
        ADD_FAILURE() << name(method) << ": teleported to " << orientation.coeffs().transpose();
      } catch (const WorldError& error) {
        EXPECT_THAT(error.what(), HasSubstr("teleport: orientation must be a finite unit quaternion")) << name(method);
      }
      EXPECT_EQ(pose_bits(world), before) << name(method);
    }
    // A unit quaternion off by rounding is taken (and normalized).
    const Eigen::Quaterniond turned(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()));
    world.teleport(limb, Pose{Eigen::Vector3d(0, 0, 2), Eigen::Quaterniond(turned.coeffs() * (1 + 1e-9))}, Motion{});
    EXPECT_LT(world.pose(limb).orientation.angularDistance(turned), 1e-9) << name(method);
    EXPECT_EQ(world.step(1.0 / 60), StepStatus::ok) << name(method);
  }
}

// A handle addresses a body of the World that gave it: another
// World refuses it instead of moving one of its own bodies, and so does a handle no World gave.
TEST(WorldHostile, HandlesOfAnotherWorldAreRefused) {
  const Model model = make_chain({1, 1, 1}, 0.2, true);
  World first(model, options_for(Method::particles)), second(model, options_for(Method::particles));
  const BodyId body = first.body("link_2");
  const JointId joint = first.joint("joint_1");
  EXPECT_NO_THROW((void)first.pose(body));
  const std::vector<double> before = pose_bits(second);
  try {
    second.apply_impulse(body, Eigen::Vector3d(0, 0, 5), Eigen::Vector3d::Zero());
    FAIL() << "another World's handle moved a body";
  } catch (const WorldError& error) {
    EXPECT_THAT(error.what(), HasSubstr("from another World"));
  }
  EXPECT_THROW((void)second.pose(body), WorldError);
  EXPECT_THROW((void)second.index(joint), WorldError);
  EXPECT_THROW(second.remove_body(body), WorldError);
  EXPECT_THROW((void)second.pose(BodyId{0}), WorldError);  // made by hand: no World's
  second.step(1.0 / 60);
  World replay(model, options_for(Method::particles));
  replay.step(1.0 / 60);
  EXPECT_EQ(pose_bits(second), pose_bits(replay)) << "the refused impulse must not have acted";
  EXPECT_NE(pose_bits(second), before);
}

// A removed body's handle stays refused when its slot is given to a body added after it (the
// handle's generation, not just its slot, must match), and every other handle keeps its body.
TEST(WorldHostile, AHandleOfARemovedThingIsRefusedAfterItsSlotIsReused) {
  const Model model = make_chain({1, 1, 1}, 0.1, true);
  World world(model, options_for(Method::lagrange));
  const BodyId removed = world.body("link_1"), kept = world.body("link_2");
  const Body description = world.body_description(removed);
  world.remove_body(removed);
  Body again = description;
  again.name = "again";
  const BodyId added = world.add_body(again);
  EXPECT_EQ(added.slot, removed.slot) << "the freed slot is reused";
  EXPECT_NE(added, removed);
  try {
    (void)world.pose(removed);
    FAIL() << "a removed body's handle addressed the body that took its slot";
  } catch (const WorldError& error) {
    EXPECT_THAT(error.what(), HasSubstr("no such body"));
  }
  EXPECT_EQ(world.body_description(added).name, "again");
  EXPECT_EQ(world.body_description(kept).name, "link_2");
  EXPECT_EQ(world.index(kept), 1u) << "the body after the removed one moved down";
}

// Two chains that do not touch, and a ball far from both. One chain blown up to infinity (a
// finite but absurd teleport or impulse) diverges; the other chain and the ball stay finite.
// Once the chain is teleported back, the World steps on exactly as a World in which it never
// blew up and was teleported the same way: nothing of the blow-up stayed behind.
TEST(WorldHostile, ABodyThatBlowsUpHarmsNoUnconnectedBodyAndTheWorldRecovers) {
  Model model = make_chain({1, 1, 1}, 0.2, true, Vector3(0, 0, 1));
  const Model other = make_chain({1, 1, 1}, 0.2, true, Vector3(0, 0, 1));
  append_model(model, other, "far_", Vector3(0, 3, 0));
  Ball ball;
  ball.position = Vector3(3, 0, 1);
  ball.radius = 0.1;
  ball.mass = 1;
  model.balls.push_back(ball);
  for (const Method method : kMethods) {
    World blown_up(model, options_for(method)), spared(model, options_for(method));
    for (World* world : {&blown_up, &spared}) {
      for (int k = 0; k < 5; ++k) ASSERT_EQ(world->step(1.0 / 240), StepStatus::ok) << name(method);
    }
    const BodyId blown = blown_up.body("link_2");
    if (method == Method::featherstone) {  // its link hangs from a joint: no teleport; an impulse will do
      blown_up.apply_impulse(blown, Eigen::Vector3d(1e300, 1e300, 1e300), blown_up.pose(blown).position);
    } else {
      blown_up.teleport(blown, Pose{Eigen::Vector3d(1e300, -1e300, 1e300), Eigen::Quaterniond::Identity()}, Motion{});
    }
    EXPECT_NE(blown_up.step(1.0 / 240), StepStatus::ok) << name(method) << ": a body at 1e300 m stepped ok";
    for (int k = 0; k < 2; ++k) blown_up.step(1.0 / 240);
    for (int k = 0; k < 3; ++k) spared.step(1.0 / 240);
    for (const char* far : {"far_link_0", "far_link_1", "far_link_2"}) {
      EXPECT_EQ(blown_up.pose(blown_up.body(far)).position, spared.pose(spared.body(far)).position) << name(method) << " " << far;
    }
    EXPECT_EQ(blown_up.ball(blown_up.balls()[0]).position, spared.ball(spared.balls()[0]).position) << name(method);
    if (method == Method::featherstone) continue;  // its coordinates cannot be set back link by link
    for (World* world : {&blown_up, &spared}) {
      for (const char* near : {"link_0", "link_1", "link_2"}) {
        const BodyId body = world->body(near);
        world->teleport(body, Pose{world->body_description(body).position, world->body_description(body).orientation()}, Motion{});
      }
    }
    for (int k = 0; k < 20; ++k) {
      const StepStatus status = blown_up.step(1.0 / 240);
      ASSERT_EQ(status, spared.step(1.0 / 240)) << name(method) << " step " << k << " after the rescue";
      ASSERT_EQ(status, StepStatus::ok) << name(method) << " step " << k << " after the rescue";
    }
    EXPECT_EQ(pose_bits(blown_up), pose_bits(spared)) << name(method);
  }
}

}  // namespace
}  // namespace limber
