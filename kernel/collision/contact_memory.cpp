#include "limber/kernel/collision/contact_memory.hpp"

#include <algorithm>
#include <utility>

#include "limber/kernel/numerics/contact_projection.hpp"

namespace limber {
namespace {

template <typename Remembered>
bool before(const Remembered& x, std::int32_t a, std::int32_t b) {
  return x.a < a || (x.a == a && x.b < b);
}

}  // namespace

void ContactMemory::reserve(std::size_t contacts) {
  remembered_.reserve(contacts), recording_.reserve(contacts), taken_.reserve(contacts);
}

void ContactMemory::clear() { remembered_.clear(), recording_.clear(), taken_.clear(), step_ = 0; }

void ContactMemory::begin_matching() { taken_.assign(remembered_.size(), 0); }

Eigen::Vector3d ContactMemory::take(const RigidContact& contact, double dt) {
  auto it = std::lower_bound(remembered_.begin(), remembered_.end(), contact,
                             [](const Remembered& x, const RigidContact& c) { return before(x, c.a, c.b); });
  std::ptrdiff_t best = -1;
  double nearest = kWarmStartReach * kWarmStartReach;
  for (; it != remembered_.end() && it->a == contact.a && it->b == contact.b; ++it) {
    const std::ptrdiff_t index = it - remembered_.begin();
    const double distance = (it->point - contact.point).squaredNorm();
    if (!taken_[static_cast<std::size_t>(index)] && distance < nearest) best = index, nearest = distance;
  }
  if (best < 0) return Eigen::Vector3d::Zero();
  taken_[static_cast<std::size_t>(best)] = 1;
  const Remembered& last = remembered_[static_cast<std::size_t>(best)];
  const double normal = scale(dt) * last.normal_impulse;
  Eigen::Vector2d tangential = scale(dt) * (contact_frame(contact.normal).bottomRows<2>() * last.tangential_impulse);
  const double bound = contact.friction * normal, size = tangential.norm();
  if (size > bound) tangential *= size > 0 ? bound / size : 0.0;
  return {normal, tangential.x(), tangential.y()};
}

void ContactMemory::begin_recording() { recording_.clear(); }

void ContactMemory::record(const RigidContact& contact, const Eigen::Vector3d& impulse) {
  if (impulse.isZero()) return;
  const Eigen::Vector3d tangential = contact_frame(contact.normal).bottomRows<2>().transpose() * impulse.tail<2>();
  recording_.push_back({contact.a, contact.b, contact.point, impulse[0], tangential});
}

void ContactMemory::finish_recording(double dt) {
  // Sorted by bodies, then place, for take()'s search.
  std::sort(recording_.begin(), recording_.end(), [](const Remembered& x, const Remembered& y) {
    if (x.a != y.a || x.b != y.b) return before(x, y.a, y.b);
    return std::lexicographical_compare(x.point.data(), x.point.data() + 3, y.point.data(), y.point.data() + 3);
  });
  std::swap(remembered_, recording_);
  step_ = dt;
}

}  // namespace limber
