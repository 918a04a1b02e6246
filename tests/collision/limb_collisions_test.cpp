// The shared limb collision world (kernel/geometry/limb_collisions.hpp): what it excludes, the
// geometry of its limb–limb and limb–static contacts against hand-made configurations, and its
// broadphase against brute force over every pair.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <numbers>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/geometry/limb_collisions.hpp"
#include "limber/kernel/threading/block_runner.hpp"
#include "tests/support/allocation_counter.hpp"

namespace limber {
namespace {

using Eigen::Vector3d;

// A capsule limb from tail to head (unit mass: collision reads only the shape and the pose).
Body capsule_limb(const Vector3d& head, const Vector3d& tail, double radius) {
  Body body;
  body.name = "limb";
  body.shape = {ShapeType::capsule, (head - tail).norm(), radius};
  body.mass = 1;
  body.position = 0.5 * (head + tail);
  body.axis = (head - tail).normalized();
  return body;
}

std::vector<LimbSegment> segments_of(const Model& model) {
  std::vector<LimbSegment> limbs;
  for (const Body& body : model.bodies) limbs.push_back({body.head(), body.tail(), body.shape.radius});
  for (const Ball& ball : model.balls) limbs.push_back({ball.position, ball.position, ball.radius});
  return limbs;
}

std::vector<LimbContact> find_all(LimbCollisions& collisions, const std::vector<LimbSegment>& limbs, double margin = 0) {
  const std::vector<std::uint8_t> awake(limbs.size(), 1);
  std::vector<LimbContact> contacts;
  collisions.find(limbs, awake, margin, contacts);
  return contacts;
}

// The limb pairs that touch, each once (limbs lying along each other touch at up to three points).
std::vector<std::pair<std::uint32_t, std::uint32_t>> touching_pairs(const std::vector<LimbContact>& contacts) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  for (const LimbContact& c : contacts) {
    if (c.second != kStaticShape && (pairs.empty() || pairs.back() != std::make_pair(c.first, c.second))) pairs.emplace_back(c.first, c.second);
  }
  return pairs;
}

StaticCollider box_collider(const Vector3d& centre, const Vector3d& half_extents) {
  StaticCollider box;
  box.name = "box";
  box.type = ColliderType::box;
  box.position = centre;
  box.half_extents = half_extents;
  box.friction = 0.7;
  box.restitution = 0.2;
  return box;
}

// One big triangle in the plane z = 0, counter-clockwise from above: its front faces +z.
StaticCollider floor_triangle() {
  StaticCollider mesh;
  mesh.name = "floor";
  mesh.type = ColliderType::mesh;
  mesh.mesh.vertices = {{-4, -4, 0}, {4, -4, 0}, {0, 4, 0}};
  mesh.mesh.triangles = {{0, 1, 2}};
  mesh.thickness = 0.1;
  return mesh;
}

// The value of C = n·p_first(a) − offset for a static contact: what the particle method projects.
double static_constraint(const LimbContact& contact, const LimbSegment& limb) {
  const Vector3d p = limb.head + contact.axial_first * (limb.tail - limb.head);
  return contact.normal.dot(p) - contact.offset;
}

TEST(LimbCollisions, JoinedNeighboursNeverCollide) {
  Model model;
  model.bodies = {capsule_limb({1, 0, 0}, {0, 0, 0}, 0.1), capsule_limb({2.5, 0, 0}, {1.5, 0, 0}, 0.1),
                  capsule_limb({5, 0, 0}, {4, 0, 0}, 0.1)};
  model.joints = {spherical_joint("j", 0, 1, {0.5, 0, 0}, {-0.5, 0, 0})};
  LimbCollisions collisions(model);
  ASSERT_TRUE(collisions.active());
  // Fold limb 1 onto limb 0 and bring limb 2 onto it too: only the unjoined pair (0, 2) meets.
  std::vector<LimbSegment> limbs = segments_of(model);
  limbs[1] = {{0.5, 0.15, 0}, {0.5, -0.85, 0}, 0.1};
  limbs[2] = {{0.5, 0, 0.15}, {0.5, 0, -0.85}, 0.1};
  const std::vector<LimbContact> contacts = find_all(collisions, limbs);
  ASSERT_EQ(contacts.size(), 2u);  // (0, 2) and (1, 2); (0, 1) is joined
  EXPECT_EQ(std::tie(contacts[0].first, contacts[0].second), std::make_tuple(0u, 2u));
  EXPECT_EQ(std::tie(contacts[1].first, contacts[1].second), std::make_tuple(1u, 2u));
}

TEST(LimbCollisions, FilterBitsDecideWhichLimbsMeet) {
  Model model;
  model.bodies = {capsule_limb({1, 0, 0}, {0, 0, 0}, 0.1), capsule_limb({1, 0, 1}, {0, 0, 1}, 0.1),
                  capsule_limb({1, 0, 2}, {0, 0, 2}, 0.1)};
  model.bodies[0].collision = {0b01, 0b10};  // meets only group 2
  model.bodies[1].collision = {0b01, 0b11};  // group 1: not what 0 asks for
  model.bodies[2].collision = {0b10, 0b01};  // group 2, meets group 1
  LimbCollisions collisions(model);
  std::vector<LimbSegment> limbs = segments_of(model);
  for (LimbSegment& limb : limbs) limb.head.z() = limb.tail.z() = 0.05 * (&limb - limbs.data());  // all overlapping
  const auto pairs = touching_pairs(find_all(collisions, limbs));
  ASSERT_EQ(pairs.size(), 2u);  // (0, 2) and (1, 2); 0 rejects 1
  EXPECT_EQ(pairs[0], std::make_pair(0u, 2u));
  EXPECT_EQ(pairs[1], std::make_pair(1u, 2u));

  // Filters that reject every pair, and no collider: nothing to do.
  for (Body& body : model.bodies) body.collision = {0b01, 0b10};
  EXPECT_FALSE(LimbCollisions(model).active());
}

TEST(LimbCollisions, LimbsOverlappingInTheModelNeverCollide) {
  Model model;
  // A torso and an arm that hangs into it; a third limb clear of both.
  model.bodies = {capsule_limb({0, 0, 1.5}, {0, 0, 0.5}, 0.2), capsule_limb({0.15, 0, 1.4}, {0.15, 0, 0.6}, 0.05),
                  capsule_limb({3, 0, 1.5}, {3, 0, 0.5}, 0.2)};
  LimbCollisions collisions(model);
  EXPECT_TRUE(find_all(collisions, segments_of(model)).empty());
  EXPECT_EQ(collisions.deepest_overlap(segments_of(model)).separation, 0.0);
  // The third limb moved into the arm does collide with it (and with the torso).
  std::vector<LimbSegment> limbs = segments_of(model);
  limbs[2] = {{0.3, 0, 1.5}, {0.3, 0, 0.5}, 0.2};
  const auto pairs = touching_pairs(find_all(collisions, limbs));
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(pairs[0], std::make_pair(0u, 2u));
  EXPECT_EQ(pairs[1], std::make_pair(1u, 2u));
}

TEST(LimbCollisions, LimbsLyingAlongEachOtherTouchAlongTheLengthTheyShare) {
  Model model;
  model.bodies = {capsule_limb({0, 0, 0}, {1, 0, 0}, 0.05), capsule_limb({5, 0, 0}, {6, 0, 0}, 0.05)};
  LimbCollisions collisions(model);
  // The second laid on the first, 10° off parallel and shifted by half a length: they share
  // x ∈ [0.5, 1] of the first, whose ends hold the contacts (with the nearest points between).
  const double angle = 10 * std::numbers::pi / 180;
  std::vector<LimbSegment> limbs = segments_of(model);
  limbs[1] = {{0.5, 0, 0.09}, {0.5 + std::cos(angle), 0, 0.09 + std::sin(angle)}, 0.05};
  std::vector<LimbContact> contacts = find_all(collisions, limbs, 0.2);
  ASSERT_EQ(contacts.size(), 2u) << "the nearest points are at the shared length's near end";
  EXPECT_NEAR(contacts[0].axial_first, 0.5, 1e-9);
  EXPECT_NEAR(contacts[1].axial_first, 1.0, 1e-9);
  for (const LimbContact& c : contacts) EXPECT_LT(c.normal.z(), -0.9) << "from the second (above) towards the first";
  EXPECT_LT(contacts[0].separation, contacts[1].separation);
  // Parallel and level: the nearest points mid-way, plus both ends.
  limbs[1] = {{0.5, 0, 0.09}, {1.5, 0, 0.09}, 0.05};
  contacts = find_all(collisions, limbs, 0.2);
  ASSERT_EQ(contacts.size(), 3u);
  EXPECT_NEAR(contacts[0].axial_first, 0.5, 1e-9);
  EXPECT_NEAR(contacts[1].axial_first, 0.75, 1e-9);
  EXPECT_NEAR(contacts[2].axial_first, 1.0, 1e-9);
  // Crossed at 60°: one contact.
  limbs[1] = {{0.5, -0.5, 0.09}, {0.5 + 0.5, -0.5 + std::sqrt(3.0) / 2, 0.09}, 0.05};
  EXPECT_EQ(find_all(collisions, limbs, 0.2).size(), 1u);
}

TEST(LimbCollisions, LimbPairContactIsAtTheClosestPointsOfTheSegments) {
  Model model;
  model.bodies = {capsule_limb({0.5, 0, 5}, {-0.5, 0, 5}, 0.1), capsule_limb({5, 0.5, 0}, {5, -0.5, 0}, 0.2)};
  LimbCollisions collisions(model);
  // Limb 0 along x at z = 0.25 crosses above limb 1 along y at x = 0.2, z = 0: the axes are 0.25
  // apart, the radii add to 0.3.
  std::vector<LimbSegment> limbs = {{{0.5, 0, 0.25}, {-0.5, 0, 0.25}, 0.1}, {{0.2, 0.5, 0}, {0.2, -0.5, 0}, 0.2}};
  std::vector<LimbContact> contacts = find_all(collisions, limbs);
  ASSERT_EQ(contacts.size(), 1u);
  const LimbContact& c = contacts[0];
  EXPECT_EQ(c.first, 0u);
  EXPECT_EQ(c.second, 1u);
  EXPECT_LT((c.normal - Vector3d::UnitZ()).norm(), 1e-12);  // from the lower (second) to the upper (first)
  EXPECT_NEAR(c.separation, 0.25 - 0.3, 1e-12);
  EXPECT_NEAR(c.axial_first, 0.3, 1e-12);   // x = 0.2 is 0.3 from the head at x = 0.5
  EXPECT_NEAR(c.axial_second, 0.5, 1e-12);  // y = 0: the middle
  // The surfaces are at z = 0.15 (limb 0's bottom) and z = 0.2 (limb 1's top).
  EXPECT_LT((c.point - Vector3d(0.2, 0, 0.175)).norm(), 1e-12);
  EXPECT_EQ(c.friction, model.settings.limb_friction);
  EXPECT_EQ(c.restitution, 0.0);

  // Swapped heights: the normal still points from the second limb to the first, now down.
  std::swap(limbs[0].head.z(), limbs[1].head.z());
  limbs[0].tail.z() = limbs[0].head.z(), limbs[1].tail.z() = limbs[1].head.z();
  contacts = find_all(collisions, limbs);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_LT((contacts[0].normal + Vector3d::UnitZ()).norm(), 1e-12);

  // Apart by 0.05: reported within a margin of 0.1, not within 0.01.
  limbs = {{{0.5, 0, 0.35}, {-0.5, 0, 0.35}, 0.1}, {{0.2, 0.5, 0}, {0.2, -0.5, 0}, 0.2}};
  contacts = find_all(collisions, limbs, 0.1);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_NEAR(contacts[0].separation, 0.05, 1e-12);
  EXPECT_TRUE(find_all(collisions, limbs, 0.01).empty());
}

TEST(LimbCollisions, CrossingSegmentsTakeTheNormalAcrossBoth) {
  Model model;
  model.bodies = {capsule_limb({0.5, 0, 5}, {-0.5, 0, 5}, 0.1), capsule_limb({5, 0.5, 0}, {5, -0.5, 0}, 0.1)};
  LimbCollisions collisions(model);
  // Both axes through the origin; limb 0's middle slightly above limb 1's.
  const std::vector<LimbSegment> limbs = {{{0.5, 0, 0.02}, {-0.5, 0, -0.02}, 0.1}, {{0, 0.5, 0}, {0, -0.5, 0}, 0.1}};
  const std::vector<LimbContact> contacts = find_all(collisions, limbs);
  ASSERT_EQ(contacts.size(), 1u);
  const Vector3d across = (limbs[0].head - limbs[0].tail).cross(limbs[1].head - limbs[1].tail).normalized();
  EXPECT_NEAR(std::abs(contacts[0].normal.dot(across)), 1, 1e-12);
  // Crossing exactly, the midpoints lie in the plane across the normal, so the documented tie
  // rule decides: upwards.
  EXPECT_GT(contacts[0].normal.z(), 0);
  EXPECT_NEAR(contacts[0].separation, -0.2, 1e-12);
}

TEST(LimbCollisions, CapsuleLyingOnABoxFaceTouchesWithBothEnds) {
  Model model;
  model.bodies = {capsule_limb({0.5, 0, 5}, {-0.5, 0, 5}, 0.1)};
  model.colliders = {box_collider({0, 0, -0.5}, {2, 2, 0.5})};  // top face z = 0
  LimbCollisions collisions(model);
  ASSERT_TRUE(collisions.active());
  const std::vector<LimbSegment> limbs = {{{0.5, 0.3, 0.09}, {-0.5, 0.3, 0.09}, 0.1}};  // 0.01 into the face
  const std::vector<LimbContact> contacts = find_all(collisions, limbs);
  ASSERT_EQ(contacts.size(), 2u);
  EXPECT_EQ(contacts[0].axial_first, 0.0);
  EXPECT_EQ(contacts[1].axial_first, 1.0);
  for (const LimbContact& c : contacts) {
    EXPECT_EQ(c.second, kStaticShape);
    EXPECT_EQ(c.collider, 0u);
    EXPECT_LT((c.normal - Vector3d::UnitZ()).norm(), 1e-12);
    EXPECT_NEAR(c.separation, -0.01, 1e-12);
    EXPECT_NEAR(static_constraint(c, limbs[0]), c.separation, 1e-12);
    EXPECT_NEAR(c.point.z(), -0.005, 1e-12);  // midway between the face (0) and the limb's bottom (−0.01)
    EXPECT_EQ(c.friction, 0.7);
    EXPECT_EQ(c.restitution, 0.2);
  }
  EXPECT_NEAR(-collisions.deepest_overlap(limbs).separation, 0.01, 1e-12);
}

TEST(LimbCollisions, CapsuleAcrossANarrowBoxTouchesItInTheMiddle) {
  Model model;
  model.bodies = {capsule_limb({1, 0, 5}, {-1, 0, 5}, 0.1)};
  model.colliders = {box_collider({0, 0, -0.5}, {0.2, 2, 0.5})};  // a ridge 0.4 wide, top at z = 0
  LimbCollisions collisions(model);
  const std::vector<LimbSegment> limbs = {{{1, 0, 0.09}, {-1, 0, 0.09}, 0.1}};
  const std::vector<LimbContact> contacts = find_all(collisions, limbs, 0.05);
  ASSERT_EQ(contacts.size(), 1u);  // the ends hang 0.8 past the ridge, far from it
  EXPECT_GE(contacts[0].axial_first, 0.4);
  EXPECT_LE(contacts[0].axial_first, 0.6);
  EXPECT_LT((contacts[0].normal - Vector3d::UnitZ()).norm(), 1e-9);
  EXPECT_NEAR(contacts[0].separation, -0.01, 1e-9);
  EXPECT_NEAR(static_constraint(contacts[0], limbs[0]), contacts[0].separation, 1e-12);
}

TEST(LimbCollisions, LimbInsideABoxLeavesThroughTheNearestFace) {
  Model model;
  model.bodies = {capsule_limb({0.5, 0, 5}, {-0.5, 0, 5}, 0.1)};
  model.colliders = {box_collider({0, 0, -0.5}, {2, 2, 0.5})};
  model.colliders[0].orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Vector3d::UnitZ()));  // turned about z: same top face
  LimbCollisions collisions(model);
  const std::vector<LimbSegment> limbs = {{{0.5, 0, -0.05}, {-0.5, 0, -0.05}, 0.1}};  // axis 0.05 below the top face
  const std::vector<LimbContact> contacts = find_all(collisions, limbs);
  ASSERT_EQ(contacts.size(), 2u);
  for (const LimbContact& c : contacts) {
    EXPECT_LT((c.normal - Vector3d::UnitZ()).norm(), 1e-12);
    EXPECT_NEAR(c.separation, -0.15, 1e-12);
  }
}

