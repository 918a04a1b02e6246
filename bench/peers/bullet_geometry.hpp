// What the two Bullet peers (bullet_chain.cpp, bullet_rigid_chain.cpp) share: a link's inertia
// and frame, and world points in double so a joint gap adds no rounding of its own to Bullet's.
// Needs Bullet's headers (bench/peers/bullet.cmake).
#pragma once

#include <array>
#include <cmath>

#include <LinearMath/btTransform.h>

#include "bench/peers/peer_chain.hpp"

namespace limber::peers {

/// Principal moments about the link's centre, link frame (x along the link), kg m²: a solid
/// cylinder of the link's radius and length, as every peer uses (peer_chain.hpp).
inline btVector3 cylinder_inertia(double mass) {
  using namespace heavy_end_chain;
  const double axial = mass * link_radius * link_radius / 2;
  const double transverse = mass * (3 * link_radius * link_radius + link_length * link_length) / 12;
  return btVector3(btScalar(axial), btScalar(transverse), btScalar(transverse));
}

/// From a link's centre to its outboard end, link frame; its inboard end (the pivot) is at minus this.
inline btVector3 half_link() { return btVector3(btScalar(heavy_end_chain::link_length / 2), 0, 0); }

using WorldPoint = std::array<double, 3>;  ///< m

/// `local` (link frame) in the world, in double.
inline WorldPoint to_world(const btTransform& frame, const btVector3& local) {
  WorldPoint point;
  for (int row = 0; row < 3; ++row) {
    point[row] = frame.getOrigin()[row];
    for (int column = 0; column < 3; ++column) point[row] += double(frame.getBasis()[row][column]) * local[column];
  }
  return point;
}

inline double distance(const WorldPoint& a, const WorldPoint& b) { return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]); }

}  // namespace limber::peers
