// What an observer reads off a state after a step (observers.hpp computes it for every method):
// plain values, in a header that includes no state type.
#pragma once

#include <Eigen/Core>

#include "limber/kernel/model/joint_coordinates.hpp"

namespace limber {

/// The deepest overlap of a state and what overlaps there (every method's limbs measured alike:
/// each limb as the capsule or cylinder collision sees, LimbCollisions, and the ground).
struct Penetration {
  double depth = 0;   ///< m, ≥ 0; 0 when nothing overlaps
  int first = -1;     ///< a Model body index, or bodies + k for ball k; −1 when nothing overlaps
  int second = -1;    ///< the other body or ball, as `first`; −1 when it is the ground or a collider
  int collider = -1;  ///< the Model::colliders index when the other side is one, else −1
};

struct Observation {
  double time = 0;                 ///< s
  /// Joint gaps |x_inboard − x_outboard| relative to the mean length of the two limbs joined
  /// (the outboard limb's for a joint to the world); 0 with shared-particle joints.
  double max_joint_gap = 0, rms_joint_gap = 0;
  /// The joint whose gap is max_joint_gap (−1: none open, or no joints). World::observe() gives
  /// a Model joint index; a method's own observer its compiled Model's, where a serial joint's
  /// axes 1… are joints after the Model's (serial_links.hpp).
  int widest_joint = -1;
  /// Largest relative link stretch | |x_head − x_tail| − L | / L.
  double max_link_stretch = 0;
  Eigen::Vector3d body_centre_of_mass = Eigen::Vector3d::Zero();  ///< of the limbs (not the ball), m
  Eigen::Vector3d linear_momentum = Eigen::Vector3d::Zero();      ///< everything, kg·m/s
  double kinetic_energy = 0;    ///< J; particles: v = (x − x*)/Δt of the last step (pbd) or the state's v (rattle)
  double potential_energy = 0;  ///< J, −Σ m g·x (zero at the origin)
  int islands = 0, islands_sleeping = 0;
  bool body_sleeping = false;   ///< every limb island asleep
  /// The joints' limits and drives (joint_coordinates.hpp, measured alike for every method):
  /// the largest violation of a limit (rad; m for a prismatic range) and the largest distance
  /// from a drive's target, over the joints that have them.
  JointMeasures joints;
  /// The deepest overlap now. World::observe() measures it (a narrow phase over the limbs); the
  /// state observers (observers.hpp), which the World's divergence check reads every step, leave
  /// it empty.
  Penetration penetration;

  double energy() const { return kinetic_energy + potential_energy; }
};

/// What an observation measures. `divergence`: only what check_divergence (divergence.hpp)
/// reads after every step — energy, momentum, the centre of mass, joint gaps and link stretch,
/// each the same bits as `full`'s; the joints' limits and drives (Observation::joints), the
/// islands and sleeping are left at their defaults. Their angles (a twist's atan2, a drive's
/// remainder per axis) cost a humanoid crowd's step more than the rest of the check.
enum class ObservationScope { full, divergence };

}  // namespace limber