TEST(LimbCollisions, OneSidedTrianglePushesOutThroughItsFront) {
  Model model;
  model.bodies = {capsule_limb({0.5, 0, 5}, {-0.5, 0, 5}, 0.1)};
  model.colliders = {floor_triangle()};
  LimbCollisions collisions(model);
  // Just behind (0.05 below the plane, within the thickness 0.1): out through the front, +z.
  std::vector<LimbSegment> limbs = {{{0.5, 0, -0.05}, {-0.5, 0, -0.05}, 0.1}};
  std::vector<LimbContact> contacts = find_all(collisions, limbs);
  ASSERT_EQ(contacts.size(), 2u);
  for (const LimbContact& c : contacts) {
    EXPECT_EQ(c.triangle, 0u);
    EXPECT_LT((c.normal - Vector3d::UnitZ()).norm(), 1e-12);
    EXPECT_NEAR(c.separation, -0.15, 1e-12);
    EXPECT_NEAR(static_constraint(c, limbs[0]), c.separation, 1e-12);
  }
  // Far behind (0.5 below): not the triangle's business.
  limbs[0].head.z() = limbs[0].tail.z() = -0.5;
  EXPECT_TRUE(find_all(collisions, limbs, 0.01).empty());
  // In front, resting into it by 0.02: pushed up as well.
  limbs[0].head.z() = limbs[0].tail.z() = 0.08;
  contacts = find_all(collisions, limbs);
  ASSERT_EQ(contacts.size(), 2u);
  EXPECT_LT((contacts[0].normal - Vector3d::UnitZ()).norm(), 1e-12);
  EXPECT_NEAR(contacts[0].separation, -0.02, 1e-12);
}

