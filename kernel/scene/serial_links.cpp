#include "limber/kernel/scene/serial_links.hpp"

#include <algorithm>
#include <string>
#include <string_view>
#include <unordered_map>

#include "limber/kernel/mass/mass_properties.hpp"

namespace limber {
namespace {

// A point's coordinates in a body's frame (the world's for kWorld).
Vector3 in_frame(const Model& model, int body, const Vector3& world) {
  if (body == kWorld) return world;
  const Body& b = model.bodies[static_cast<std::size_t>(body)];
  return b.orientation().conjugate() * (world - b.position);
}

// A link's length where its two axes meet: a quarter of the outboard's length (its diameter for
// a sphere, its longest side for a box or ellipsoid, whose length is 0), so that a particle limb
// has an axis to hold a frame on.
double link_length(const Body& outboard) {
  const Shape& shape = outboard.shape;
  return 0.25 * (has_half_extents(shape) ? 2 * shape.half_extents.maxCoeff() : std::max(shape.length, 2 * shape.radius));
}

// The revolute or prismatic joint of one axis between `inboard` and `outboard`, anchored at the
// world point `at` (on the axis).
Joint axis_joint(const Model& model, std::string name, const SerialAxis& axis, int inboard, int outboard, const Vector3& at) {
  Joint joint;
  joint.name = std::move(name);
  joint.type = axis.slide ? JointType::prismatic : JointType::revolute;
  joint.inboard = inboard, joint.outboard = outboard;
  joint.inboard_anchor = in_frame(model, inboard, at);
  joint.outboard_anchor = in_frame(model, outboard, at);
  joint.axis = axis.axis;
  joint.limits.range = axis.range;
  joint.drive = axis.drive;
  joint.friction = axis.friction;
  joint.armature = axis.armature;
  return joint;
}

// Link i of a serial joint: from axis i's point to the nearest point of axis i + 1 (skew axes,
// such as an ankle's), or where they meet, along axis i + 1. Returns the link and the anchor of
// axis i + 1 on it (world).
std::pair<Body, Vector3> virtual_link(const Joint& joint, std::size_t i, const Body& outboard, double mass) {
  const SerialAxis &here = joint.serial_axes[i], &next = joint.serial_axes[i + 1];
  const Vector3 from = here.point;
  const Vector3 nearest = next.point + (from - next.point).dot(next.axis) * next.axis;  // on axis i + 1
  const double length = link_length(outboard);
  Vector3 to = nearest;
  if ((nearest - from).norm() < 0.25 * length) to = from + length * next.axis;
  Body link;
  link.name = joint.name + "/link" + std::to_string(i);
  link.shape = {ShapeType::cylinder, (to - from).norm(), 0.25 * (to - from).norm()};
  link.mass = mass;
  link.position = 0.5 * (from + to);
  link.axis = (to - from).normalized();
  link.linear_velocity = outboard.linear_velocity + outboard.angular_velocity.cross(link.position - outboard.position);
  link.angular_velocity = outboard.angular_velocity;
  link.collision = {0, 0};  // collides with nothing; its joints pass on (LimbCollisions)
  return {link, nearest};
}

// Scales a body's mass and its distribution by `factor` (its centre of mass stays).
void scale_mass(Body& body, double factor) {
  body.mass *= factor;
  for (PointMass& lump : body.point_masses) lump.mass *= factor;
  if (body.inertial) body.inertial->inertia *= factor;
}

// A hinge's armature a as a rotor on its outboard body: a solid disc's inertia about the axis
// (a) and across it (a/2), added to the body's tensor about its centre of mass.
void add_rotor(Body& body, const Vector3& world_axis, double armature) {
  const MassProperties properties = body_mass_properties(body);
  const Vector3 s = body.orientation().conjugate() * world_axis;
  Inertial inertial{properties.centre_of_mass, properties.inertia};
  inertial.inertia += armature * (0.5 * Eigen::Matrix3d::Identity() + 0.5 * s * s.transpose());
  body.inertial = inertial;
  body.point_masses.clear();
}

}  // namespace

bool needs_serial_expansion(const Model& model, Armature armature) {
  return std::any_of(model.joints.begin(), model.joints.end(), [armature](const Joint& joint) {
    return joint.type == JointType::serial || (armature == Armature::as_rotor && joint.type == JointType::revolute && joint.armature > 0);
  });
}

CoordinateAxes CoordinateAxes::of(const SerialExpansion& expansion) {
  CoordinateAxes axes = of(expansion.model);
  axes.first_added_joint = expansion.first_added_joint;
  return axes;
}

CoordinateAxes CoordinateAxes::of(const Model& model) {
  CoordinateAxes axes;
  axes.first_added_joint.assign(model.joints.size(), 0);
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    const Body& outboard = model.bodies[static_cast<std::size_t>(joint.outboard)];
    axes.joints.push_back({joint.inboard, joint.outboard, outboard.orientation().conjugate() * joint.axis, joint.type == JointType::prismatic,
                           joint, joint_frame(model, j)});
  }
  return axes;
}

