// The model generators: the sizes of the models and of their compiled particle states, the
// geometry that makes joined link ends meet, and one clear line for each spec that describes no
// model.
#include <algorithm>
#include <cmath>
#include <functional>
#include <set>
#include <string>
#include <tuple>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/verlet/compile.hpp"

namespace limber {
namespace {

// The particle method with each joint one particle: the workloads' usual form.
VerletOptions shared_joints() {
  VerletOptions options;
  options.verlet.joints = ParticleJoints::shared_particle;
  return options;
}

using ::testing::HasSubstr;
using ::testing::StartsWith;

std::size_t pinned_particles(const VerletState<double>& state) {
  std::size_t pinned = 0;
  for (std::size_t p = 0; p < state.particles.size(); ++p) pinned += state.particles.inverse_mass[p] == 0;
  return pinned;
}

// ---- chain ----

TEST(ChainModel, SharedParticlesMergeThePinIntoTheFirstHead) {
  const Model model = make_chain_model({.links = 50});
  EXPECT_NO_THROW(validate(model));
  ASSERT_EQ(model.bodies.size(), 50u);
  ASSERT_EQ(model.joints.size(), 50u);  // the pin and joint_1 … joint_49
  EXPECT_EQ(model.joints.front().name, "pin");
  EXPECT_EQ(model.joints.back().name, "joint_49");

  const auto state = compile<double>(model, shared_joints());
  // In shared mode the pin's world slot merges with link_0's head: no particle of its own, and
  // no constraints for joints. One particle per link end: 51.
  EXPECT_EQ(state.particles.size(), 51u);
  EXPECT_EQ(state.constraints.size(), 50u);
  EXPECT_EQ(pinned_particles(state), 1u);
  const std::uint32_t first_head = state.limbs.head[state.body_limb[0]];
  EXPECT_EQ(state.particles.inverse_mass[first_head], 0.0);
  EXPECT_EQ(particle_name(model, state.particle_origins[first_head]), "link_0.head");
}

TEST(ChainModel, ZeroLengthConstraintsKeepAParticlePerLinkEndAndPin) {
  const Model model = make_chain_model({.links = 50});
  const auto state = compile<double>(model);
  EXPECT_EQ(state.particles.size(), 2 * 50u + 1);  // head and tail of each link, and the pin
  EXPECT_EQ(state.constraints.size(), 50u + 49u + 1u);  // links, joints between them, the pin
  EXPECT_EQ(pinned_particles(state), 1u);
}

TEST(ChainModel, UnpinnedChainHasNoWorldJoint) {
  const Model model = make_chain_model({.links = 50, .pinned = false});
  EXPECT_EQ(model.joints.size(), 49u);
  const auto state = compile<double>(model, shared_joints());
  EXPECT_EQ(state.particles.size(), 51u);
  EXPECT_EQ(pinned_particles(state), 0u);
}

TEST(ChainModel, EndLinkCarriesTheEndMassRatio) {
  const Model model = make_chain_model({.links = 10, .link_mass = 2, .end_mass_ratio = 3});
  EXPECT_EQ(model.bodies.back().mass, 6.0);
  EXPECT_EQ(model.bodies[8].mass, 2.0);
  EXPECT_DOUBLE_EQ(model.body_mass(), 9 * 2.0 + 6.0);
  // The free end particle carries half the end link, the one before it half of each neighbour.
  const auto state = compile<double>(model, shared_joints());
  const std::uint32_t last = state.body_limb[9];
  EXPECT_DOUBLE_EQ(state.particle_mass[state.limbs.tail[last]], 3.0);
  EXPECT_DOUBLE_EQ(state.particle_mass[state.limbs.head[last]], 1.0 + 3.0);
}

TEST(ChainModel, LinksLieHeadToTailAlongTheNormalizedDirection) {
  const Vector3 anchor(1, 2, 3);
  const Model model = make_chain_model({.links = 7, .link_length = 0.5, .anchor = anchor, .direction = {0, 3, -4}});
  const Vector3 unit(0, 0.6, -0.8);
  EXPECT_LT((model.bodies.front().head() - anchor).norm(), 1e-12);
  EXPECT_LT((model.bodies.back().tail() - (anchor + 7 * 0.5 * unit)).norm(), 1e-12);
  for (std::size_t k = 1; k < model.bodies.size(); ++k) {
    EXPECT_LT((model.bodies[k].head() - model.bodies[k - 1].tail()).norm(), 1e-12) << k;
  }
  EXPECT_EQ(model.bodies[3].shape.type, ShapeType::capsule);
  EXPECT_DOUBLE_EQ(model.bodies[3].shape.radius, 0.005);
  EXPECT_EQ(model.joints.front().inboard_anchor, anchor);
}

// ---- tree ----

TEST(TreeModel, ChildHeadsMeetParentTails) {
  const TreeSpec spec{.links = 40, .branching = 3};
  const Model model = make_tree_model(spec);
  EXPECT_NO_THROW(validate(model));
  ASSERT_EQ(model.bodies.size(), 40u);
  ASSERT_EQ(model.joints.size(), 40u);  // the pin and one joint per child
  EXPECT_LT(model.bodies[0].head().norm(), 1e-12);
  for (std::size_t k = 1; k < model.bodies.size(); ++k) {
    const std::size_t parent = (k - 1) / spec.branching;
    EXPECT_LT((model.bodies[k].head() - model.bodies[parent].tail()).norm(), 1e-12) << k;
    EXPECT_EQ(model.joints[k].inboard, static_cast<int>(parent));
    EXPECT_EQ(model.joints[k].outboard, static_cast<int>(k));
    EXPECT_LT(model.bodies[k].tail().z(), model.bodies[k].head().z()) << "children hang downward";
  }
  // Siblings fan out: their tails are apart.
  EXPECT_GT((model.bodies[1].tail() - model.bodies[2].tail()).norm(), 0.01);
  EXPECT_GT((model.bodies[2].tail() - model.bodies[3].tail()).norm(), 0.01);
}

TEST(TreeModel, CompilesToOneParticlePerLinkPlusTheRootHead) {
  const Model model = make_tree_model({.links = 40, .branching = 3});
  const auto state = compile<double>(model, shared_joints());
  EXPECT_EQ(state.particles.size(), 41u);
  EXPECT_EQ(state.constraints.size(), 40u);
  EXPECT_EQ(state.islands.size(), 1u);
  // The root's tail is a hub: the root's link and its three children's meet there.
  const std::uint32_t hub = state.limbs.tail[state.body_limb[0]];
  std::size_t limbs_at_hub = 0;
  for (std::size_t l = 0; l < state.limbs.size(); ++l) limbs_at_hub += (state.limbs.head[l] == hub) + (state.limbs.tail[l] == hub);
  EXPECT_EQ(limbs_at_hub, 1u + 3u);
}

TEST(TreeModel, BranchingOneIsAChainHangingStraightDown) {
  const Model model = make_tree_model({.links = 5, .branching = 1, .link_length = 0.2, .pinned = false});
  EXPECT_EQ(model.joints.size(), 4u);
  EXPECT_LT((model.bodies.back().tail() - Vector3(0, 0, -1.0)).norm(), 1e-12);
}

// ---- grid ----

TEST(GridModel, EveryEdgeIsALinkAndEveryNodeOneParticle) {
  const GridSpec spec{.columns = 10, .rows = 10, .spacing = 0.1, .link_mass = 0.1};
  const Model model = make_grid_model(spec);
  EXPECT_NO_THROW(validate(model));
  EXPECT_EQ(model.bodies.size(), 10u * 9 + 10u * 9);
  // Per node, one joint fewer than the link ends meeting there: 2·180 ends − 100 nodes; 2 pins.
  EXPECT_EQ(model.joints.size(), 2u * 180 - 100 + 2);

  const auto state = compile<double>(model, shared_joints());
  EXPECT_EQ(state.particles.size(), 100u);
  EXPECT_EQ(state.constraints.size(), 180u);
  EXPECT_EQ(state.islands.size(), 1u);
  for (std::size_t c = 0; c < state.constraints.size(); ++c) EXPECT_DOUBLE_EQ(state.constraints.rest_length[c], 0.1);
  double mass = 0;
  for (double m : state.particle_mass) mass += m;
  EXPECT_NEAR(mass, 180 * 0.1, 1e-12);

  // Each particle sits on its own node (c·s, 0, −r·s); the two pinned ones on the top corners.
  std::set<std::pair<long, long>> nodes;
  std::set<std::pair<long, long>> pinned;
  for (std::size_t p = 0; p < state.particles.size(); ++p) {
    const Vector3 x = state.particles.position(p);
    const std::pair<long, long> node{std::lround(-x.z() / 0.1), std::lround(x.x() / 0.1)};
    EXPECT_LT((x - Vector3(0.1 * node.second, 0, -0.1 * node.first)).norm(), 1e-12) << p;
    nodes.insert(node);
    if (state.particles.inverse_mass[p] == 0) pinned.insert(node);
  }
  EXPECT_EQ(nodes.size(), 100u);
  EXPECT_EQ(pinned, (std::set<std::pair<long, long>>{{0, 0}, {0, 9}}));
}

TEST(GridModel, RectangularUnpinnedGrid) {
  const Model model = make_grid_model({.columns = 5, .rows = 3, .pin_top_corners = false});
  EXPECT_EQ(model.bodies.size(), 3u * 4 + 5u * 2);
  EXPECT_EQ(model.joints.size(), 2u * 22 - 15);
  const auto state = compile<double>(model, shared_joints());
  EXPECT_EQ(state.particles.size(), 15u);
  EXPECT_EQ(state.constraints.size(), 22u);
  EXPECT_EQ(pinned_particles(state), 0u);
}

// ---- humanoid pile ----

TEST(HumanoidPile, CopiesTheHumanoidWithoutTheBall) {
  Model humanoid = load_scene_text(embedded_humanoid_scene(), "humanoid").model;
  humanoid.balls.clear();
  const auto one = compile<double>(humanoid);

  const Model pile = make_humanoid_pile(5, 1.5);
  EXPECT_NO_THROW(validate(pile));
  EXPECT_EQ(pile.bodies.size(), 5 * humanoid.bodies.size());
  EXPECT_EQ(pile.joints.size(), 5 * humanoid.joints.size());
  EXPECT_TRUE(pile.balls.empty());
  ASSERT_TRUE(pile.ground.has_value());
  EXPECT_EQ(pile.ground->friction, humanoid.ground->friction);
  EXPECT_EQ(pile.settings.time_step, humanoid.settings.time_step);
  EXPECT_EQ(pile.settings.sleep.start_asleep, humanoid.settings.sleep.start_asleep);

  const auto state = compile<double>(pile);
  EXPECT_EQ(state.particles.size(), 5 * one.particles.size());
  EXPECT_EQ(state.constraints.size(), 5 * one.constraints.size());
  EXPECT_EQ(state.islands.size(), 5u);
}

TEST(HumanoidPile, CopiesAreNamedAndLaidOnAGrid) {
  const Model pile = make_humanoid_pile(5, 1.5);  // 3 per row
  const int head_0 = pile.find_body("h0.head"), head_1 = pile.find_body("h1.head"), head_3 = pile.find_body("h3.head");
  ASSERT_GE(head_0, 0);
  ASSERT_GE(head_1, 0);
  ASSERT_GE(head_3, 0);
  EXPECT_GE(pile.find_body("h4.tibia_right"), 0);
  EXPECT_LT((pile.bodies[head_1].position - pile.bodies[head_0].position - Vector3(1.5, 0, 0)).norm(), 1e-12);
  EXPECT_LT((pile.bodies[head_3].position - pile.bodies[head_0].position - Vector3(0, 1.5, 0)).norm(), 1e-12);
  const auto neck_joint = std::find_if(pile.joints.begin(), pile.joints.end(), [](const Joint& j) { return j.name == "h3.head-neck"; });
  ASSERT_NE(neck_joint, pile.joints.end());
  EXPECT_EQ(neck_joint->inboard, head_3);
  EXPECT_EQ(pile.bodies[neck_joint->outboard].name, "h3.neck");
}

TEST(HumanoidPile, JoltRagdollTestSize) {
  const Model pile = make_humanoid_pile(160);
  EXPECT_EQ(pile.bodies.size(), 160u * 9);
  EXPECT_EQ(pile.joints.size(), 160u * 8);
  EXPECT_NO_THROW(validate(pile));
}

// ---- nonsense specs ----

std::string error_of(const std::function<Model()>& generate) {
  try {
    generate();
  } catch (const ModelError& error) {
    return error.what();
  }
  return "(no error)";
}

TEST(Generators, RejectNonsenseSpecsWithOneLine) {
  const double nan = std::nan("");
  const std::vector<std::tuple<std::function<Model()>, std::string>> cases = {
      {[] { return make_chain_model({.links = 0}); }, "chain.links: must be >= 1, got 0"},
      {[] { return make_chain_model({.links = 3'000'000'000}); },
       "chain.links: 3000000000 bodies, more than int body indices can name"},
      {[] { return make_chain_model({.links = 2, .link_length = 0}); }, "chain.link_length: must be > 0, got 0"},
      {[] { return make_chain_model({.links = 2, .link_mass = -1}); }, "chain.link_mass: must be > 0, got -1"},
      {[] { return make_chain_model({.links = 2, .end_mass_ratio = 0}); }, "chain.end_mass_ratio: must be > 0, got 0"},
      {[&] { return make_chain_model({.links = 2, .anchor = {nan, 0, 0}}); },
       "chain.anchor[0]: must be a finite number, got nan"},
      {[] { return make_chain_model({.links = 2, .direction = Vector3::Zero()}); },
       "chain.direction: must be a non-zero vector, got [0, 0, 0]"},
      {[] { return make_tree_model({.links = 0}); }, "tree.links: must be >= 1, got 0"},
      {[] { return make_tree_model({.links = 3, .branching = 0}); }, "tree.branching: must be >= 1, got 0"},
      {[&] { return make_tree_model({.links = 3, .link_length = nan}); }, "tree.link_length: must be a finite number, got nan"},
      {[] { return make_tree_model({.links = 3, .link_mass = 0}); }, "tree.link_mass: must be > 0, got 0"},
      {[] { return make_grid_model({.columns = 1}); }, "grid.columns: must be >= 2, got 1"},
      {[] { return make_grid_model({.rows = 0}); }, "grid.rows: must be >= 2, got 0"},
      {[] { return make_grid_model({.spacing = -0.1}); }, "grid.spacing: must be > 0, got -0.1"},
      {[] { return make_grid_model({.link_mass = 0}); }, "grid.link_mass: must be > 0, got 0"},
      {[] { return make_grid_model({.columns = 1'000'000, .rows = 1'000'000}); },
       "grid: 1999998000000 bodies, more than int body indices can name"},
      {[] { return make_humanoid_pile(0); }, "humanoid_pile.count: must be >= 1, got 0"},
      {[&] { return make_humanoid_pile(2, nan); }, "humanoid_pile.spacing: must be a finite number, got nan"},
  };
  for (const auto& [generate, message] : cases) EXPECT_EQ(error_of(generate), message);
}

TEST(Generators, HumanoidPileRejectsOverlappingCopies) {
  const std::string message = error_of([] { return make_humanoid_pile(2, 0.1); });
  EXPECT_THAT(message, StartsWith("humanoid_pile.spacing: must be >= 0.2"));
  EXPECT_THAT(message, HasSubstr("got 0.1"));
  EXPECT_EQ(message.find('\n'), std::string::npos);
  EXPECT_NO_THROW(make_humanoid_pile(2, 0.25));
}

// A box's or ellipsoid's head and tail are its centre: its extent is its bounding sphere's
// (model.hpp's bounding_radius), however it is turned, beside a capsule's axis ± radius.
TEST(Footprint, ABoxOrEllipsoidReachesItsBoundingRadius) {
  Model model;
  Body box;
  box.name = "box", box.mass = 1, box.position = {0, 0, 1};
  box.shape.type = ShapeType::box, box.shape.half_extents = {0.1, 0.2, 0.2};  // corner 0.3 m out
  box.shape.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()));
  model.bodies = {box};
  EXPECT_NEAR(footprint(model), 0.6, 1e-12);
  EXPECT_NEAR(vertical_extent(model), 0.6, 1e-12);
  Body egg = box;
  egg.name = "egg", egg.position = {1, 0, 1};
  egg.shape.type = ShapeType::ellipsoid;  // longest semi-axis 0.2 m
  Body rod;
  rod.name = "rod", rod.mass = 1, rod.position = {-1, 0, 1}, rod.shape = {ShapeType::capsule, 0.4, 0.05};  // along z
  model.bodies = {box, egg, rod};
  EXPECT_NEAR(footprint(model), 1 + 0.2 + 1 + 0.05, 1e-12) << "x: the rod's radius to the egg's semi-axis";
  EXPECT_NEAR(vertical_extent(model), 0.6, 1e-12) << "z: the box's corners, above and below the rod's 0.5 m";
}

}  // namespace
}  // namespace limber
