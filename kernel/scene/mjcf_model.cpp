#include "limber/kernel/scene/mjcf_model.hpp"

#include "limber/kernel/scene/inertial_import.hpp"
#include "limber/kernel/scene/mjcf_reader.hpp"
#include "limber/kernel/scene/model_origins.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

namespace limber {
namespace {

using Isometry = Eigen::Isometry3d;

// "FILE:LINE: <element>", where a problem is.
std::string origin(const mjcf::Source& at, const std::string& element) {
  return at.file + ":" + std::to_string(at.line) + ": <" + element + ">";
}

// "FILE:LINE: <element>: problem" as a ModelError.
[[noreturn]] void refuse(const mjcf::Source& at, const std::string& element, const std::string& problem) {
  throw ModelError(origin(at, element) + ": " + problem);
}

Isometry pose(const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation) {
  Isometry x = Isometry::Identity();
  x.linear() = orientation.normalized().toRotationMatrix();
  x.translation() = position;
  return x;
}

// Each MJCF body's frame in the world at the file's pose (qpos0).
std::vector<Isometry> world_frames(const mjcf::Document& document) {
  std::vector<Isometry> frames;
  frames.reserve(document.bodies.size());
  for (const mjcf::Body& body : document.bodies) {
    const Isometry local = pose(body.position, body.orientation);
    frames.push_back(body.parent < 0 ? local : frames[static_cast<std::size_t>(body.parent)] * local);
  }
  return frames;
}

std::string geom_element(const mjcf::Geom& geom) {
  static constexpr const char* kNames[] = {"plane", "sphere", "capsule", "cylinder", "box", "ellipsoid"};
  return "geom" + (geom.name.empty() ? std::string() : " name='" + geom.name + "'") + " type=" + kNames[static_cast<int>(geom.type)];
}

// A geom of a moving body as a limber body at its world pose, with the geom's mass over its shape.
// A box's or ellipsoid's body axis is its longest (the particle method's capsule proxy lies
// along it, capsule_proxy.hpp), its own frame the geom's.
Body geom_body(const mjcf::Geom& geom, const Isometry& body_frame, std::string name) {
  Body body;
  body.name = std::move(name);
  if (!(geom.mass > 0)) refuse(geom.at, geom_element(geom), "a moving body's geom needs a mass > 0 (mass or density)");
  const Isometry world = body_frame * pose(geom.position, geom.orientation);
  if (!world.translation().allFinite()) {
    refuse(geom.at, geom_element(geom), "its world position is not finite: the pos of its body and the bodies above overflow when added up");
  }
  body.mass = geom.mass;
  body.position = world.translation();
  int along = 2;  // the geom frame's axis that is the body's
  switch (geom.type) {
    case mjcf::GeomType::sphere: body.shape = {ShapeType::capsule, 0, geom.size[0]}; break;
    case mjcf::GeomType::capsule: body.shape = {ShapeType::capsule, 2 * geom.size[1], geom.size[0]}; break;
    case mjcf::GeomType::cylinder: body.shape = {ShapeType::cylinder, 2 * geom.size[1], geom.size[0]}; break;
    case mjcf::GeomType::box:
    case mjcf::GeomType::ellipsoid:
      body.shape.type = geom.type == mjcf::GeomType::box ? ShapeType::box : ShapeType::ellipsoid;
      body.shape.half_extents = geom.size;
      geom.size.maxCoeff(&along);
      break;
    case mjcf::GeomType::plane: refuse(geom.at, geom_element(geom), "a plane must belong to the worldbody");
  }
  body.axis = world.linear().col(along).normalized();
  if (has_half_extents(body.shape)) {
    body.shape.rotation = (body.orientation().conjugate() * Eigen::Quaterniond(world.linear())).normalized();
  }
  body.collision = {static_cast<std::uint32_t>(geom.contype), static_cast<std::uint32_t>(geom.conaffinity)};
  if (geom.contype != geom.conaffinity) {
    refuse(geom.at, geom_element(geom),
           "contype and conaffinity differ: limber's filter needs both directions (MuJoCo's either); not supported yet");
  }
  return body;
}

// An explicit <inertial> moved into a one-geom body's limber frame.
void take_inertial(Body& body, const mjcf::Body& source, const Isometry& body_frame) {
  body.mass = source.mass;
  body.inertial = inertial_in_body_frame(body, body_frame * source.centre_of_mass, body_frame.linear(), source.inertia);
}

// A fixed joint between two limber bodies (or a body and the world) at `point` (world, m).
Joint weld(std::string name, const Model& model, int inboard, int outboard, const Eigen::Vector3d& point) {
  Joint joint;
  joint.name = std::move(name);
  joint.type = JointType::fixed;
  joint.inboard = inboard, joint.outboard = outboard;
  const Body& out = model.bodies[static_cast<std::size_t>(outboard)];
  joint.outboard_anchor = out.orientation().conjugate() * (point - out.position);
  joint.inboard_anchor = inboard == kWorld ? point
                                           : Eigen::Vector3d(model.bodies[static_cast<std::size_t>(inboard)].orientation().conjugate() *
                                                             (point - model.bodies[static_cast<std::size_t>(inboard)].position));
  return joint;
}

std::string joint_element(const mjcf::Joint& joint) { return "joint" + (joint.name.empty() ? std::string() : " name='" + joint.name + "'"); }

// A hinge's or slide's limit in limber's coordinate (q − ref), holding 0 and within (−π, π) for a hinge.
std::optional<Range> axis_range(const mjcf::Joint& joint) {
  if (!joint.limited) return std::nullopt;
  const Range range{joint.range_min - joint.ref, joint.range_max - joint.ref};
  if (!(range.min <= 0 && range.max >= 0)) {
    refuse(joint.at, joint_element(joint), "range [" + std::to_string(joint.range_min) + ", " + std::to_string(joint.range_max) +
                                               "] does not hold the initial pose (ref " + std::to_string(joint.ref) + ")");
  }
  if (joint.type == mjcf::JointType::hinge && !(range.min > -std::numbers::pi && range.max < std::numbers::pi)) {
    refuse(joint.at, joint_element(joint), "a hinge range past ±180° from its initial pose is not supported");
  }
  return range;
}

// MuJoCo's passive spring and damper, −k(q − springref) − c·q̇, as a drive in limber's coordinate.
std::optional<JointDrive> axis_drive(const mjcf::Joint& joint) {
  if (!(joint.stiffness > 0) && !(joint.damping > 0)) return std::nullopt;
  JointDrive drive;
  drive.stiffness = joint.stiffness, drive.damping = joint.damping;
  drive.target = joint.springref - joint.ref;
  return drive;
}

// The joints of MJCF body `source` as one limber joint from `inboard` (kWorld or a body) to `outboard`.
Joint body_joint(const mjcf::Body& source, const Isometry& frame, const Model& model, int inboard, int outboard) {
  const auto at_world = [&](const Eigen::Vector3d& local) -> Eigen::Vector3d { return frame * local; };
  const auto direction = [&](const Eigen::Vector3d& local) -> Eigen::Vector3d { return (frame.linear() * local).normalized(); };
  const mjcf::Joint& first = source.joints.front();
  Joint joint = weld(first.name.empty() ? source.name + ".joint" : first.name, model, inboard, outboard, at_world(first.position));
  if (source.joints.size() == 1 && first.type != mjcf::JointType::slide && first.type != mjcf::JointType::hinge) {
    if (first.type != mjcf::JointType::ball) refuse(first.at, joint_element(first), "a free joint must be a body's only joint");
    if (first.limited) refuse(first.at, joint_element(first), "a ball joint's range (a rotation-angle limit) is not supported yet");
    if (first.stiffness > 0 || first.frictionloss > 0 || first.armature > 0) {
      refuse(first.at, joint_element(first), "a ball joint's stiffness, frictionloss and armature are not supported yet");
    }
    joint.type = JointType::spherical;
    if (first.damping > 0) joint.drive = JointDrive{.damping = first.damping};
    return joint;
  }
  if (source.joints.size() == 1) {
    joint.type = first.type == mjcf::JointType::hinge ? JointType::revolute : JointType::prismatic;
    joint.axis = direction(first.axis);
    joint.limits.range = axis_range(first);
    joint.drive = axis_drive(first);
    joint.friction = first.frictionloss, joint.armature = first.armature;
    return joint;
  }
  joint.type = JointType::serial;
  joint.name.clear();
  for (const mjcf::Joint& each : source.joints) {
    if (each.type != mjcf::JointType::hinge && each.type != mjcf::JointType::slide) {
      refuse(each.at, joint_element(each), "a ball or free joint must be its body's only joint");
    }
    SerialAxis axis;
    axis.name = each.name.empty() ? source.name + ".axis" + std::to_string(joint.serial_axes.size()) : each.name;
    axis.slide = each.type == mjcf::JointType::slide;
    axis.axis = direction(each.axis), axis.point = at_world(each.position);
    axis.range = axis_range(each), axis.drive = axis_drive(each);
    axis.friction = each.frictionloss, axis.armature = each.armature;
    joint.name += (joint.name.empty() ? "" : "+") + axis.name;
    joint.serial_axes.push_back(axis);
  }
  // The outboard anchor is the last axis's point (Joint::serial_axes).
  const Body& out = model.bodies[static_cast<std::size_t>(outboard)];
  joint.outboard_anchor = out.orientation().conjugate() * (joint.serial_axes.back().point - out.position);
  return joint;
}

// The world's own geoms: a plane facing +z is the ground; capsules and boxes are static colliders.
void add_world_geoms(const mjcf::Document& document, Model& model, double body_friction, ModelOrigins& origins) {
  for (const mjcf::Geom& geom : document.world_geoms) {
    const Isometry world = pose(geom.position, geom.orientation);
    const Eigen::Vector3d normal = world.linear() * Eigen::Vector3d::UnitZ();
    if (geom.type == mjcf::GeomType::plane) {
      if (model.ground) refuse(geom.at, geom_element(geom), "a second plane: limber has one ground");
      if (normal.z() < 1 - 1e-12) refuse(geom.at, geom_element(geom), "a plane that does not face +z is not supported");
      model.ground = Ground{.height = geom.position.z(), .restitution = 0, .friction = std::max(geom.friction[0], body_friction)};
      continue;
    }
    StaticCollider collider;
    collider.name = geom.name.empty() ? "world.geom" + std::to_string(model.colliders.size()) : geom.name;
    collider.position = world.translation();
    collider.orientation = Eigen::Quaterniond(world.linear());
    collider.friction = std::max(geom.friction[0], body_friction);
    collider.collision = {static_cast<std::uint32_t>(geom.contype), static_cast<std::uint32_t>(geom.conaffinity)};
    if (geom.type == mjcf::GeomType::box) {
      collider.type = ColliderType::box, collider.half_extents = geom.size;
    } else if (geom.type == mjcf::GeomType::capsule) {
      collider.type = ColliderType::capsule, collider.radius = geom.size[0], collider.length = 2 * geom.size[1];
    } else {
      refuse(geom.at, geom_element(geom), "a world geom must be a plane, capsule or box");
    }
    model.colliders.push_back(collider);
    origins.colliders.push_back(origin(geom.at, geom_element(geom)));
  }
}

// One MJCF body's limber bodies (a geom each), welds between them, and its joint to its parent.
// Returns its own (first) limber body.
int add_body(const mjcf::Body& source, const Isometry& frame, int parent, Model& model, ModelOrigins& origins) {
  const std::string body_element = "body name='" + source.name + "'";
  if (source.geoms.empty()) refuse(source.at, body_element, "a body without geoms is not supported yet");
  const int own = static_cast<int>(model.bodies.size());
  for (std::size_t g = 0; g < source.geoms.size(); ++g) {
    const mjcf::Geom& geom = source.geoms[g];
    std::string name = g == 0 ? source.name : source.name + "/" + (geom.name.empty() ? "geom" + std::to_string(g) : geom.name);
    model.bodies.push_back(geom_body(geom, frame, std::move(name)));
    origins.bodies.push_back(origin(geom.at, geom_element(geom)));
  }
  if (source.explicit_inertial) {
    if (source.geoms.size() > 1) refuse(source.at, body_element, "an <inertial> on a body of several geoms is not supported yet");
    take_inertial(model.bodies.back(), source, frame);
    origins.bodies.back() = origin(source.at, body_element);  // the mass distribution is the body's <inertial>
  }
  for (std::size_t g = 1; g < source.geoms.size(); ++g) {
    const int part = own + static_cast<int>(g);
    model.joints.push_back(weld(model.bodies[part].name + ".weld", model, own, part, model.bodies[part].position));
    origins.joints.push_back(origin(source.geoms[g].at, geom_element(source.geoms[g])));
  }
  const bool free = source.joints.size() == 1 && source.joints.front().type == mjcf::JointType::free;
  if (free) {
    if (parent != kWorld) refuse(source.joints.front().at, joint_element(source.joints.front()), "a free joint is only for a child of the worldbody");
  } else if (source.joints.empty()) {
    model.joints.push_back(weld(source.name + ".weld", model, parent, own, frame.translation()));
    origins.joints.push_back(origin(source.at, body_element));
  } else {
    model.joints.push_back(body_joint(source, frame, model, parent, own));
    origins.joints.push_back(origin(source.joints.front().at, joint_element(source.joints.front())));
  }
  return own;
}

// Friction between limbs and against the world: MuJoCo mixes a pair by the larger of the two
// geoms' and a pair with condim 1 is frictionless.
void set_friction(const mjcf::Document& document, Model& model, std::vector<std::string>& notes, double& body_friction) {
  body_friction = 0;
  bool any_frictional = false, mixed = false;
  double first = -1;
  for (const mjcf::Body& body : document.bodies) {
    for (const mjcf::Geom& geom : body.geoms) {
      body_friction = std::max(body_friction, geom.friction[0]);
      any_frictional = any_frictional || geom.condim > 1;
      mixed = mixed || (first >= 0 && geom.friction[0] != first);
      first = geom.friction[0];
    }
  }
  model.settings.limb_friction = any_frictional ? body_friction : 0;
  if (mixed) {
    notes.push_back(document.file + ": <geom friction>: the body geoms' frictions differ; limber takes the largest, " +
                    std::to_string(body_friction) + ", for every limb (per-geom friction is not supported yet)");
  }
}

// A <motor>, <position> or <velocity> on a hinge or slide: the joint (and serial axis) that
// holds its coordinate, its kind and gain, and the joint's ref (MuJoCo's length is gear·qpos).
std::string actuator_element(const mjcf::Actuator& source) {
  const char* kinds[] = {"motor", "position", "velocity"};
  return std::string(kinds[static_cast<int>(source.type)]) + (source.name.empty() ? "" : " name='" + source.name + "'");
}

Actuator actuator(const mjcf::Document& document, const mjcf::Actuator& source, const Model& model, const std::vector<int>& joint_of) {
  const std::string element = actuator_element(source);
  if (source.forcelimited) refuse(source.at, element, "forcerange is not supported yet (ctrlrange is)");
  const mjcf::Joint& joint = document.bodies[static_cast<std::size_t>(source.joint_body)].joints[static_cast<std::size_t>(source.joint)];
  if (joint.type != mjcf::JointType::hinge && joint.type != mjcf::JointType::slide) {
    refuse(source.at, element, "an actuator on a ball or free joint is not supported yet (hinges and slides are)");
  }
  Actuator actuator;
  actuator.name = source.name.empty() ? "actuator" + std::to_string(model.actuators.size()) : source.name;
  actuator.joint = joint_of[static_cast<std::size_t>(source.joint_body)];
  actuator.axis = model.joints[static_cast<std::size_t>(actuator.joint)].type == JointType::serial ? source.joint : 0;
  actuator.gear = source.gear;
  switch (source.type) {
    case mjcf::ActuatorType::motor: break;
    case mjcf::ActuatorType::position: actuator.kind = ActuatorKind::position, actuator.gain = source.kp, actuator.reference = joint.ref; break;
    case mjcf::ActuatorType::velocity: actuator.kind = ActuatorKind::velocity, actuator.gain = source.kv; break;
  }
  if (source.ctrllimited) actuator.control_range = Range{source.ctrl_min, source.ctrl_max};
  return actuator;
}

}  // namespace

Model model_from_mjcf(const mjcf::Document& document, std::vector<std::string>& notes) {
  Model model;
  notes.insert(notes.end(), document.notes.begin(), document.notes.end());
  model.name = document.model_name.empty() ? "mjcf" : document.model_name;
  model.settings.time_step = document.timestep;
  model.settings.gravity = document.gravity;
  model.settings.sleep.enabled = false;  // MuJoCo never puts a body to sleep
  double body_friction = 0;
  set_friction(document, model, notes, body_friction);
  const std::vector<Isometry> frames = world_frames(document);
  std::vector<int> own(document.bodies.size(), kWorld), joint_of(document.bodies.size(), -1);
  ModelOrigins origins;
  for (std::size_t b = 0; b < document.bodies.size(); ++b) {
    const mjcf::Body& source = document.bodies[b];
    const int parent = source.parent < 0 ? kWorld : own[static_cast<std::size_t>(source.parent)];
    if (source.name.empty()) {  // limber's bodies are named: an unnamed one takes MuJoCo's body id
      mjcf::Body named = source;
      named.name = "body" + std::to_string(b + 1);
      own[b] = add_body(named, frames[b], parent, model, origins);
    } else {
      own[b] = add_body(source, frames[b], parent, model, origins);
    }
    const bool jointed = !source.joints.empty() && source.joints.front().type != mjcf::JointType::free;
    if (jointed) joint_of[b] = static_cast<int>(model.joints.size()) - 1;  // add_body adds the body's joint last
  }
  add_world_geoms(document, model, body_friction, origins);
  for (const mjcf::Actuator& each : document.actuators) {
    model.actuators.push_back(actuator(document, each, model, joint_of));
    origins.actuators.push_back(origin(each.at, actuator_element(each)));
  }
  validate_model_from(model, origins, document.file);
  return model;
}

}  // namespace limber