std::size_t model_joint_of(const Model& model, std::size_t expanded) {
  std::size_t next = model.joints.size();  // the first added joint of the next serial joint
  for (std::size_t j = 0; j < model.joints.size() && next <= expanded; ++j) {
    if (model.joints[j].type != JointType::serial) continue;
    next += model.joints[j].serial_axes.size() - 1;
    if (expanded < next) return j;
  }
  return expanded;
}

std::vector<std::int64_t> with_virtual_links(const Model& old_model, const Model& fresh, std::vector<std::int64_t> old_body_of_new) {
  std::unordered_map<std::string_view, std::pair<std::int64_t, std::size_t>> old_links;  // joint name → first link, axes
  auto next = static_cast<std::int64_t>(old_model.bodies.size());
  for (const Joint& joint : old_model.joints) {
    if (joint.type != JointType::serial) continue;
    old_links.emplace(joint.name, std::pair{next, joint.serial_axes.size()});
    next += static_cast<std::int64_t>(joint.serial_axes.size()) - 1;
  }
  for (const Joint& joint : fresh.joints) {
    if (joint.type != JointType::serial) continue;
    const auto found = old_links.find(joint.name);
    const bool same = found != old_links.end() && found->second.second == joint.serial_axes.size();
    for (std::size_t i = 0; i + 1 < joint.serial_axes.size(); ++i) {
      old_body_of_new.push_back(same ? found->second.first + static_cast<std::int64_t>(i) : -1);
    }
  }
  return old_body_of_new;
}

SerialExpansion expand_serial_joints(const Model& model, Armature armature, double link_mass_share) {
  SerialExpansion result;
  result.model = model;
  result.first_added_joint.assign(model.joints.size(), 0);
  Model& out = result.model;
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    if (joint.type != JointType::serial) continue;
    const std::size_t k = joint.serial_axes.size();
    const Body& outboard = model.bodies[static_cast<std::size_t>(joint.outboard)];
    const double link_mass = link_mass_share * outboard.mass;
    result.first_added_joint[j] = static_cast<std::uint32_t>(out.joints.size());
    int inboard = joint.inboard;
    Vector3 at = joint.serial_axes[0].point;
    std::vector<Joint> chain;
    for (std::size_t i = 0; i + 1 < k; ++i) {
      auto [link, next_at] = virtual_link(joint, i, outboard, link_mass);
      out.bodies.push_back(std::move(link));
      const int link_index = static_cast<int>(out.bodies.size() - 1);
      chain.push_back(axis_joint(out, i == 0 ? joint.name : joint.name + "/" + joint.serial_axes[i].name, joint.serial_axes[i],
                                 inboard, link_index, at));
      inboard = link_index, at = next_at;
    }
    if (k > 1) scale_mass(out.bodies[static_cast<std::size_t>(joint.outboard)], 1 - static_cast<double>(k - 1) * link_mass_share);
    chain.push_back(axis_joint(out, k == 1 ? joint.name : joint.name + "/" + joint.serial_axes[k - 1].name, joint.serial_axes[k - 1],
                               inboard, joint.outboard, at));
    out.joints[j] = chain.front();
    out.joints.insert(out.joints.end(), chain.begin() + 1, chain.end());
  }
  for (Actuator& actuator : out.actuators) {  // each on its axis's joint
    actuator.joint = static_cast<int>(result.joint_of_axis(static_cast<std::size_t>(actuator.joint), actuator.axis));
    actuator.axis = 0;
  }
  for (Joint& joint : out.joints) {
    if (armature != Armature::as_rotor || joint.type != JointType::revolute || !(joint.armature > 0)) continue;
    add_rotor(out.bodies[static_cast<std::size_t>(joint.outboard)], joint.axis, joint.armature);
    joint.armature = 0;
  }
  return result;
}

}  // namespace limber
