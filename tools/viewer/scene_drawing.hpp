// The World, as the viewer shows it: limbs as their shapes, balls, colliders, the ground and the
// overlays (bounding spheres, contacts and normals, joint gaps, the centre of mass and its path,
// push and drag arrows), into a DrawList. Reads the World through its API only, so it shows
// every method alike; contacts are found again here, by the collision world every method shares
// (kernel/geometry/limb_collisions.hpp), the ground and the balls' touches on limbs.
#pragma once

#include <cstdint>
#include <vector>

#include "limber/kernel/geometry/limb_collisions.hpp"
#include "tools/viewer/draw_list.hpp"
#include "tools/viewer/view_state.hpp"

namespace limber::viewer {

/// A point where two shapes touch now, with its normal (unit) and depth (m, ≥ 0).
struct ShownContact {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double depth = 0;
};

/// Turns a view into draw lists, keeping the collision world it needs between frames (rebuilt
/// when the World's Model changes).
class SceneDrawer {
 public:
  /// Fills `list` (cleared first) with `view`'s World now and the overlays it asks for.
  void draw(const ViewState& view, DrawList& list);
  /// The touching shapes now: limb–limb, limb–collider and ball–ball (the collision world at
  /// margin 0), limb–ground and ball–limb.
  const std::vector<ShownContact>& contacts(const World& world);

 private:
  void refresh(const World& world);

  const Model* model_ = nullptr;
  std::size_t bodies_ = 0, balls_ = 0, colliders_ = 0;
  LimbCollisions collisions_;
  std::vector<LimbSegment> segments_;
  std::vector<std::uint8_t> awake_;
  std::vector<LimbContact> found_;
  std::vector<ShownContact> contacts_;
};

/// A colour for a joint gap relative to link length: green at ≤ 1e-4, through yellow at 1e-2,
/// to red at ≥ 1e-1 (log scale).
Colour gap_colour(double relative_gap);

}  // namespace limber::viewer
