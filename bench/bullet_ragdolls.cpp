// A pile of ragdolls in limber's particle method and in Bullet 3's rigid bodies, in one run:
// time per step and the deepest penetration of each (bench/ragdolls.md, "The pile against
// Bullet"). Bullet's RagdollDemo is the model of the Bullet side: one btRigidBody per limb,
// btConeTwistConstraint for spherical joints with swing and twist limits, btHingeConstraint for
// knees and elbows, collisions between jointed limbs off.
//
//   build/bench/bullet_ragdolls [SCENE] [--copies N] [--stack N] [--steps N] [--repeats R] [--sleep]
//                               [--limber SxN[:rows|:tree][:1t|:2t][:double|:float] ...] [--bullet SxN ...]
//                               [--cylinders cylinder|capsule]
//
// Each --limber setting is substeps × sweeps (with the joint solve and the threads), each --bullet
// setting substeps × solver iterations; every setting runs in each round, round after round, so a
// busy machine slows them alike. A row gives the median over rounds of the stepping thread's CPU
// time and of wall time, and, from the first round, the largest joint gap, limit violation and
// penetration, measured on both engines' poses by the same functions.
//
// SCENE defaults to tools/scenes/ragdoll_pile.json, or, while that file does not exist, to
// tools/scenes/ragdoll.json stacked 32 times (--stack N: N copies of the scene's bodies laid in
// crossed layers of four, each ragdoll on its back, 0.1 m apart, so the pile falls onto itself).
//
// Bullet gets the same scene, body by body:
// - a limb is a btRigidBody of the limb's mass, centre of mass and principal inertia
//   (body_mass_properties): a btCylinderShapeZ or btCapsuleShapeZ of the limb's length and
//   radius, inside a btCompoundShape when the centre of mass is off the shape's centre or the
//   inertia is not diagonal in the body frame (Bullet's body frame is the principal frame);
// - spherical joints: btConeTwistConstraint (the cone about the limit's swing axis, the twist
//   about the outboard limb's axis; an asymmetric twist range is centred by turning the
//   outboard frame), or btPoint2PointConstraint without limits; revolute: btHingeConstraint with
//   the range (its sign calibrated with getHingeAngle) and joint friction as a zero-velocity
//   motor of impulse friction·Δt; fixed: btFixedConstraint; universal: btUniversalConstraint;
//   prismatic: btSliderConstraint;
// - limb pairs that limber never collides (joined by a joint, overlapping at the Model's poses,
//   or rejected by their CollisionFilter) never collide in Bullet either (setIgnoreCollisionCheck
//   and the broadphase group and mask);
// - the ground, static colliders (box, capsule, mesh: btBvhTriangleMeshShape), the bounds (six
//   planes) and the ball (a sphere; this bench drops the ball, which its measure does not see);
// - materials as limber pairs them (a contact callback): a static surface's friction and
//   restitution, Settings::limb_friction and restitution 0 between limbs.
// Bullet's default solver settings but for the iterations; a substep is stepSimulation(Δt / S, 0).
//
// Both engines run in this process, alternately; each repetition rebuilds the world, and the time
// is the sum of the step() calls only (measuring happens outside them, in the first repetition).
// The deepest penetration is measured on both engines' poses by the same function
// (deepest_penetration below), and Bullet's own contact distances are reported beside it.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <numbers>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <btBulletDynamicsCommon.h>
#include <BulletCollision/CollisionShapes/btTriangleMesh.h>

#include "limber/kernel/geometry/limb_collisions.hpp"
#include "limber/kernel/mass/mass_properties.hpp"
#include "limber/kernel/model/joint_coordinates.hpp"
#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/world/world.hpp"
#include "thread_time.hpp"

