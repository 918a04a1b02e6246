#include "tools/viewer/meshes.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace limber::viewer {
namespace {

using Eigen::Affine3f;
using Eigen::Vector3f;

constexpr float kPi = 3.14159265358979f;

std::uint32_t add_vertex(UnitMeshes& meshes, const Vector3f& position, const Vector3f& normal) {
  const auto index = static_cast<std::uint32_t>(meshes.vertices.size() / 6);
  meshes.vertices.insert(meshes.vertices.end(), {position.x(), position.y(), position.z(), normal.x(), normal.y(), normal.z()});
  return index;
}

// One ring of a surface of revolution about z: radius ρ at height z, normal (n_ρ, n_z) in the
// meridian plane.
struct Ring {
  float radius, z, normal_radial, normal_z;
};

// Rings listed upwards (increasing z along the surface) joined by quads. With θ increasing
// counter-clockwise about +z, (∂/∂θ) × (∂/∂up) points outwards, which sets the winding.
void add_revolution(UnitMeshes& meshes, int segments, const std::vector<Ring>& rings) {
  const auto first = static_cast<std::uint32_t>(meshes.vertices.size() / 6);
  for (const Ring& ring : rings) {
    for (int i = 0; i <= segments; ++i) {  // the seam vertex repeats so θ runs 0 → 2π without wrap
      const float theta = 2 * kPi * static_cast<float>(i % segments) / static_cast<float>(segments);
      const float c = std::cos(theta), s = std::sin(theta);
      add_vertex(meshes, {ring.radius * c, ring.radius * s, ring.z},
                 {ring.normal_radial * c, ring.normal_radial * s, ring.normal_z});
    }
  }
  const auto stride = static_cast<std::uint32_t>(segments + 1);
  for (std::uint32_t row = 0; row + 1 < rings.size(); ++row) {
    for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(segments); ++i) {
      const std::uint32_t a = first + row * stride + i, b = a + stride;
      meshes.indices.insert(meshes.indices.end(), {a, a + 1, b, a + 1, b + 1, b});
    }
  }
}

// Latitudes from `from` to `to` (radians, −π/2 south pole … π/2 north pole) of the unit sphere.
std::vector<Ring> sphere_rings(float from, float to, int bands) {
  std::vector<Ring> rings;
  for (int j = 0; j <= bands; ++j) {
    const float phi = from + (to - from) * static_cast<float>(j) / static_cast<float>(bands);
    const float c = std::cos(phi), s = std::sin(phi);
    rings.push_back({c, s, c, s});
  }
  return rings;
}

void add_disk(UnitMeshes& meshes, int segments) {
  const std::uint32_t centre = add_vertex(meshes, Vector3f::Zero(), Vector3f::UnitZ());
  for (int i = 0; i < segments; ++i) {
    const float theta = 2 * kPi * static_cast<float>(i) / static_cast<float>(segments);
    add_vertex(meshes, {std::cos(theta), std::sin(theta), 0}, Vector3f::UnitZ());
  }
  for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(segments); ++i) {
    const std::uint32_t next = (i + 1) % static_cast<std::uint32_t>(segments);
    meshes.indices.insert(meshes.indices.end(), {centre, centre + 1 + i, centre + 1 + next});
  }
}

// Each face has its own four vertices so that its normal is flat; u × v = n keeps the corners
// counter-clockwise seen from outside.
void add_box(UnitMeshes& meshes) {
  for (int axis = 0; axis < 3; ++axis) {
    for (const float sign : {1.0f, -1.0f}) {
      const Vector3f n = sign * Vector3f::Unit(axis);
      Vector3f u = Vector3f::Unit((axis + 1) % 3), v = Vector3f::Unit((axis + 2) % 3);
      if (sign < 0) std::swap(u, v);
      const std::uint32_t a = add_vertex(meshes, n - u - v, n);
      add_vertex(meshes, n + u - v, n);
      add_vertex(meshes, n + u + v, n);
      add_vertex(meshes, n - u + v, n);
      meshes.indices.insert(meshes.indices.end(), {a, a + 1, a + 2, a, a + 2, a + 3});
    }
  }
}

