// The unit shapes the renderer scales into solids (renderer.cpp), a frame's solids as instances
// of them, and triangle soups as flat-shaded vertices: plain arrays, no OpenGL.
//
// Each unit shape exists at a few detail levels (segments around its axis); a solid gets the
// coarsest level whose outline stays within about a pixel of the true circle, since on llvmpipe
// the triangle count of a thousand limbs, not the number of draws, sets the frame time.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "tools/viewer/draw_list.hpp"

namespace limber::viewer {

enum class UnitShape : std::uint8_t {
  sphere,         ///< radius 1 about the origin
  hemisphere,     ///< the z ≥ 0 half of the unit sphere, open at the equator
  cylinder_side,  ///< radius 1, z from −1 to 1, open ends
  disk,           ///< radius 1 in the plane z = 0, facing +z
  box,            ///< the cube [−1, 1]³, flat faces (the same at every level)
};
inline constexpr std::size_t kUnitShapeCount = 5;
inline constexpr std::array<int, 3> kLevelSegments{8, 16, 32};  ///< segments around, coarse to fine
inline constexpr std::size_t kLevelCount = kLevelSegments.size();
/// Shapes × levels: a group's index is level · kUnitShapeCount + shape.
inline constexpr std::size_t kGroupCount = kLevelCount * kUnitShapeCount;

/// A group's triangles: indices [first, first + count) of UnitMeshes::indices.
struct IndexRange {
  std::uint32_t first = 0, count = 0;
};

/// All unit shapes at all levels in one vertex and one index array. Each vertex is a position
/// and its unit outward normal (6 floats); triangles are counter-clockwise seen from outside.
struct UnitMeshes {
  std::vector<float> vertices;
  std::vector<std::uint32_t> indices;
  std::array<IndexRange, kGroupCount> ranges;
};

UnitMeshes build_unit_meshes();

/// This frame's solids as instances, grouped by (level, shape), each group's shadow casters
/// first (so shadows draw a prefix). Per instance `kFloats` floats, column-major: the model
/// matrix (4 × 4, the unit shape's scale included), the normal matrix (3 × 3) and the colour.
struct SolidInstances {
  static constexpr std::size_t kFloats = 16 + 9 + 3;
  struct Group {
    std::size_t first = 0, count = 0, casters = 0;  ///< instances
  };
  std::vector<float> data;
  std::array<Group, kGroupCount> groups{};
  std::array<std::vector<float>, kGroupCount> sorting;  ///< kept only to reuse its memory
};

/// Fills `instances` from `solids` seen by `camera` in a viewport `viewport_height` pixels tall.
void gather_instances(const std::vector<Solid>& solids, const CameraMatrices& camera, int viewport_height,
                      SolidInstances& instances);

/// The triangles of `soups` one after the other, each vertex as position and the triangle's unit
/// normal (6 floats; +z for a degenerate triangle); a soup's trailing 1–2 vertices are dropped.
void soup_vertices(const std::vector<TriangleSoup>& soups, std::vector<float>& vertices);

}  // namespace limber::viewer
