// The model: an immutable, solver-independent description of a scene.
//
// Every method (particles, springs, Lagrange, Featherstone) compiles from this one description,
// so the same scene can be run by each and the numbers compared. How a method solves it (sweeps,
// substeps, integrators) is not here but in the method's options (method_settings.hpp). Nothing
// here changes while stepping; everything that does lives in a method's State.
//
// Units are SI throughout (m, kg, s, N); z is up. The thesis's cm, ms and lb are converted at
// the scene boundary (tools/scenes/*.json are already in SI), never here.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

using Vector3 = Eigen::Vector3d;

/// A scene or model that fails validation. what() is one line: "<where>: <problem>", where
/// <where> names the field (e.g. "bodies[2].mass") and, from a file, the file first.
class ModelError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class ShapeType { cylinder, capsule, box, ellipsoid };

/// A limb's shape in its body frame, centred at the origin.
/// - cylinder: axis local +z, flat end faces at z = ±length/2, radius `radius`.
/// - capsule: axis local +z, hemispherical caps centred at z = ±length/2 (total extent
///   length + 2·radius); of length 0, a sphere (MuJoCo's sphere geoms: a head, a hand).
/// - box: half-sizes `half_extents` along the shape frame's x, y, z; the shape frame is the body
///   frame turned by `rotation` (a box's roll about the body's axis, which the body frame, a
///   shortest arc from +z, does not carry).
/// - ellipsoid: semi-axes `half_extents` along the shape frame's axes, as a box's.
/// A cylinder's or capsule's axis end points (0, 0, ±length/2) are the limb's *head* (+) and
/// *tail* (−); a box's and an ellipsoid's are both the centre (length 0). Cylinders and capsules
/// use length and radius only, boxes and ellipsoids half_extents and rotation only.
struct Shape {
  ShapeType type = ShapeType::cylinder;
  double length = 0;  ///< m, > 0 (a capsule: ≥ 0)
  double radius = 0;  ///< m, ≥ 0 (a capsule of length 0: > 0)
  Vector3 half_extents = Vector3::Zero();                      ///< m, each > 0 (box, ellipsoid)
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  ///< unit: shape frame → body frame (box, ellipsoid)
};

/// The name of a shape type as scene files and messages spell it ("box", "capsule", …).
std::string_view shape_type_name(ShapeType type);

/// Whether a shape is a box or an ellipsoid (half-extents and a rotation) rather than a
/// cylinder or capsule (a length along the body's axis and a radius).
inline bool has_half_extents(const Shape& shape) { return shape.type == ShapeType::box || shape.type == ShapeType::ellipsoid; }

/// Volume of a shape, m³: π r² L for a cylinder, π r² L + 4/3 π r³ for a capsule, 8·x·y·z for a
/// box and 4/3 π x·y·z for an ellipsoid of half-extents (x, y, z).
double volume(const Shape& shape);

/// The radius of the smallest sphere about the shape's centre that holds it, m: length/2 + radius
/// for a capsule, √((length/2)² + radius²) for a cylinder (its rim), |half_extents| for a box
/// (a corner) and the longest semi-axis for an ellipsoid. Needs no rotation: a sphere about the
/// centre holds the shape however it is turned.
inline double bounding_radius(const Shape& shape) {
  switch (shape.type) {
    case ShapeType::capsule: return 0.5 * shape.length + shape.radius;
    case ShapeType::cylinder: return std::hypot(0.5 * shape.length, shape.radius);
    case ShapeType::box: return shape.half_extents.norm();
    case ShapeType::ellipsoid: return shape.half_extents.maxCoeff();
  }
  return std::hypot(0.5 * shape.length, shape.radius);
}

/// A lump of a limb's mass (thesis 4.1, eq. 4.1): a solid sphere of `radius` (0: a point)
/// centred at `position` in the body frame.
struct PointMass {
  Vector3 position = Vector3::Zero();  ///< m, body frame
  double mass = 0;                     ///< kg, > 0
  double radius = 0;                   ///< m, ≥ 0; its own inertia is (2/5) m r²
};

/// A limb's mass distribution given directly, as an engine's asset pipeline or MuJoCo's
/// <inertial> gives it: the centre of mass and the inertia tensor about it, in the body frame.
/// The tensor must be symmetric and positive definite with principal moments obeying the
/// triangle inequality (I₁ + I₂ ≥ I₃: a physical body), as validate() checks.
struct Inertial {
  Vector3 centre_of_mass = Vector3::Zero();                 ///< m, body frame
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();        ///< kg·m², about the centre of mass, body frame
};

