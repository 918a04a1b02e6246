// World::add_collider and remove_collider: structural edits like adding a body, which carry every
// body's state bit for bit, keep handles stable, and refuse a bad collider by its field.
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "limber/kernel/world/world.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

using ::testing::HasSubstr;
using testing::make_chain;

StaticCollider box_collider(std::string name, const Vector3& position) {
  StaticCollider box;
  box.name = std::move(name);
  box.type = ColliderType::box;
  box.position = position;
  box.half_extents = {0.5, 0.5, 0.1};
  return box;
}

/// Every body's pose and motion, as bits.
std::vector<double> snapshot(const World& world) {
  std::vector<double> bits;
  for (const BodyId body : world.bodies()) {
    const Pose pose = world.pose(body);
    const Motion motion = world.motion(body);
    bits.insert(bits.end(), {pose.position.x(), pose.position.y(), pose.position.z(), pose.orientation.w(), pose.orientation.x(),
                             pose.orientation.y(), pose.orientation.z(), motion.linear.x(), motion.linear.y(), motion.linear.z()});
  }
  return bits;
}

TEST(WorldColliders, AddingAndRemovingCollidersCarriesEveryBodyBitForBit) {
  Model model = make_chain({1, 1, 1}, 0.2, true);
  model.settings.sleep.enabled = false;
  World world(model);  // the particle method
  for (int s = 0; s < 30; ++s) ASSERT_EQ(world.step(1.0 / 240), StepStatus::ok);
  const std::vector<double> before = snapshot(world);

  // Far from the chain, so the steps after are the chain's alone.
  const ColliderId wall = world.add_collider(box_collider("wall", {5, 0, 0}));
  const ColliderId shelf = world.add_collider(box_collider("shelf", {-5, 0, 0}));
  EXPECT_EQ(snapshot(world), before);
  ASSERT_EQ(world.model().colliders.size(), 2u);
  EXPECT_EQ(world.model().colliders[1].name, "shelf");
  EXPECT_EQ(world.collider("wall"), wall);
  EXPECT_EQ(world.index(shelf), 1u);

  world.remove_collider(wall);
  EXPECT_EQ(snapshot(world), before);
  ASSERT_EQ(world.model().colliders.size(), 1u);
  EXPECT_EQ(world.index(shelf), 0u);  // the later handle moves down and stays valid
  EXPECT_EQ(world.collider("shelf"), shelf);
  EXPECT_THROW(world.index(wall), WorldError);
  EXPECT_THROW(world.remove_collider(wall), WorldError);
  EXPECT_THROW(world.collider("wall"), WorldError);
  for (int s = 0; s < 10; ++s) ASSERT_EQ(world.step(1.0 / 240), StepStatus::ok);
}

TEST(WorldColliders, AModelsCollidersHaveHandlesFromTheStart) {
  Model model = make_chain({1}, 0.2, false);
  model.colliders = {box_collider("floor", {0, 0, -1}), box_collider("roof", {0, 0, 3})};
  World world(model);
  EXPECT_EQ(world.index(world.collider("roof")), 1u);
  const ColliderId added = world.add_collider(box_collider("wall", {3, 0, 0}));
  EXPECT_EQ(world.index(added), 2u);
  EXPECT_NE(added, world.collider("floor"));
}

TEST(WorldColliders, AnInvalidColliderIsRefusedByItsFieldAndNothingChanges) {
  World world(make_chain({1, 1}, 0.2, true));
  world.add_collider(box_collider("wall", {5, 0, 0}));
  StaticCollider flat = box_collider("flat", {0, 0, -1});
  flat.half_extents.z() = 0;
  try {
    world.add_collider(flat);
    ADD_FAILURE() << "a box without height was added";
  } catch (const ModelError& error) {
    EXPECT_THAT(error.what(), HasSubstr("colliders[1].half_extents[2]: must be > 0, got 0"));
  }
  EXPECT_THROW(world.add_collider(box_collider("wall", {-5, 0, 0})), ModelError);  // a duplicate name
  EXPECT_EQ(world.model().colliders.size(), 1u);
  EXPECT_EQ(world.step(1.0 / 240), StepStatus::ok);
}

}  // namespace
}  // namespace limber