TEST(LimbCollisions, LimbPiercingATriangleIsPushedOutAtItsDeeperEnd) {
  Model model;
  model.bodies = {capsule_limb({0, 0, 5.3}, {0, 0, 4.95}, 0.05)};
  model.colliders = {floor_triangle()};
  LimbCollisions collisions(model);
  const std::vector<LimbSegment> limbs = {{{0.1, 0, 0.3}, {0, 0, -0.05}, 0.05}};  // tail 0.05 behind
  const std::vector<LimbContact> contacts = find_all(collisions, limbs);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_EQ(contacts[0].axial_first, 1.0);
  EXPECT_LT((contacts[0].normal - Vector3d::UnitZ()).norm(), 1e-12);
  EXPECT_NEAR(contacts[0].separation, -0.1, 1e-12);
}

TEST(LimbCollisions, BallMeetsStaticGeometryButNotLimbs) {
  Model model;
  model.bodies = {capsule_limb({0.5, 0, 5}, {-0.5, 0, 5}, 0.1)};
  model.balls = {Ball{0.2, 1, 0.5, {3, 0, 5}, {0, 0, 0}}};
  model.colliders = {box_collider({0, 0, -0.5}, {5, 5, 0.5})};
  LimbCollisions collisions(model);
  // The ball rests 0.05 into the box's top; the limb lies into the ball, clear of the box.
  const std::vector<LimbSegment> limbs = {{{0.5, 0, 0.3}, {-0.5, 0, 0.3}, 0.1}, {{0, 0, 0.15}, {0, 0, 0.15}, 0.2}};
  const std::vector<LimbContact> contacts = find_all(collisions, limbs);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_EQ(contacts[0].first, 1u);
  EXPECT_EQ(contacts[0].second, kStaticShape);
  EXPECT_NEAR(contacts[0].separation, -0.05, 1e-12);
}

