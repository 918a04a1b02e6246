// Range checks shared by validate() and the scene loader, so every message reads the same:
// "<path>: <problem>", e.g. "bodies[3].mass: must be > 0, got -1". Internal to the kernel.
#pragma once

#include <charconv>
#include <cmath>
#include <string>
#include <string_view>
#include <algorithm>
#include <functional>
#include <type_traits>
#include <utility>
#include <vector>

#include "limber/kernel/model/model.hpp"

namespace limber::checks {

/// Shortest text that reads back to the same double ("0.1", "-1", "nan", "inf").
inline std::string format_number(double value) {
  if (std::isnan(value)) return "nan";
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return {buffer, result.ptr};
}

// Appended piece by piece: `"[" + std::string&&` trips GCC 12's -Wrestrict false positive (bug 105329).
inline std::string format_vector(const Vector3& v) {
  std::string text = "[";
  text.append(format_number(v.x())).append(", ").append(format_number(v.y())).append(", ").append(format_number(v.z()));
  return text.append("]");
}

/// "<path>[index]": an array element or a vector component.
inline std::string indexed(std::string_view path, std::size_t index) {
  return std::string(path) + "[" + std::to_string(index) + "]";
}

/// A field path is a string, or a callable returning one: validating a million bodies must not
/// build a million path strings, so validate() passes callables, formatted only on failure.
template <typename Path>
std::string path_text(const Path& path) {
  if constexpr (std::is_invocable_v<const Path&>) {
    return std::string(path());
  } else {
    return std::string(path);
  }
}

/// Throws ModelError "<path>: <problem>" (just the problem when the path is empty: the root).
template <typename Path>
[[noreturn]] void fail(const Path& path, std::string_view problem) {
  std::string message = path_text(path);
  if (!message.empty()) message += ": ";
  message += problem;
  throw ModelError(message);
}

template <typename Path>
void require_finite(double value, const Path& path) {
  if (!std::isfinite(value)) fail(path, "must be a finite number, got " + format_number(value));
}

/// Each component, named "<path>[i]".
template <typename Path>
void require_finite(const Vector3& value, const Path& path) {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(value[i])) require_finite(value[i], indexed(path_text(path), i));
  }
}

template <typename Path>
void require_positive(double value, const Path& path) {
  require_finite(value, path);
  if (!(value > 0)) fail(path, "must be > 0, got " + format_number(value));
}

template <typename Path>
void require_non_negative(double value, const Path& path) {
  require_finite(value, path);
  if (!(value >= 0)) fail(path, "must be >= 0, got " + format_number(value));
}

/// value in [low, high]; `low_open` / `high_open` exclude an end.
template <typename Path>
void require_in_range(double value, double low, double high, const Path& path, bool low_open = false,
                      bool high_open = false) {
  require_finite(value, path);
  const bool above_low = low_open ? value > low : value >= low;
  const bool below_high = high_open ? value < high : value <= high;
  if (!above_low || !below_high) {
    fail(path, "must be in " + std::string(low_open ? "(" : "[") + format_number(low) + ", " +
                   format_number(high) + (high_open ? ")" : "]") + ", got " + format_number(value));
  }
}

template <typename Path>
void require_at_least(long value, long low, const Path& path) {
  if (value < low) {
    fail(path, "must be >= " + std::to_string(low) + ", got " + std::to_string(value));
  }
}

template <typename Path>
void require_at_most(long value, long high, const Path& path) {
  if (value > high) {
    fail(path, "must be <= " + std::to_string(high) + ", got " + std::to_string(value));
  }
}

/// A direction the loader will normalize: finite and not (numerically) zero.
template <typename Path>
void require_non_zero(const Vector3& value, const Path& path) {
  require_finite(value, path);
  if (!(value.norm() > 0)) fail(path, "must be a non-zero vector, got " + format_vector(value));
}

/// |value| within 1e-9 of 1.
template <typename Path>
void require_unit(const Vector3& value, const Path& path) {
  require_finite(value, path);
  const double length = value.norm();
  if (!(std::abs(length - 1) <= 1e-9))
    fail(path, "must be a unit vector, got length " + format_number(length));
}

