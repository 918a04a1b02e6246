// Bullet 3's reduced-coordinate articulated body (btMultiBody) on the "heavy-end chain" workload
// that the peer engines (MuJoCo, Bullet, ODE) are compared with limber on:
//   N capsule links 0.1 m long, radius 0.01 m, 1 kg each except the last (2 kg); link 0 pinned to
//   the world at the origin by a ball joint, consecutive links joined end to end by ball joints;
//   released at rest, straight along +x; gravity 9.81 m/s² along −z; no contacts, no damping.
// Build: bench/peers/bullet.cmake (target limber_peer_bullet); this header needs no Bullet headers.
#pragma once

namespace limber::peers {

struct PeerChainResult {
  /// Wall time inside Bullet's stepSimulation only, total / steps taken, s.
  double seconds_per_step = 0;
  /// Largest distance between where the parent and where the child put a joint's pivot (link 0:
  /// the world pin against link 0's end), over every step, m. Reduced coordinates close joints by
  /// construction, so this measures only the rounding in Bullet's link transforms.
  double max_joint_gap = 0;
  /// Kinetic plus gravitational potential energy (z = 0 is the release height), J.
  double final_kinetic_plus_potential = 0, initial_kinetic_plus_potential = 0;
  /// False once a link position or joint velocity is NaN or infinite; stepping stops there. (Bullet
  /// has no silent reset, unlike MuJoCo, so non-finite state is the only failure to detect.)
  bool finite = true;
};

/// Runs `steps` steps of `time_step` seconds (one Bullet step each, no substeps) on a chain of
/// `links` links. Bullet clamps every joint-velocity coordinate to ±100 rad/s by default;
/// `raise_velocity_clamp` lifts that to ±10⁴ rad/s. Throws std::invalid_argument for links < 1,
/// steps < 0 or a time_step Bullet would round to zero (≤ SIMD_EPSILON, 1.2e-7 s in single
/// precision). Memory is O(links²): Bullet sizes a buffer by (3 links)² scalars.
PeerChainResult run_bullet_multibody_chain(int links, double time_step, int steps, bool raise_velocity_clamp);

/// Whether this was compiled against Bullet's double-precision build (btScalar = double).
bool bullet_uses_double_precision();

}  // namespace limber::peers