// Random capsules among a box and a triangle; the Model's poses far apart so nothing is excluded.
struct RandomScene {
  Model model;
  std::vector<LimbSegment> limbs;
};
RandomScene random_scene(std::size_t count, double extent, std::mt19937& rng) {
  std::uniform_real_distribution<double> position(-extent, extent), unit(-1, 1), radius(0.03, 0.15), length(0.1, 0.8);
  RandomScene scene;
  for (std::size_t i = 0; i < count; ++i) {
    const Vector3d centre(position(rng), position(rng), position(rng));
    const Vector3d axis = Vector3d(unit(rng), unit(rng), unit(rng)).normalized();
    const double half = 0.5 * length(rng), r = radius(rng);
    scene.limbs.push_back({centre + half * axis, centre - half * axis, r});
    const Vector3d far(100.0 * static_cast<double>(i), 0, 50);
    scene.model.bodies.push_back(capsule_limb(far + half * axis, far - half * axis, r));
  }
  scene.model.colliders = {box_collider({0.5, 0, -0.3}, {0.6, 0.4, 0.2}), floor_triangle()};
  return scene;
}

TEST(LimbCollisions, ShuffledBodyOrderFindsTheSameContacts) {
  std::mt19937 rng(7);
  const RandomScene scene = random_scene(60, 1.0, rng);
  std::vector<std::uint32_t> order(scene.limbs.size());  // new index k holds old body order[k]
  std::iota(order.begin(), order.end(), 0u);
  std::shuffle(order.begin(), order.end(), rng);
  Model shuffled = scene.model;
  std::vector<LimbSegment> shuffled_limbs(scene.limbs.size());
  const std::vector<std::uint32_t>& old_of_new = order;
  for (std::uint32_t k = 0; k < order.size(); ++k) {
    shuffled.bodies[k] = scene.model.bodies[order[k]];
    shuffled_limbs[k] = scene.limbs[order[k]];
  }
  LimbCollisions original(scene.model), permuted(shuffled);
  const std::vector<LimbContact> expected = find_all(original, scene.limbs, 0.02);
  std::vector<LimbContact> found = find_all(permuted, shuffled_limbs, 0.02);
  ASSERT_GT(expected.size(), 20u);  // the test means something
  // Back to the original numbering: a limb pair whose order flips has its normal flipped too.
  for (LimbContact& c : found) {
    c.first = old_of_new[c.first];
    if (c.second != kStaticShape) {
      c.second = old_of_new[c.second];
      if (c.first > c.second) std::swap(c.first, c.second), std::swap(c.axial_first, c.axial_second), c.normal = -c.normal;
    }
  }
  std::sort(found.begin(), found.end(), [](const LimbContact& a, const LimbContact& b) {
    return std::tie(a.first, a.second, a.collider, a.triangle, a.axial_first) <
           std::tie(b.first, b.second, b.collider, b.triangle, b.axial_first);
  });
  ASSERT_EQ(found.size(), expected.size());
  for (std::size_t k = 0; k < found.size(); ++k) {
    EXPECT_EQ(std::tie(found[k].first, found[k].second, found[k].collider, found[k].triangle),
              std::tie(expected[k].first, expected[k].second, expected[k].collider, expected[k].triangle));
    EXPECT_NEAR(found[k].separation, expected[k].separation, 1e-12);
    EXPECT_NEAR(found[k].axial_first, expected[k].axial_first, 1e-9);
    EXPECT_LT((found[k].normal - expected[k].normal).norm(), 1e-9);
  }
}

