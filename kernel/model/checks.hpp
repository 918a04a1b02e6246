// Range checks shared by validate() and the scene loader, so every message reads the same:
// "<path>: <problem>", e.g. "bodies[3].mass: must be > 0, got -1". Internal to the kernel.
#pragma once

#include <charconv>
#include <cmath>
#include <string>
#include <string_view>
#include <unordered_map>

#include "kernel/model/model.hpp"

namespace limber::checks {

/// Shortest text that reads back to the same double ("0.1", "-1", "nan", "inf").
inline std::string format_number(double value) {
  if (std::isnan(value)) return "nan";
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return {buffer, result.ptr};
}

inline std::string format_vector(const Vector3& v) {
  return "[" + format_number(v.x()) + ", " + format_number(v.y()) + ", " + format_number(v.z()) +
         "]";
}

/// "<path>[index]": an array element or a vector component.
inline std::string indexed(std::string_view path, std::size_t index) {
  return std::string(path) + "[" + std::to_string(index) + "]";
}

/// Throws ModelError "<path>: <problem>" (just the problem when the path is empty: the root).
[[noreturn]] inline void fail(std::string_view path, std::string_view problem) {
  std::string message(path);
  if (!message.empty()) message += ": ";
  message += problem;
  throw ModelError(message);
}

inline void require_finite(double value, std::string_view path) {
  if (!std::isfinite(value)) fail(path, "must be a finite number, got " + format_number(value));
}

/// Each component, named "<path>[i]".
inline void require_finite(const Vector3& value, std::string_view path) {
  for (int i = 0; i < 3; ++i) require_finite(value[i], indexed(path, i));
}

inline void require_positive(double value, std::string_view path) {
  require_finite(value, path);
  if (!(value > 0)) fail(path, "must be > 0, got " + format_number(value));
}

inline void require_non_negative(double value, std::string_view path) {
  require_finite(value, path);
  if (!(value >= 0)) fail(path, "must be >= 0, got " + format_number(value));
}

/// value in [low, high]; `low_open` / `high_open` exclude an end.
inline void require_in_range(double value, double low, double high, std::string_view path,
                             bool low_open = false, bool high_open = false) {
  require_finite(value, path);
  const bool above_low = low_open ? value > low : value >= low;
  const bool below_high = high_open ? value < high : value <= high;
  if (!above_low || !below_high) {
    fail(path, "must be in " + std::string(low_open ? "(" : "[") + format_number(low) + ", " +
                   format_number(high) + (high_open ? ")" : "]") + ", got " + format_number(value));
  }
}

inline void require_at_least(long value, long low, std::string_view path) {
  if (value < low) {
    fail(path, "must be >= " + std::to_string(low) + ", got " + std::to_string(value));
  }
}

/// A direction the loader will normalize: finite and not (numerically) zero.
inline void require_non_zero(const Vector3& value, std::string_view path) {
  require_finite(value, path);
  if (!(value.norm() > 0)) fail(path, "must be a non-zero vector, got " + format_vector(value));
}

/// |value| within 1e-9 of 1.
inline void require_unit(const Vector3& value, std::string_view path) {
  require_finite(value, path);
  const double length = value.norm();
  if (!(std::abs(length - 1) <= 1e-9))
    fail(path, "must be a unit vector, got length " + format_number(length));
}

/// Names must be non-empty; body names also must not be "world" (the fixed frame in joints).
inline void require_name(std::string_view name, std::string_view path, bool is_body) {
  if (name.empty()) fail(path, "must be a non-empty name");
  if (is_body && name == "world") fail(path, "\"world\" is reserved for the fixed frame");
}

/// Finite corners with max > min on every axis; fails at "<path>.max[i]".
inline void require_box(const Vector3& min, const Vector3& max, std::string_view path) {
  const std::string min_path = std::string(path) + ".min";
  const std::string max_path = std::string(path) + ".max";
  require_finite(min, min_path);
  require_finite(max, max_path);
  for (int i = 0; i < 3; ++i) {
    if (!(max[i] > min[i])) {
      fail(indexed(max_path, i), "must be > " + indexed(min_path, i) + " = " +
                                     format_number(min[i]) + ", got " + format_number(max[i]));
    }
  }
}

/// Name -> where it was first seen (e.g. "bodies[1]").
using NameRegistry = std::unordered_map<std::string, std::string>;

/// Registers the name of `owner`; fails at "<owner>.name" when it was seen before.
inline void require_unique(NameRegistry& seen, const std::string& name, const std::string& owner) {
  const auto [first, inserted] = seen.emplace(name, owner);
  if (!inserted)
    fail(owner + ".name", "duplicate name \"" + name + "\" (also " + first->second + ")");
}

}  // namespace limber::checks