/// Which bodies and colliders touch (Box2D's category and mask filter): two collide when each
/// one's `group` shares a bit with the other's `mask`. Besides the filter, bodies joined by a joint
/// never collide (their shapes meet at the joint by design), nor do two bodies that overlap in
/// the Model's poses (a torso and the arm that hangs into it; Jolt's ragdoll does the same).
/// Bodies welded by fixed joints count as one body (a compound shape, MuJoCo's weld body): none
/// of them collides with another, nor with a body jointed to any of them.
struct CollisionFilter {
  std::uint32_t group = 1;           ///< the categories it belongs to, bits
  std::uint32_t mask = 0xFFFFFFFFu;  ///< the categories it collides with, bits
};

/// Whether filters `a` and `b` let their owners collide.
inline bool filters_collide(const CollisionFilter& a, const CollisionFilter& b) {
  return (a.group & b.mask) != 0 && (b.group & a.mask) != 0;
}

/// A rigid limb with distributed mass.
///
/// Its mass is spread uniformly over its shape, unless `point_masses` is given: then the limb's
/// mass, centre of mass and inertia are those of the point masses (eq. 4.1), `mass` is their
/// sum, and the shape is only its surface for contacts. Or `inertial` gives the centre of mass
/// and inertia tensor directly (with `mass`), and the shape is again only a surface.
/// body_mass_properties() (kernel/mass/mass_properties.hpp) gives the result in every case.
/// The particle method keeps a limb's mass on its axis: it rejects a centre of mass off the axis.
struct Body {
  std::string name;
  Shape shape;
  double mass = 0;                            ///< kg, > 0 (a scene may give density × volume instead)
  std::vector<PointMass> point_masses;        ///< empty: uniform density over the shape
  std::optional<Inertial> inertial;           ///< given: the mass distribution (not with point_masses)
  Vector3 position = Vector3::Zero();         ///< world position of the body-frame origin (the centre), m
  Vector3 axis = Vector3::UnitZ();            ///< unit world direction of local +z (tail → head)
  Vector3 linear_velocity = Vector3::Zero();  ///< of the centre, m/s
  Vector3 angular_velocity = Vector3::Zero(); ///< world frame, rad/s
  CollisionFilter collision;                  ///< with other limbs and the colliders

  /// Rotation from body frame to world: the shortest arc taking local +z onto `axis`.
  Eigen::Quaterniond orientation() const;
  /// World position of a body-frame point, m.
  Vector3 to_world(const Vector3& local_point) const;
  /// World velocity of a body-frame point, m/s (v + ω × r).
  Vector3 velocity_at(const Vector3& local_point) const;
  Vector3 head() const { return position + 0.5 * shape.length * axis; }
  Vector3 tail() const { return position - 0.5 * shape.length * axis; }
};

// What a body is doing now, whatever the method: the World's read-outs and teleports, and each
// method's side of them (kernel/methods/method_contract.hpp).