TEST(LimbCollisions, TwoHundredLimbsAgreeWithBruteForceOverEveryPair) {
  std::mt19937 rng(11);
  const RandomScene scene = random_scene(200, 1.5, rng);
  std::vector<std::uint8_t> awake(scene.limbs.size());
  for (std::uint8_t& flag : awake) flag = std::uniform_int_distribution<int>(0, 3)(rng) != 0;  // a quarter asleep
  LimbCollisions collisions(scene.model);
  const double margin = 0.02;
  std::vector<LimbContact> contacts;
  collisions.find(scene.limbs, awake, margin, contacts);

  // Every pair with an awake limb whose capsules are within the margin, by the segments' closest points.
  std::vector<std::tuple<std::uint32_t, std::uint32_t, double>> expected;
  for (std::uint32_t i = 0; i < scene.limbs.size(); ++i) {
    for (std::uint32_t j = i + 1; j < scene.limbs.size(); ++j) {
      if (!awake[i] && !awake[j]) continue;
      const LimbSegment &a = scene.limbs[i], &b = scene.limbs[j];
      const double separation = closest_points_between_segments(a.head, a.tail, b.head, b.tail).distance - a.radius - b.radius;
      if (separation <= margin) expected.emplace_back(i, j, separation);
    }
  }
  // Per pair, its nearest contact (limbs lying along each other get two more, no nearer).
  std::vector<std::tuple<std::uint32_t, std::uint32_t, double>> found;
  for (const LimbContact& c : contacts) {
    if (c.second == kStaticShape) continue;
    if (!found.empty() && std::get<0>(found.back()) == c.first && std::get<1>(found.back()) == c.second) {
      std::get<2>(found.back()) = std::min(std::get<2>(found.back()), c.separation);
    } else {
      found.emplace_back(c.first, c.second, c.separation);
    }
  }
  ASSERT_GT(expected.size(), 50u);
  ASSERT_EQ(found.size(), expected.size());
  for (std::size_t k = 0; k < found.size(); ++k) {
    EXPECT_EQ(std::get<0>(found[k]), std::get<0>(expected[k]));
    EXPECT_EQ(std::get<1>(found[k]), std::get<1>(expected[k]));
    EXPECT_NEAR(std::get<2>(found[k]), std::get<2>(expected[k]), 1e-12);
  }
  // Static contacts only for awake limbs, and every one within the margin.
  for (const LimbContact& c : contacts) {
    if (c.second == kStaticShape) {
      EXPECT_TRUE(awake[c.first]);
      EXPECT_LE(c.separation, margin);
    }
  }
  // The deepest penetration is the deepest overlap of any pair, asleep or not.
  double deepest = 0;
  std::vector<LimbContact> all;
  collisions.find(scene.limbs, std::vector<std::uint8_t>(scene.limbs.size(), 1), 0, all);
  for (const LimbContact& c : all) deepest = std::max(deepest, -c.separation);
  EXPECT_GT(deepest, 0);
  EXPECT_EQ(-collisions.deepest_overlap(scene.limbs).separation, deepest);
}