namespace limber {
namespace {

using Clock = std::chrono::steady_clock;
using Eigen::Quaterniond;
using Eigen::Vector3d;

// ---------------------------------------------------------------------------------------------
// The pile: copies of one ragdoll, each turned onto its back and stacked.

// A body-frame vector of `before` as the same material vector in `after`'s frame, once the body
// has been turned by `rotation` (Body::orientation is the shortest arc onto the axis, so turning
// a limb can change its roll: anchors and inertia must follow).
Quaterniond frame_change(const Body& before, const Body& after, const Quaterniond& rotation) {
  return after.orientation().conjugate() * rotation * before.orientation();
}

// Moves bodies [first_body, end_body) and joints [first_joint, end_joint) of `model` rigidly:
// x → rotation·x + translation, everything given in world axes turned with them.
void move_rigidly(Model& model, std::size_t first_body, std::size_t end_body, std::size_t first_joint, std::size_t end_joint,
                  const Quaterniond& rotation, const Vector3d& translation) {
  std::vector<Quaterniond> change(model.bodies.size(), Quaterniond::Identity());
  for (std::size_t b = first_body; b < end_body; ++b) {
    Body& body = model.bodies[b];
    const Body before = body;
    body.position = rotation * body.position + translation;
    body.axis = (rotation * body.axis).normalized();
    body.linear_velocity = rotation * body.linear_velocity;
    body.angular_velocity = rotation * body.angular_velocity;
    change[b] = frame_change(before, body, rotation);
    for (PointMass& lump : body.point_masses) lump.position = change[b] * lump.position;
    if (body.inertial) {
      const Eigen::Matrix3d turn = change[b].toRotationMatrix();
      body.inertial->centre_of_mass = turn * body.inertial->centre_of_mass;
      body.inertial->inertia = turn * body.inertial->inertia * turn.transpose();
    }
  }
  for (std::size_t j = first_joint; j < end_joint; ++j) {
    Joint& joint = model.joints[j];
    joint.inboard_anchor = joint.inboard == kWorld ? Vector3d(rotation * joint.inboard_anchor + translation)
                                                   : Vector3d(change[static_cast<std::size_t>(joint.inboard)] * joint.inboard_anchor);
    joint.outboard_anchor = change[static_cast<std::size_t>(joint.outboard)] * joint.outboard_anchor;
    joint.axis = rotation * joint.axis;
    joint.second_axis = rotation * joint.second_axis;
    if (joint.limits.swing_axis) joint.limits.swing_axis = rotation * *joint.limits.swing_axis;
    if (joint.drive) {
      joint.drive->target_rotation = rotation * joint.drive->target_rotation;
      joint.drive->target_angular_velocity = rotation * joint.drive->target_angular_velocity;
    }
  }
}

// `count` copies of `one` (one ragdoll standing on the ground, facing +x), each on its back,
// in layers of four side by side 0.4 m apart, every layer turned 90° from the one below and
// 0.3 m above it, with a small deterministic yaw each. No ball.
Model stack_ragdolls(const Model& one, std::size_t count) {
  const double spacing = std::max(footprint(one), 0.1);
  Model pile = copies_of(one, count, spacing, "r", "stack");
  pile.balls.clear();
  const std::size_t bodies = one.bodies.size(), joints = one.joints.size();
  const std::size_t per_row = static_cast<std::size_t>(std::ceil(std::sqrt(static_cast<double>(count))));
  // The standing ragdoll's middle (its bodies' centres' extent), which goes to each slot.
  Vector3d low = Vector3d::Constant(1e300), high = Vector3d::Constant(-1e300);
  for (const Body& body : one.bodies) low = low.cwiseMin(body.position), high = high.cwiseMax(body.position);
  const Vector3d middle = (low + high) / 2;
  const double ground = one.ground ? one.ground->height : 0;
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t layer = k / 4, slot = k % 4;
    const Vector3d lattice = spacing * Vector3d(static_cast<double>(k % per_row), static_cast<double>(k / per_row), 0);
    // On its back: +z (head) onto −x, +x (face) onto +z; then the layer's yaw.
    const double yaw = (layer % 2 ? std::numbers::pi / 2 : 0.0) + 0.15 * std::sin(1.7 * static_cast<double>(k));
    const Quaterniond rotation = Quaterniond(Eigen::AngleAxisd(yaw, Vector3d::UnitZ())) *
                                 Quaterniond(Eigen::AngleAxisd(-std::numbers::pi / 2, Vector3d::UnitY()));
    const Vector3d across = Quaterniond(Eigen::AngleAxisd(yaw, Vector3d::UnitZ())) * Vector3d::UnitY();
    const Vector3d place = Vector3d(0, 0, ground + 0.25 + 0.3 * static_cast<double>(layer)) +
                           (static_cast<double>(slot) - 1.5) * 0.4 * across;
    // Undo the lattice offset and centre the copy, then turn it and put it in its slot.
    move_rigidly(pile, k * bodies, (k + 1) * bodies, k * joints, (k + 1) * joints, Quaterniond::Identity(), -lattice - middle);
    move_rigidly(pile, k * bodies, (k + 1) * bodies, k * joints, (k + 1) * joints, rotation, place);
  }
  return pile;
}

// ---------------------------------------------------------------------------------------------
// Which limb pairs never collide: limber's rule (CollisionFilter, model.hpp) — filters that
// reject each other, a joint between them, or an overlap at the Model's poses.

struct Segment {
  Vector3d tail, head;
  double radius = 0;
  ShapeType type = ShapeType::capsule;
};

Segment segment_of(const Body& body, const FramePose& pose) {
  const Vector3d half = pose.orientation * Vector3d(0, 0, body.shape.length / 2);
  return {pose.position - half, pose.position + half, body.shape.radius, body.shape.type};
}

// Distance between segments [p0, p1] and [q0, q1] (Ericson, Real-Time Collision Detection 5.1.9).
double segment_distance(const Vector3d& p0, const Vector3d& p1, const Vector3d& q0, const Vector3d& q1) {
  const Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a <= 1e-30 && e <= 1e-30) return r.norm();
  if (a <= 1e-30) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 1e-30) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denominator = a * e - b * b;
      s = denominator > 1e-30 ? std::clamp((b * f - c * e) / denominator, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) t = 0, s = std::clamp(-c / a, 0.0, 1.0);
      else if (t > 1) t = 1, s = std::clamp((b - c) / a, 0.0, 1.0);
    }
  }
  return ((p0 + s * d1) - (q0 + t * d2)).norm();
}

struct PairRules {
  std::set<std::pair<std::size_t, std::size_t>> excluded;  // (lower, higher) body indices
  std::size_t jointed = 0, overlapping = 0, filtered = 0;
  bool collide(std::size_t a, std::size_t b) const { return !excluded.contains({std::min(a, b), std::max(a, b)}); }
};

PairRules pair_rules(const Model& model) {
  PairRules rules;
  for (const Joint& joint : model.joints) {
    if (joint.inboard == kWorld) continue;
    const auto a = static_cast<std::size_t>(joint.inboard), b = static_cast<std::size_t>(joint.outboard);
    if (rules.excluded.insert({std::min(a, b), std::max(a, b)}).second) ++rules.jointed;
  }
  std::vector<Segment> rest;
  for (const Body& body : model.bodies) rest.push_back(segment_of(body, {body.orientation(), body.position}));
  for (std::size_t a = 0; a < model.bodies.size(); ++a) {
    for (std::size_t b = a + 1; b < model.bodies.size(); ++b) {
      if (rules.excluded.contains({a, b})) continue;
      if (!filters_collide(model.bodies[a].collision, model.bodies[b].collision)) {
        rules.excluded.insert({a, b}), ++rules.filtered;
        continue;
      }
      const double reach = rest[a].radius + rest[b].radius;
      if ((model.bodies[a].position - model.bodies[b].position).norm() >
          reach + (model.bodies[a].shape.length + model.bodies[b].shape.length) / 2)
        continue;
      if (segment_distance(rest[a].tail, rest[a].head, rest[b].tail, rest[b].head) < reach) {
        rules.excluded.insert({a, b}), ++rules.overlapping;
      }
    }
  }
  return rules;
}

// ---------------------------------------------------------------------------------------------
// The deepest penetration, m (≥ 0), given every body's pose, measured alike on limber's and
// Bullet's poses: limb–limb and limb–static collider overlaps by LimbCollisions::
// deepest_overlap (kernel/geometry/limb_collisions.hpp: each limb as the capsule around its
// segment, the pairs PairRules excludes left out, meshes with their thickness), and, THE BENCH'S
// OWN PART, limb–ground: the ground height minus the limb's lowest point (a cylinder's exact rim).
double deepest_penetration(const Model& model, LimbCollisions& collisions, const std::vector<FramePose>& poses) {
  std::vector<LimbSegment> limbs(model.bodies.size());
  double deepest = 0;
  for (std::size_t b = 0; b < limbs.size(); ++b) {
    const Segment s = segment_of(model.bodies[b], poses[b]);
    limbs[b] = {s.head, s.tail, s.radius};
    if (model.ground) {
      const Vector3d axis = (s.head - s.tail).normalized();
      const double rim = s.type == ShapeType::cylinder ? s.radius * std::sqrt(std::max(0.0, 1 - axis.z() * axis.z())) : s.radius;
      deepest = std::max(deepest, model.ground->height - (std::min(s.head.z(), s.tail.z()) - rim));
    }
  }
  return std::max(deepest, -collisions.deepest_overlap(limbs).separation);
}

