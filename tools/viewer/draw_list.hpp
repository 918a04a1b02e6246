// What the viewer draws in one frame, as plain data: the scene turned into solids, triangles and
// lines (view_state.cpp fills it from the World), then drawn by the renderer (renderer.cpp, the
// only file that speaks OpenGL). World frame, metres, +z up (kernel/model/model.hpp); floats,
// since they only go to the screen.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace limber::viewer {

/// Linear RGB, each in [0, 1].
struct Colour {
  float r = 1, g = 1, b = 1;
};

enum class SolidKind : std::uint8_t {
  capsule,    ///< core segment along local z from −half_length to +half_length, hemispherical caps of `radius`
  cylinder,   ///< along local z from −half_length to +half_length, flat ends, `radius`
  sphere,     ///< `radius` about the origin
  box,        ///< half_extents along local x, y, z
  ellipsoid,  ///< semi-axes half_extents along local x, y, z (the unit sphere scaled per axis)
};

/// A shaded solid: a limb, a ball, a collider.
struct Solid {
  SolidKind kind = SolidKind::sphere;
  Eigen::Isometry3f placement = Eigen::Isometry3f::Identity();  ///< local → world (rotation and translation, no scale)
  float radius = 0;                                              ///< m (capsule, cylinder, sphere)
  float half_length = 0;                                         ///< m (capsule, cylinder)
  Eigen::Vector3f half_extents = Eigen::Vector3f::Zero();        ///< m (box, ellipsoid)
  Colour colour;
  bool casts_shadow = true;
};

/// Shaded triangles in world coordinates (a mesh collider), counter-clockwise seen from outside.
struct TriangleSoup {
  std::vector<Eigen::Vector3f> vertices;  ///< three per triangle
  Colour colour;
};

/// A line segment drawn unlit, on top of the solids' depth (overlays: contact normals, joint
/// gaps, bounding volumes, paths, force arrows).
struct Line {
  Eigen::Vector3f from = Eigen::Vector3f::Zero(), to = Eigen::Vector3f::Zero();
  Colour colour;
};

/// The ground plane z = height, drawn as a tiled floor with a grid of `spacing` m out to
/// `extent` m around `centre` (x, y), solids' shadows cast straight down onto it.
struct Floor {
  float height = 0;
  Eigen::Vector2f centre = Eigen::Vector2f::Zero();
  float extent = 10;
  float spacing = 0.5f;
};

/// The camera: world → eye (view) and eye → clip (projection), OpenGL conventions.
struct CameraMatrices {
  Eigen::Matrix4f view = Eigen::Matrix4f::Identity();
  Eigen::Matrix4f projection = Eigen::Matrix4f::Identity();
  Eigen::Vector3f eye = Eigen::Vector3f::Zero();  ///< the camera's position, world (for lighting)
};

struct DrawList {
  std::vector<Solid> solids;
  std::vector<TriangleSoup> meshes;
  std::vector<Line> lines;   ///< depth-tested against the solids
  std::vector<Line> on_top;  ///< drawn over everything (what must not hide inside a limb: contact normals)
  std::optional<Floor> floor;
  Colour background{0.62f, 0.70f, 0.78f};
  void clear() {
    solids.clear(), meshes.clear(), lines.clear(), on_top.clear();
    floor.reset();
  }
};

}  // namespace limber::viewer
