// The scene loader's static colliders (format in scene_file.hpp): "colliders" entries of type
// box, capsule, mesh, and the "stairs" generator that becomes a mesh; and the "collision" filter
// that bodies and colliders share.
//
// As in scene_file.cpp, every value is checked as it is read, with paths in the file's own
// terms ("colliders[2].triangles[5]"), so validate() later finds nothing it must report in the
// Model's terms ("colliders[2].mesh.triangles[5]").
#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <string_view>
#include <vector>

#include "limber/kernel/model/checks.hpp"
#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/scene/scene_json.hpp"

namespace limber::scene_json {

namespace {

/// The fields each collider type takes besides the common ones (name, type, restitution,
/// friction, collision). A field of another type is refused: a box given a radius is a mistake.
struct TypeFields {
  std::string_view type;
  std::vector<std::string_view> fields;
};
constexpr std::string_view kCommonFields[] = {"name", "type", "restitution", "friction", "collision"};
const TypeFields kTypeFields[] = {
    {"box", {"position", "rotation", "half_extents"}},
    {"capsule", {"position", "rotation", "axis", "length", "radius"}},
    {"mesh", {"position", "rotation", "vertices", "triangles", "thickness"}},
    {"stairs", {"position", "direction", "steps", "rise", "run", "width", "landing", "thickness"}},
};

/// A rotation vector (axis × angle, rad; the drive's target_rotation convention) as a unit
/// quaternion.
Eigen::Quaterniond read_rotation(const Object& object) {
  const Vector3 rotation = object.vector("rotation");
  const double angle = rotation.norm();
  if (angle == 0) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, rotation / angle));
}

/// A length that must be > 0.
double read_positive(const Object& object, const std::string& key) {
  const double value = object.number(key);
  require_positive(value, object.path(key));
  return value;
}

/// "vertices": an array of [x, y, z]; "triangles": an array of [i, j, k] vertex indices.
TriangleMesh read_mesh(const Object& object) {
  TriangleMesh mesh;
  const Json& vertices = object.at("vertices");
  const std::string vertices_path = object.path("vertices");
  if (!vertices.is_array()) wrong_type(vertices, vertices_path, "an array of [x, y, z]");
  mesh.vertices.reserve(vertices.size());
  for (std::size_t i = 0; i < vertices.size(); ++i) mesh.vertices.push_back(read_vector(vertices[i], indexed(vertices_path, i)));
  const Json& triangles = object.at("triangles");
  const std::string triangles_path = object.path("triangles");
  if (!triangles.is_array()) wrong_type(triangles, triangles_path, "an array of [i, j, k]");
  mesh.triangles.reserve(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Json& triangle = triangles[t];
    const std::string path = indexed(triangles_path, t);
    if (!triangle.is_array() || triangle.size() != 3) {
      const std::string found = triangle.is_array() ? "an array of " + std::to_string(triangle.size()) : std::string(triangle.type_name());
      fail(path, "must be an array of 3 vertex indices, got " + found);
    }
    mesh.triangles.push_back({read_uint32(triangle[0], indexed(path, 0)), read_uint32(triangle[1], indexed(path, 1)),
                              read_uint32(triangle[2], indexed(path, 2))});
  }
  return mesh;
}

/// A mesh's triangle's corners, starting from the least (by x, then y, then z) and in the
/// triangle's turn: a triangle listed again, from another corner or through other vertices at the
/// same points, has the same corners; turned over (facing the other way), it has not.
std::array<std::array<double, 3>, 3> corners(const TriangleMesh& mesh, const std::array<std::uint32_t, 3>& triangle) {
  std::array<std::array<double, 3>, 3> points;
  for (int k = 0; k < 3; ++k) {
    const Vector3& v = mesh.vertices[triangle[static_cast<std::size_t>(k)]];
    points[static_cast<std::size_t>(k)] = {v.x(), v.y(), v.z()};
  }
  std::rotate(points.begin(), std::min_element(points.begin(), points.end()), points.end());
  return points;
}

