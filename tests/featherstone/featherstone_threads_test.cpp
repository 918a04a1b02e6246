// The Featherstone method on threads (FeatherstoneOptions::threads; step.hpp;
// joint_space_contacts.hpp, "Groups"): each island is integrated as a task, and the islands the
// contacts join are solved as one task, apart from the others, so the
// state is the same bits on one thread or two, whichever way the islands and groups are split; an
// island moves as it would alone (its own substeps); and a step on threads allocates nothing.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/featherstone/compile.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "tests/support/allocation_counter.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

// What a run of the pile saw: the most groups in a step, the most islands in one group.
struct Grouping {
  std::size_t most_groups = 0;
  int most_islands = 0;
};

Grouping step_pile(FeatherstoneState& state, int steps) {
  Grouping seen;
  for (int s = 0; s < steps; ++s) {
    EXPECT_EQ(step(state).status, StepStatus::ok) << "step " << s;
    seen.most_groups = std::max(seen.most_groups, state.contact.groups.size());
    for (const ConstraintGroup& group : state.contact.groups) seen.most_islands = std::max(seen.most_islands, group.last_island - group.first_island);
  }
  return seen;
}

// The ragdoll pile (ragdolls falling down stairs onto each other: groups of one ragdoll and groups
// that contacts join, limits), as shipped (joint friction: the islands integrate on the calling
// thread) and with drives in place of the friction (the islands integrate as tasks too).
std::vector<Model> piles() {
  const Model shipped = testing::load_shipped_scene("ragdoll_pile.json");
  Model driven = shipped;
  for (Joint& joint : driven.joints) {
    joint.friction = 0;
    joint.drive = JointDrive{.stiffness = 5, .damping = 0.5};
  }
  return {shipped, driven};
}

TEST(FeatherstoneThreads, TheSameBitsOnOneThreadOrTwo) {
  constexpr int kSteps = 240;
  for (const Model& pile : piles()) {
    FeatherstoneState one = compile_featherstone(pile, {.integrator = Integrator::semi_implicit_euler, .threads = 1});
    const Grouping seen = step_pile(one, kSteps);
    EXPECT_GE(seen.most_groups, 2u) << "the groups are what the threads share";
    EXPECT_GE(seen.most_islands, 2) << "some contact joined two ragdolls";
    for (const Threading threading : {Threading::workers, Threading::parallel_for}) {
      FeatherstoneState two = compile_featherstone(pile, {.integrator = Integrator::semi_implicit_euler, .threads = 2, .threading = threading});
      ASSERT_NE(two.runner.get(), nullptr);
      EXPECT_EQ(two.runner->threads(), 2);
      EXPECT_EQ(two.joint_friction, one.joint_friction);
      step_pile(two, kSteps);
      EXPECT_TRUE(two.q == one.q) << "threading " << static_cast<int>(threading) << ", friction " << one.joint_friction;
      EXPECT_TRUE(two.v == one.v) << "threading " << static_cast<int>(threading) << ", friction " << one.joint_friction;
    }
  }
}

TEST(FeatherstoneThreads, AStepOnTwoThreadsAllocatesNothing) {
  for (const Model& pile : piles()) {
    FeatherstoneState state = compile_featherstone(pile, {.integrator = Integrator::semi_implicit_euler, .threads = 2});
    step_pile(state, 120);  // the ragdolls reach the stairs and each other
    const long before = testing::allocation_count();
    step_pile(state, 60);
    EXPECT_EQ(testing::allocation_count() - before, 0) << "friction " << state.joint_friction;
  }
}

TEST(FeatherstoneThreads, AnIslandStepsAsIfItWereAlone) {
  // Two pinned chains far apart, the second's last link spinning about its axis fast enough to
  // need substeps (300 rad/s: 1.25 rad a 1/240 s step, over the 0.5 rad a substep allows): the
  // first chain moves exactly as it does in a scene of its own, under both integrators and on
  // one thread or two. Its bodies are the first of both scenes.
  const Model alone = testing::make_chain({1, 1, 1, 1}, 0.2, true);
  Model both = alone;
  const Model other = testing::make_chain({1, 1, 1, 1}, 0.2, true, Vector3(0, 5, 1));
  const int offset = static_cast<int>(both.bodies.size());
  for (Body body : other.bodies) {
    body.name += "_other";
    both.bodies.push_back(body);
  }
  both.bodies.back().angular_velocity = 300 * both.bodies.back().axis;
  for (Joint joint : other.joints) {
    joint.name += "_other";
    if (joint.inboard != kWorld) joint.inboard += offset;
    joint.outboard += offset;
    both.joints.push_back(joint);
  }
  for (const Integrator integrator : {Integrator::semi_implicit_euler, Integrator::rk4}) {
    FeatherstoneState single = compile_featherstone(alone, {.integrator = integrator});
    for (int s = 0; s < 240; ++s) step(single);
    for (const int threads : {1, 2}) {
      FeatherstoneState pair = compile_featherstone(both, {.integrator = integrator, .threads = threads});
      for (int s = 0; s < 240; ++s) step(pair);
      for (std::size_t b = 0; b < alone.bodies.size(); ++b) {
        EXPECT_TRUE(pair.bodies.state.position[b] == single.bodies.state.position[b]) << integrator_name(integrator) << ", body " << b;
        EXPECT_TRUE(pair.bodies.state.orientation[b].coeffs() == single.bodies.state.orientation[b].coeffs())
            << integrator_name(integrator) << ", body " << b;
      }
    }
  }
}

TEST(FeatherstoneThreads, OneThreadStartsNoneAndTooManyAreRefused) {
  const Model pile = testing::load_shipped_scene("ragdoll_pile.json");
  EXPECT_EQ(compile_featherstone(pile, {.threads = 1}).runner.get(), nullptr);
  EXPECT_THROW(compile_featherstone(pile, {.threads = kMaxThreads + 1}), std::invalid_argument);
  EXPECT_THROW(compile_featherstone(pile, {.threads = -1}), std::invalid_argument);
}

}  // namespace
}  // namespace limber
