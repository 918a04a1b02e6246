// The rigid-body scene every rigid-body method shares (springs, Lagrange multipliers,
// Featherstone): limbs and the ball as rigid bodies with their shapes, islands, the planes and
// static colliders they touch, and the contacts of the last step. A method's state derives from it and adds its
// joints' representation.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/kernel/geometry/limb_collisions.hpp"
#include "limber/kernel/geometry/geometry.hpp"
#include "limber/kernel/model/island_sleep.hpp"
#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/step_status.hpp"
#include "limber/kernel/rigid/rigid_integration.hpp"
#include "limber/layouts/bodies/rigid_body_buffer.hpp"

namespace limber {

/// The limbs' geometry for contacts, per body (the balls are the last bodies).
struct RigidShapes {
  std::vector<ShapeType> shape;
  /// m (a ball: length 0, its radius; a box or an ellipsoid: length 0, its bounding_radius, so
  /// every bound read from them holds)
  std::vector<double> length, radius;
  /// A box's or ellipsoid's Shape::half_extents (m) and Shape::rotation (its frame in the Model's
  /// body frame); zero and identity for the other shapes.
  std::vector<Eigen::Vector3d> half_extents;
  std::vector<Eigen::Quaterniond> shape_rotation;
  std::vector<Eigen::Vector3d> centre_offset;   ///< centre of mass in the Model's body frame (shape-centred), m
  /// Rotation from the rigid body's frame (its principal axes) to the Model's body frame: a
  /// Model body-frame point p is at x + q·principal_frame⁻¹·(p − centre_offset) in world.
  std::vector<Eigen::Quaterniond> principal_frame;
  std::vector<bool> is_ball;
  std::vector<double> restitution;              ///< a ball's, [0, 1]; 0 for a limb
};

/// Bodies joined by joints, simulated, put to sleep and woken together (thesis 4.5.3).
struct RigidIsland : IslandSleep {
  std::vector<std::uint32_t> bodies;
};

/// The farthest a body reaches for speculative contacts in a step (RigidScene::speculative_time), m.
inline constexpr double kMostSpeculativeReach = 0.05;

/// A contact found this step: body `a` touches body `b` (−1: a plane, immovable), normal from b
/// to a, depth ≥ 0 (m; with RigidScene::speculative_time, a gap's is negative).
struct RigidContact {
  std::int32_t a = 0, b = -1;
  Eigen::Vector3d point = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::UnitZ();
  double depth = 0;
  double restitution = 0, friction = 0;
  double approach_speed = 0;  ///< normal speed towards each other before the impulses, m/s, ≥ 0
};

/// The approach speed below which a contact does not bounce, m/s: 2|g|Δt, what gravity alone
/// gives a resting contact over a step or two, so resting contacts stay at rest.
inline double resting_approach(const Settings& settings, double dt) { return 2 * settings.gravity.norm() * dt; }

/// Records a contact's approach (m/s, the normal speed towards each other before any impulse)
/// in approach_speed; below resting_approach it bounces with e = 0. Every rigid method's contacts.
inline void record_approach(RigidContact& contact, double approach, const Settings& settings, double dt) {
  if (approach < resting_approach(settings, dt)) contact.restitution = 0;
  contact.approach_speed = std::max(approach, 0.0);
}

/// How far the push-out moves a contact's bodies apart along its normal, m: its depth less the
/// separation it may keep (allowed_separation, with the separation at the step's start taken as
/// −depth + approach·Δt). ≤ 0: nothing to push.
inline double push_out_distance(const RigidContact& contact, const Settings& settings, double dt) {
  return contact.depth + allowed_separation(contact.approach_speed * dt - contact.depth, settings.contact_recovery_speed * dt);
}

/// When a method solves its contacts before the move (speculative contacts found at the step's
/// start), a contact's depth up to this is left to rest in, m: the velocity solve keeps it from
/// growing, and pushing out its round-off every step would cost a re-projection every step.
inline constexpr double kRestingSlop = 1e-4;

/// The normal speed a contact's impulses hold it to, m/s (relative, along its normal, ≥ target):
/// a contact still apart by a gap (depth < 0: found with RigidScene::speculative_time) may close
/// it within the next move and no more (Catto's speculative contacts), else it stops; a bouncing
/// one (e > 0) leaves at e times its approach, from where it is. Found after the move
/// (`before_move` false), a bouncing contact bounces only when it touches or its approach closes
/// its gap within the step: bounced across the gap, two balls passing 2 cm apart turned (each
/// left at 4.0 m/s of its 5 and 2.8 m/s sideways). Before the move every bouncing contact still
/// bounces from where it is: holding those too to their gaps left the ragdoll stack moving at
/// 0.62 m/s after 3 s under Lagrange.
inline double contact_target_speed(const RigidContact& contact, bool before_move, double dt) {
  const double gap = std::max(-contact.depth, 0.0);
  if (contact.restitution > 0 && (before_move || gap <= contact.approach_speed * dt)) return contact.restitution * contact.approach_speed;
  return -gap / dt;
}

/// How far the push-out moves a contact apart when the contacts are solved before the move, m:
/// its depth is the last steps' (found at the step's start); once past twice kRestingSlop it is
/// pushed back to kRestingSlop, by at most push_out_distance (a step's approach in full and an
/// older overlap at the recovery speed, as after the move). ≤ 0: nothing to push.
inline double push_out_before_move(const RigidContact& contact, const Settings& settings, double dt) {
  return contact.depth > 2 * kRestingSlop ? std::min(contact.depth - kRestingSlop, push_out_distance(contact, settings, dt)) : 0.0;
}

/// The Model's joints as anchor pairs on the rigid bodies, one per joint, one array per field:
/// a joint's separation is d = p_inboard − p_outboard (m). A world anchor has body −1 and its
/// point in world coordinates; a body anchor is in the rigid body's (principal) frame, relative
/// to its centre of mass (m). Every rigid-body method starts from these (springs pull d to 0,
/// Lagrange constrains it to 0).
struct JointAnchors {
  std::vector<std::int32_t> inboard, outboard;
  std::vector<Eigen::Vector3d> inboard_anchor, outboard_anchor;
  /// What the joint gap is measured against, as in the Verlet method: the mean length of the
  /// two limbs (the outboard limb's for a joint to the world), m.
  std::vector<double> reference_length;
  std::size_t size() const { return inboard.size(); }
};

/// The shared part of a rigid-body method's state.
struct RigidScene {
  RigidBodyBuffer bodies;
  RigidShapes shapes;
  std::vector<RigidIsland> islands;
  std::vector<std::uint32_t> island_of_body;
  std::vector<Plane> planes;
  std::uint32_t ball_begin = 0;  ///< the balls are bodies ball_begin… (Model::balls, in order), after the limbs
  Settings settings;
  int contact_iterations = 8;  ///< passes of sequential impulses over a step's contacts
  /// s, ≥ 0: contacts are also found across a gap the two bodies may close in this time, with a
  /// negative depth (speculative contacts, for a method that solves them before the bodies move):
  /// each body reaches t·(|v| + |ω|·(its farthest point from its centre of mass) + |g|·t), at
  /// most kMostSpeculativeReach, its velocity the one detection sees. 0: overlaps only.
  double speculative_time = 0;

