#include "limber/kernel/geometry/broadphase.hpp"

#include <algorithm>

namespace limber {
namespace {

// The axis along which the centres of `boxes` vary most (0 for fewer than two boxes).
int axis_of_largest_spread(std::span<const Aabb> boxes) {
  if (boxes.size() < 2) return 0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum_of_squares = Eigen::Vector3d::Zero();
  for (const Aabb& box : boxes) {
    const Eigen::Vector3d centre = 0.5 * (box.min + box.max);
    sum += centre;
    sum_of_squares += centre.cwiseProduct(centre);
  }
  const double n = static_cast<double>(boxes.size());
  // n² × variance, without the division.
  const Eigen::Vector3d spread = n * sum_of_squares - sum.cwiseProduct(sum);
  int axis = 0;
  for (int k = 1; k < 3; ++k) {
    if (spread[k] > spread[axis]) axis = k;
  }
  return axis;
}

}  // namespace

const std::vector<CandidatePair>& SweepAndPrune::find_pairs(std::span<const Aabb> boxes) {
  pairs_.clear();
  const int axis = axis_of_largest_spread(boxes);
  const auto before = [](const Interval& a, const Interval& b) {
    return a.min < b.min || (a.min == b.min && a.box < b.box);
  };

  if (sorted_.size() == boxes.size() && axis == axis_) {
    // Same boxes, same axis: refresh the intervals in last call's order, then insertion sort.
    for (Interval& interval : sorted_) {
      interval.min = boxes[interval.box].min[axis];
      interval.max = boxes[interval.box].max[axis];
    }
    for (std::size_t i = 1; i < sorted_.size(); ++i) {
      const Interval moving = sorted_[i];
      std::size_t j = i;
      for (; j > 0 && before(moving, sorted_[j - 1]); --j) sorted_[j] = sorted_[j - 1];
      sorted_[j] = moving;
    }
  } else {
    sorted_.resize(boxes.size());
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      sorted_[i] = Interval{boxes[i].min[axis], boxes[i].max[axis], static_cast<std::uint32_t>(i)};
    }
    std::sort(sorted_.begin(), sorted_.end(), before);
  }
  axis_ = axis;

  // Sweep: a box meets the boxes after it that start before it ends (ties in min included, as
  // touching counts); those are checked on the other two axes.
  for (std::size_t i = 0; i < sorted_.size(); ++i) {
    const Interval& current = sorted_[i];
    for (std::size_t j = i + 1; j < sorted_.size() && sorted_[j].min <= current.max; ++j) {
      const std::uint32_t a = current.box, b = sorted_[j].box;
      if (overlaps(boxes[a], boxes[b])) pairs_.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  std::sort(pairs_.begin(), pairs_.end());
  return pairs_;
}

std::size_t SweepAndPrune::reserved_bytes() const {
  return sorted_.capacity() * sizeof(Interval) + pairs_.capacity() * sizeof(CandidatePair);
}

std::vector<CandidatePair> brute_force_pairs(std::span<const Aabb> boxes) {
  std::vector<CandidatePair> pairs;
  for (std::uint32_t i = 0; i < boxes.size(); ++i) {
    for (std::uint32_t j = i + 1; j < boxes.size(); ++j) {
      if (overlaps(boxes[i], boxes[j])) pairs.emplace_back(i, j);
    }
  }
  return pairs;
}

}  // namespace limber
