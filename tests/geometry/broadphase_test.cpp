// The broadphase (kernel/geometry/broadphase.hpp): sweep and prune against brute force over every
// pair, in one set and between two; the balls' candidate lists against brute force; and its work
// — the box pairs it compares — growing with the boxes, not faster, where they spread along a
// line, over a plane or through a volume.
#include <algorithm>
#include <cstdint>
#include <limits>
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

TEST(SweepAndPrune, BetweenTwoSetsFindsExactlyTheBruteForcePairs) {
  std::mt19937 rng(12);
  SweepAndPrune sweep;
  for (const auto& [first_count, second_count] : {std::pair{0, 5}, {5, 0}, {1, 1}, {3, 10}, {60, 7}, {250, 250}}) {
    std::vector<Aabb> first = random_boxes(rng, first_count, 6.0), second = random_boxes(rng, second_count, 6.0);
    // Several frames: the boxes drift (keeping the order nearly sorted), then one jumps in each set.
    for (int frame = 0; frame < 4; ++frame) {
      EXPECT_EQ(sweep.find_pairs_between(first, second), brute_force_pairs_between(first, second))
          << first_count << " and " << second_count << " boxes, frame " << frame;
      for (std::vector<Aabb>* set : {&first, &second}) {
        for (Aabb& box : *set) {
          const Vector3d drift = 0.25 * Vector3d(double(rng() % 3) - 1, double(rng() % 3) - 1, double(rng() % 3) - 1);
          box.min += drift;
          box.max += drift;
        }
        if (!set->empty()) std::swap(set->front(), set->back());
      }
    }
  }
}

TEST(SweepAndPrune, FindsExactlyTheBruteForcePairsAmongBoxesOfVeryDifferentSizes) {
  // A few long boxes among many small ones widen the cells (at most four entries a box): still
  // every pair, each once.
  std::mt19937 rng(13);
  std::vector<Aabb> boxes = random_boxes(rng, 300, 6.0);
  for (int i = 0; i < 6; ++i) {
    const Vector3d corner(0.25 * double(rng() % 24), 0.25 * double(rng() % 24), 0.25 * double(rng() % 24));
    boxes.push_back(Aabb{corner, corner + Vector3d(40.0 * (i % 2), 40.0 * (i % 3 == 0), 0.5)});
  }
  SweepAndPrune sweep;
  EXPECT_EQ(sweep.find_pairs(boxes), brute_force_pairs(boxes));
  const std::vector<Aabb> small(boxes.begin(), boxes.begin() + 100), rest(boxes.begin() + 100, boxes.end());
  EXPECT_EQ(sweep.find_pairs_between(small, rest), brute_force_pairs_between(small, rest));
}

// `per_side`^dimensions boxes 1.25 m wide on a 1 m lattice along the first `dimensions` axes:
// each overlaps its neighbours (2 in a row, 8 on a plane, 26 in a volume).
std::vector<Aabb> lattice(int per_side, int dimensions) {
  std::vector<Aabb> boxes;
  const int count = dimensions == 1 ? per_side : dimensions == 2 ? per_side * per_side : per_side * per_side * per_side;
  for (int k = 0; k < count; ++k) {
    const Vector3d corner(k % per_side, dimensions > 1 ? (k / per_side) % per_side : 0, dimensions > 2 ? k / (per_side * per_side) : 0);
    boxes.push_back(Aabb{corner, corner + Vector3d::Constant(1.25)});
  }
  return boxes;
}

// The box pairs one sweep of `boxes` compares.
std::uint64_t comparisons_of(const std::vector<Aabb>& boxes) {
  SweepAndPrune sweep;
  sweep.find_pairs(boxes);
  return sweep.comparisons();
}

TEST(SweepAndPrune, FindsExactlyTheBruteForcePairsOnLattices) {
  SweepAndPrune sweep;
  for (const int dimensions : {1, 2, 3}) {
    const std::vector<Aabb> boxes = lattice(dimensions == 3 ? 7 : 20, dimensions);
    EXPECT_EQ(sweep.find_pairs(boxes), brute_force_pairs(boxes)) << dimensions << " dimensions";
  }
}

TEST(SweepAndPrune, WorkGrowsWithTheBoxesOnALineAPlaneAndInAVolume) {
  // One sweep axis alone compares a box with the boxes of its column and the next: on a square
  // lattice of n boxes about 1.5·n·√n pairs (8 times the work for 4 times the boxes), in a cube
  // about n^(5/3) (32 times for 8 times). The cells over the other two axes leave each box its
  // neighbours: the work grows as the boxes do.
  const std::uint64_t line = comparisons_of(lattice(1000, 1)), line_4x = comparisons_of(lattice(4000, 1));
  EXPECT_LT(line_4x, 5 * line) << line << " then " << line_4x;
  const std::uint64_t plane = comparisons_of(lattice(50, 2)), plane_4x = comparisons_of(lattice(100, 2));
  EXPECT_LT(plane_4x, 5 * plane) << plane << " then " << plane_4x;
  const std::uint64_t volume = comparisons_of(lattice(12, 3)), volume_8x = comparisons_of(lattice(24, 3));
  EXPECT_LT(volume_8x, 10 * volume) << volume << " then " << volume_8x;
}

