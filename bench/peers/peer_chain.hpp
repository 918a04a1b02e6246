// Other engines (Bullet 3.24, ODE 0.16, MuJoCo 2.2.2) on the "heavy-end chain" that limber is
// compared with them on (bench/chains.md, "The heavy-end chain"):
//   N links 0.1 m long, radius 0.01 m, 1 kg each except the last (2 kg); link 0 pinned to the
//   world at the origin by a ball joint, consecutive links joined end to end by ball joints;
//   released at rest, straight along +x; gravity 9.81 m/s² along −z; no contacts, no damping,
//   no sleeping.
// Every peer gives each link the same mass properties: a solid cylinder of the link's radius and
// length, centre at the link's middle (the workload names a capsule but not its inertia; a capsule
// whose caps lie within the 0.1 m would have a 12% smaller transverse moment).
//
// One function per engine and method, each compiled only where its library is found
// (bench/peers/peers.cmake: LIMBER_HAVE_BULLET, LIMBER_HAVE_ODE, LIMBER_HAVE_MUJOCO). This
// header needs none of their headers. Each throws std::invalid_argument for links < 1, steps < 0
// or a time step the engine cannot take, and times only the engine's own step call.
#pragma once

#include <algorithm>
#include <chrono>

namespace limber::peers {

/// The workload's numbers, shared by every peer.
namespace heavy_end_chain {
constexpr double link_length = 0.1;     ///< m
constexpr double link_radius = 0.01;    ///< m
constexpr double link_mass = 1.0;       ///< kg
constexpr double last_link_mass = 2.0;  ///< kg, the heavy end
constexpr double gravity = 9.81;        ///< m/s², along −z
}  // namespace heavy_end_chain

struct PeerChainResult {
  /// Wall time inside the engine's step call only, total / steps taken, s.
  double seconds_per_step = 0;
  /// Largest distance between where the parent and where the child put a joint's pivot (link 0:
  /// the world pin against link 0's inboard end), over every step, m. Reduced coordinates
  /// (btMultiBody, MuJoCo) close joints by construction, so there it measures only rounding.
  double max_joint_gap = 0;
  /// Kinetic plus gravitational potential energy (z = 0 is the release height), J; the final one
  /// is NaN after a non-finite state or an engine's reset.
  double final_kinetic_plus_potential = 0, initial_kinetic_plus_potential = 0;
  /// False once a link position or velocity is NaN or infinite, or once the engine reported that
  /// it reset a diverged state (MuJoCo's bad-acceleration warning); stepping stops there.
  bool finite = true;
  /// Steps taken before stopping (all of them unless `finite` turned false).
  int steps_taken = 0;
  /// Steps after which some link turned faster than the engine lets an orientation turn in one
  /// step, so the engine silently turned it less than its angular velocity says (Bullet's rigid
  /// bodies: π/4 rad per step, btTransformUtil::integrateTransform). 0 for engines without one.
  int steps_with_clamped_rotation = 0;
};

// Bullet 3 --------------------------------------------------------------------------------------

/// Bullet's reduced-coordinate articulated body (btMultiBody, spherical joints, one Bullet step
/// each, no substeps). Bullet clamps every joint-velocity coordinate to ±100 rad/s by default;
/// `raise_velocity_clamp` lifts that to ±10⁴ rad/s. Time steps ≤ SIMD_EPSILON (1.2e-7 s in single
/// precision) are refused: Bullet would silently skip them. Memory is O(links²): Bullet sizes a
/// buffer by (3 links)² scalars (3.5 GB at 10⁴ links).
PeerChainResult run_bullet_multibody_chain(int links, double time_step, int steps, bool raise_velocity_clamp);

/// Bullet's maximal-coordinate rigid bodies (btRigidBody, no collision pairs) joined by
/// btPoint2PointConstraint (link 0 to a world point), solved by btSequentialImpulseConstraintSolver
/// with `solver_iterations` sweeps per step (Bullet's default 10; ≥ 1) and Bullet's other defaults
/// (joint ERP 0.2, CFM 0, warm starting, implicit gyroscopic term). Bullet turns a body's
/// orientation by at most π/4 rad per step whatever its angular velocity: see
/// PeerChainResult::steps_with_clamped_rotation.
PeerChainResult run_bullet_rigid_chain(int links, double time_step, int steps, int solver_iterations);

/// Whether this was compiled against Bullet's double-precision build (btScalar = double).
bool bullet_uses_double_precision();

// ODE 0.16 --------------------------------------------------------------------------------------

enum class OdeStepper {
  world_step,  ///< dWorldStep: the "big matrix" method, a dense LCP over every joint row, O(rows³)
  quick_step,  ///< dWorldQuickStep: projected Gauss-Seidel (SOR, ODE's ω = 1.3), O(rows · iterations)
};

/// ODE's rigid bodies joined by dBallJoint (link 0 to the static world), no collision space,
/// ODE's defaults otherwise (ERP 0.2, CFM 1e-10 in double precision, gyroscopic term on, no
/// angular-speed limit, auto-disable off). `quick_step_iterations` (≥ 1) is used by quick_step
/// only. Time steps must be positive and finite.
PeerChainResult run_ode_chain(int links, double time_step, int steps, OdeStepper stepper, int quick_step_iterations);

/// Whether this was compiled against ODE's double-precision build (dReal = double).
bool ode_uses_double_precision();

// MuJoCo 2.2.2 ----------------------------------------------------------------------------------

enum class MujocoIntegrator {
  euler,  ///< MuJoCo's default: semi-implicit Euler (velocity first, then position)
  rk4,    ///< classical Runge-Kutta, four mj_forward evaluations per step
};

/// MuJoCo on the chain written as MJCF (nested <body> elements with ball joints, contacts
/// disabled), one mj_step per step. MuJoCo 2.2.2's XML parser refuses elements nested deeper than
/// 100 levels, so the chain is split into <include>d files of at most 64 links each, held in a
/// virtual file system (MuJoCo merges an included file after parsing it on its own). MuJoCo
/// resets the state to the initial one when an acceleration, velocity or position is NaN or
/// beyond 1e10, and only counts a warning: such a run is reported with finite = false. Cost:
/// MuJoCo factors the joint-space inertia as a dense matrix along a chain, O(links³) per step.
PeerChainResult run_mujoco_chain(int links, double time_step, int steps, MujocoIntegrator integrator);

// For the peer implementations -------------------------------------------------------------------

/// Steps `chain` `steps` times of `time_step` s, or until its state is not finite, timing only
/// chain.step(time_step). `Chain` has step(double), state_is_finite(), largest_joint_gap() (m)
/// and kinetic_plus_potential() (J). `after_step(result)` runs after each timed step, before the
/// state is measured (to refresh derived transforms, or count a clamp).
template <typename Chain, typename AfterStep>
PeerChainResult measure_chain(Chain& chain, double time_step, int steps, AfterStep after_step) {
  PeerChainResult result;
  result.initial_kinetic_plus_potential = chain.kinetic_plus_potential();
  std::chrono::steady_clock::duration stepping{};
  while (result.steps_taken < steps && result.finite) {
    const auto start = std::chrono::steady_clock::now();
    chain.step(time_step);
    stepping += std::chrono::steady_clock::now() - start;
    ++result.steps_taken;
    after_step(result);
    result.finite = chain.state_is_finite();
    result.max_joint_gap = std::max(result.max_joint_gap, chain.largest_joint_gap());
  }
  result.final_kinetic_plus_potential = chain.kinetic_plus_potential();
  if (result.steps_taken > 0) result.seconds_per_step = std::chrono::duration<double>(stepping).count() / result.steps_taken;
  return result;
}

}  // namespace limber::peers