void add_level(UnitMeshes& meshes, std::size_t level) {
  const int segments = kLevelSegments[level];
  const int quarter_bands = std::max(segments / 4, 2);  // latitude bands from equator to pole
  const auto build = [&](UnitShape shape, auto&& add) {
    const auto first = static_cast<std::uint32_t>(meshes.indices.size());
    add();
    meshes.ranges[level * kUnitShapeCount + static_cast<std::size_t>(shape)] = {
        first, static_cast<std::uint32_t>(meshes.indices.size()) - first};
  };
  build(UnitShape::sphere, [&] { add_revolution(meshes, segments, sphere_rings(-kPi / 2, kPi / 2, 2 * quarter_bands)); });
  build(UnitShape::hemisphere, [&] { add_revolution(meshes, segments, sphere_rings(0, kPi / 2, quarter_bands)); });
  build(UnitShape::cylinder_side, [&] { add_revolution(meshes, segments, {{1, -1, 1, 0}, {1, 1, 1, 0}}); });
  build(UnitShape::disk, [&] { add_disk(meshes, segments); });
  build(UnitShape::box, [&] { add_box(meshes); });
}

// One unit shape in a solid: scaled by `scale` (per axis), then placed by `local` in the solid's frame.
struct Part {
  UnitShape shape = UnitShape::sphere;
  Affine3f local = Affine3f::Identity();  // rotation and translation only
  Vector3f scale = Vector3f::Ones();
};

// A capsule is a cylinder side and two hemispheres scaled separately: scaling one capsule mesh
// non-uniformly would squash its caps. Returns how many of `parts` it filled.
int parts_of(const Solid& solid, std::array<Part, 3>& parts) {
  const float r = solid.radius, h = solid.half_length;
  const Affine3f turned(Eigen::AngleAxisf(kPi, Vector3f::UnitX()));  // +z → −z, still a rotation
  const Affine3f up(Eigen::Translation3f(0, 0, h)), down(Eigen::Translation3f(0, 0, -h));
  const Affine3f identity = Affine3f::Identity();
  switch (solid.kind) {
    case SolidKind::capsule:
      parts = {Part{UnitShape::hemisphere, up, Vector3f::Constant(r)},
               Part{UnitShape::hemisphere, down * turned, Vector3f::Constant(r)},
               Part{UnitShape::cylinder_side, identity, {r, r, h}}};
      return h > 0 ? 3 : 2;
    case SolidKind::cylinder:
      parts = {Part{UnitShape::cylinder_side, identity, {r, r, h}}, Part{UnitShape::disk, up, {r, r, 1}},
               Part{UnitShape::disk, down * turned, {r, r, 1}}};
      return 3;
    case SolidKind::sphere:
      parts[0] = Part{UnitShape::sphere, identity, Vector3f::Constant(r)};
      return 1;
    case SolidKind::box:
      parts[0] = Part{UnitShape::box, identity, solid.half_extents};
      return 1;
    case SolidKind::ellipsoid:  // the normal matrix (append_instance) keeps its shading true
      parts[0] = Part{UnitShape::sphere, identity, solid.half_extents};
      return 1;
  }
  return 0;
}

// A regular n-gon strays r (1 − cos(π/n)) from its circle of radius r: the coarsest level
// keeping that within a pixel. All parts of a solid share the level, so their seams match.
std::size_t level_of(const Solid& solid, const Eigen::RowVector4f& clip_w, float pixels_per_unit) {
  const bool scaled = solid.kind == SolidKind::box || solid.kind == SolidKind::ellipsoid;
  const float reach = scaled ? solid.half_extents.norm() : solid.radius + solid.half_length;
  // w of the solid's nearest possible point (perspective), or the constant w (orthographic).
  const float w = clip_w.head<3>().dot(solid.placement.translation()) + clip_w(3) - reach * clip_w.head<3>().norm();
  if (!(w > 0)) return kLevelCount - 1;
  // An ellipsoid's outline strays most along its longest semi-axis (a box is the same at every level).
  const float radius = solid.kind == SolidKind::ellipsoid ? solid.half_extents.maxCoeff() : solid.radius;
  const float radius_pixels = radius * pixels_per_unit / w;
  for (std::size_t level = 0; level + 1 < kLevelCount; ++level) {
    if (radius_pixels * (1 - std::cos(kPi / static_cast<float>(kLevelSegments[level]))) <= 1) return level;
  }
  return kLevelCount - 1;
}