// Whether two contact lists are the same, field by field and bit for bit.
void expect_same_contacts(const std::vector<LimbContact>& found, const std::vector<LimbContact>& expected, const std::string& where) {
  ASSERT_EQ(found.size(), expected.size()) << where;
  for (std::size_t k = 0; k < found.size(); ++k) {
    const LimbContact &a = found[k], &b = expected[k];
    EXPECT_EQ(std::tie(a.first, a.second, a.collider, a.triangle), std::tie(b.first, b.second, b.collider, b.triangle)) << where;
    EXPECT_EQ(std::tie(a.separation, a.axial_first, a.axial_second, a.offset, a.friction, a.restitution),
              std::tie(b.separation, b.axial_first, b.axial_second, b.offset, b.friction, b.restitution))
        << where;
    EXPECT_EQ(a.normal, b.normal) << where;
    EXPECT_EQ(a.point, b.point) << where;
  }
}

// The limb pairs of a contact list (static contacts left out).
std::vector<std::pair<std::uint32_t, std::uint32_t>> limb_pairs(const std::vector<LimbContact>& contacts) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  for (const LimbContact& c : contacts) {
    if (c.second != kStaticShape) pairs.emplace_back(c.first, c.second);
  }
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  return pairs;
}

// A step's later substeps reuse the pairs of its first substep's search (limb_contacts.hpp):
// moved by less than their search reach, the segments get from the kept pairs exactly the
// contacts a fresh search finds — including pairs that were not yet within the margin.
TEST(LimbCollisions, KeptPairsFindWhatASearchFindsWhileNoSegmentOutrunsThem) {
  std::mt19937 rng(5);
  RandomScene scene = random_scene(200, 1.5, rng);
  std::vector<std::uint8_t> awake(scene.limbs.size());
  for (std::uint8_t& flag : awake) flag = std::uniform_int_distribution<int>(0, 3)(rng) != 0;  // a quarter asleep
  constexpr double kMargin = 0.005, kReach = 0.01, kSearchReach = 0.06;
  for (LimbSegment& limb : scene.limbs) limb.reach = kReach, limb.search_reach = kSearchReach;
  LimbCollisions collisions(scene.model);
  std::vector<LimbContact> searched, kept, fresh;
  collisions.find(scene.limbs, awake, kMargin, searched);
  // Three substeps on: each awake segment shifted by up to 2.5 cm and stretched by up to 6 mm at
  // each end (its bounding sphere's centre moves 2.5 cm, its radius 6 mm): within 6 cm − 1 cm of reach.
  std::uniform_real_distribution<double> step(-0.0144, 0.0144);  // per coordinate: |Δ| ≤ 2.5 cm
  std::vector<LimbSegment> moved = scene.limbs;
  std::size_t new_pairs = 0;
  for (int substep = 1; substep <= 3; ++substep) {
    for (std::size_t s = 0; s < moved.size(); ++s) {
      if (!awake[s]) continue;
      const Vector3d shift(step(rng), step(rng), step(rng)), stretch(step(rng), step(rng), step(rng));
      moved[s].head = scene.limbs[s].head + shift + 0.25 * stretch, moved[s].tail = scene.limbs[s].tail + shift - 0.25 * stretch;
    }
    const std::string where = "substep " + std::to_string(substep);
    ASSERT_TRUE(collisions.find_kept_pairs(moved, awake, kMargin, kept)) << where;
    LimbCollisions search(scene.model);
    search.find(moved, awake, kMargin, fresh);
    expect_same_contacts(kept, fresh, where);
    const auto before = limb_pairs(searched), after = limb_pairs(fresh);
    for (const auto& pair : after) new_pairs += !std::binary_search(before.begin(), before.end(), pair);
  }
  EXPECT_GT(searched.size(), 50u);
  EXPECT_GT(new_pairs, 5u);  // the moves brought pairs into the margin that the search had not found in it
}

