// Particle storage for the Verlet family: structure of arrays, aligned and padded.
#pragma once

#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "limber/layouts/aligned_array.hpp"

namespace limber {

/// Particles in structure-of-arrays form (one array per coordinate). Under the pbd projection
/// rule the state is that of Verlet integration (thesis eq. 3.6): current and previous
/// positions, velocity implicit, v ≈ (x − x_previous) / Δt. Under the rattle rule it is (x, v):
/// the velocity arrays hold v, and the previous positions hold x at the start of the (sub)step
/// (where the constraints' start gradients are taken).
///
/// Shapes: every array holds capacity() ≥ size() + 1 elements, a multiple of the lane count
/// of its element type (kLanesPerLine). Index size() is the *null particle*: inverse mass 0,
/// at the origin. It and the padding behind it are never integrated or moved, so SIMD lanes
/// and padded constraint slots can point at it and need no masks (Box2D v3 does the same).
///
/// Scalar is float or double.
template <typename Scalar>
struct ParticleBuffer {
  using scalar_type = Scalar;
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;

  /// Current positions x(t), m.
  AlignedArray<Scalar> position_x, position_y, position_z;
  /// Previous positions x(t − Δt), m.
  AlignedArray<Scalar> previous_x, previous_y, previous_z;
  /// Velocities, m/s (the rattle rule's state; zero and unused under pbd).
  AlignedArray<Scalar> velocity_x, velocity_y, velocity_z;
  /// Inverse mass w = 1/m, 1/kg. w = 0 pins a particle (weighted relaxation never moves it).
  AlignedArray<Scalar> inverse_mass;

  /// The field list: every per-particle array, once, with its name.
  template <typename Visitor>
  void for_each_field(Visitor&& visit) {
    visit("position_x", position_x), visit("position_y", position_y), visit("position_z", position_z);
    visit("previous_x", previous_x), visit("previous_y", previous_y), visit("previous_z", previous_z);
    visit("velocity_x", velocity_x), visit("velocity_y", velocity_y), visit("velocity_z", velocity_z);
    visit("inverse_mass", inverse_mass);
  }
  template <typename Visitor>
  void for_each_field(Visitor&& visit) const {
    const_cast<ParticleBuffer*>(this)->for_each_field([&](const char* name, auto& array) {
      visit(name, static_cast<const std::decay_t<decltype(array)>&>(array));
    });
  }

  /// Resizes to `count` live particles (plus the null particle and padding), all zero.
  void resize(std::size_t count) {
    count_ = count;
    const std::size_t capacity = padded_size(count + 1, kLanesPerLine<Scalar>);
    for_each_field([&](const char*, auto& array) { array.assign(capacity, 0); });
  }

  /// Number of live particles.
  std::size_t size() const { return count_; }
  /// Allocated length of every array (≥ size() + 1, padded to the lane count).
  std::size_t capacity() const { return position_x.size(); }
  /// Index of the null particle (inverse mass 0, never moves).
  std::uint32_t null_particle() const { return static_cast<std::uint32_t>(count_); }

  Vector3 position(std::size_t i) const { return {position_x[i], position_y[i], position_z[i]}; }
  Vector3 previous(std::size_t i) const { return {previous_x[i], previous_y[i], previous_z[i]}; }
  void set_position(std::size_t i, const Vector3& x) { position_x[i] = x.x(), position_y[i] = x.y(), position_z[i] = x.z(); }
  void set_previous(std::size_t i, const Vector3& x) { previous_x[i] = x.x(), previous_y[i] = x.y(), previous_z[i] = x.z(); }
  Vector3 velocity(std::size_t i) const { return {velocity_x[i], velocity_y[i], velocity_z[i]}; }
  void set_velocity(std::size_t i, const Vector3& v) { velocity_x[i] = v.x(), velocity_y[i] = v.y(), velocity_z[i] = v.z(); }

 private:
  std::size_t count_ = 0;
};

}  // namespace limber