  double time = 0;                     ///< s
  /// Per body: its centre of mass at the start of the step being taken, m, world
  /// (remember_step_start): the start of the path the ball is swept along (rigid_contacts.hpp).
  std::vector<Eigen::Vector3d> step_start_position;
  std::vector<RigidContact> contacts;  ///< of the last step
  bool ball_touching = false;          ///< a ball touched a limb in the last step (overlapping, or a speculative contact it closes)
  std::vector<Eigen::Vector3d> velocity, angular_velocity;  ///< scratch: v and ω of the state being evaluated, world
  /// Limbs against limbs and against the static colliders (kernel/geometry/limb_collisions.hpp),
  /// and its per-step buffers, sized only when it is active (a scene without either pays nothing).
  LimbCollisions collisions;
  std::vector<LimbSegment> limb_segments;  ///< per body (the balls last): the Model's head → tail now
  std::vector<std::uint8_t> limb_awake;    ///< per body: its island is awake
  std::vector<LimbContact> limb_contacts;  ///< the last detection's, before they became `contacts`
  /// Loads applied from outside over the next step, per body, world frame: a force at the
  /// centre of mass (N) and a torque (N·m). Every method's step adds them to its own forces
  /// (accumulate_applied_forces; Featherstone through its joint forces) and zeroes them at its end.
  std::vector<Eigen::Vector3d> applied_force, applied_torque;
};

/// The rigid scene of `model`:
/// - each limb becomes a rigid body at its centre of mass, with the mass properties of
///   body_mass_properties() (kernel/mass/): uniform over its shape, or its point masses; its
///   frame is on its principal axes (diagonal inertia), and principal moments below 10⁻⁶ of the
///   largest (a limb of zero radius about its axis) are raised to that floor, which only keeps
///   M invertible: nothing but a twist (an angular joint row, a drive) acts about such a limb's
///   axis, and the integrators keep the momentum about it (rotate_free_body, detail::advance in
///   rigid_integration.hpp), so thin-rod stability does not hang on the floor's value (measured
///   the same from 10⁻⁹ to 10⁻²; a floor of 10⁻² alone still diverged: kernel/lagrange/README.md);
/// - each ball becomes a solid sphere body, after the limbs;
/// - bodies joined by joints (not through the world) form islands, which start asleep when the
///   scene asks (Settings::sleep.start_asleep) and they are at rest; each ball is its own;
/// - the ground and the bounds' walls become planes;
/// - limb pairs and static colliders go to `collisions` (LimbCollisions of the Model).
/// Throws ModelError when the model is invalid, or a limb's mass properties cannot be computed
/// (a capsule whose volume under- or overflows) or give no rotational inertia (its mass at one
/// point), naming the limb and the field.
RigidScene compile_rigid_scene(const Model& model);

/// The anchors of `model`'s joints on `scene`'s bodies.
JointAnchors joint_anchors(const RigidScene& scene, const Model& model);

/// Joint j's separation d = p_inboard − p_outboard at state y, m.
Eigen::Vector3d joint_separation(const JointAnchors& joints, const RigidBodyState& y, std::size_t j);

/// World position of Model body `body`'s body-frame point `local_point` (Model frame: the
/// shape's centre), m.
Eigen::Vector3d world_point(const RigidScene& scene, std::size_t body, const Eigen::Vector3d& local_point);

/// A Model body-frame point (shape-centred) in the rigid body's frame, relative to its centre of
/// mass, m: what the methods keep as a joint's anchor.
Eigen::Vector3d body_anchor(const RigidScene& scene, std::size_t body, const Eigen::Vector3d& local_point);

/// Fills scene.velocity / scene.angular_velocity (v = P/m, ω = I_world⁻¹ L) for state y.
void body_velocities(RigidScene& scene, const RigidBodyState& y);

/// Adds the applied forces at state y for every awake body: gravity m·g; Settings::damping as
/// −damping·m·v and −damping·I·ω; Settings::drag in the limb's own frame (z: its axis; thesis
/// 2.1.5, 2.1.6); scene.applied_force and applied_torque. Fills scene.velocity /
/// angular_velocity for y first.
void accumulate_applied_forces(RigidScene& scene, const RigidBodyState& y, RigidForces& forces);

/// Zeroes scene.applied_force and applied_torque: the end of a step.
void clear_applied_loads(RigidScene& scene);

/// After a step of length dt: reports divergence (non-finite, or a surface point faster than
/// settings.divergence_speed) and puts islands whose bodies' fastest surface points all stayed
/// below settings.sleep.speed_threshold for settings.sleep.time_to_sleep to sleep (zeroing P, L).
StepStatus update_sleep(RigidScene& scene, double dt);
/// The same from scene.velocity and scene.angular_velocity, which the caller has filled for the
/// awake bodies' state now (Featherstone's mirror has them at hand); update_sleep finds them
/// from the momenta first.
StepStatus update_sleep_from_velocities(RigidScene& scene, double dt);

/// Puts island k to sleep at rest (its bodies' momenta zeroed, so it wakes at rest): what
/// falling asleep does, and what an engine asks for with World::sleep.
void rest_island(RigidScene& scene, std::size_t k);

}  // namespace limber
