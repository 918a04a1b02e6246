// Sweep and prune (kernel/geometry/broadphase.hpp) against brute force over every pair.
#include <random>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/geometry/broadphase.hpp"

namespace limber {
namespace {

using Eigen::Vector3d;

// ---- Sweep and prune ----

// Boxes on a 0.25 m grid (exact in binary), so that many touch exactly, plus some duplicates.
std::vector<Aabb> random_boxes(std::mt19937& rng, int count, double extent) {
  std::uniform_int_distribution<int> cell(0, static_cast<int>(extent / 0.25)), size(0, 6);
  std::vector<Aabb> boxes;
  for (int i = 0; i < count; ++i) {
    if (i > 2 && i % 7 == 0) {
      boxes.push_back(boxes[static_cast<std::size_t>(i / 2)]);  // a duplicate
      continue;
    }
    const Vector3d min(0.25 * cell(rng), 0.25 * cell(rng), 0.25 * cell(rng));
    boxes.push_back(Aabb{min, min + 0.25 * Vector3d(size(rng), size(rng), size(rng))});
  }
  return boxes;
}

TEST(SweepAndPrune, FindsExactlyTheBruteForcePairs) {
  std::mt19937 rng(9);
  SweepAndPrune sweep;
  for (const int count : {0, 1, 2, 3, 10, 60, 250}) {
    std::vector<Aabb> boxes = random_boxes(rng, count, 6.0);
    // Several frames: the boxes drift (keeping the order nearly sorted), then one jumps.
    for (int frame = 0; frame < 4; ++frame) {
      const auto expected = brute_force_pairs(boxes);
      EXPECT_EQ(sweep.find_pairs(boxes), expected) << count << " boxes, frame " << frame;
      for (Aabb& box : boxes) {
        const Vector3d drift = 0.25 * Vector3d(double(rng() % 3) - 1, double(rng() % 3) - 1, 0);
        box.min += drift;
        box.max += drift;
      }
      if (!boxes.empty()) std::swap(boxes.front(), boxes.back());
    }
  }
}

TEST(SweepAndPrune, ReportsTouchingAndDuplicateBoxes) {
  SweepAndPrune sweep;
  const std::vector<Aabb> boxes{
      {Vector3d(0, 0, 0), Vector3d(1, 1, 1)},
      {Vector3d(1, 0, 0), Vector3d(2, 1, 1)},  // touches 0 face to face
      {Vector3d(2, 1, 1), Vector3d(3, 2, 2)},  // touches 1 at a corner
      {Vector3d(0, 0, 0), Vector3d(1, 1, 1)},  // duplicate of 0
      {Vector3d(5, 5, 5), Vector3d(6, 6, 6)},  // alone
  };
  const std::vector<CandidatePair> expected{{0, 1}, {0, 3}, {1, 2}, {1, 3}};
  EXPECT_EQ(brute_force_pairs(boxes), expected);
  EXPECT_EQ(sweep.find_pairs(boxes), expected);
}

TEST(SweepAndPrune, SweepsAlongTheAxisOfLargestSpread) {
  SweepAndPrune sweep;
  std::vector<Aabb> row;
  for (int i = 0; i < 10; ++i) row.push_back(Aabb{Vector3d(0, 2.0 * i, 0), Vector3d(1, 2.0 * i + 1, 1)});
  EXPECT_TRUE(sweep.find_pairs(row).empty());
  EXPECT_EQ(sweep.axis(), 1);
  for (Aabb& box : row) {
    std::swap(box.min.y(), box.min.z());
    std::swap(box.max.y(), box.max.z());
  }
  EXPECT_TRUE(sweep.find_pairs(row).empty());
  EXPECT_EQ(sweep.axis(), 2);
}

TEST(SweepAndPrune, RepeatCallWithTheSameCountAllocatesNothing) {
  std::mt19937 rng(10);
  std::vector<Aabb> boxes = random_boxes(rng, 200, 6.0);
  SweepAndPrune sweep;
  const std::vector<CandidatePair>& pairs = sweep.find_pairs(boxes);
  ASSERT_FALSE(pairs.empty());
  const std::size_t bytes = sweep.reserved_bytes();
  const CandidatePair* data = pairs.data();
  // The same boxes, then all moved together (the same pairs, new coordinates).
  EXPECT_EQ(sweep.find_pairs(boxes), brute_force_pairs(boxes));
  for (Aabb& box : boxes) {
    box.min += Vector3d(0.5, -0.25, 1);
    box.max += Vector3d(0.5, -0.25, 1);
  }
  EXPECT_EQ(sweep.find_pairs(boxes), brute_force_pairs(boxes));
  EXPECT_EQ(sweep.reserved_bytes(), bytes);
  EXPECT_EQ(sweep.find_pairs(boxes).data(), data);
}

}  // namespace
}  // namespace limber