// A segment that moved farther than its search reach may meet what the search did not keep: the
// kept pairs refuse (and a fresh search finds the contact they would have missed).
TEST(LimbCollisions, KeptPairsRefuseASegmentThatOutranThem) {
  Model model;
  model.bodies = {capsule_limb({0, 0, 0.5}, {0, 0, 0}, 0.05), capsule_limb({0.4, 0, 0.5}, {0.4, 0, 0}, 0.05)};
  model.bodies[0].position.y() = 10, model.bodies[1].position.y() = -10;  // apart in the Model
  LimbCollisions collisions(model);
  std::vector<LimbSegment> limbs = {{{0, 0, 0.5}, {0, 0, 0}, 0.05, 0.01, 0.05}, {{0.4, 0, 0.5}, {0.4, 0, 0}, 0.05, 0.01, 0.05}};
  const std::vector<std::uint8_t> awake(2, 1);
  std::vector<LimbContact> contacts;
  collisions.find(limbs, awake, 0.005, contacts);
  EXPECT_TRUE(contacts.empty());  // 30 cm apart
  // The first moves 4 cm towards the second (plus its 1 cm of reach: within 5 cm), then 33 cm
  // (into it).
  for (const double x : {0.04, 0.33}) {
    limbs[0].head.x() = limbs[0].tail.x() = x;
    const bool kept = collisions.find_kept_pairs(limbs, awake, 0.005, contacts);
    EXPECT_EQ(kept, x < 0.05) << "moved " << x << " m";
    collisions.find(limbs, awake, 0.005, contacts);
    EXPECT_EQ(contacts.empty(), x < 0.05) << "moved " << x << " m";
    limbs[0].head.x() = limbs[0].tail.x() = 0;
    collisions.find(limbs, awake, 0.005, contacts);  // the search again at the start
  }
}