/// Drops the triangles that add nothing but cost: degenerate ones (checks.hpp's
/// degenerate_triangle) and duplicates (the same corners in the same turn as an earlier
/// triangle: sorted by corners, each run keeps its first in file order). The rest keep their
/// order. Adds a note when any is dropped; refuses a mesh left with none, by its name. The
/// indices must name vertices (checked before).
void drop_useless_triangles(TriangleMesh& mesh, const std::string& name, const std::string& path, std::vector<std::string>& notes) {
  const std::size_t count = mesh.triangles.size();
  std::vector<bool> useless(count, false);
  std::size_t degenerate = 0, duplicate = 0;
  std::vector<std::uint32_t> order;
  order.reserve(count);
  for (std::size_t t = 0; t < count; ++t) {
    const auto& triangle = mesh.triangles[t];
    if (degenerate_triangle(mesh.vertices[triangle[0]], mesh.vertices[triangle[1]], mesh.vertices[triangle[2]])) {
      useless[t] = true, ++degenerate;
    } else {
      order.push_back(static_cast<std::uint32_t>(t));
    }
  }
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    const auto first = corners(mesh, mesh.triangles[a]), second = corners(mesh, mesh.triangles[b]);
    return first != second ? first < second : a < b;
  });
  for (std::size_t k = 1; k < order.size(); ++k) {
    if (corners(mesh, mesh.triangles[order[k]]) == corners(mesh, mesh.triangles[order[k - 1]])) useless[order[k]] = true, ++duplicate;
  }
  if (degenerate + duplicate == 0) return;
  const std::string counts = std::to_string(degenerate) + " degenerate (no area: repeated or collinear vertices) and " +
                             std::to_string(duplicate) + " duplicate (the same corners as an earlier triangle)";
  if (degenerate + duplicate == count) {
    fail(path, "mesh " + in_quotes(name) + " has no useful triangle: of " + std::to_string(count) + ", " + counts);
  }
  std::size_t kept = 0;
  for (std::size_t t = 0; t < count; ++t) {
    if (!useless[t]) mesh.triangles[kept++] = mesh.triangles[t];
  }
  mesh.triangles.resize(kept);
  notes.push_back(path + ": dropped " + std::to_string(count - kept) + " of " + std::to_string(count) + " triangles of mesh " +
                  in_quotes(name) + ", " + counts + ": they add no surface, only cost");
}

/// The "stairs" generator's fields, checked with their paths, as generators.hpp's StairsSpec.
StairsSpec read_stairs(const Object& object) {
  StairsSpec spec;
  const int steps = object.integer("steps");
  require_at_least(steps, 1, object.path("steps"));
  require_at_most(steps, 1'000'000, object.path("steps"));
  spec.steps = static_cast<std::size_t>(steps);
  spec.rise = read_positive(object, "rise");
  spec.run = read_positive(object, "run");
  spec.width = read_positive(object, "width");
  spec.landing = object.find("landing") ? read_positive(object, "landing") : spec.run;
  spec.position = object.vector("position");
  spec.direction = object.direction("direction");
  if (!(std::abs(spec.direction.z()) <= 1e-9)) {
    fail(object.path("direction"), "must be horizontal (z = 0), got " + format_vector(object.vector("direction")));
  }
  spec.direction.z() = 0;
  return spec;
}

/// Takes `triangles` from the scene's triangle budget (SceneOptions::max_triangles), or refuses
/// the collider before its mesh is allocated.
void take_triangles(std::size_t triangles, std::size_t& budget, std::size_t max_triangles, const std::string& path) {
  if (triangles > budget) {
    fail(path, "asks for " + std::to_string(triangles) + " triangles, more than the " + std::to_string(budget) + " left of the " +
                   std::to_string(max_triangles) + " the colliders may have");
  }
  budget -= triangles;
}