/// A body frame's pose, world: origin (m) and orientation (body → world).
struct Pose {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

/// A ball's centre (m) and velocity (m/s), world.
struct BallMotion {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
};

/// A body frame's motion, world: the velocity of its origin (m/s) and its angular velocity (rad/s).
struct Motion {
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular = Eigen::Vector3d::Zero();
};

/// A joint coordinate's value q (rad or m, 0 at the initial poses) and rate q̇ (rad/s or m/s).
struct CoordinateMotion {
  double position = 0;
  double velocity = 0;
};

/// What a joint transmits: the force (N) and the torque (N·m, about the joint's anchor on the
/// outboard body) its inboard body exerts on its outboard body through it, world frame.
struct JointReaction {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();
};

/// What a joint lets its outboard body do relative to its inboard body (rows: the constraint
/// equations it adds in maximal coordinates; DOF: the coordinates it adds in reduced ones).
enum class JointType {
  spherical,  ///< turn freely about the anchor (3 rows, 3 DOF): a ball joint
  revolute,   ///< turn about `axis` through the anchor (5 rows, 1 DOF): a hinge
  prismatic,  ///< slide along `axis`, no turning (5 rows, 1 DOF)
  universal,  ///< turn about `axis` (fixed in the inboard body) and `second_axis` (fixed in the
              ///< outboard body), which stay perpendicular (4 rows, 2 DOF): a Cardan joint
  fixed,      ///< no relative motion (6 rows, 0 DOF): welds two limbs
  serial,     ///< 1–6 hinges and slides in a row with nothing between them (Joint::serial_axes):
              ///< MuJoCo's several joints in one body, such as a hip's three hinges or an ankle's
              ///< two skew ones (6 − k rows, k DOF)
};

/// The scene-file name of a joint type ("spherical", "revolute", ...).
std::string_view joint_type_name(JointType type);

/// Index that stands for the world (a fixed frame) in Joint::inboard.
inline constexpr int kWorld = -1;

/// A closed interval [min, max] of a joint coordinate (rad or m).
struct Range {
  double min = 0, max = 0;
};

/// Joint limits: inequality constraints on the joint's coordinates, measured from its zero (the
/// bodies' poses in the Model) by joint_coordinates() (kernel/model/joint_coordinates.hpp).
/// Every method holds them as one-sided constraints that act only when violated, with
/// restitution 0 (a limit stops the motion into it; it does not bounce). The swing-twist
/// decomposition is Bullet's cone-twist (and, for a cone centred on the rest pose, Jolt's
/// SwingTwistConstraint): the relative rotation is a twist about the cone's axis followed by a
/// swing (the shortest turn of the cone's axis onto the outboard's).
struct JointLimits {
  /// Spherical: the half-angle of a cone, rad, in (0, π): the outboard body's axis (its local +z,
  /// tail → head) stays within this angle of `swing_axis`.
  std::optional<double> swing;
  /// Spherical, with `swing`: the cone's axis, unit, world frame at the initial poses, fixed in
  /// the inboard body (the world, for a joint to the world). Unset: the outboard's axis at rest,
  /// so the cone is centred on the rest pose. The outboard's axis at rest must lie inside the cone.
  std::optional<Vector3> swing_axis;
  /// Spherical: the twist of the outboard body about its own axis relative to the inboard, rad,
  /// with −π < min ≤ 0 ≤ max < π (0 at rest), measured against a reference carried by the
  /// shortest arc from the cone's axis (`swing_axis`, else the rest axis), Bullet's cone-twist:
  /// defined everywhere inside the cone (joint_coordinates.hpp).
  std::optional<Range> twist;
  /// Revolute: the hinge angle about `Joint::axis` (right hand, outboard relative to inboard),
  /// rad, with −π < min ≤ 0 ≤ max < π. Prismatic: the slide along `Joint::axis`, m, with
  /// min ≤ 0 ≤ max. Both 0 at rest.
  std::optional<Range> range;
  bool any() const { return swing || twist || range; }
};

/// A joint drive (a motor; thesis 5.2's blend of key-framed animation and simulation): a
/// proportional-derivative pull of the joint's coordinates toward a target,
///   τ = stiffness·(target − q) + damping·(target_velocity − q̇),
/// per axis, q the joint's coordinates from its zero (joint_coordinates()). Each method applies
/// it implicitly where it can (a compliant constraint, XPBD; or a stable PD), so stiff drives do
/// not make a step unstable. Stiffness 0 with damping > 0 is a velocity motor; both 0 is limp.
struct JointDrive {
  double stiffness = 0;  ///< N·m/rad (spherical, revolute) or N/m (prismatic), ≥ 0
  double damping = 0;    ///< N·m·s/rad or N·s/m, ≥ 0
  /// Revolute: the target hinge angle, rad; prismatic: the target slide, m.
  double target = 0;
  double target_velocity = 0;  ///< rad/s or m/s
  /// Spherical: the target rotation of the outboard relative to the inboard, from the rest
  /// poses, as a rotation vector (axis × angle, rad) in world axes at the initial poses (the
  /// inboard body's frame carries them), |rotation| < π.
  Vector3 target_rotation = Vector3::Zero();
  Vector3 target_angular_velocity = Vector3::Zero();  ///< rad/s, the same axes
};

/// One degree of freedom of a serial joint: a hinge about, or a slide along, an axis through a
/// point. The axes compose in order from the inboard body (MuJoCo's `mj_kinematics`): the
/// outboard body's pose is G₁(q₁)·G₂(q₂)⋯G_k(q_k) applied to its initial pose, G_i the screw about
/// axis i as it lies at the initial poses, so each axis is carried by the turns before it. Its
/// coordinate q is 0 at the initial poses (MuJoCo's q − ref).
struct SerialAxis {
  std::string name;                ///< the coordinate's name (MuJoCo's joint name), unique in the Model
  bool slide = false;              ///< false: a hinge (q in rad); true: a slide (q in m)
  Vector3 axis = Vector3::UnitX(); ///< unit, world frame at the initial poses
  Vector3 point = Vector3::Zero(); ///< a point on the axis, m, world frame at the initial poses
  /// The coordinate's limits, holding 0: a hinge's within (−π, π) rad, a slide's in m.
  std::optional<Range> range;
  /// A spring and damper on the coordinate (MuJoCo's joint stiffness, springref − ref and damping;
  /// the same pull as a revolute joint's drive): target and target_velocity, stiffness, damping.
  std::optional<JointDrive> drive;
  double friction = 0;  ///< dry friction, N·m or N, ≥ 0 (MuJoCo's frictionloss)
  double armature = 0;  ///< added to the coordinate's diagonal of the mass matrix, kg·m² or kg, ≥ 0
};

/// A joint between an inboard and an outboard body, at an anchor fixed in each body's frame.
/// With inboard == kWorld, inboard_anchor is a world point, m.
///
/// The bodies' poses in the Model are the joint's zero: a revolute or universal joint's angles,
/// a prismatic joint's slide and a fixed joint's relative rotation are measured from them, and
/// the axes are given in world coordinates *at those poses* (each method carries them into the
/// bodies' frames when it compiles). A prismatic joint's anchors may start apart along its axis
/// (that offset is the slide's zero); any other gap at the initial poses is an error the methods
/// close.
struct Joint {
  std::string name;
  JointType type = JointType::spherical;
  int inboard = kWorld;                       ///< body index or kWorld
  int outboard = 0;                           ///< body index
  Vector3 inboard_anchor = Vector3::Zero();   ///< m, inboard body frame (world if inboard == kWorld)
  Vector3 outboard_anchor = Vector3::Zero();  ///< m, outboard body frame
  /// Unit, world frame at the initial poses: the hinge axis (revolute), the slide axis
  /// (prismatic), the axis fixed in the inboard body (universal). Unused by spherical and fixed.
  Vector3 axis = Vector3::UnitX();
  /// Unit, world frame at the initial poses: universal only, the axis fixed in the outboard body,
  /// perpendicular to `axis`.
  Vector3 second_axis = Vector3::UnitY();
  /// The stiff-spring method's spring for this joint (thesis 4.4.1); unset:
  /// SpringOptions::defaults (kernel/model/options.hpp).
  std::optional<double> stiffness;  ///< N/m, > 0
  std::optional<double> damping;    ///< N·s/m, ≥ 0
  /// Limits on the joint's coordinates (spherical: swing and twist; revolute: angle range;
  /// prismatic: travel range).
  JointLimits limits;
  /// Joint friction (thesis 5.2: "friction in a revolute joint"): the joint resists relative
  /// motion with a torque (N·m; spherical, revolute, universal) or force (N; prismatic) of at
  /// most this magnitude — dry (Coulomb) friction: it holds below it and slides above it. ≥ 0.
  double friction = 0;
  /// A drive toward a target (spherical, revolute, prismatic).
  std::optional<JointDrive> drive;
  /// Revolute and prismatic: inertia added to the coordinate's diagonal of the joint-space mass
  /// matrix (a rotor's reflected inertia; MuJoCo's armature), kg·m² or kg, ≥ 0.
  double armature = 0;
  /// Serial only: its degrees of freedom in order from the inboard body, 1 to 6. The anchors are
  /// then the first axis's point (inboard frame) and the last axis's point (outboard frame), each
  /// fixed in its body; the other fields of a joint (axis, limits, friction, drive, armature) are
  /// per axis here.
  std::vector<SerialAxis> serial_axes;
};

/// Whether the joint has a limit, friction or a drive: something beyond its type's equality rows.
inline bool has_joint_controls(const Joint& joint) {
  if (joint.limits.any() || joint.friction > 0 || joint.drive.has_value()) return true;
  for (const SerialAxis& axis : joint.serial_axes) {
    if (axis.range || axis.friction > 0 || axis.drive) return true;
  }
  return false;
}

/// A spherical joint with the default spring (the common case, without naming every field).
inline Joint spherical_joint(std::string name, int inboard, int outboard, const Vector3& inboard_anchor,
                             const Vector3& outboard_anchor) {
  Joint joint;
  joint.name = std::move(name);
  joint.inboard = inboard, joint.outboard = outboard;
  joint.inboard_anchor = inboard_anchor, joint.outboard_anchor = outboard_anchor;
  return joint;
}

/// A velocity constraint between two bodies that turn on axles (thesis 3.5's example of what
/// maximal coordinates can express and reduced ones cannot: two meshed gears): their angular
/// velocities about their axes keep a fixed ratio,
///   ω_second · n_second = ratio · (ω_first · n_first),
/// n the axes, fixed in each body. Two meshed gears of pitch radii r₁, r₂ have equal rim speeds
/// and turn opposite ways: ratio = −r₁/r₂. Only the Lagrange method supports it.
struct Gear {
  std::string name;
  int first = 0, second = 0;                ///< body indices, distinct
  Vector3 first_axis = Vector3::UnitX();    ///< n_first: unit, world frame at the initial poses
  Vector3 second_axis = Vector3::UnitX();   ///< n_second: unit, world frame at the initial poses
  double ratio = -1;                        ///< finite, ≠ 0
};

/// What an actuator's force answers to (MuJoCo's <motor>, <position>, <velocity>).
enum class ActuatorKind { motor, position, velocity };

/// An actuator on one joint coordinate: a joint force, N·m on a hinge, N on a slide, with the
/// control set while stepping (World::set_controls) and 0 until then. The force acts between the
/// joint's two bodies and nowhere else: a generalized force on the coordinate, computed from the
/// state at the start of each step (explicit, as MuJoCo's are: a servo is stable while
/// gear²·gain·h²/I, or gear²·gain·h/I for a velocity servo, stays below about 2–4). Featherstone
/// and Lagrange take a servo implicitly instead, its force at the end of the step as a drive's
/// (stable at any gain: their bodies.hpp, apply_actuator). MuJoCo's actuator models
/// (XMLreference, "actuator"), u the control and l = gear·(q + reference) the actuator's length:
/// - motor: gear·u;
/// - position: gear·gain·(u − l), a PD servo's P (MuJoCo's kp);
/// - velocity: gear·gain·(u − l̇), l̇ = gear·q̇ (MuJoCo's kv).
struct Actuator {
  std::string name;
  int joint = 0;  ///< Model joint index: revolute, prismatic or serial
  int axis = 0;   ///< a serial joint's axis (serial_axes index); 0 for revolute and prismatic
  ActuatorKind kind = ActuatorKind::motor;
  double gear = 1;  ///< motor: N·m (or N) per unit of control; position, velocity: length per unit of q. Finite
  /// position: N·m/rad (N/m) per unit of length (kp); velocity: N·m·s/rad (N·s/m) (kv); ≥ 0,
  /// finite; 0 for a motor.
  double gain = 0;
  /// The coordinate's value at the initial poses, where limber's q is 0 (MuJoCo's joint ref),
  /// rad or m, finite: a position actuator's length is gear·(q + reference).
  double reference = 0;
  /// The controls it takes: a control outside is clamped to it (MuJoCo's ctrlrange with
  /// ctrllimited). Unset: any finite control.
  std::optional<Range> control_range;
};

/// An actuator's joint force at `control` with its coordinate at q = `position` (rad or m, 0 at
/// the initial poses) moving at q̇ = `velocity`: the force of its kind (Actuator), the control
/// clamped to its range first. N·m or N.
inline double actuator_force(const Actuator& actuator, double control, double position = 0, double velocity = 0) {
  if (const auto& range = actuator.control_range) control = control < range->min ? range->min : control > range->max ? range->max : control;
  switch (actuator.kind) {
    case ActuatorKind::position: return actuator.gear * actuator.gain * (control - actuator.gear * (position + actuator.reference));
    case ActuatorKind::velocity: return actuator.gear * actuator.gain * (control - actuator.gear * velocity);
    case ActuatorKind::motor: break;
  }
  return actuator.gear * control;
}

/// The plane z = height, solid below. Coulomb friction and restitution against everything.
struct Ground {
  double height = 0;       ///< m
  double restitution = 0;  ///< [0, 1]
  double friction = 0;     ///< Coulomb coefficient, ≥ 0
};

/// An axis-aligned box that keeps everything inside it (thesis 3.2.3, eq. 3.8).
struct Bounds {
  Vector3 min = Vector3::Zero();  ///< m
  Vector3 max = Vector3::Zero();  ///< m, > min on every axis
  double restitution = 0;
  double friction = 0;
};

/// The largest ball a Model takes: radius (m) and mass (kg). Guards against a slip of the
/// keyboard (a radius of 10³⁰⁰ m has an infinite moment of inertia), not physical limits.
inline constexpr double kMaxBallRadius = 1e3;
inline constexpr double kMaxBallMass = 1e9;

/// A solid sphere thrown at the scene (thesis 4.5: the elastic ball; several make a volley). A
/// free rigid body of its own island, in every method; it meets limbs, the ground, the bounds,
/// static colliders and the other balls. (A capsule or cylinder projectile is a Body without
/// joints.)
struct Ball {
  double radius = 0;                    ///< m, in (0, kMaxBallRadius]
  double mass = 0;                      ///< kg, in (0, kMaxBallMass]
  double restitution = 0;               ///< [0, 1], used for its contacts with limbs
  Vector3 position = Vector3::Zero();   ///< centre, m
  Vector3 velocity = Vector3::Zero();   ///< initial, m/s
};

/// A triangle mesh, world coordinates: each triangle's vertices counter-clockwise seen from
/// outside, so its normal (v1 − v0) × (v2 − v0) points out of the solid. Triangles are
/// one-sided: a limb behind a triangle (within its thickness) is pushed out through its front.
struct TriangleMesh {
  std::vector<Vector3> vertices;                 ///< m
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< indices into vertices, non-degenerate
};

enum class ColliderType { box, capsule, mesh };

/// Static level geometry (it never moves): limbs and balls collide with it, with its Coulomb
/// friction and restitution (a ball's restitution where that is larger, as on the ground).
struct StaticCollider {
  std::string name;
  ColliderType type = ColliderType::box;
  /// box: its centre; capsule: the middle of its core segment. m, world.
  Vector3 position = Vector3::Zero();
  /// box: its orientation (box frame → world); capsule: turns local +z onto the core segment.
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Vector3 half_extents = Vector3::Zero();  ///< box: m, > 0 each
  double length = 0;                       ///< capsule: core segment along local z, m, ≥ 0
  double radius = 0;                       ///< capsule: m, > 0
  TriangleMesh mesh;                       ///< mesh: world coordinates
  double thickness = 0.1;                  ///< mesh: how far behind a triangle still counts as inside, m, > 0
  double restitution = 0;                  ///< [0, 1]
  double friction = 0.5;                   ///< Coulomb coefficient, ≥ 0
  CollisionFilter collision;
};

/// Bodies at rest are not simulated (thesis 4.5.3): an island sleeps after its particles have
/// moved slower than `speed_threshold` for `time_to_sleep`, and wakes on contact or force.
struct SleepSettings {
  bool enabled = true;
  bool start_asleep = false;      ///< islands with no initial velocity start asleep (the standing humanoid)
  double speed_threshold = 0.05;  ///< m/s
  double time_to_sleep = 0.5;     ///< s
};

/// Drag on rigid bodies (thesis 2.1.5, 2.1.6), in each body's frame (z: the limb's axis), so a
/// limb can move more freely along its axis than across it: F_body = −diag(linear)·v_body and
/// τ_body = −diag(angular)·ω_body. Used by the rigid-body methods; Settings::damping applies too.
struct DragSettings {
  Vector3 linear = Vector3::Zero();   ///< N·s/m along body x, y, z, ≥ 0
  Vector3 angular = Vector3::Zero();  ///< N·m·s about body x, y, z, ≥ 0
};

/// What a run may do and still be called accurate: its verdict (kernel/metrics/run_verdict.hpp)
/// is "ok" only when, over every step, its joints, penetration, limits and energy stayed within
/// these. An absent bound is derived from the Model, as said beside it.
struct Tolerances {
  /// Largest joint gap, or particle limb stretch, relative to the link length, ≥ 0.
  double joint_gap = 0.01;
  /// Deepest overlap of a limb into another, static geometry or the ground, m, ≥ 0. Absent: the
  /// radius of the Model's thinnest limb with a radius, or a box's or ellipsoid's smallest
  /// half-extent (0.01 m without one): a limb sunk that deep has half its thickness through
  /// whatever it met.
  std::optional<double> penetration;
  /// Largest violation of a joint limit, rad (m for a prismatic range), ≥ 0.
  double limit = 0.1;
  /// Largest energy gain, relative to the World's energy scale (kernel/metrics/divergence.hpp),
  /// ≥ 0. Absent: 0.01 for a Model without actuators or drives (no method may gain energy then),
  /// 1 with them (motors put energy in; a servo past its stability limit gains tens of scales).
  std::optional<double> energy_gain;
};

struct Settings {
  Vector3 gravity{0, 0, -9.81};  ///< m/s²
  double time_step = 1.0 / 240;  ///< s, > 0
  double duration = 5;           ///< simulated time of a run, s, > 0
  /// Linear velocity damping, 1/s: without forces, speed decays as exp(−damping·t), whatever Δt.
  double damping = 0;
  SleepSettings sleep;
  DragSettings drag;
  /// A particle faster than this is reported as divergence, m/s.
  double divergence_speed = 1000;
  /// Penetration that a step begins with (an initial overlap, a deep hit) is pushed out at most
  /// this fast, m/s, so resolving it cannot fling bodies (Box2D's contact push-out limit).
  /// Penetration made by the step's own motion is always resolved in full.
  double contact_recovery_speed = 0.5;
  /// An active ragdoll's switch (thesis 5.2): once a ball has touched a limb, every joint
  /// drive goes limp (stiffness and damping 0), so a body that tracked a pose falls like a
  /// ragdoll. Applied after each step by release_drives_after_impact (methods/method.hpp).
  bool release_drives_on_impact = false;
  /// Coulomb friction between two limbs that touch (limb–limb contacts; restitution 0).
  double limb_friction = 0.5;
  Tolerances tolerances;  ///< what a run's verdict calls accurate
};

/// A whole scene. Build one in C++ or load it with load_scene (kernel/scene/scene_file.hpp).
struct Model {
  std::string name;
  std::vector<Body> bodies;
  std::vector<Joint> joints;
  std::vector<Gear> gears;
  std::vector<Actuator> actuators;  ///< motors on joint coordinates, in the order of their controls
  std::optional<Ground> ground;
  std::optional<Bounds> bounds;
  std::vector<Ball> balls;                ///< projectiles, in order (the first: the thesis's ball)
  std::vector<StaticCollider> colliders;  ///< static level geometry
  Settings settings;