// The narrowphase runs in blocks on a BlockRunner's threads (limb_collisions.hpp): a search and
// the kept pairs' narrowphase give a serial search's contacts bit for bit, and keep the same
// pairs (the kept narrowphase after a move finds the same contacts), for each way of threading.
TEST(LimbCollisions, TheNarrowphaseOnThreadsFindsTheSerialContactsBitForBit) {
  std::mt19937 rng(9);
  RandomScene scene = random_scene(400, 1.5, rng);
  std::vector<std::uint8_t> awake(scene.limbs.size());
  for (std::uint8_t& flag : awake) flag = std::uniform_int_distribution<int>(0, 3)(rng) != 0;  // a quarter asleep
  for (LimbSegment& limb : scene.limbs) limb.reach = 0.01, limb.search_reach = 0.06;
  std::vector<LimbSegment> moved = scene.limbs;
  for (std::size_t s = 0; s < moved.size(); ++s) moved[s].head.x() += 0.02, moved[s].tail.y() -= 0.02;
  LimbCollisions serial(scene.model);
  std::vector<LimbContact> searched, kept;
  serial.find(scene.limbs, awake, 0.005, searched);
  ASSERT_TRUE(serial.find_kept_pairs(moved, awake, 0.005, kept));
  ASSERT_GT(searched.size(), 200u);  // many blocks of pairs, and of static queries
  for (const Threading threading : {Threading::workers, Threading::parallel_for}) {
    const std::string where = threading == Threading::workers ? "workers" : "parallel_for";
    BlockRunner runner(threading, 2);
    LimbCollisions threaded(scene.model);
    std::vector<LimbContact> contacts;
    // The blocks' buffers reused; the helpers woken by the caller (rounds 0 and 2) or by the
    // narrowphase itself (round 1).
    for (int round = 0; round < 3; ++round) {
      const bool caller_wakes = round != 1;
      if (caller_wakes) runner.begin();
      threaded.find(scene.limbs, awake, 0.005, contacts, &runner);
      expect_same_contacts(contacts, searched, where + ", search");
      ASSERT_TRUE(threaded.find_kept_pairs(moved, awake, 0.005, contacts, &runner)) << where;
      expect_same_contacts(contacts, kept, where + ", kept pairs");
      if (caller_wakes) runner.end();
    }
    EXPECT_EQ(threaded.candidate_pairs(), 0u);
  }
}

TEST(LimbCollisions, FindAllocatesNothingOnceWarm) {
  std::mt19937 rng(3);
  RandomScene scene = random_scene(100, 1.0, rng);
  LimbCollisions collisions(scene.model);
  const std::vector<std::uint8_t> awake(scene.limbs.size(), 1);
  std::vector<LimbContact> contacts;
  // Two configurations in turn: after one call at each, the buffers hold the larger of both.
  const std::vector<LimbSegment> first = scene.limbs;
  std::vector<LimbSegment> moved = scene.limbs;
  for (LimbSegment& limb : moved) limb.head.x() += 0.01, limb.tail.x() -= 0.01;
  collisions.find(first, awake, 0.02, contacts);
  collisions.find(moved, awake, 0.02, contacts);
  collisions.deepest_overlap(first);
  const long before = testing::allocation_count();
  collisions.find(first, awake, 0.02, contacts);
  collisions.find(moved, awake, 0.02, contacts);
  collisions.deepest_overlap(moved);
  EXPECT_EQ(testing::allocation_count(), before);
  EXPECT_FALSE(contacts.empty());
}

}  // namespace
}  // namespace limber
