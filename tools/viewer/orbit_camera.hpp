// The viewer's camera: it orbits a target point, pans it and zooms toward it (MuJoCo's
// `simulate` and Jolt's Samples move the same way). World frame, +z up, metres and radians;
// pixels have their origin at the top left, y down (as GLFW reports the cursor).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "tools/viewer/draw_list.hpp"

namespace limber::viewer {

/// A ray from the eye through a pixel, world: origin + t·direction for t ≥ 0; direction unit.
struct Ray {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d direction = Eigen::Vector3d::UnitX();
};

struct OrbitCamera {
  Eigen::Vector3d target{0, 0, 0.9};  ///< m: what the camera looks at and orbits
  double yaw = -1.2;                  ///< rad about +z; 0 puts the eye on the +x side of the target
  double pitch = 0.25;                ///< rad above the horizontal, within ±1.5
  double distance = 3.5;              ///< m from the target, in [0.1, 500]
  double fov_y = 0.7854;              ///< rad, vertical field of view (45°)

  /// Turns the eye about the target by a cursor move (pixels).
  void orbit(double dx, double dy);
  /// Moves the target in the view plane so the scene follows a cursor move (pixels) in a
  /// viewport `height` pixels high.
  void pan(double dx, double dy, int height);
  /// Moves the eye toward the target (steps > 0) or away, 12% of the distance per step.
  void zoom(double steps);

  Eigen::Vector3d eye() const;
  /// The view and projection for a width × height viewport; near 0.02 m and far 1000 m.
  CameraMatrices matrices(int width, int height) const;
  /// The ray through pixel (x, y) of a width × height viewport.
  Ray ray(double x, double y, int width, int height) const;
};

}  // namespace limber::viewer