// The largest distance between a joint's two anchors, m, and the largest limit violation (rad),
// by limber's joint_coordinates: the same measure for both engines.
struct JointErrors {
  double gap = 0, limit_violation = 0;
  std::string worst_limit;  // the joint of the largest violation
};

JointErrors joint_errors(const Model& model, const JointControls& controls, const std::vector<FramePose>& poses) {
  JointErrors errors;
  for (const Joint& joint : model.joints) {
    const Vector3d inboard = joint.inboard == kWorld
                                 ? joint.inboard_anchor
                                 : Vector3d(poses[static_cast<std::size_t>(joint.inboard)].position +
                                            poses[static_cast<std::size_t>(joint.inboard)].orientation * joint.inboard_anchor);
    const FramePose& out = poses[static_cast<std::size_t>(joint.outboard)];
    if (joint.type != JointType::prismatic) errors.gap = std::max(errors.gap, (inboard - (out.position + out.orientation * joint.outboard_anchor)).norm());
  }
  for (std::size_t k = 0; k < controls.joints.size(); ++k) {
    const Joint& joint = controls.joints[k];
    if (!joint.limits.any()) continue;
    const FramePose inboard = joint.inboard == kWorld ? FramePose{} : poses[static_cast<std::size_t>(joint.inboard)];
    const double violation = limit_violation(joint, joint_coordinates(joint, controls.frames[k], inboard, poses[static_cast<std::size_t>(joint.outboard)]));
    if (violation > errors.limit_violation) errors.limit_violation = violation, errors.worst_limit = joint.name;
  }
  return errors;
}

// ---------------------------------------------------------------------------------------------
// The scene in Bullet.

btVector3 bt(const Vector3d& v) { return {btScalar(v.x()), btScalar(v.y()), btScalar(v.z())}; }
btQuaternion bt(const Quaterniond& q) { return {btScalar(q.x()), btScalar(q.y()), btScalar(q.z()), btScalar(q.w())}; }
Vector3d eigen(const btVector3& v) { return {v.x(), v.y(), v.z()}; }
Quaterniond eigen(const btQuaternion& q) { return Quaterniond(q.w(), q.x(), q.y(), q.z()).normalized(); }
btTransform bt(const Quaterniond& q, const Vector3d& p) { return btTransform(bt(q), bt(p)); }

// A frame whose first column is `x` (unit), the other two any right-handed completion.
Quaterniond frame_with_x(const Vector3d& x) { return Quaterniond::FromTwoVectors(Vector3d::UnitX(), x); }
Quaterniond frame_with_z(const Vector3d& z) { return Quaterniond::FromTwoVectors(Vector3d::UnitZ(), z); }

// What a collision object is, for the material callback (btCollisionObject::getUserIndex).
enum MaterialKind : int { kLimb = 0, kStatic = 1, kBall = 2 };
double g_limb_friction = 0.5;

// limber's materials: a static surface's own friction and restitution (the ball's restitution
// where larger), limb–limb Settings::limb_friction with restitution 0, ball–limb the ball's
// restitution without friction. Bullet would multiply the two objects' coefficients.
bool combine_materials(btManifoldPoint& point, const btCollisionObjectWrapper* first, int, int, const btCollisionObjectWrapper* second,
                       int, int) {
  const btCollisionObject* a = first->getCollisionObject();
  const btCollisionObject* b = second->getCollisionObject();
  if (b->getUserIndex() == kStatic) std::swap(a, b);
  if (a->getUserIndex() == kStatic) {
    point.m_combinedFriction = a->getFriction();
    point.m_combinedRestitution = b->getUserIndex() == kBall ? std::max(a->getRestitution(), b->getRestitution()) : a->getRestitution();
  } else if (a->getUserIndex() == kBall || b->getUserIndex() == kBall) {
    point.m_combinedFriction = 0;
    point.m_combinedRestitution = a->getUserIndex() == kBall ? a->getRestitution() : b->getRestitution();
  } else {
    point.m_combinedFriction = btScalar(g_limb_friction);
    point.m_combinedRestitution = 0;
  }
  return true;
}

struct BulletOptions {
  bool sleep = false;            // Bullet's deactivation, as limber's sleeping
  bool cylinders_as_capsules = false;
  int substeps = 1;              // Bullet steps of Δt / substeps in one limber step
  int iterations = 10;           // btContactSolverInfo::m_numIterations (Bullet's default 10)
};

class BulletScene {
 public:
  BulletScene(const Model& model, const PairRules& rules, const BulletOptions& options);
  ~BulletScene();
  BulletScene(const BulletScene&) = delete;
  BulletScene& operator=(const BulletScene&) = delete;

  // `substeps` steps of Δt / substeps, each a variable step (no interpolation, no accumulator).
  void step(double dt) {
    for (int k = 0; k < substeps_; ++k) world_->stepSimulation(btScalar(dt / substeps_), 0);
  }
  // Body b's limber body frame (origin at the shape's centre, z along its axis), world.
  FramePose pose(std::size_t b) const;
  bool finite() const;
  // The most negative btManifoldPoint::getDistance() over every manifold now, m (0 when none
  // overlaps): the distance between the shapes' surfaces, their collision margins included.
  double deepest_contact();
  const btContactSolverInfo& solver_info() { return world_->getSolverInfo(); }
  int constraints() const { return world_->getNumConstraints(); }
  std::string margins() const;
  int compound_bodies = 0, point_to_points = 0, cone_twists = 0, hinges = 0, others = 0;
  std::vector<std::string> notes;

 private:
  btRigidBody* add_static(btCollisionShape* shape, const btTransform& pose, double friction, double restitution, const CollisionFilter& filter);

