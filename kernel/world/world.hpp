// The World: what an engine drives. One Model under one method, stepped, read and pushed through
// one set of calls, whatever the method (Box2D v3's world and body functions, Jolt's
// BodyInterface and MuJoCo's mjData fields are the models).
//
//   limber::World world(limber::load_scene_file("ragdoll.json"), limber::Method::featherstone);
//   const limber::BodyId head = world.body("head");
//   world.apply_impulse(head, {2, 0, 0}, world.pose(head).position);
//   world.step(1.0 / 60);
//   const limber::Pose pose = world.pose(head);   // position and orientation of the body frame
//
// The World owns no physics: every call maps onto the method's state (kernel/verlet, springs,
// lagrange, featherstone), and what a method cannot do is refused with a WorldError naming the
// method and the call, never done silently wrong. Loads (forces, impulses, torques, joint
// torques, kinematic targets) act over the next step and are then gone. Structural edits (add or
// remove a body, a joint, a collider or a ball, pin or unpin) recompile the state from the edited
// Model and carry every surviving body's and ball's state across bit for bit (positions,
// velocities; islands wake).
//
// The World is the one step path: the command line, the viewer and the studies step through it,
// and what follows a method's step (the shared divergence check, drives released on impact,
// the particle limbs' frames) happens here alone. The Model stays the description it was given
// (and edited by the structural calls): the drives set since, and the held points' moved anchors,
// are the World's own state, which a recompile reads.
//
// Frames. A body's pose is that of its Model body frame: origin at the centre of its shape,
// z along its axis (tail → head). A particle limb has no spin about its axis, so its
// orientation's roll is carried by parallel transport: each step the frame turns by the
// smallest rotation that takes the old axis to the new one — continuous in time.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/kernel/metrics/observation.hpp"
#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/options.hpp"
#include "limber/kernel/model/step_status.hpp"
#include "limber/kernel/scene/scene_file.hpp"

