#include "limber/kernel/model/model.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <limits>
#include <numeric>
#include <string>
#include <unordered_set>

#include "limber/kernel/model/capabilities.hpp"
#include "limber/kernel/model/checks.hpp"
#include "limber/kernel/model/step_status.hpp"
#include "limber/layouts/graph/disjoint_sets.hpp"

namespace limber {

using namespace checks;

double volume(const Shape& shape) {
  const double r = shape.radius;
  const double cylinder = std::numbers::pi * r * r * shape.length;
  switch (shape.type) {
    case ShapeType::cylinder:
      return cylinder;
    case ShapeType::capsule:
      return cylinder + 4.0 / 3.0 * std::numbers::pi * r * r * r;
    case ShapeType::box:
      return 8 * shape.half_extents.prod();
    case ShapeType::ellipsoid:
      return 4.0 / 3.0 * std::numbers::pi * shape.half_extents.prod();
  }
  return cylinder;
}

std::string_view shape_type_name(ShapeType type) {
  switch (type) {
    case ShapeType::cylinder: return "cylinder";
    case ShapeType::capsule: return "capsule";
    case ShapeType::box: return "box";
    case ShapeType::ellipsoid: return "ellipsoid";
  }
  return "unknown";
}

std::string_view joint_type_name(JointType type) {
  switch (type) {
    case JointType::spherical: return "spherical";
    case JointType::revolute: return "revolute";
    case JointType::prismatic: return "prismatic";
    case JointType::universal: return "universal";
    case JointType::fixed: return "fixed";
    case JointType::serial: return "serial";
  }
  return "unknown";
}

Eigen::Quaterniond Body::orientation() const {
  return Eigen::Quaterniond::FromTwoVectors(Vector3::UnitZ(), axis);
}

Vector3 Body::to_world(const Vector3& local_point) const {
  return position + orientation() * local_point;
}

Vector3 Body::velocity_at(const Vector3& local_point) const {
  return linear_velocity + angular_velocity.cross(orientation() * local_point);
}

int Model::find_body(std::string_view body_name) const {
  for (std::size_t i = 0; i < bodies.size(); ++i)
    if (bodies[i].name == body_name) return static_cast<int>(i);
  return -1;
}

double Model::body_mass() const {
  return std::accumulate(bodies.begin(), bodies.end(), 0.0,
                         [](double sum, const Body& body) { return sum + body.mass; });
}

void append_model(Model& model, const Model& other, std::string_view prefix, const Vector3& offset) {
  const int first = static_cast<int>(model.bodies.size()), first_joint = static_cast<int>(model.joints.size());
  const std::string lead(prefix);
  for (Body body : other.bodies) {
    body.name = lead + body.name, body.position += offset;
    model.bodies.push_back(std::move(body));
  }
  for (Joint joint : other.joints) {
    joint.name = lead + joint.name;
    if (joint.inboard == kWorld) {
      joint.inboard_anchor += offset;
    } else {
      joint.inboard += first;
    }
    joint.outboard += first;
    for (SerialAxis& axis : joint.serial_axes) axis.point += offset;
    model.joints.push_back(std::move(joint));
  }
  for (Gear gear : other.gears) {
    gear.name = lead + gear.name, gear.first += first, gear.second += first;
    model.gears.push_back(std::move(gear));
  }
  for (Actuator actuator : other.actuators) {
    actuator.name = lead + actuator.name, actuator.joint += first_joint;
    model.actuators.push_back(std::move(actuator));
  }
}

BodyIslands body_islands(const Model& model) {
  const auto body_count = static_cast<std::uint32_t>(model.bodies.size());
  DisjointSets connected(body_count);
  for (const Joint& joint : model.joints) {
    if (joint.inboard != kWorld) connected.unite(static_cast<std::uint32_t>(joint.inboard), static_cast<std::uint32_t>(joint.outboard));
  }
  for (const Gear& gear : model.gears) connected.unite(static_cast<std::uint32_t>(gear.first), static_cast<std::uint32_t>(gear.second));
  // The representative is the lowest body of its set, so it is met before the rest of its set.
  BodyIslands islands;
  islands.island_of_body.resize(body_count);
  for (std::uint32_t b = 0; b < body_count; ++b) {
    const std::uint32_t root = connected.find(b);
    islands.island_of_body[b] = root == b ? static_cast<std::uint32_t>(islands.count++) : islands.island_of_body[root];
  }
  return islands;
}

namespace {

constexpr double kPi = std::numbers::pi;

// "<collection>[index].<field>", built only when a check fails.
auto field_path(const char* collection, std::size_t index) {
  return [collection, index](const char* field) {
    return [collection, index, field] { return indexed(collection, index) + "." + field; };
  };
}

/// A physical inertia tensor: finite, symmetric, principal moments positive and each at most
/// the sum of the other two (equality: a flat body).
template <typename Path>
void validate_inertial(const Body& body, const Path& path) {
  const Inertial& inertial = *body.inertial;
  if (!body.point_masses.empty()) fail(path("inertial"), "give either inertial or point_masses, not both");
  require_finite(inertial.centre_of_mass, [&] { return path("inertial")() + ".centre_of_mass"; });
  const Eigen::Matrix3d& tensor = inertial.inertia;
  const auto inertia_path = [&] { return path("inertial")() + ".inertia"; };
  if (!tensor.allFinite()) fail(inertia_path, "must be finite");
  const double scale = tensor.diagonal().cwiseAbs().maxCoeff();
  if (!((tensor - tensor.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * scale)) fail(inertia_path, "must be symmetric");
  const Eigen::Vector3d moments = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(tensor, Eigen::EigenvaluesOnly).eigenvalues();
  if (!(moments[0] > 0)) fail(inertia_path, "must be positive definite, smallest principal moment " + format_number(moments[0]));
  if (moments[0] + moments[1] < moments[2] * (1 - 1e-12)) {
    fail(inertia_path, "principal moments " + format_vector(moments) + " break the triangle inequality I1 + I2 >= I3 (no body has them)");
  }
}

// What the methods derive from a body must be finite too, or they fail or step to NaN: its
// inverse mass 1/m, the squares of its extent (a particle limb's constraint, the rigid bodies'
// inertia m·extent²) and its kinetic energy (m·|v|², I·|ω|²). Refused at the field that makes
// one of them overflow, e.g. a capsule 1e300 m long, or a spin of 1e300 rad/s.
template <typename Path>
void require_finite_derived(const Body& body, const Path& path) {
  if (!std::isfinite(1 / body.mass)) {
    fail(path("mass"), "must be large enough that 1/mass is a finite number, got " + format_number(body.mass));
  }
  const auto overflows = [](double value) { return !std::isfinite(value); };
  const bool boxlike = has_half_extents(body.shape);
  const double shape_extent = boxlike ? 2 * bounding_radius(body.shape) : body.shape.length + 2 * body.shape.radius;
  if (overflows(shape_extent * shape_extent) || overflows(body.mass * shape_extent * shape_extent)) {
    const std::string size = boxlike ? "half_extents " + format_vector(body.shape.half_extents) + " m"
                                     : "length " + format_number(body.shape.length) + " m and radius " + format_number(body.shape.radius) + " m";
    fail(path("shape"), size + " with mass " + format_number(body.mass) +
                            " kg: the body's extent squared, or its inertia (mass × extent²), is not a finite number");
  }
  double extent = shape_extent;  // from the centre of mass outwards, twice over: a bound on the inertia's lever arm
  for (std::size_t k = 0; k < body.point_masses.size(); ++k) {
    const PointMass& lump = body.point_masses[k];
    const double reach = 2 * (lump.position.norm() + lump.radius);
    if (overflows(reach * reach) || overflows(body.mass * reach * reach)) {
      fail([&] { return indexed(path("point_masses")(), k); },
           "position " + format_vector(lump.position) + " m and radius " + format_number(lump.radius) +
               " m: the body's inertia (mass × distance²) is not a finite number");
    }
    extent = std::max(extent, reach);
  }
  const double inertia = body.mass * extent * extent + (body.inertial ? body.inertial->inertia.trace() : 0.0);
  if (overflows(body.mass * body.linear_velocity.squaredNorm())) {
    fail(path("linear_velocity"), "with mass " + format_number(body.mass) + " kg, its kinetic energy (m·|v|²/2) is not a finite number");
  }
  if (overflows(inertia * body.angular_velocity.squaredNorm())) {
    fail(path("angular_velocity"), "its rotational kinetic energy (about I·|ω|²/2, I ≈ " + format_number(inertia) +
                                       " kg·m²) is not a finite number");
  }
}

// A shape's own fields: a cylinder's or capsule's length and radius, a box's or ellipsoid's
// half-extents and rotation, and the other type's fields left at zero (never silently ignored).
template <typename Path>
void validate_shape(const Shape& shape, const Path& path) {
  const auto unused = [&](const char* field, std::string_view uses) {
    const char* article = shape.type == ShapeType::ellipsoid ? "an " : "a ";
    fail(path(field), article + std::string(shape_type_name(shape.type)) + " has " + std::string(uses) + ", not this field; leave it out");
  };
  if (has_half_extents(shape)) {
    if (shape.length != 0) unused("shape.length", "half_extents");
    if (shape.radius != 0) unused("shape.radius", "half_extents");
    for (std::size_t k = 0; k < 3; ++k) {
      require_positive(shape.half_extents[static_cast<int>(k)], [&] { return indexed(path("shape.half_extents")(), k); });
    }
    const Eigen::Vector4d q = shape.rotation.coeffs();
    if (!q.allFinite() || !(std::abs(q.norm() - 1) <= 1e-9)) fail(path("shape.rotation"), "must be a unit quaternion");
    return;
  }
  if (!shape.half_extents.isZero(0)) unused("shape.half_extents", "a length and a radius");
  if (shape.rotation.coeffs() != Eigen::Quaterniond::Identity().coeffs()) unused("shape.rotation", "its axis along the body's");
  if (shape.type == ShapeType::capsule) {
    require_non_negative(shape.length, path("shape.length"));
    if (shape.length == 0) require_positive(shape.radius, path("shape.radius"));  // a sphere
  } else {
    require_positive(shape.length, path("shape.length"));
  }
  require_non_negative(shape.radius, path("shape.radius"));
}

void validate_body(const Body& body, std::size_t index) {
  const auto path = field_path("bodies", index);
  require_name(body.name, path("name"), /*is_body=*/true);
  validate_shape(body.shape, path);
  require_positive(body.mass, path("mass"));
  double point_mass_sum = 0;
  for (std::size_t k = 0; k < body.point_masses.size(); ++k) {
    const PointMass& lump = body.point_masses[k];
    const auto lump_path = [&](const char* field) {
      return [&, field] { return indexed(path("point_masses")(), k) + "." + field; };
    };
    require_finite(lump.position, lump_path("position"));
    require_positive(lump.mass, lump_path("mass"));
    require_non_negative(lump.radius, lump_path("radius"));
    point_mass_sum += lump.mass;
  }
  if (!body.point_masses.empty() && std::abs(point_mass_sum - body.mass) > 1e-12 * point_mass_sum) {
    fail(path("mass"), "must equal the sum of point_masses' masses, " + format_number(point_mass_sum) + ", got " +
                           format_number(body.mass));
  }
  if (body.inertial) validate_inertial(body, path);
  require_finite(body.position, path("position"));
  require_unit(body.axis, path("axis"));
  require_finite(body.linear_velocity, path("linear_velocity"));
  require_finite(body.angular_velocity, path("angular_velocity"));
  require_finite_derived(body, path);
}

template <typename Path>
void require_body_index(int index, std::size_t body_count, const Path& path) {
  if (index < 0 || static_cast<std::size_t>(index) >= body_count) {
    fail(path, "names body index " + std::to_string(index) + " but there are " +
                   std::to_string(body_count) + " bodies");
  }
}

// Limits, friction and drive: each only on the joint types that have the coordinate.
template <typename Path>
void validate_joint_controls(const Joint& joint, const Model& model, const Path& path) {
  const JointLimits& limits = joint.limits;
  const std::string type(joint_type_name(joint.type));
  const auto refuse = [&](const char* field, std::string_view uses) {
    fail(path(field), "is not used by a " + type + " joint (" + std::string(uses) + ")");
  };
  const auto require_range = [&](const Range& range, const char* field, double bound) {
    const std::string at = path_text(path(field));
    if (bound > 0) {
      require_in_range(range.min, -bound, 0, at + ".min", /*low_open=*/true);
      require_in_range(range.max, 0, bound, at + ".max", false, /*high_open=*/true);
    } else {
      require_finite(range.min, at + ".min"), require_finite(range.max, at + ".max");
      if (!(range.min <= 0)) fail(at + ".min", "must be <= 0 (the rest pose is the slide's zero), got " + format_number(range.min));
      if (!(range.max >= 0)) fail(at + ".max", "must be >= 0 (the rest pose is the slide's zero), got " + format_number(range.max));
    }
  };
  const bool spherical = joint.type == JointType::spherical;
  if (limits.swing) {
    if (!spherical) refuse("limits.swing", "swing and twist limit spherical joints");
    require_in_range(*limits.swing, 0, kPi, path("limits.swing"), /*low_open=*/true, /*high_open=*/true);
  }
  if (limits.swing_axis) {
    if (!limits.swing) fail(path("limits.swing_axis"), "needs limits.swing (the cone's half-angle)");
    require_unit(*limits.swing_axis, path("limits.swing_axis"));
    const Vector3 outboard_axis = model.bodies[static_cast<std::size_t>(joint.outboard)].axis;
    const double rest_swing = std::acos(std::clamp(limits.swing_axis->dot(outboard_axis), -1.0, 1.0));
    if (rest_swing >= *limits.swing) {
      fail(path("limits.swing_axis"), "the outboard body's axis at rest is " + format_number(rest_swing) +
                                          " rad from it, outside the cone of half-angle " + format_number(*limits.swing) + " rad");
    }
  }
  if (limits.twist) {
    if (!spherical) refuse("limits.twist", "swing and twist limit spherical joints");
    require_range(*limits.twist, "limits.twist", kPi);
  }
  if (limits.range) {
    if (joint.type != JointType::revolute && joint.type != JointType::prismatic) {
      refuse("limits.range", "range limits revolute and prismatic joints; spherical joints take swing and twist");
    }
    require_range(*limits.range, "limits.range", joint.type == JointType::revolute ? kPi : 0);
  }
  require_non_negative(joint.friction, path("friction"));
  if (joint.friction > 0 && joint.type == JointType::fixed) refuse("friction", "a fixed joint does not move");
  if (const auto& drive = joint.drive) {
    if (joint.type != JointType::spherical && joint.type != JointType::revolute && joint.type != JointType::prismatic) {
      refuse("drive", "drives act on spherical, revolute and prismatic joints");
    }
    require_non_negative(drive->stiffness, path("drive.stiffness"));
    require_non_negative(drive->damping, path("drive.damping"));
    require_finite(drive->target, path("drive.target"));
    require_finite(drive->target_velocity, path("drive.target_velocity"));
    require_finite(drive->target_rotation, path("drive.target_rotation"));
    require_finite(drive->target_angular_velocity, path("drive.target_angular_velocity"));
    if (!(drive->target_rotation.norm() < kPi)) {
      fail(path("drive.target_rotation"), "must turn by less than pi rad, got " + format_number(drive->target_rotation.norm()));
    }
    if (!spherical && (drive->target_rotation != Vector3::Zero() || drive->target_angular_velocity != Vector3::Zero())) {
      fail(path("drive.target_rotation"), "is for spherical joints; a " + type + " joint's drive takes target and target_velocity");
    }
    if (spherical && (drive->target != 0 || drive->target_velocity != 0)) {
      fail(path("drive.target"), "is for revolute and prismatic joints; a spherical joint's drive takes target_rotation");
    }
  }
}

// A serial joint's axes: 1 to 6, each with its own range, drive, friction and armature; the
// joint-wide controls are per axis instead.
template <typename Path>
void validate_serial_axes(const Joint& joint, const Path& path) {
  if (joint.serial_axes.empty() || joint.serial_axes.size() > 6) {
    fail(path("serial_axes"), "must hold 1 to 6 axes, got " + std::to_string(joint.serial_axes.size()));
  }
  for (std::size_t a = 0; a < joint.serial_axes.size(); ++a) {
    const SerialAxis& axis = joint.serial_axes[a];
    const auto at = [&](const char* field) {
      return [&, field] { return indexed(path("serial_axes")(), a) + "." + field; };
    };
    require_name(axis.name, at("name"), /*is_body=*/false);
    require_unit(axis.axis, at("axis"));
    require_finite(axis.point, at("point"));
    if (axis.range) {
      const std::string range = at("range")();
      const double bound = axis.slide ? std::numeric_limits<double>::infinity() : kPi;
      require_in_range(axis.range->min, -bound, 0, range + ".min", /*low_open=*/true);
      require_in_range(axis.range->max, 0, bound, range + ".max", false, /*high_open=*/true);
    }
    require_non_negative(axis.friction, at("friction"));
    require_non_negative(axis.armature, at("armature"));
    if (const auto& drive = axis.drive) {
      require_non_negative(drive->stiffness, at("drive.stiffness"));
      require_non_negative(drive->damping, at("drive.damping"));
      require_finite(drive->target, at("drive.target"));
      require_finite(drive->target_velocity, at("drive.target_velocity"));
      if (drive->target_rotation != Vector3::Zero() || drive->target_angular_velocity != Vector3::Zero()) {
        fail(at("drive.target_rotation"), "is for spherical joints; an axis's drive takes target and target_velocity");
      }
    }
  }
  if (joint.limits.any() || joint.friction > 0 || joint.drive) {
    fail(path(joint.drive ? "drive" : joint.friction > 0 ? "friction" : "limits"),
         "is per axis on a serial joint (serial_axes[i].range, .friction, .drive)");
  }
}

void check_joint(const Joint& joint, const Model& model, std::size_t index) {
  const std::size_t body_count = model.bodies.size();
  const auto path = field_path("joints", index);
  require_name(joint.name, path("name"), /*is_body=*/false);
  if (joint.inboard != kWorld) require_body_index(joint.inboard, body_count, path("inboard"));
  require_body_index(joint.outboard, body_count, path("outboard"));
  if (joint.inboard == joint.outboard) {
    fail(path("outboard"), "must differ from inboard, both are body index " + std::to_string(joint.inboard));
  }
  require_finite(joint.inboard_anchor, path("inboard_anchor"));
  require_finite(joint.outboard_anchor, path("outboard_anchor"));
  if (joint.stiffness) require_positive(*joint.stiffness, path("stiffness"));
  if (joint.damping) require_non_negative(*joint.damping, path("damping"));
  validate_joint_controls(joint, model, path);
  require_non_negative(joint.armature, path("armature"));
  if (joint.armature > 0 && joint.type != JointType::revolute && joint.type != JointType::prismatic) {
    fail(path("armature"), "is for revolute and prismatic joints (a serial joint's is per axis), not " +
                               std::string(joint_type_name(joint.type)));
  }
  if (joint.type == JointType::serial) {
    validate_serial_axes(joint, path);
    return;
  }
  if (!joint.serial_axes.empty()) fail(path("serial_axes"), "is for serial joints, not " + std::string(joint_type_name(joint.type)));
  if (joint.type == JointType::spherical || joint.type == JointType::fixed) return;
  require_unit(joint.axis, path("axis"));
  if (joint.type != JointType::universal) return;
  require_unit(joint.second_axis, path("second_axis"));
  if (std::abs(joint.axis.dot(joint.second_axis)) > 1e-6) {
    fail(path("second_axis"), "must be perpendicular to axis (their dot product is " +
                                  format_number(joint.axis.dot(joint.second_axis)) + ")");
  }
}

// An actuator: a joint coordinate that exists and moves, a finite gear, a range min ≤ max.
void validate_actuator(const Actuator& actuator, const Model& model, std::size_t index) {
  const auto path = field_path("actuators", index);
  require_name(actuator.name, path("name"), /*is_body=*/false);
  if (actuator.joint < 0 || static_cast<std::size_t>(actuator.joint) >= model.joints.size()) {
    fail(path("joint"), "names joint index " + std::to_string(actuator.joint) + " but there are " + std::to_string(model.joints.size()) + " joints");
  }
  const Joint& joint = model.joints[static_cast<std::size_t>(actuator.joint)];
  if (joint.type != JointType::revolute && joint.type != JointType::prismatic && joint.type != JointType::serial) {
    fail(path("joint"), "names '" + joint.name + "', a " + std::string(joint_type_name(joint.type)) +
                            " joint: an actuator drives a revolute, prismatic or serial joint's coordinate");
  }
  const std::size_t axes = joint.type == JointType::serial ? joint.serial_axes.size() : 1;
  if (actuator.axis < 0 || static_cast<std::size_t>(actuator.axis) >= axes) {
    fail(path("axis"), "must be in [0, " + std::to_string(axes) + ") for '" + joint.name + "', got " + std::to_string(actuator.axis));
  }
  require_finite(actuator.gear, path("gear"));
  require_finite(actuator.reference, path("reference"));
  if (!(actuator.gain >= 0) || !std::isfinite(actuator.gain)) fail(path("gain"), "must be finite and >= 0, got " + format_number(actuator.gain));
  if (actuator.kind == ActuatorKind::motor && actuator.gain != 0) fail(path("gain"), "a motor has no gain (its force is gear x control)");
  if (const auto& range = actuator.control_range) {
    require_finite(range->min, path("control_range.min")), require_finite(range->max, path("control_range.max"));
    if (!(range->min <= range->max)) fail(path("control_range"), "min must be <= max, got [" + format_number(range->min) + ", " + format_number(range->max) + "]");
  }
}

void validate_gear(const Gear& gear, std::size_t body_count, std::size_t index) {
  const auto path = field_path("gears", index);
  require_name(gear.name, path("name"), /*is_body=*/false);
  require_body_index(gear.first, body_count, path("first"));
  require_body_index(gear.second, body_count, path("second"));
  if (gear.first == gear.second) {
    fail(path("second"), "must differ from first, both are body index " + std::to_string(gear.first));
  }
  require_unit(gear.first_axis, path("first_axis"));
  require_unit(gear.second_axis, path("second_axis"));
  require_finite(gear.ratio, path("ratio"));
  if (gear.ratio == 0) fail(path("ratio"), "must not be 0 (the second gear would be held still)");
}

// A static collider: the fields its type uses, and the surface's coefficients. Fields another
// type uses are not looked at (a box's radius means nothing).
void validate_collider(const StaticCollider& collider, std::size_t index) {
  const auto path = field_path("colliders", index);
  require_name(collider.name, path("name"), /*is_body=*/false);
  require_finite(collider.position, path("position"));
  const Eigen::Vector4d rotation = collider.orientation.coeffs();
  for (int k = 0; k < 4; ++k) require_finite(rotation[k], [&] { return path("orientation")() + ".coeffs[" + std::to_string(k) + "]"; });
  if (!(std::abs(rotation.norm() - 1) <= 1e-6)) {
    fail(path("orientation"), "must be a unit quaternion (normalize it), got norm " + format_number(rotation.norm()));
  }
  switch (collider.type) {
    case ColliderType::box:
      for (int axis = 0; axis < 3; ++axis) {
        require_positive(collider.half_extents[axis], [&] { return indexed(path("half_extents")(), static_cast<std::size_t>(axis)); });
      }
      break;
    case ColliderType::capsule:
      require_non_negative(collider.length, path("length"));
      require_positive(collider.radius, path("radius"));
      break;
    case ColliderType::mesh:
      require_triangle_mesh(collider.mesh, path("mesh.vertices")(), path("mesh.triangles")());
      require_positive(collider.thickness, path("thickness"));
      break;
    default:
      fail(path("type"), "is not a collider type (box, capsule or mesh), got " + std::to_string(static_cast<int>(collider.type)));
  }
  require_in_range(collider.restitution, 0, 1, path("restitution"));
  require_non_negative(collider.friction, path("friction"));
}

// Collider names: unique among the colliders, and no body's name either, so a name in a contact
// report or a World lookup means one thing.
void require_collider_names(const Model& model) {
  const auto name_of = [](const StaticCollider& collider) -> std::string_view { return collider.name; };
  require_unique_names(model.colliders, name_of, "colliders");
  if (model.colliders.empty()) return;
  std::unordered_set<std::string_view> body_names;
  body_names.reserve(model.bodies.size());
  for (const Body& body : model.bodies) body_names.insert(body.name);
  for (std::size_t c = 0; c < model.colliders.size(); ++c) {
    if (body_names.contains(model.colliders[c].name)) {
      fail(indexed("colliders", c) + ".name", "\"" + model.colliders[c].name + "\" is also a body's name");
    }
  }
}

void validate_settings(const Settings& settings) {
  require_finite(settings.gravity, "settings.gravity");
  require_positive(settings.time_step, "settings.time_step");
  if (settings.time_step < kMinimumTimeStep) {
    fail("settings.time_step", "must be >= " + format_number(kMinimumTimeStep) + " s (the shortest step a method takes), got " +
                                   format_number(settings.time_step));
  }
  require_positive(settings.duration, "settings.duration");
  require_non_negative(settings.damping, "settings.damping");
  require_positive(settings.divergence_speed, "settings.divergence_speed");
  require_non_negative(settings.contact_recovery_speed, "settings.contact_recovery_speed");
  require_non_negative(settings.limb_friction, "settings.limb_friction");
  for (int axis = 0; axis < 3; ++axis) {
    require_non_negative(settings.drag.linear[axis], [axis] { return indexed("settings.drag.linear", axis); });
    require_non_negative(settings.drag.angular[axis], [axis] { return indexed("settings.drag.angular", axis); });
  }
  require_non_negative(settings.sleep.speed_threshold, "settings.sleep.speed_threshold");
  require_non_negative(settings.sleep.time_to_sleep, "settings.sleep.time_to_sleep");
  const Tolerances& tolerances = settings.tolerances;
  require_non_negative(tolerances.joint_gap, "settings.tolerances.joint_gap");
  if (tolerances.penetration) require_non_negative(*tolerances.penetration, "settings.tolerances.penetration");
  require_non_negative(tolerances.limit, "settings.tolerances.limit");
  if (tolerances.energy_gain) require_non_negative(*tolerances.energy_gain, "settings.tolerances.energy_gain");
}

// The names of the methods whose capability row passes `has`, "a, b".
template <typename Has>
std::string methods_where(Has has) {
  std::string names;
  for (const MethodCapabilities& row : kMethodCapabilities) {
    if (has(row)) names += (names.empty() ? "" : ", ") + std::string(method_name(row.method));
  }
  return names;
}

}  // namespace

void validate(const Model& model) {
  for (std::size_t i = 0; i < model.bodies.size(); ++i) validate_body(model.bodies[i], i);
  require_unique_names(model.bodies, [](const Body& body) -> std::string_view { return body.name; }, "bodies");
  for (std::size_t i = 0; i < model.joints.size(); ++i) check_joint(model.joints[i], model, i);
  require_unique_names(model.joints, [](const Joint& joint) -> std::string_view { return joint.name; }, "joints");
  for (std::size_t i = 0; i < model.gears.size(); ++i) validate_gear(model.gears[i], model.bodies.size(), i);
  require_unique_names(model.gears, [](const Gear& gear) -> std::string_view { return gear.name; }, "gears");
  for (std::size_t i = 0; i < model.actuators.size(); ++i) validate_actuator(model.actuators[i], model, i);
  require_unique_names(model.actuators, [](const Actuator& actuator) -> std::string_view { return actuator.name; }, "actuators");

  if (const auto& ground = model.ground) {
    require_finite(ground->height, "ground.height");
    require_in_range(ground->restitution, 0, 1, "ground.restitution");
    require_non_negative(ground->friction, "ground.friction");
  }

  if (const auto& bounds = model.bounds) {
    require_box(bounds->min, bounds->max, "bounds");
    require_in_range(bounds->restitution, 0, 1, "bounds.restitution");
    require_non_negative(bounds->friction, "bounds.friction");
  }

  for (std::size_t i = 0; i < model.balls.size(); ++i) {
    const Ball& ball = model.balls[i];
    const std::string field = "balls[" + std::to_string(i) + "].";
    require_in_range(ball.radius, 0, kMaxBallRadius, field + "radius", /*low_open=*/true);
    require_in_range(ball.mass, 0, kMaxBallMass, field + "mass", /*low_open=*/true);
    require_in_range(ball.restitution, 0, 1, field + "restitution");
    require_finite(ball.position, field + "position");
    require_finite(ball.velocity, field + "velocity");
  }

  for (std::size_t i = 0; i < model.colliders.size(); ++i) validate_collider(model.colliders[i], i);
  require_collider_names(model);

  validate_settings(model.settings);
}

std::string ball_name(const Model& model, std::size_t index) {
  return model.balls.size() == 1 ? std::string("ball") : "ball" + std::to_string(index);
}

void require_supported(const Model& model, Method method) {
  const MethodCapabilities& row = capabilities(method);
  const std::string name(method_name(method));
  std::string names;
  for (std::size_t t = 0; t < row.joints.size(); ++t) {
    if (row.joints[t]) names += (names.empty() ? "" : ", ") + std::string(joint_type_name(static_cast<JointType>(t)));
  }
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    if (row.joints[static_cast<std::size_t>(joint.type)]) continue;
    const std::string others = methods_where([&](const MethodCapabilities& other) { return other.joints[static_cast<std::size_t>(joint.type)]; });
    throw ModelError("joints[" + std::to_string(j) + "] '" + joint.name + "': the " + name + " method does not support " +
                     std::string(joint_type_name(joint.type)) + " joints (it supports " + names + "; " + others + " " +
                     (others.find(',') == std::string::npos ? "does" : "do") + ")");
  }
  for (std::size_t b = 0; b < model.bodies.size() && !row.spheres; ++b) {
    const Shape& shape = model.bodies[b].shape;
    if (shape.type != ShapeType::capsule || shape.length > 0) continue;
    throw ModelError("bodies[" + std::to_string(b) + "] '" + model.bodies[b].name + "': the " + name +
                     " method does not support spheres (a capsule of length 0: its springs need an axis); particles, lagrange and featherstone do");
  }
  if (!row.gears && !model.gears.empty()) {
    throw ModelError("gears[0] '" + model.gears[0].name + "': the " + name + " method does not support gears (velocity constraints); lagrange does");
  }
  for (std::size_t a = 0; a < model.actuators.size(); ++a) require_actuator_supported(model, method, a, 0);
}

void require_actuator_supported(const Model& model, Method method, std::size_t index, double control) {
  const Actuator& actuator = model.actuators.at(index);
  const Joint& joint = model.joints.at(static_cast<std::size_t>(actuator.joint));
  if (capabilities(method).serial_actuators || joint.type != JointType::serial || joint.serial_axes.size() < 2) return;
  if (actuator.kind == ActuatorKind::motor && control == 0) return;  // no force
  const std::string others = methods_where([](const MethodCapabilities& other) { return other.serial_actuators; });
  throw ModelError("actuators[" + std::to_string(index) + "] '" + actuator.name + "': the " + std::string(method_name(method)) +
                   " method does not drive an axis of serial joint '" + joint.name + "' (" + std::to_string(joint.serial_axes.size()) +
                   " axes in one body: its virtual links move the body wrongly under a joint force); " + others + " do");
}

void validate_joint(const Model& model, std::size_t index) { check_joint(model.joints.at(index), model, index); }

void validate_joint(const Joint& joint, const Model& model, std::size_t index) { check_joint(joint, model, index); }

void require_joint_controls(const Model& model, JointControlSupport supported, std::string_view method) {
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    bool limits = joint.limits.any(), friction = joint.friction > 0, drives = joint.drive.has_value(), armature = joint.armature > 0;
    for (const SerialAxis& axis : joint.serial_axes) {
      limits |= axis.range.has_value(), friction |= axis.friction > 0, drives |= axis.drive.has_value(), armature |= axis.armature > 0;
    }
    const char* missing = limits && !supported.limits       ? "joint limits"
                          : friction && !supported.friction ? "joint friction"
                          : drives && !supported.drives     ? "joint drives"
                          : armature && !supported.armature ? "joint armature"
                                                            : nullptr;
    if (missing) {
      throw ModelError("joints[" + std::to_string(j) + "] '" + joint.name + "': the " + std::string(method) +
                       " method does not apply " + missing);
    }
  }
}

}  // namespace limber