  /// Index of the body called `name`, or −1.
  int find_body(std::string_view name) const;
  /// Total mass of the bodies (not the balls), kg.
  double body_mass() const;
};

/// The name outputs give ball `index` of model.balls: "ball" when the model has one, else
/// "ball0", "ball1", …
std::string ball_name(const Model& model, std::size_t index);

/// Appends `other`'s bodies, joints, gears and actuators to `model`: names led by `prefix`, moved
/// by `offset` (m; joints to the world too), body and joint indices renumbered. Settings, ground, bounds and
/// balls stay `model`'s. (Several ragdolls in one world; copies of a scene on a lattice.)
void append_model(Model& model, const Model& other, std::string_view prefix, const Vector3& offset);

/// The Model's islands: bodies joined by joints between bodies and by gears (a joint to the world
/// joins nothing), which every method simulates, puts to sleep and wakes together (thesis
/// 4.5.3). Islands are numbered in order of their lowest body, so bodies listed in order visit
/// the islands in order.
struct BodyIslands {
  std::vector<std::uint32_t> island_of_body;  ///< per body
  std::size_t count = 0;
};
BodyIslands body_islands(const Model& model);

/// Checks every field for range and consistency (finite numbers, positive masses and lengths,
/// unit axes, joints naming existing and distinct bodies, unique names, ...).
/// Throws ModelError naming the first bad field.
void validate(const Model& model);

/// Checks joint `index` of `model` alone, as validate() does (its bodies must exist). Throws
/// ModelError naming the field. For a change to one joint between steps (World::set_joint_drive).
void validate_joint(const Model& model, std::size_t index);
/// Checks `joint` as if it were joint `index` of `model` (whose bodies it names), leaving
/// `model` as it is: for a joint the World holds a changed copy of (its current drive).
void validate_joint(const Joint& joint, const Model& model, std::size_t index);


/// Which joint controls (limits, friction, drives) a method applies.
struct JointControlSupport {
  bool limits = false, friction = false, drives = false, armature = false;
};

/// Throws ModelError naming the first joint with a limit, friction, drive or armature (its own
/// or an axis's) that `method` does not apply: "joints[3] 'knee': the <method> method does not apply joint limits".
void require_joint_controls(const Model& model, JointControlSupport supported, std::string_view method);

}  // namespace limber