TEST(SweepAndPrune, BetweenTwoSetsNeverComparesTwoBoxesOfOneSet) {
  // 10⁴ limbs in a row, each overlapping its neighbours (the sweep over them alone compares
  // about 2·10⁴ pairs), and one ball overlapping three of them: the two-set sweep compares the ball
  // with the limbs near it only.
  std::vector<Aabb> limbs;
  for (int k = 0; k < 10000; ++k) limbs.push_back(Aabb{Vector3d(k, 0, 0), Vector3d(k + 2.5, 0.5, 0.5)});
  const std::vector<Aabb> ball{Aabb{Vector3d(5000.75, 0, 0), Vector3d(5001.25, 0.5, 0.5)}};
  SweepAndPrune sweep;
  const std::vector<CandidatePair> expected{{4999, 0}, {5000, 0}, {5001, 0}};
  EXPECT_EQ(sweep.find_pairs_between(limbs, ball), expected);
  EXPECT_LE(sweep.comparisons(), 8u);
}

TEST(BallCandidates, ListsEveryBallsOverlappingBoxesInIncreasingOrder) {
  std::mt19937 rng(14);
  BallCandidates candidates;
  for (const auto& [shape_count, ball_count] : {std::pair{0, 9}, {4, 8}, {1, 10}, {40, 30}, {200, 120}}) {
    const std::vector<Aabb> shapes = random_boxes(rng, shape_count, 6.0), balls = random_boxes(rng, ball_count, 6.0);
    for (const bool other_balls : {false, true}) {
      const std::span<Aabb> boxes = candidates.boxes(shapes.size(), balls.size());
      std::copy(shapes.begin(), shapes.end(), boxes.begin());
      std::copy(balls.begin(), balls.end(), boxes.begin() + static_cast<std::ptrdiff_t>(shapes.size()));
      candidates.find(other_balls);
      for (std::size_t b = 0; b < balls.size(); ++b) {
        std::vector<std::uint32_t> expected;
        for (std::size_t s = 0; s < shapes.size(); ++s) {
          if (overlaps(shapes[s], balls[b])) expected.push_back(static_cast<std::uint32_t>(s));
        }
        for (std::size_t other = 0; other < balls.size() && other_balls; ++other) {
          if (other != b && overlaps(balls[other], balls[b])) expected.push_back(static_cast<std::uint32_t>(shapes.size() + other));
        }
        const std::span<const std::uint32_t> found = candidates.of(b);
        EXPECT_EQ(std::vector<std::uint32_t>(found.begin(), found.end()), expected)
            << "ball " << b << " of " << balls.size() << ", " << shapes.size() << " shapes, other balls " << other_balls;
      }
    }
  }
}

TEST(BallCandidates, AFewBallsOrTheReferenceGetEveryBody) {
  // Boxes far apart: a search would list nothing. Below kSearchFromBalls balls, or under the
  // reference, every ball gets every shape (and every ball, itself included, for the caller to
  // skip), and there are no boxes to fill.
  BallCandidates candidates;
  for (const bool reference : {false, true}) {
    candidates.use_reference(reference);
    const std::size_t balls = reference ? 2 * BallCandidates::kSearchFromBalls : 3;
    const std::span<Aabb> boxes = candidates.boxes(2, balls);
    EXPECT_TRUE(boxes.empty());
    candidates.find(/*other_balls=*/true);
    const std::span<const std::uint32_t> second = candidates.of(1);
    EXPECT_EQ(second.size(), 2 + balls);
    for (std::size_t k = 0; k < second.size(); ++k) EXPECT_EQ(second[k], k);
    candidates.find(/*other_balls=*/false);
    const std::span<const std::uint32_t> third = candidates.of(2);
    EXPECT_EQ(std::vector<std::uint32_t>(third.begin(), third.end()), (std::vector<std::uint32_t>{0, 1}));
  }
}

TEST(BallCandidates, ABoxNotFiniteGivesEveryBallEveryBody) {
  // A ball gone NaN (a diverged world still stepped) cannot be sorted: the search falls back to
  // every body for every ball, and the exact tests refuse what is not finite.
  BallCandidates candidates;
  const std::size_t balls = 2 * BallCandidates::kSearchFromBalls;
  const std::span<Aabb> boxes = candidates.boxes(3, balls);
  ASSERT_EQ(boxes.size(), 3 + balls);
  for (std::size_t k = 0; k < boxes.size(); ++k) boxes[k] = {Vector3d(10.0 * k, 0, 0), Vector3d(10.0 * k + 1, 1, 1)};
  boxes[4].min.x() = std::numeric_limits<double>::quiet_NaN();
  candidates.find(/*other_balls=*/false);
  for (std::size_t b = 0; b < balls; ++b) {
    const std::span<const std::uint32_t> found = candidates.of(b);
    EXPECT_EQ(std::vector<std::uint32_t>(found.begin(), found.end()), (std::vector<std::uint32_t>{0, 1, 2})) << "ball " << b;
  }
}

}  // namespace
}  // namespace limber