StaticCollider read_collider(const Object& object, std::size_t& triangle_budget, std::size_t max_triangles,
                             std::vector<std::string>& notes) {
  object.allow_only({"name", "type", "position", "rotation", "axis", "half_extents", "length", "radius", "vertices", "triangles",
                     "thickness", "restitution", "friction", "collision", "steps", "rise", "run", "width", "landing", "direction"});
  StaticCollider collider;
  collider.name = object.string("name");
  require_name(collider.name, object.path("name"), /*is_body=*/false);
  const std::string type = object.string("type");
  const auto known = std::find_if(std::begin(kTypeFields), std::end(kTypeFields), [&](const TypeFields& t) { return t.type == type; });
  if (known == std::end(kTypeFields)) {
    fail(object.path("type"), "must be \"box\", \"capsule\", \"mesh\" or \"stairs\", got " + in_quotes(type));
  }
  for (const auto& [key, value] : object.json().items()) {
    const bool common = std::find(std::begin(kCommonFields), std::end(kCommonFields), key) != std::end(kCommonFields);
    if (!common && std::find(known->fields.begin(), known->fields.end(), key) == known->fields.end()) {
      fail(object.path(key), "is not used by a " + type + " collider");
    }
  }

  if (type == "box") {
    collider.type = ColliderType::box;
    collider.position = object.vector("position");
    if (object.find("rotation")) collider.orientation = read_rotation(object);
    collider.half_extents = object.vector("half_extents");
    for (int axis = 0; axis < 3; ++axis) {
      require_positive(collider.half_extents[axis], indexed(object.path("half_extents"), static_cast<std::size_t>(axis)));
    }
  } else if (type == "capsule") {
    collider.type = ColliderType::capsule;
    collider.position = object.vector("position");
    if (object.find("rotation") && object.find("axis")) fail(object.path(), "give either \"rotation\" or \"axis\", not both");
    if (object.find("rotation")) collider.orientation = read_rotation(object);
    if (object.find("axis")) collider.orientation = Eigen::Quaterniond::FromTwoVectors(Vector3::UnitZ(), object.direction("axis"));
    collider.length = object.number("length");
    require_non_negative(collider.length, object.path("length"));
    collider.radius = read_positive(object, "radius");
  } else {
    collider.type = ColliderType::mesh;
    if (type == "mesh") {
      const Json& triangles = object.at("triangles");
      if (triangles.is_array()) take_triangles(triangles.size(), triangle_budget, max_triangles, object.path("triangles"));
      collider.mesh = read_mesh(object);
      // The vertices are in the frame that position and rotation give (both optional); the Model
      // holds them in world coordinates, so its position and orientation stay unused.
      const Vector3 position = object.find("position") ? object.vector("position") : Vector3::Zero();
      const Eigen::Quaterniond rotation = object.find("rotation") ? read_rotation(object) : Eigen::Quaterniond::Identity();
      for (Vector3& vertex : collider.mesh.vertices) vertex = rotation * vertex + position;
      for (std::size_t i = 0; i < collider.mesh.vertices.size(); ++i) {
        require_finite(collider.mesh.vertices[i], indexed(object.path("vertices"), i));
      }
      require_vertex_indices(collider.mesh, object.path("triangles"));
      drop_useless_triangles(collider.mesh, collider.name, object.path("triangles"), notes);
    } else {
      const StairsSpec stairs = read_stairs(object);
      take_triangles(stairs_triangles(stairs), triangle_budget, max_triangles, object.path("steps"));
      collider.mesh = make_stairs_mesh(stairs);
    }
    require_triangle_mesh(collider.mesh, object.path("vertices"), object.path("triangles"));
    if (object.find("thickness")) collider.thickness = read_positive(object, "thickness");
  }

  object.optional("restitution", collider.restitution);
  require_in_range(collider.restitution, 0, 1, object.path("restitution"));
  object.optional("friction", collider.friction);
  require_non_negative(collider.friction, object.path("friction"));
  if (const Json* collision = object.find("collision")) collider.collision = read_collision_filter(Object(*collision, object.path("collision")));
  return collider;
}

}  // namespace

CollisionFilter read_collision_filter(const Object& object) {
  object.allow_only({"group", "mask"});
  CollisionFilter filter;
  if (const Json* group = object.find("group")) filter.group = read_uint32(*group, object.path("group"));
  if (const Json* mask = object.find("mask")) filter.mask = read_uint32(*mask, object.path("mask"));
  return filter;
}

std::vector<StaticCollider> read_colliders(const Json& value, const std::string& path, std::size_t max_triangles,
                                           std::vector<std::string>& notes) {
  if (!value.is_array()) wrong_type(value, path, "an array");
  std::vector<StaticCollider> colliders;
  colliders.reserve(value.size());
  std::size_t triangle_budget = max_triangles;
  for (std::size_t i = 0; i < value.size(); ++i) {
    colliders.push_back(read_collider(Object(value[i], indexed(path, i)), triangle_budget, max_triangles, notes));
  }
  require_unique_names(colliders, [](const StaticCollider& collider) -> std::string_view { return collider.name; }, path);
  return colliders;
}

}  // namespace limber::scene_json