  btDefaultCollisionConfiguration configuration_;
  btCollisionDispatcher dispatcher_{&configuration_};
  btDbvtBroadphase broadphase_;
  btSequentialImpulseConstraintSolver solver_;
  std::vector<std::unique_ptr<btCollisionShape>> shapes_;
  std::vector<std::unique_ptr<btTriangleMesh>> meshes_;
  std::vector<std::unique_ptr<btRigidBody>> statics_;
  std::vector<std::unique_ptr<btRigidBody>> limbs_;
  std::unique_ptr<btRigidBody> ball_;
  std::vector<btTransform> body_in_principal_;  // limber body frame in Bullet's (principal) frame
  std::vector<std::unique_ptr<btTypedConstraint>> constraints_;
  std::unique_ptr<btDiscreteDynamicsWorld> world_;
  int substeps_ = 1;
};

BulletScene::BulletScene(const Model& model, const PairRules& rules, const BulletOptions& options) {
  world_ = std::make_unique<btDiscreteDynamicsWorld>(&dispatcher_, &broadphase_, &solver_, &configuration_);
  world_->setGravity(bt(model.settings.gravity));
  world_->getSolverInfo().m_numIterations = options.iterations;
  substeps_ = options.substeps;
  const double substep = model.settings.time_step / options.substeps;
  g_limb_friction = model.settings.limb_friction;
  gContactAddedCallback = combine_materials;
  // limber's damping: speed × exp(−damping·t); Bullet's: speed × (1 − d)^t.
  const btScalar linear_damping = btScalar(1 - std::exp(-model.settings.damping));

  // The limbs.
  for (const Body& body : model.bodies) {
    const MassProperties mass = body_mass_properties(body);
    // A diagonal tensor keeps the body frame (principal_axes would sort the moments, a needless turn).
    PrincipalAxes principal;
    const Eigen::Matrix3d off_diagonal = mass.inertia - Eigen::Matrix3d(mass.inertia.diagonal().asDiagonal());
    if (off_diagonal.norm() <= 1e-12 * mass.inertia.norm()) principal.moments = mass.inertia.diagonal();
    else principal = principal_axes(mass.inertia);
    std::unique_ptr<btCollisionShape> shape;
    const double r = body.shape.radius, half = body.shape.length / 2;
    if (body.shape.type == ShapeType::capsule || options.cylinders_as_capsules) {
      shape = std::make_unique<btCapsuleShapeZ>(btScalar(r), btScalar(body.shape.length));
    } else {
      shape = std::make_unique<btCylinderShapeZ>(btVector3(btScalar(r), btScalar(r), btScalar(half)));
    }
    // Bullet's frame: origin at the centre of mass, axes the principal axes.
    const Quaterniond principal_in_body(principal.axes);
    const btTransform principal_frame = bt(principal_in_body, mass.centre_of_mass);
    const btTransform body_in_principal = principal_frame.inverse();
    btCollisionShape* used = shape.get();
    shapes_.push_back(std::move(shape));
    if (mass.centre_of_mass.norm() > 1e-9 || principal_in_body.angularDistance(Quaterniond::Identity()) > 1e-9) {
      auto compound = std::make_unique<btCompoundShape>();
      compound->addChildShape(body_in_principal, used);
      used = compound.get();
      shapes_.push_back(std::move(compound));
      ++compound_bodies;
    }
    const Quaterniond orientation = body.orientation();
    const btTransform start = bt(orientation, body.position) * principal_frame;
    btRigidBody::btRigidBodyConstructionInfo info(btScalar(mass.mass), nullptr, used, bt(principal.moments));
    info.m_startWorldTransform = start;
    info.m_linearDamping = linear_damping;
    auto rigid = std::make_unique<btRigidBody>(info);
    const Vector3d com_offset = orientation * mass.centre_of_mass;
    rigid->setLinearVelocity(bt(Vector3d(body.linear_velocity + body.angular_velocity.cross(com_offset))));
    rigid->setAngularVelocity(bt(body.angular_velocity));
    rigid->setUserIndex(kLimb);
    rigid->setFriction(btScalar(model.settings.limb_friction));
    rigid->setRestitution(0);
    rigid->setCollisionFlags(rigid->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
    if (!options.sleep) rigid->setActivationState(DISABLE_DEACTIVATION);
    world_->addRigidBody(rigid.get(), int(body.collision.group), int(body.collision.mask));
    body_in_principal_.push_back(body_in_principal);
    limbs_.push_back(std::move(rigid));
  }
  for (const auto& [a, b] : rules.excluded) {
    limbs_[a]->setIgnoreCollisionCheck(limbs_[b].get(), true);
    limbs_[b]->setIgnoreCollisionCheck(limbs_[a].get(), true);
  }

  // The joints. Each frame is built in the world at the Model's poses, then carried into each
  // body's (principal) frame.
  auto body_of = [&](int index) -> btRigidBody& { return index == kWorld ? btTypedConstraint::getFixedBody() : *limbs_[static_cast<std::size_t>(index)]; };
  auto local = [&](int index, const btTransform& world_frame) {
    return index == kWorld ? world_frame : limbs_[static_cast<std::size_t>(index)]->getWorldTransform().inverse() * world_frame;
  };
  for (const Joint& joint : model.joints) {
    const Vector3d anchor_in = joint.inboard == kWorld ? joint.inboard_anchor : model.bodies[static_cast<std::size_t>(joint.inboard)].to_world(joint.inboard_anchor);
    const Body& outboard = model.bodies[static_cast<std::size_t>(joint.outboard)];
    const Vector3d anchor_out = outboard.to_world(joint.outboard_anchor);
    btRigidBody& a = body_of(joint.inboard);
    btRigidBody& b = *limbs_[static_cast<std::size_t>(joint.outboard)];
    std::unique_ptr<btTypedConstraint> constraint;
    switch (joint.type) {
      case JointType::spherical: {
        if (!joint.limits.swing && !joint.limits.twist) {
          const btTransform in = local(joint.inboard, bt(Quaterniond::Identity(), anchor_in));
          const btTransform out = local(joint.outboard, bt(Quaterniond::Identity(), anchor_out));
          constraint = std::make_unique<btPoint2PointConstraint>(a, b, in.getOrigin(), out.getOrigin());
          ++point_to_points;
          break;
        }
        // Twist about the outboard's axis (frame B's x); the cone about the swing axis (frame
        // A's x), frame A the shortest arc from B's x onto it, so the rest pose has no twist.
        const Vector3d twist_axis = outboard.axis;
        const Vector3d cone_axis = joint.limits.swing_axis ? joint.limits.swing_axis->normalized() : twist_axis;
        const Quaterniond frame_b = frame_with_x(twist_axis);
        const Quaterniond frame_a = Quaterniond::FromTwoVectors(twist_axis, cone_axis) * frame_b;
        // Bullet's twist span is symmetric: turn B's frame by −centre so [min, max] is centre ± span.
        double twist_span = std::numbers::pi, twist_centre = 0;
        if (joint.limits.twist) {
          twist_span = (joint.limits.twist->max - joint.limits.twist->min) / 2;
          twist_centre = (joint.limits.twist->max + joint.limits.twist->min) / 2;
        }
        const Quaterniond frame_b_centred = frame_b * Quaterniond(Eigen::AngleAxisd(-twist_centre, Vector3d::UnitX()));
        const double swing = joint.limits.swing.value_or(std::numbers::pi);
        auto cone = std::make_unique<btConeTwistConstraint>(a, b, local(joint.inboard, bt(frame_a, anchor_in)),
                                                            local(joint.outboard, bt(frame_b_centred, anchor_out)));
        cone->setLimit(btScalar(swing), btScalar(swing), btScalar(twist_span));
        constraint = std::move(cone);
        ++cone_twists;
        break;
      }
      case JointType::revolute: {
        const Quaterniond frame = frame_with_z(joint.axis.normalized());
        auto hinge = std::make_unique<btHingeConstraint>(a, b, local(joint.inboard, bt(frame, anchor_in)),
                                                         local(joint.outboard, bt(frame, anchor_out)));
        if (joint.limits.range) {
          // Calibrate the sign: turn B by +0.1 rad about the axis (limber's positive angle).
          const Quaterniond turn(Eigen::AngleAxisd(0.1, joint.axis.normalized()));
          btTransform turned_b = b.getWorldTransform();
          turned_b.setBasis(btMatrix3x3(bt(turn)) * turned_b.getBasis());
          const double sign = hinge->getHingeAngle(a.getWorldTransform(), turned_b) > 0 ? 1 : -1;
          const double low = sign * joint.limits.range->min, high = sign * joint.limits.range->max;
          hinge->setLimit(btScalar(std::min(low, high)), btScalar(std::max(low, high)));
        }
        if (joint.friction > 0) hinge->enableAngularMotor(true, 0, btScalar(joint.friction * substep));
        constraint = std::move(hinge);
        ++hinges;
        break;
      }
      case JointType::fixed:
        constraint = std::make_unique<btFixedConstraint>(a, b, local(joint.inboard, bt(Quaterniond::Identity(), anchor_in)),
                                                         local(joint.outboard, bt(Quaterniond::Identity(), anchor_out)));
        ++others;
        break;
      case JointType::universal: {
        if (joint.inboard == kWorld) throw ModelError("bullet_ragdolls: " + joint.name + ": a universal joint to the world is not mapped");
        btVector3 anchor = bt(anchor_in), axis1 = bt(joint.axis), axis2 = bt(joint.second_axis);
        constraint = std::make_unique<btUniversalConstraint>(a, b, anchor, axis1, axis2);
        ++others;
        break;
      }
      case JointType::prismatic: {
        const Quaterniond frame = frame_with_x(joint.axis.normalized());
        auto slider = std::make_unique<btSliderConstraint>(a, b, local(joint.inboard, bt(frame, anchor_in)),
                                                           local(joint.outboard, bt(frame, anchor_in)), true);
        const double low = joint.limits.range ? joint.limits.range->min : -1e30, high = joint.limits.range ? joint.limits.range->max : 1e30;
        slider->setLowerLinLimit(btScalar(low)), slider->setUpperLinLimit(btScalar(high));
        slider->setLowerAngLimit(0), slider->setUpperAngLimit(0);
        constraint = std::move(slider);
        ++others;
        break;
      }
      case JointType::serial: throw ModelError("bullet_ragdolls: " + joint.name + ": a serial joint is not mapped");
    }
    if (joint.friction > 0 && joint.type != JointType::revolute) notes.push_back("joint friction dropped: " + joint.name);
    if (joint.drive) notes.push_back("joint drive dropped: " + joint.name);
    world_->addConstraint(constraint.get(), /*disableCollisionsBetweenLinkedBodies=*/true);
    constraints_.push_back(std::move(constraint));
  }
  if (!model.gears.empty()) notes.push_back("gears dropped");

  // The world's surfaces.
  if (model.ground) {
    auto plane = std::make_unique<btStaticPlaneShape>(btVector3(0, 0, 1), btScalar(model.ground->height));
    add_static(plane.get(), btTransform::getIdentity(), model.ground->friction, model.ground->restitution, {});
    shapes_.push_back(std::move(plane));
  }
  if (model.bounds) {
    const Bounds& box = *model.bounds;
    for (int axis = 0; axis < 3; ++axis) {
      for (const double side : {1.0, -1.0}) {  // the wall at min faces +axis, the wall at max −axis
        btVector3 normal(0, 0, 0);
        normal[axis] = btScalar(side);
        const double offset = side > 0 ? box.min[axis] : -box.max[axis];
        auto plane = std::make_unique<btStaticPlaneShape>(normal, btScalar(offset));
        add_static(plane.get(), btTransform::getIdentity(), box.friction, box.restitution, {});
        shapes_.push_back(std::move(plane));
      }
    }
  }
  for (const StaticCollider& collider : model.colliders) {
    std::unique_ptr<btCollisionShape> shape;
    btTransform pose = bt(collider.orientation, collider.position);
    if (collider.type == ColliderType::box) {
      shape = std::make_unique<btBoxShape>(bt(collider.half_extents));
    } else if (collider.type == ColliderType::capsule) {
      shape = std::make_unique<btCapsuleShapeZ>(btScalar(collider.radius), btScalar(collider.length));
    } else {
      auto mesh = std::make_unique<btTriangleMesh>();
      for (const auto& triangle : collider.mesh.triangles) {
        mesh->addTriangle(bt(collider.mesh.vertices[triangle[0]]), bt(collider.mesh.vertices[triangle[1]]), bt(collider.mesh.vertices[triangle[2]]));
      }
      shape = std::make_unique<btBvhTriangleMeshShape>(mesh.get(), true);
      meshes_.push_back(std::move(mesh));
      pose = btTransform::getIdentity();
    }
    add_static(shape.get(), pose, collider.friction, collider.restitution, collider.collision);
    shapes_.push_back(std::move(shape));
  }
  if (!model.balls.empty()) {  // the first ball (the scenes compared have at most one)
    const Ball& ball = model.balls.front();
    auto sphere = std::make_unique<btSphereShape>(btScalar(ball.radius));
    const double moment = 0.4 * ball.mass * ball.radius * ball.radius;
    btRigidBody::btRigidBodyConstructionInfo info(btScalar(ball.mass), nullptr, sphere.get(), btVector3(btScalar(moment), btScalar(moment), btScalar(moment)));
    info.m_startWorldTransform = bt(Quaterniond::Identity(), ball.position);
    ball_ = std::make_unique<btRigidBody>(info);
    ball_->setLinearVelocity(bt(ball.velocity));
    ball_->setUserIndex(kBall);
    ball_->setRestitution(btScalar(ball.restitution));
    ball_->setCollisionFlags(ball_->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
    if (!options.sleep) ball_->setActivationState(DISABLE_DEACTIVATION);
    world_->addRigidBody(ball_.get());
    shapes_.push_back(std::move(sphere));
  }
}

btRigidBody* BulletScene::add_static(btCollisionShape* shape, const btTransform& pose, double friction, double restitution,
                                     const CollisionFilter& filter) {
  btRigidBody::btRigidBodyConstructionInfo info(0, nullptr, shape);
  info.m_startWorldTransform = pose;
  auto rigid = std::make_unique<btRigidBody>(info);
  rigid->setUserIndex(kStatic);
  rigid->setFriction(btScalar(friction));
  rigid->setRestitution(btScalar(restitution));
  rigid->setCollisionFlags(rigid->getCollisionFlags() | btCollisionObject::CF_CUSTOM_MATERIAL_CALLBACK);
  world_->addRigidBody(rigid.get(), int(filter.group), int(filter.mask));
  statics_.push_back(std::move(rigid));
  return statics_.back().get();
}

BulletScene::~BulletScene() {
  for (auto& constraint : constraints_) world_->removeConstraint(constraint.get());
  for (auto& limb : limbs_) world_->removeRigidBody(limb.get());
  for (auto& surface : statics_) world_->removeRigidBody(surface.get());
  if (ball_) world_->removeRigidBody(ball_.get());
  world_.reset();
  gContactAddedCallback = nullptr;
}

FramePose BulletScene::pose(std::size_t b) const {
  const btTransform frame = limbs_[b]->getWorldTransform() * body_in_principal_[b];
  return {eigen(frame.getRotation()), eigen(frame.getOrigin())};
}

bool BulletScene::finite() const {
  for (const auto& limb : limbs_) {
    const btVector3& p = limb->getWorldTransform().getOrigin();
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) return false;
  }
  return true;
}

double BulletScene::deepest_contact() {
  double deepest = 0;
  for (int m = 0; m < dispatcher_.getNumManifolds(); ++m) {
    const btPersistentManifold* manifold = dispatcher_.getInternalManifoldPointer()[m];
    for (int c = 0; c < manifold->getNumContacts(); ++c) deepest = std::max(deepest, -double(manifold->getContactPoint(c).getDistance()));
  }
  return deepest;
}

std::string BulletScene::margins() const {
  std::set<std::pair<std::string, double>> seen;
  for (const auto& shape : shapes_) seen.insert({shape->getName(), double(shape->getMargin())});
  std::string text;
  for (const auto& [name, margin] : seen) text += (text.empty() ? "" : ", ") + name + " " + std::to_string(margin).substr(0, 6);
  return text;
}

// ---------------------------------------------------------------------------------------------
// The runs.

// One engine at one setting: limber "SxN[:rows|:tree][:1t|:2t][:double|:float]" (substeps ×
// sweeps, joint solve, threads, precision) or Bullet "SxN" (substeps × iterations).
struct Setting {
  bool bullet = false;
  int substeps = 1, iterations = 10, threads = 1;
  bool tree = false, single_precision = false;
  std::string label;  // as given on the command line
  std::string name() const { return (bullet ? "Bullet " : "limber ") + label; }
};

Setting parse_setting(const std::string& text, bool bullet) {
  const auto bad = [&](const std::string& why) {
    return CLI::ValidationError(std::string(bullet ? "--bullet" : "--limber") + " " + text + ": " + why);
  };
  Setting setting;
  setting.bullet = bullet;
  setting.label = text;
  std::vector<std::string> parts;
  for (std::size_t at = 0;;) {
    const std::size_t colon = text.find(':', at);
    parts.push_back(text.substr(at, colon - at));
    if (colon == std::string::npos) break;
    at = colon + 1;
  }
  const std::size_t x = parts[0].find('x');
  try {
    std::size_t used = 0;
    setting.substeps = std::stoi(parts[0].substr(0, x), &used);
    if (x == std::string::npos || used != x) throw bad("expected SUBSTEPSxITERATIONS, like 4x10");
    setting.iterations = std::stoi(parts[0].substr(x + 1), &used);
    if (used != parts[0].size() - x - 1) throw bad("expected SUBSTEPSxITERATIONS, like 4x10");
  } catch (const std::logic_error&) {
    throw bad("expected SUBSTEPSxITERATIONS, like 4x10");
  }
  if (setting.substeps < 1 || setting.substeps > 64 || setting.iterations < 1 || setting.iterations > 1000) {
    throw bad("substeps must be in [1, 64] and iterations in [1, 1000]");
  }
  for (std::size_t k = 1; k < parts.size(); ++k) {
    if (bullet) throw bad("Bullet takes SUBSTEPSxITERATIONS only");
    if (parts[k] == "tree" || parts[k] == "rows") {
      setting.tree = parts[k] == "tree";
    } else if (parts[k] == "1t" || parts[k] == "2t") {
      setting.threads = parts[k][0] - '0';
    } else if (parts[k] == "float" || parts[k] == "double") {
      setting.single_precision = parts[k] == "float";
    } else {
      throw bad("unknown suffix \"" + parts[k] + "\" (rows, tree, 1t, 2t, double, float)");
    }
  }
  return setting;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

struct Run {
  std::vector<double> cpu, wall;  // per repetition: the sum of its step() calls, s
  double penetration = 0;         // deepest_penetration over the first repetition, m
  double contact = 0;             // Bullet: the deepest btManifoldPoint distance, m
  JointErrors joints;             // over the first repetition
  std::string status = "ok";
};

template <typename Step, typename Poses>
void run_steps(int steps, bool measure, const Model& model, LimbCollisions& collisions, const JointControls& controls, Run& run, Step&& step,
               Poses&& poses) {
  double cpu = 0, wall = 0;
  std::vector<FramePose> now(model.bodies.size());
  for (int s = 0; s < steps; ++s) {
    const double cpu_start = thread_seconds();
    const auto wall_start = Clock::now();
    const bool ok = step();
    wall += std::chrono::duration<double>(Clock::now() - wall_start).count();
    cpu += thread_seconds() - cpu_start;
    if (!ok) {
      run.status = "diverged at step " + std::to_string(s);
      break;
    }
    if (measure) {
      poses(now);
      run.penetration = std::max(run.penetration, deepest_penetration(model, collisions, now));
      const JointErrors errors = joint_errors(model, controls, now);
      run.joints.gap = std::max(run.joints.gap, errors.gap);
      if (errors.limit_violation > run.joints.limit_violation) run.joints.limit_violation = errors.limit_violation, run.joints.worst_limit = errors.worst_limit;
    }
  }
  run.cpu.push_back(cpu);
  run.wall.push_back(wall);
}

// What every setting of a race shares: the scene, its measures and the run's length.
struct Race {
  const Model& model;
  const PairRules& rules;
  LimbCollisions& collisions;
  const JointControls& controls;
  const WorldOptions& scene_world;
  int steps;
  bool sleep, capsules;
};

// The race's scene and both engines' fixed settings (Bullet's read from a world built for it).
void print_header(const std::string& scene_label, const Race& race) {
  const Model& model = race.model;
  const PairRules& rules = race.rules;
  const WorldOptions& world = race.scene_world;
  const int steps = race.steps;
  const bool sleep = race.sleep;
  BulletScene bullet(model, rules, {sleep, race.capsules});
  const btContactSolverInfo& info = bullet.solver_info();
  const double dt = model.settings.time_step;
  std::printf("# bullet_ragdolls\n\nscene: %s, %zu bodies in %zu islands (a ragdoll is one), %zu joints, Δt = %.6g s, %d steps (%.3g s), sleep %s\n",
              scene_label.c_str(), model.bodies.size(), body_islands(model).count, model.joints.size(), dt, steps, steps * dt,
              sleep ? "on" : "off (both engines)");
  std::printf("limb pairs that never collide: %zu jointed, %zu overlapping at rest, %zu filtered\n", rules.jointed, rules.overlapping, rules.filtered);
  std::printf("limber: particles, weighted Gauss-Seidel (%s), %s projection, limb masses %s, joints %s\n",
              world.particles.order == SweepOrder::coloured ? "coloured" : "sequential",
              world.particles.relaxation.projection == ProjectionRule::rattle ? "rattle" : "pbd",
              world.particles.verlet.limb_masses == LimbMasses::ends ? "ends" : world.particles.verlet.limb_masses == LimbMasses::inertia ? "inertia" : "lumps",
              world.particles.verlet.joints == ParticleJoints::shared_particle ? "shared particles" : "zero-length constraints");
  std::printf("Bullet %d.%02d (%s precision): btDiscreteDynamicsWorld, btSequentialImpulseConstraintSolver, ERP %.2g, ERP2 %.2g, "
              "split impulse %s (threshold %.3g m), warm starting %.2g, linear slop %.3g m, contact breaking threshold %.3g m, "
              "substeps as stepSimulation(Δt / substeps, 0) each\n",
              btGetVersion() / 100, btGetVersion() % 100, sizeof(btScalar) == 4 ? "single" : "double", double(info.m_erp), double(info.m_erp2),
              info.m_splitImpulse ? "on" : "off", double(info.m_splitImpulsePenetrationThreshold), double(info.m_warmstartingFactor),
              double(info.m_linearSlop), double(gContactBreakingThreshold));
  std::printf("Bullet shapes (collision margins, m): %s; %d compound (centre of mass off the shape's centre)\n", bullet.margins().c_str(),
              bullet.compound_bodies);
  std::printf("Bullet joints: %d btConeTwistConstraint, %d btHingeConstraint, %d btPoint2PointConstraint, %d other\n", bullet.cone_twists,
              bullet.hinges, bullet.point_to_points, bullet.others);
  std::size_t shown = 0;
  for (const std::string& note : bullet.notes) {
    if (shown++ < 3) std::printf("Bullet note: %s\n", note.c_str());
  }
  if (bullet.notes.size() > 3) std::printf("Bullet note: ... %zu in all\n", bullet.notes.size());
  std::fflush(stdout);
}

// One run of `setting`: a fresh world stepped race.steps times, timed into `run` (and, with
// `measure`, its joint errors and penetration).
void run_setting(const Race& race, const Setting& setting, bool measure, Run& run) {
  const double dt = race.model.settings.time_step;
  if (setting.bullet) {
    BulletScene bullet(race.model, race.rules, {race.sleep, race.capsules, setting.substeps, setting.iterations});
    run_steps(
        race.steps, measure, race.model, race.collisions, race.controls, run,
        [&] {
          bullet.step(dt);
          return bullet.finite();
        },
        [&](std::vector<FramePose>& poses) {
          run.contact = std::max(run.contact, bullet.deepest_contact());
          for (std::size_t b = 0; b < poses.size(); ++b) poses[b] = bullet.pose(b);
        });
    return;
  }
  WorldOptions world = race.scene_world;
  world.particles.threads = setting.threads;
  world.particles.relaxation.substeps = setting.substeps;
  world.particles.relaxation.iterations = setting.iterations;
  world.particles.verlet.joint_solve = setting.tree ? JointSolve::tree : JointSolve::rows;
  world.single_precision = setting.single_precision;
  World limber_world(race.model, world);
  const std::vector<BodyId> ids = limber_world.bodies();
  run_steps(race.steps, measure, race.model, race.collisions, race.controls, run, [&] { return limber_world.step(dt) == StepStatus::ok; },
            [&](std::vector<FramePose>& poses) {
              for (std::size_t b = 0; b < ids.size(); ++b) {
                const Pose pose = limber_world.pose(ids[b]);
                poses[b] = {pose.orientation, pose.position};
              }
            });
}

int run(int argc, char** argv) {
  CLI::App app{"Ragdolls in limber's particle method and in Bullet's btRigidBody, settings raced in one run: steps/s against joint gap and penetration"};
  const std::filesystem::path source = LIMBER_SOURCE_DIR;
  std::string scene_path;
  std::optional<int> stack, steps_flag, copies;
  int repeats = 3;
  bool sleep = false;
  std::string cylinders = "cylinder";
  std::vector<std::string> limber_texts, bullet_texts{"1x10"};
  app.add_option("scene", scene_path, "scene file (default tools/scenes/ragdoll_pile.json, or ragdoll.json --stack 32 while it is missing)");
  app.add_option("--stack", stack, "stack this many copies of the scene's bodies, each on its back, in crossed layers of four")->check(CLI::Range(1, 100000));
  app.add_option("--copies", copies, "the scene's copies count (its \"copies\" layout)")->check(CLI::Range(1, 100000));
  app.add_option("--steps", steps_flag, "steps per run (default: the scene's duration / time step)")->check(CLI::PositiveNumber);
  app.add_option("--repeats", repeats, "timed runs of each setting, interleaved; the median is reported")->check(CLI::Range(1, 100));
  app.add_option("--limber", limber_texts,
                 "limber settings SxN[:rows|:tree][:1t|:2t][:double|:float]: substeps × sweeps, joint solve, threads, precision "
                 "(default: the scene's settings, double)");
  app.add_option("--bullet", bullet_texts, "Bullet settings SxN: substeps × iterations (default 1x10, Bullet's own)");
  app.add_flag("--sleep", sleep, "let islands sleep (limber) and bodies deactivate (Bullet); default: both off");
  app.add_option("--cylinders", cylinders, "Bullet shape of cylinder limbs")->check(CLI::IsMember({"cylinder", "capsule"}));
  CLI11_PARSE(app, argc, argv);

  if (scene_path.empty()) {
    scene_path = (source / "tools/scenes/ragdoll_pile.json").string();
    if (!std::filesystem::exists(scene_path)) {
      scene_path = (source / "tools/scenes/ragdoll.json").string();
      if (!stack) stack = 32;
    }
  }
  SceneOptions scene_options;
  if (copies) scene_options.copies = *copies;
  Scene scene = load_scene_file(scene_path, scene_options);
  if (stack) scene.model = stack_ragdolls(scene.model, static_cast<std::size_t>(*stack));
  Model& model = scene.model;
  model.settings.sleep.enabled = sleep;
  const double dt = model.settings.time_step;
  const int steps = steps_flag.value_or(static_cast<int>(std::lround(model.settings.duration / dt)));
  model.balls.clear();  // not measured by deepest_penetration; the piles have none
  const PairRules rules = pair_rules(model);
  LimbCollisions collisions(model);
  const JointControls controls = joint_controls(model);
  const WorldOptions scene_world = world_options(Method::particles, scene.methods);
  const std::string scene_label = scene_path + (stack ? " stacked ×" + std::to_string(*stack) : "") +
                                  (copies ? " (" + std::to_string(*copies) + " copies)" : "");

  std::vector<Setting> settings;
  try {
    if (limber_texts.empty()) {
      const auto& relaxation = scene_world.particles.relaxation;
      limber_texts.push_back(std::to_string(relaxation.substeps) + "x" + std::to_string(relaxation.iterations) +
                             (scene_world.particles.verlet.joint_solve == JointSolve::tree ? ":tree" : ":rows"));
    }
    for (const std::string& text : limber_texts) settings.push_back(parse_setting(text, false));
    for (const std::string& text : bullet_texts) settings.push_back(parse_setting(text, true));
  } catch (const CLI::Error& error) {
    return app.exit(error);
  }

  const Race race{model, rules, collisions, controls, scene_world, steps, sleep, cylinders == "capsule"};
  print_header(scene_label, race);
  std::vector<Run> runs(settings.size());
  for (int rep = 0; rep < repeats; ++rep) {
    for (std::size_t k = 0; k < settings.size(); ++k) {
      if (runs[k].status != "ok") continue;  // diverged: not timed again
      run_setting(race, settings[k], rep == 0, runs[k]);
      std::fprintf(stderr, "round %d: %s %.2f s\n", rep + 1, settings[k].name().c_str(), runs[k].cpu.back());
    }
  }

  // Cost per island (a ragdoll) per 1/60 s of simulated time, from the stepping thread's CPU time.
  const double per_body_per_frame = (1.0 / 60) / dt / double(body_islands(model).count);
  std::printf("\n| engine and setting | steps/s (CPU) | steps/s (wall) | µs per ragdoll per 1/60 s (CPU) | largest joint gap (m) | "
              "largest limit violation (rad) | deepest penetration (m) | Bullet contact distance (m) | status |\n"
              "|---|---|---|---|---|---|---|---|---|\n");
  for (std::size_t k = 0; k < settings.size(); ++k) {
    const Run& run = runs[k];
    const double cpu = median(run.cpu) / steps, wall = median(run.wall) / steps;
    char contact[32] = "—";
    if (settings[k].bullet) std::snprintf(contact, sizeof contact, "%.3g", run.contact);
    std::printf("| %s%s | %.3g | %.3g | %.0f | %.3g | %.3g | %.3g | %s | %s |\n", settings[k].name().c_str(),
                settings[k].bullet ? "" : (settings[k].threads == 1 ? ", 1 thread" : ", 2 threads"), 1 / cpu, 1 / wall,
                1e6 * cpu * per_body_per_frame, run.joints.gap, run.joints.limit_violation, run.penetration, contact, run.status.c_str());
  }
  std::printf("\nmedian of %d interleaved runs each; the CPU time is the stepping thread's (a second thread's work is in wall time only)\n",
              repeats);
  bool ok = true;
  for (const Run& run : runs) ok = ok && run.status == "ok";
  return ok ? 0 : 1;
}

}  // namespace
}  // namespace limber

int main(int argc, char** argv) {
  try {
    return limber::run(argc, argv);
  } catch (const limber::ModelError& error) {
    std::fprintf(stderr, "bullet_ragdolls: %s\n", error.what());
    return 2;
  }
}