/// Names must be non-empty; body names also must not be "world" (the fixed frame in joints).
template <typename Path>
void require_name(std::string_view name, const Path& path, bool is_body) {
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

/// Whether triangle a, b, c is degenerate: twice its area, |(b − a) × (c − a)|, at most 1e-10 of
/// its longest edge squared (a sliver has no normal to push along), or all three corners one point.
inline bool degenerate_triangle(const Vector3& a, const Vector3& b, const Vector3& c) {
  const Vector3 ab = b - a, ac = c - a;
  const double longest = std::max({ab.squaredNorm(), ac.squaredNorm(), (ac - ab).squaredNorm()});
  return !(ab.cross(ac).norm() > 1e-10 * longest) || longest == 0;
}

/// At least one triangle, and every triangle's indices name vertices. Fails at "<triangles_path>"
/// or "<triangles_path>[t]".
inline void require_vertex_indices(const TriangleMesh& mesh, std::string_view triangles_path) {
  if (mesh.triangles.empty()) fail(triangles_path, "must list at least one triangle");
  const std::size_t count = mesh.vertices.size();
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (const std::uint32_t index : mesh.triangles[t]) {
      if (index >= count) {
        fail(indexed(triangles_path, t), "vertex index " + std::to_string(index) + " names no vertex (there are " +
                                             std::to_string(count) + ")");
      }
    }
  }
}

/// A triangle mesh (model.hpp's TriangleMesh): finite vertices, at least one triangle, indices
/// naming vertices, no degenerate triangle (degenerate_triangle). Fails at "<vertices_path>[i]"
/// or "<triangles_path>[t]".
inline void require_triangle_mesh(const TriangleMesh& mesh, std::string_view vertices_path, std::string_view triangles_path) {
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) require_finite(mesh.vertices[i], indexed(vertices_path, i));
  require_vertex_indices(mesh, triangles_path);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& triangle = mesh.triangles[t];
    const Vector3 &a = mesh.vertices[triangle[0]], &b = mesh.vertices[triangle[1]], &c = mesh.vertices[triangle[2]];
    if (degenerate_triangle(a, b, c)) {
      fail(indexed(triangles_path, t), "is degenerate (area " + format_number(0.5 * (b - a).cross(c - a).norm()) +
                                           " m^2): its vertices are repeated or in a line");
    }
  }
}

/// Every item's name differs from the others'. Fails at "<collection>[j].name" for the first j
/// whose name an earlier item has. Sorts contiguous (hash, index) pairs — no allocation per name,
/// ~0.1 s for a million — and compares names only where hashes meet.
template <typename Items, typename NameOf>
void require_unique_names(const Items& items, NameOf&& name_of, std::string_view collection) {
  std::vector<std::pair<std::size_t, std::size_t>> hashed(items.size());
  for (std::size_t i = 0; i < items.size(); ++i) hashed[i] = {std::hash<std::string_view>{}(name_of(items[i])), i};
  std::sort(hashed.begin(), hashed.end());
  std::size_t later = items.size(), earlier = 0;  // the duplicate to report
  for (std::size_t run = 0; run < hashed.size();) {
    std::size_t end = run + 1;
    while (end < hashed.size() && hashed[end].first == hashed[run].first) ++end;
    for (std::size_t a = run; a < end; ++a) {  // indices ascend within a run
      for (std::size_t b = a + 1; b < end && hashed[b].second < later; ++b) {
        if (name_of(items[hashed[a].second]) == name_of(items[hashed[b].second])) {
          later = hashed[b].second, earlier = hashed[a].second;
        }
      }
    }
    run = end;
  }
  if (later < items.size()) {
    fail(indexed(collection, later) + ".name", "duplicate name \"" + std::string(name_of(items[later])) + "\" (also " +
                                                   indexed(collection, earlier) + ")");
  }
}

}  // namespace limber::checks
