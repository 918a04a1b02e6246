// The scene loader's typed reading of JSON values, shared by its files (scene_file.cpp, the
// sections; scene_joints.cpp, joints, gears and actuators; scene_colliders.cpp, the static
// colliders). Internal to kernel/scene: it includes
// nlohmann-json, which limber keeps private, so no public header may include this one.
//
// Every reader checks as it reads and fails with ModelError "<path>: <problem>", the path in the
// file's own terms ("bodies[3].shape.radius"); load_scene_text adds the source in one place.
#pragma once

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "limber/kernel/model/checks.hpp"
#include "limber/kernel/model/model.hpp"

namespace limber::scene_json {

// Ordered, so unknown fields and available variants are reported in file order.
using Json = nlohmann::ordered_json;
using namespace checks;

inline std::string child(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

// Appended rather than `"\"" + std::string(text) + "\""`, which GCC 12 flags with a false
// -Wrestrict (GCC bug 105329).
inline std::string in_quotes(std::string_view text) {
  std::string quoted(1, '"');
  quoted.append(text);
  quoted.push_back('"');
  return quoted;
}

// ---- Typed values: each failure names the path and what was found instead.

[[noreturn]] inline void wrong_type(const Json& value, const std::string& path, std::string_view wanted) {
  fail(path, "must be " + std::string(wanted) + ", got " + value.type_name());
}

inline double read_number(const Json& value, const std::string& path) {
  if (!value.is_number()) wrong_type(value, path, "a number");
  const double number = value.get<double>();
  require_finite(number, path);  // a guard: nlohmann itself refuses 1e999 (ParseErrorLocator)
  return number;
}

/// A JSON integer literal that fits an int (body and joint indices are ints).
inline int read_int(const Json& value, const std::string& path) {
  if (value.is_number_float()) fail(path, "must be an integer, got " + value.dump());
  if (!value.is_number_integer()) wrong_type(value, path, "an integer");
  if (value.is_number_unsigned() ? value.get<std::uint64_t>() > INT_MAX
                                 : value.get<std::int64_t>() > INT_MAX) {
    fail(path, "must be at most " + std::to_string(INT_MAX) + ", got " + value.dump());
  }
  if (value.get<std::int64_t>() < INT_MIN) {
    fail(path, "must be at least " + std::to_string(INT_MIN) + ", got " + value.dump());
  }
  return value.get<int>();
}

inline std::string read_string(const Json& value, const std::string& path) {
  if (!value.is_string()) wrong_type(value, path, "a string");
  return value.get<std::string>();
}

inline bool read_bool(const Json& value, const std::string& path) {
  if (!value.is_boolean()) wrong_type(value, path, "true or false");
  return value.get<bool>();
}

inline Vector3 read_vector(const Json& value, const std::string& path) {
  if (!value.is_array() || value.size() != 3) {
    const std::string found = value.is_array() ? "an array of " + std::to_string(value.size())
                                               : std::string(value.type_name());
    fail(path, "must be an array of 3 numbers, got " + found);
  }
  return {read_number(value[0], indexed(path, 0)), read_number(value[1], indexed(path, 1)),
          read_number(value[2], indexed(path, 2))};
}

/// A JSON integer literal in [0, 2^32): collision bits, mesh vertex indices.
inline std::uint32_t read_uint32(const Json& value, const std::string& path) {
  if (value.is_number_float()) fail(path, "must be an integer, got " + value.dump());
  if (!value.is_number_integer()) wrong_type(value, path, "an integer");
  if (!value.is_number_unsigned() && value.get<std::int64_t>() < 0) fail(path, "must be >= 0, got " + value.dump());
  if (value.get<std::uint64_t>() > 0xFFFFFFFFull) fail(path, "must be < 2^32 (4294967296), got " + value.dump());
  return static_cast<std::uint32_t>(value.get<std::uint64_t>());
}

/// A non-zero vector, normalized (axes and directions).
inline Vector3 read_direction(const Json& value, const std::string& path) {
  const Vector3 direction = read_vector(value, path);
  require_non_zero(direction, path);
  return direction.normalized();
}

/// A unit quaternion [w, x, y, z]: four finite numbers whose norm is 1 within 1e-9 (as
/// validate() holds a shape's rotation to), kept as given.
inline Eigen::Quaterniond read_unit_quaternion(const Json& value, const std::string& path) {
  if (!value.is_array() || value.size() != 4) {
    const std::string found = value.is_array() ? "an array of " + std::to_string(value.size()) : std::string(value.type_name());
    fail(path, "must be a unit quaternion [w, x, y, z], got " + found);
  }
  double q[4];
  for (std::size_t k = 0; k < 4; ++k) q[k] = read_number(value[k], indexed(path, k));
  const Eigen::Quaterniond rotation(q[0], q[1], q[2], q[3]);
  const double norm = rotation.norm();
  if (!(std::abs(norm - 1) <= 1e-9)) fail(path, "must be a unit quaternion [w, x, y, z], got one of norm " + format_number(norm) + " (1 within 1e-9)");
  return rotation;
}

inline ShapeType read_shape_type(const Json& value, const std::string& path) {
  const std::string type = read_string(value, path);
  for (const ShapeType each : {ShapeType::cylinder, ShapeType::capsule, ShapeType::box, ShapeType::ellipsoid}) {
    if (type == shape_type_name(each)) return each;
  }
  fail(path, "must be \"cylinder\", \"capsule\", \"box\" or \"ellipsoid\", got " + in_quotes(type));
}

/// A shape type with its article, as messages name it: "a box", "an ellipsoid".
inline std::string a_shape(ShapeType type) { return (type == ShapeType::ellipsoid ? "an " : "a ") + std::string(shape_type_name(type)); }

/// A JSON object being read: known fields only, required ones present.
class Object {
 public:
  Object(const Json& json, std::string path) : json_(json), path_(std::move(path)) {
    if (!json.is_object()) wrong_type(json, path_, "an object");
  }

  /// Fails at the first key not in `known`: "unknown field", or at the key with `why` when given.
  void allow_only(std::initializer_list<std::string_view> known, std::string_view why = {}) const {
    for (const auto& [key, value] : json_.items()) {
      if (std::find(known.begin(), known.end(), key) == known.end()) {
        if (why.empty()) fail(path_, "unknown field " + in_quotes(key));
        fail(child(path_, key), std::string(why));
      }
    }
  }

  const std::string& path() const { return path_; }
  std::string path(const std::string& key) const { return child(path_, key); }
  const Json& json() const { return json_; }

  const Json* find(const std::string& key) const {
    const auto it = json_.find(key);
    return it == json_.end() ? nullptr : &*it;
  }
  const Json& at(const std::string& key) const {
    if (const Json* value = find(key)) return *value;
    fail(path(key), "missing required field");
  }

  double number(const std::string& key) const { return read_number(at(key), path(key)); }
  int integer(const std::string& key) const { return read_int(at(key), path(key)); }
  std::string string(const std::string& key) const { return read_string(at(key), path(key)); }
  bool boolean(const std::string& key) const { return read_bool(at(key), path(key)); }
  Vector3 vector(const std::string& key) const { return read_vector(at(key), path(key)); }
  Vector3 direction(const std::string& key) const { return read_direction(at(key), path(key)); }

  // Optional fields keep the target's default (model.hpp's member initializers) when absent.
  void optional(const std::string& key, double& target) const {
    if (const Json* value = find(key)) target = read_number(*value, path(key));
  }
  void optional(const std::string& key, bool& target) const {
    if (const Json* value = find(key)) target = read_bool(*value, path(key));
  }
  void optional(const std::string& key, Vector3& target) const {
    if (const Json* value = find(key)) target = read_vector(*value, path(key));
  }
  /// An optional string field naming one of `choices` (name, value): the value, or "must be "a",
  /// "b" or "c", got …" for any other string.
  template <typename Enum>
  void optional_choice(const std::string& key, Enum& target, std::initializer_list<std::pair<std::string_view, Enum>> choices) const {
    const Json* value = find(key);
    if (value == nullptr) return;
    const std::string name = read_string(*value, path(key));
    std::string listed;
    std::size_t k = 0;
    for (const auto& [choice, meaning] : choices) {
      if (name == choice) {
        target = meaning;
        return;
      }
      listed += (k == 0 ? "" : k + 1 == choices.size() ? " or " : ", ") + in_quotes(choice);
      ++k;
    }
    fail(path(key), "must be " + listed + ", got " + in_quotes(name));
  }

 private:
  const Json& json_;
  std::string path_;
};

/// A body as read, before its mass is settled: variants may still change radius and mass, and
/// a density becomes a mass only afterwards.
struct BodySpec {
  Body body;
  std::optional<double> density;  ///< set instead of body.mass when the mass comes from density
  std::string density_path;       ///< where that density was given, for messages
};

// ---- Defined in scene_joints.cpp

/// Entry `object` of "joints" (any type, serial joints' "serial_axes" and armature included);
/// `bodies` as read so far, `body_index` their names.
Joint read_joint(const Object& object, const std::vector<BodySpec>& bodies, const std::unordered_map<std::string, int>& body_index);
/// Entry `object` of "gears".
Gear read_gear(const Object& object, const std::vector<BodySpec>& bodies, const std::unordered_map<std::string, int>& body_index);
/// The top-level "actuators": motors, position and velocity actuators on the coordinates of
/// `joints` (by name; a serial joint's axis by its name too).
std::vector<Actuator> read_actuators(const Json& value, const std::string& path, const std::vector<Joint>& joints);

// ---- Defined in scene_colliders.cpp

/// A body's or collider's "collision": {"group": bits, "mask": bits}, each optional (an integer
/// in [0, 2^32); CollisionFilter's defaults 1 and 0xFFFFFFFF).
CollisionFilter read_collision_filter(const Object& object);

/// The top-level "colliders": an array of static colliders, "stairs" generated into meshes; a mesh
/// or stairs that would take the colliders past `max_triangles` in all is refused before its
/// mesh is allocated (SceneOptions::max_triangles). A mesh's degenerate and duplicate triangles
/// are dropped, with a line in `notes` ("colliders[k].triangles: dropped ...").
std::vector<StaticCollider> read_colliders(const Json& value, const std::string& path, std::size_t max_triangles,
                                           std::vector<std::string>& notes);

}  // namespace limber::scene_json
