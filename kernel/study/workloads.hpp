// The accuracy studies' workloads: small articulated bodies whose exact motion a reference
// integrator can reach, built so that every method simulates the same mechanical system.
#pragma once

#include <cstdint>

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/scene/scene_file.hpp"

namespace limber::study {

/// How the heavy-end chain starts (at rest, pinned at the origin).
enum class ChainRelease : std::uint8_t {
  /// Planar: link k points 5°·k below the horizontal +x axis — an arc bending down, so the chain
  /// is not released exactly straight. Swings through large angles; its end whips.
  arc,
  /// Three-dimensional and small: the chain hangs down, link k tilted 0.15 rad off −z towards
  /// azimuth 1.3·k rad, so the links swing in different vertical planes.
  small_3d,
};

/// The heavy-end chain of the accuracy studies: 5 massless rods of 0.1 m and point masses of
/// 1, 1, 1, 1, 2 kg at their outer ends, pinned at the origin. Each rod is a capsule (radius
/// 1 mm, for contacts only) whose mass is two point masses at its ends: a joint's mass is shared
/// half and half by the two rods that meet there (the end mass wholly by the last rod, and the
/// first rod carries 0.5 kg at the pin, where it changes nothing), so every method's rigid
/// bodies and the particle method's particles (the scene's method settings: limb_masses "lumps",
/// shared-particle joints; five particles of 1, 1, 1, 1, 2 kg) are the same point-mass system
/// exactly.
/// Sleeping is off; gravity −9.81 m/s² along z.
Scene heavy_end_chain(ChainRelease release);

/// Two uniform rods of 0.5 m and 1 kg (capsules of radius 5 mm) joined end to end, pinned at
/// (0, 0, 1) and released at rest in a straight line `release_angle` rad from the downward
/// vertical, towards +x: π/2 (horizontal, the default) is the double pendulum of the
/// run-time-against-error study, which is chaotic; small angles swing regularly. The particle
/// method (shared-particle joints) needs limb_masses "inertia" to carry a rod's inertia exactly.
Scene double_pendulum(double release_angle = 1.5707963267948966);

}  // namespace limber::study