void append_instance(std::vector<float>& data, const Solid& solid, const Part& part) {
  constexpr float kMinimumScale = 1e-6f;  // keeps the normal matrix finite for degenerate sizes
  const Vector3f scale = part.scale.cwiseMax(kMinimumScale);
  const Affine3f placed = Affine3f(solid.placement.matrix()) * part.local;
  const Eigen::Matrix4f model = (placed * Eigen::Scaling(scale)).matrix();
  // The inverse transpose of rotation × scale is rotation × scale⁻¹.
  const Eigen::Matrix3f normals = placed.linear() * scale.cwiseInverse().asDiagonal();
  data.insert(data.end(), model.data(), model.data() + 16);
  data.insert(data.end(), normals.data(), normals.data() + 9);
  data.insert(data.end(), {solid.colour.r, solid.colour.g, solid.colour.b});
}

}  // namespace

UnitMeshes build_unit_meshes() {
  UnitMeshes meshes;
  for (std::size_t level = 0; level < kLevelCount; ++level) add_level(meshes, level);
  return meshes;
}

void gather_instances(const std::vector<Solid>& solids, const CameraMatrices& camera, int viewport_height,
                      SolidInstances& instances) {
  for (std::vector<float>& group : instances.sorting) group.clear();
  std::array<std::size_t, kGroupCount> casters{};
  const Eigen::RowVector4f clip_w = (camera.projection * camera.view).row(3);
  const float pixels_per_unit = std::abs(camera.projection(1, 1)) * static_cast<float>(viewport_height) / 2;
  std::array<Part, 3> parts;
  for (const bool casting : {true, false}) {
    for (const Solid& solid : solids) {
      if (solid.casts_shadow != casting) continue;
      const std::size_t level = level_of(solid, clip_w, pixels_per_unit);
      const int count = parts_of(solid, parts);
      for (int i = 0; i < count; ++i) {
        const std::size_t group = level * kUnitShapeCount + static_cast<std::size_t>(parts[i].shape);
        append_instance(instances.sorting[group], solid, parts[i]);
        if (casting) ++casters[group];
      }
    }
  }
  instances.data.clear();
  for (std::size_t group = 0; group < kGroupCount; ++group) {
    const std::vector<float>& sorted = instances.sorting[group];
    instances.groups[group] = {instances.data.size() / SolidInstances::kFloats, sorted.size() / SolidInstances::kFloats,
                               casters[group]};
    instances.data.insert(instances.data.end(), sorted.begin(), sorted.end());
  }
}

void soup_vertices(const std::vector<TriangleSoup>& soups, std::vector<float>& vertices) {
  vertices.clear();
  for (const TriangleSoup& soup : soups) {
    for (std::size_t i = 0; i + 2 < soup.vertices.size(); i += 3) {
      const Vector3f& a = soup.vertices[i];
      const Vector3f& b = soup.vertices[i + 1];
      const Vector3f& c = soup.vertices[i + 2];
      const Vector3f cross = (b - a).cross(c - a);
      const Vector3f normal = cross.squaredNorm() > 0 ? Vector3f(cross.normalized()) : Vector3f::UnitZ();
      for (const Vector3f* p : {&a, &b, &c}) {
        vertices.insert(vertices.end(), {p->x(), p->y(), p->z(), normal.x(), normal.y(), normal.z()});
      }
    }
  }
}

}  // namespace limber::viewer