namespace limber {

struct LimbSegment;    // kernel/geometry/limb_collisions.hpp
struct WorldInternals;  // kernel/world/world_internals.hpp: the method's state

/// A call the world's method cannot do, or a bad argument (an unknown handle, a non-finite
/// vector). what() is one line naming the call and, where it is the method's limit, the method.
class WorldError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Handles (Box2D v3's ids): a slot of the World's handle table, the slot's generation, and the
/// issuing World's serial. Stable across structural edits; a removed thing's handle is refused
/// thereafter (its slot has moved on a generation), and another World refuses every one of them
/// with a WorldError instead of addressing a thing of its own.
template <typename Tag>
struct Handle {
  std::uint32_t slot = ~0u;
  std::uint32_t generation = 0;
  std::uint32_t world = 0;  ///< the issuing World's serial (0: none)
  friend bool operator==(Handle, Handle) = default;
};
using BodyId = Handle<struct BodyTag>;
using JointId = Handle<struct JointTag>;
/// Static level geometry (Model::colliders; World::add_collider).
using ColliderId = Handle<struct ColliderTag>;
/// A ball (Model::balls; World::add_ball).
using BallId = Handle<struct BallTag>;
/// A point of a body held to the world (World::pin): a spherical joint to the world.
using PinId = Handle<struct PinTag>;

class World {
 public:
  /// Compiles `model` under `options.method`. Throws ModelError when the model is invalid or the
  /// method cannot represent it (the message names the part), std::invalid_argument for options
  /// that do not go together.
  explicit World(Model model, WorldOptions options = {});
  /// A loaded scene under `method`, with the method settings the scene gives
  /// (world_options(method, scene.methods), kernel/model/options.hpp).
  World(const Scene& scene, Method method);
  ~World();
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;

  /// One step of dt seconds (the Model's time step without an argument), of any length from the
  /// method's minimum (kMinimumTimeStep, 10⁻⁹ s; float particles: substeps of 1 µs) up: a short
  /// step among long ones keeps the energy. Never throws; a bad dt (shorter, subnormal, not
  /// finite: invalid_time_step, nothing done) or a divergence is the status: the method's own
  /// guard (a non-finite position, a point past Settings::divergence_speed), then the checks
  /// every method shares (metrics/divergence.hpp:
  /// any non-finite number, energy gained past its bound, a joint come apart), measured against
  /// the World's start or its last structural edit or teleport.
  StepStatus step(double dt);
  StepStatus step() { return step(model_.settings.time_step); }
  /// The last step's report, whatever the method: status, contacts, the relaxation's sweeps and
  /// stop (particles), the linear solver's (springs, Lagrange), constraint errors. Its status is
  /// the World's verdict (step()'s return); the method's own report is left as it wrote it.
  const StepReport& last_report() const;

  double time() const;
  const Model& model() const { return model_; }
  Method method() const { return options_.method; }
  /// What the state is now, measured alike for every method (kernel/metrics/observation.hpp):
  /// time, joint gaps, stretch, energy, momentum, limits, sleeping, and the deepest penetration,
  /// which costs a narrow phase over the limbs (the first call after a compile builds its pairs).
  /// Not to be called from two threads at once: the penetration's buffers are the World's.
  Observation observe() const;
  /// Each Model body's limb as collision sees it now (head, tail, radius; LimbSegment), then each
  /// ball's (head = tail = its centre), into `out`: what a debug drawer or a query of one's own
  /// reads, whatever the method.
  void segments(std::vector<LimbSegment>& out) const;

  // --- Handles ---
  /// The body or joint called `name`. Throws WorldError when there is none.
  BodyId body(std::string_view name) const;
  JointId joint(std::string_view name) const;
  std::vector<BodyId> bodies() const;  ///< every body, in Model order
  const Body& body_description(BodyId body) const;  ///< its Model entry (initial pose, shape, mass)

  // --- Reading ---
  Pose pose(BodyId body) const;
  Motion motion(BodyId body) const;
  /// Every body's pose (motion) into `out`, in Model order (bodies()), in one call: the same
  /// values pose() (motion()) gives one at a time, as an engine's render arrays take them
  /// (MuJoCo's xpos and xquat). Throws WorldError, writing nothing, when out.size() is not the
  /// number of bodies.
  void poses(std::span<Pose> out) const;
  void motions(std::span<Motion> out) const;

  // --- Loads over the next step (each wakes the body's island) ---
  /// A force (N) at a world point (m). Particle limbs take what particles can: the force at the
  /// limb's centre of mass and the torque about it across the axis (none about the axis).
  void apply_force(BodyId body, const Eigen::Vector3d& force, const Eigen::Vector3d& world_point);
  /// An impulse (N·s) at a world point: the force impulse/dt over the next step of dt, which
  /// changes the body's momentum by exactly the impulse (with no other force).
  void apply_impulse(BodyId body, const Eigen::Vector3d& impulse, const Eigen::Vector3d& world_point);
  /// A torque (N·m) about the body's centre of mass (particle limbs: its part across the axis).
  void apply_torque(BodyId body, const Eigen::Vector3d& torque);
  /// A joint's actuation torque (N·m, world): +torque on the outboard body, −torque on the
  /// inboard one (none on the world).
  void apply_joint_torque(JointId joint, const Eigen::Vector3d& torque);

  // --- Drives (Joint::drive: a PD pull toward a target pose; thesis 5.2's blend of animation
  // and simulation) ---
  /// Sets the joint's drive from the next step on: new gains (stiffness 0 and damping 0 go limp)
  /// or a new target each frame to track a key-framed pose. Cheap when the joint already had a
  /// drive; giving a joint its first drive, or removing one (nullopt), recompiles. Throws
  /// WorldError on a bad value or a joint type without drives.
  void set_joint_drive(JointId joint, const std::optional<JointDrive>& drive);
  /// The actuators' controls, one per Model::actuators entry in its order: from each next step
  /// on, each actuator's joint gets its generalized force at the state the step starts from
  /// (model.hpp's actuator_force: a motor's gear × control, a position or velocity servo's pull;
  /// Featherstone's and Lagrange's servos at the state it ends with, as their drives), until set
  /// again; 0 until the first call. Throws WorldError when the count is not the actuators' or a
  /// control is not finite (nothing changes).
  void set_controls(std::span<const double> controls);
  /// The controls as set (before clamping), Model::actuators order.
  std::span<const double> controls() const;
  // Joint space (MuJoCo's qpos, qvel, mj_fullM, qfrc_bias, qfrc_passive + qfrc_actuator,
  // mj_inverse), in the layout of kernel/featherstone/joint_space.hpp: walking the bodies in
  // order, a floating body's 7 positions (centre of mass, quaternion w x y z) and 6 velocities
  // (ω, v of the centre, body frame), then each joint whose outboard it is (an angle or slide, a
  // relative quaternion, a serial joint's axes). For a Model read from MJCF, MuJoCo's order. Only
  // reduced coordinates have them: the other methods refuse each call by name (WorldError).
  /// Per velocity coordinate: its name ("torso.wx", "knee", "hip_y").
  std::vector<std::string> joint_space_names() const;
  /// Per position coordinate: its name ("torso.x", "torso.qw", "knee", "shoulder.qx").
  std::vector<std::string> joint_position_names() const;
  Eigen::VectorXd joint_positions() const;   ///< nq
  Eigen::VectorXd joint_velocities() const;  ///< nv
  /// Sets every coordinate and rate (sizes nq, nv; quaternions normalized); the bodies follow and
  /// every island wakes. Throws WorldError on a wrong size or a non-finite value (nothing changes).
  void set_joint_state(const Eigen::VectorXd& positions, const Eigen::VectorXd& velocities);
  /// M(q), nv × nv, kg·m² / kg, with the joints' armature.
  Eigen::MatrixXd joint_mass_matrix() const;
  /// C(q, v): gravity, Coriolis and centrifugal forces, nv (τ = M v̇ + C).
  Eigen::VectorXd joint_bias_forces() const;
  /// The joints' springs and dampers (explicit) and the actuators at the current controls, nv.
  Eigen::VectorXd joint_passive_forces() const;
  /// v̇ = M⁻¹(τ − C) for joint forces τ (nv): no contacts, limits, springs or motors.
  Eigen::VectorXd joint_accelerations(const Eigen::VectorXd& forces) const;
  /// τ = M v̇ + C for accelerations v̇ (nv).
  Eigen::VectorXd inverse_dynamics(const Eigen::VectorXd& accelerations) const;
  /// What each joint transmits for accelerations v̇ (nv; e.g. joint_accelerations(τ)), in
  /// Model::joints order: the force and torque (about its outboard anchor) the inboard body
  /// exerts on the outboard body, world frame (model.hpp's JointReaction; MuJoCo's cfrc_int, by
  /// recursive Newton–Euler). The joint's own force along its axes is in it; contact forces are
  /// not taken, so it is a body out of contact's.
  std::vector<JointReaction> joint_reactions(const Eigen::VectorXd& accelerations) const;

  /// The joint's drive now: the Model's, or the last set_joint_drive's, limp once
  /// Settings::release_drives_on_impact has released it.
  std::optional<JointDrive> joint_drive(JointId joint) const;
  /// Whether a ball's impact has made the drives limp (Settings::release_drives_on_impact).
  bool drives_released() const { return drives_released_; }

  // --- Held points ---
  /// Holds the body's point `local_point` (its Model body frame, m) where it is now: a spherical
  /// joint to the world, added by recompiling. The particle method holds only a limb's head or
  /// tail (its particles; ModelError otherwise).
  PinId pin(BodyId body, const Eigen::Vector3d& local_point);
  void unpin(PinId pin);
  /// A kinematic target for the next step (a rope in a moving hand). Particles: the held point
  /// moves to `world_target` along a straight path at constant velocity, exactly. Springs and
  /// Lagrange: the joint's world anchor jumps to `world_target` before the step, and the body
  /// follows through the joint.
  /// Featherstone: refused (a moving world anchor is not a joint of its tree).
  void move_pin(PinId pin, const Eigen::Vector3d& world_target);
  Eigen::Vector3d pin_position(PinId pin) const;  ///< where the held point's world anchor is, m

  // --- Sleeping ---
  void wake(BodyId body);       ///< wakes the body's island
  void wake_all();
  /// Puts the body's island to sleep now, at rest (its velocities zeroed), as Box2D's
  /// b2Body_SetAwake(false); a contact, a load or wake() wakes it.
  void sleep(BodyId body);
  bool sleeping(BodyId body) const;

  // --- Teleport ---
  /// Sets the body's pose and motion. The orientation must be a unit quaternion to within 10⁻³
  /// (it is normalized); a position, velocity or orientation that is not finite, or an
  /// orientation far from unit (a zero quaternion), is refused with a WorldError and nothing
  /// changes. Featherstone: only a body that is its tree's floating root (its coordinates are its
  /// own); others are refused.
  void teleport(BodyId body, const Pose& pose, const Motion& motion);

  // --- Structure (each recompiles and carries every surviving body's state) ---
  BodyId add_body(const Body& body);
  JointId add_joint(const Joint& joint);  ///< inboard/outboard: Model indices of bodies(), or kWorld
  void remove_body(BodyId body);         ///< and its joints
  void remove_joint(JointId joint);
  /// Adds every body, joint and gear of `other` (another ragdoll; append_model), names prefixed
  /// with `prefix`, moved by `offset` (m). Returns the new bodies' handles in `other`'s order.
  std::vector<BodyId> add_model(const Model& other, std::string_view prefix, const Eigen::Vector3d& offset = Eigen::Vector3d::Zero());
  /// Adds static level geometry (a wall, a ramp, a mesh; Model::colliders) from the next step
  /// on. Throws ModelError naming the field ("colliders[3].radius: ...") when it is invalid,
  /// and nothing changes. A collider that starts inside a limb pushes it out at
  /// Settings::contact_recovery_speed, as any initial penetration.
  ColliderId add_collider(const StaticCollider& collider);
  void remove_collider(ColliderId collider);
  /// The collider called `name`. Throws WorldError when there is none.
  ColliderId collider(std::string_view name) const;

  /// Throws a ball (a projectile: Model::balls) into the world from the next step on; every
  /// body and ball keeps its state. Throws ModelError naming the field ("balls[2].mass: ...")
  /// when it is invalid, and nothing changes.
  BallId add_ball(const Ball& ball);
  void remove_ball(BallId ball);
  std::vector<BallId> balls() const;  ///< every ball, in Model order
  BallMotion ball(BallId ball) const;

  /// The Model index of a handle (for the state's own arrays); throws WorldError when removed.
  std::size_t index(BodyId body) const;
  std::size_t index(JointId joint) const;
  std::size_t index(ColliderId collider) const;
  std::size_t index(BallId ball) const;

  /// The method's state and the World's divergence bounds, for what the World does not wrap
  /// (observers, counters): limber's own tools read them through
  /// kernel/world/world_internals.hpp, which includes the whole kernel.
  const WorldInternals& internals() const { return *internals_; }

 private:
  void reset_loads();
  void add_at_point(BodyId body, const Eigen::Vector3d& amount, const Eigen::Vector3d& world_point, std::vector<Eigen::Vector3d>& linear,
                    std::vector<Eigen::Vector3d>& angular);
  // joint_slots: each edited joint's handle slot (kNewJoint: added by this edit); old_ball_of_new:
  // which old ball each new one continues (−1: new), nullopt: all, in order.
  void recompile(const Model& edited, const std::vector<std::int64_t>& old_body_of_new, const std::vector<std::uint32_t>& joint_slots,
                 std::optional<std::vector<std::int64_t>> old_ball_of_new = std::nullopt);
  void keep_joints(const std::vector<char>& kept, Model edited, const std::vector<std::int64_t>& old_body_of_new);
  std::size_t index(PinId pin, std::string_view call) const;
  // `edited` as the method compiles it: the World's drives and held anchors over the Model's.
  Model as_compiled(Model edited, const std::vector<std::uint32_t>& joint_slots) const;
  std::optional<JointDrive> current_drive(std::size_t joint) const;
  void release_drives();
  static constexpr std::uint32_t kNewJoint = ~0u;
  // observe() but the penetration; ObservationScope::divergence: what the divergence check reads after every step.
  Observation observe_state(ObservationScope scope) const;
  [[noreturn]] void refuse(std::string_view call, std::string_view why) const;
  [[noreturn]] void refuse_joint_space(std::string_view call) const;  ///< a method without joint coordinates
  void check_vector(const Eigen::Vector3d& v, std::string_view call) const;
  // A handle of this World, or a WorldError naming `call` (if any) and `kind` (a handle from
  // another World). Builds no string unless it throws: step() paths call it.
  template <typename Id>
  void check_world(Id id, std::string_view kind, std::string_view call = {}) const;
  // The handle of body index `b`.
  BodyId body_id(std::size_t b) const;

  Model model_;
  WorldOptions options_;
  std::uint32_t serial_;  // this World's, in every handle it issues
  // The method's state, the divergence bounds, the handle tables, the pins and the drives.
  std::unique_ptr<WorldInternals> internals_;
  bool drives_released_ = false;
  // Loads for the next step, per body, world, about its centre of mass: forces (N) and torques
  // (N·m), and impulses (N·s) and angular impulses (N·m·s), turned into forces when dt is known.
  std::vector<Eigen::Vector3d> load_force_, load_torque_, impulse_force_, impulse_torque_;
};

}  // namespace limber
