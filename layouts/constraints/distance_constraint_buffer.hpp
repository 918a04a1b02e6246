// Distance-constraint storage: structure of arrays, aligned and padded.
#pragma once

#include <cstddef>
#include <cstdint>

#include "limber/layouts/aligned_array.hpp"

namespace limber {

/// Distance constraints C = |x_i − x_j| − d between particle pairs, in structure-of-arrays form.
/// A limb's rigid length and a spherical joint (d = 0) are both distance constraints.
///
/// Shapes: arrays hold capacity() ≥ size() elements padded to kLanesPerLine; padding slots join
/// the null particle to itself with d = 0, so projecting them is a no-op (zero inverse mass).
/// A compliance (XPBD) is a further field when a method needs it; adding it is one line in
/// for_each_field.
template <typename Scalar>
struct DistanceConstraintBuffer {
  using scalar_type = Scalar;

  /// Particle indices of the two ends.
  AlignedArray<std::uint32_t> particle_i, particle_j;
  /// Rest length d, m (0 for a joint).
  AlignedArray<Scalar> rest_length;

  template <typename Visitor>
  void for_each_field(Visitor&& visit) {
    visit("particle_i", particle_i), visit("particle_j", particle_j), visit("rest_length", rest_length);
  }
  template <typename Visitor>
  void for_each_field(Visitor&& visit) const {
    const_cast<DistanceConstraintBuffer*>(this)->for_each_field([&](const char* name, auto& array) {
      visit(name, static_cast<const std::decay_t<decltype(array)>&>(array));
    });
  }

  /// Resizes to `count` live constraints; every slot (live and padding) starts as a no-op on
  /// `null_particle`.
  void resize(std::size_t count, std::uint32_t null_particle) {
    count_ = count;
    const std::size_t capacity = padded_size(count, kLanesPerLine<Scalar>);
    particle_i.assign(capacity, null_particle);
    particle_j.assign(capacity, null_particle);
    rest_length.assign(capacity, 0);
  }

  std::size_t size() const { return count_; }
  std::size_t capacity() const { return rest_length.size(); }

 private:
  std::size_t count_ = 0;
};

}  // namespace limber
