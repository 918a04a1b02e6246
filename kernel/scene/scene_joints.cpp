// The scene loader's joints, gears and actuators (format in scene_file.hpp): every joint type,
// a serial joint's axes, and the motors on joint coordinates. As in scene_file.cpp, every value is
// checked as it is read, with paths in the file's own terms ("joints[2].serial_axes[1].range").
#include <algorithm>
#include <iterator>
#include <string>
#include <unordered_map>
#include <vector>

#include "limber/kernel/model/checks.hpp"
#include "limber/kernel/scene/scene_json.hpp"

namespace limber::scene_json {

namespace {

/// "head" | "tail" (the axis end points of `shape`, a cylinder or capsule) or a 3-vector; a world
/// point when `shape` is null (inboard "world").
Vector3 read_anchor(const Json& value, const std::string& path, const Shape* shape) {
  if (value.is_string()) {
    const std::string end = value.get<std::string>();
    if (!shape) {
      fail(path,
           "must be a world point [x, y, z] when inboard is \"world\", got " + in_quotes(end));
    }
    // Both ends of a box or ellipsoid are its centre (model.hpp's Shape): a name that says an end
    // and means the middle is refused.
    if (has_half_extents(*shape) && (end == "head" || end == "tail")) {
      fail(path, "must be a body-frame point [x, y, z] on " + a_shape(shape->type) + ", which has no " + end + ", got " + in_quotes(end));
    }
    if (end == "head") return {0, 0, 0.5 * shape->length};
    if (end == "tail") return {0, 0, -0.5 * shape->length};
    fail(path, "must be \"head\", \"tail\" or [x, y, z], got " + in_quotes(end));
  }
  return read_vector(value, path);
}

/// The index of the body that field `key` names, or kWorld for "world" where that is allowed.
int read_body_name(const Object& object, const std::string& key, const std::unordered_map<std::string, int>& body_index,
                   bool world_allowed) {
  const std::string name = object.string(key);
  if (name == "world") {
    if (!world_allowed) fail(object.path(key), "must name a body, not \"world\"");
    return kWorld;
  }
  const auto found = body_index.find(name);
  if (found == body_index.end()) fail(object.path(key), "no body named " + in_quotes(name));
  return found->second;
}

/// [min, max]: two finite numbers (the Model's validation checks their bounds).
Range read_range(const Json& value, const std::string& path) {
  if (!value.is_array() || value.size() != 2) fail(path, "must be [min, max], two numbers");
  Range range{read_number(value[0], path + "[0]"), read_number(value[1], path + "[1]")};
  if (range.min > range.max) fail(path, "min must be <= max, got [" + format_number(range.min) + ", " + format_number(range.max) + "]");
  return range;
}

JointLimits read_limits(const Object& object) {
  object.allow_only({"swing", "swing_axis", "twist", "range"});
  JointLimits limits;
  if (object.find("swing")) limits.swing = object.number("swing");
  if (object.find("swing_axis")) limits.swing_axis = object.direction("swing_axis");
  if (const Json* twist = object.find("twist")) limits.twist = read_range(*twist, object.path("twist"));
  if (const Json* range = object.find("range")) limits.range = read_range(*range, object.path("range"));
  return limits;
}

JointDrive read_drive(const Object& object) {
  object.allow_only({"stiffness", "damping", "target", "target_velocity", "target_rotation", "target_angular_velocity"});
  JointDrive drive;
  object.optional("stiffness", drive.stiffness);
  object.optional("damping", drive.damping);
  object.optional("target", drive.target);
  object.optional("target_velocity", drive.target_velocity);
  object.optional("target_rotation", drive.target_rotation);
  object.optional("target_angular_velocity", drive.target_angular_velocity);
  return drive;
}

/// One entry of a serial joint's "serial_axes" (model.hpp's SerialAxis).
SerialAxis read_serial_axis(const Object& object) {
  object.allow_only({"name", "slide", "axis", "point", "range", "drive", "friction", "armature"});
  SerialAxis axis;
  axis.name = object.string("name");
  if (const Json* slide = object.find("slide")) axis.slide = read_bool(*slide, object.path("slide"));
  axis.axis = object.direction("axis");
  axis.point = read_vector(object.at("point"), object.path("point"));
  if (const Json* range = object.find("range")) axis.range = read_range(*range, object.path("range"));
  if (const Json* drive = object.find("drive")) axis.drive = read_drive(Object(*drive, object.path("drive")));
  object.optional("friction", axis.friction);
  object.optional("armature", axis.armature);
  return axis;
}

}  // namespace

Joint read_joint(const Object& object, const std::vector<BodySpec>& bodies,
                 const std::unordered_map<std::string, int>& body_index) {
  object.allow_only({"name", "type", "inboard", "outboard", "inboard_anchor", "outboard_anchor", "axis", "second_axis",
                     "stiffness", "damping", "limits", "friction", "drive", "armature", "serial_axes"});
  Joint joint;
  joint.name = object.string("name");
  require_name(joint.name, object.path("name"), /*is_body=*/false);
  const std::string type = object.string("type");
  constexpr JointType kTypes[] = {JointType::spherical, JointType::revolute, JointType::prismatic, JointType::universal,
                                  JointType::fixed, JointType::serial};
  const auto known = std::find_if(std::begin(kTypes), std::end(kTypes), [&](JointType t) { return joint_type_name(t) == type; });
  if (known == std::end(kTypes)) {
    fail(object.path("type"),
         "must be \"spherical\", \"revolute\", \"prismatic\", \"universal\", \"fixed\" or \"serial\", got " + in_quotes(type));
  }
  joint.type = *known;
  // Axes: required exactly where the type uses them, refused elsewhere (a stray axis is a mistake).
  const bool uses_axis = joint.type != JointType::spherical && joint.type != JointType::fixed && joint.type != JointType::serial;
  const bool uses_second_axis = joint.type == JointType::universal;
  if (!uses_axis && object.find("axis")) fail(object.path("axis"), "is not used by a " + type + " joint");
  if (!uses_second_axis && object.find("second_axis")) fail(object.path("second_axis"), "is used by universal joints only");
  if (uses_axis) joint.axis = object.direction("axis");
  if (uses_second_axis) joint.second_axis = object.direction("second_axis");

  joint.inboard = read_body_name(object, "inboard", body_index, /*world_allowed=*/true);
  joint.outboard = read_body_name(object, "outboard", body_index, /*world_allowed=*/false);
  if (joint.inboard == joint.outboard) {
    fail(object.path("outboard"),
         "must differ from inboard, both are " + in_quotes(bodies[joint.outboard].body.name));
  }

  const Shape* inboard_shape =
      joint.inboard == kWorld ? nullptr : &bodies[joint.inboard].body.shape;
  joint.inboard_anchor =
      read_anchor(object.at("inboard_anchor"), object.path("inboard_anchor"), inboard_shape);
  joint.outboard_anchor = read_anchor(object.at("outboard_anchor"), object.path("outboard_anchor"),
                                      &bodies[joint.outboard].body.shape);
  if (object.find("stiffness")) {
    joint.stiffness = object.number("stiffness");
    require_positive(*joint.stiffness, object.path("stiffness"));
  }
  if (object.find("damping")) {
    joint.damping = object.number("damping");
    require_non_negative(*joint.damping, object.path("damping"));
  }
  if (const Json* limits = object.find("limits")) joint.limits = read_limits(Object(*limits, object.path("limits")));
  object.optional("friction", joint.friction);
  if (const Json* drive = object.find("drive")) joint.drive = read_drive(Object(*drive, object.path("drive")));
  object.optional("armature", joint.armature);
  const Json* axes = object.find("serial_axes");
  if ((joint.type == JointType::serial) != (axes != nullptr)) {
    fail(object.path("serial_axes"), joint.type == JointType::serial ? "is required for a serial joint" : "is for serial joints only");
  }
  if (axes) {
    if (!axes->is_array()) wrong_type(*axes, object.path("serial_axes"), "an array");
    for (std::size_t i = 0; i < axes->size(); ++i) {
      joint.serial_axes.push_back(read_serial_axis(Object((*axes)[i], indexed(object.path("serial_axes"), i))));
    }
  }
  return joint;
}

Gear read_gear(const Object& object, const std::vector<BodySpec>& bodies, const std::unordered_map<std::string, int>& body_index) {
  object.allow_only({"name", "first", "second", "first_axis", "second_axis", "ratio"});
  Gear gear;
  gear.name = object.string("name");
  require_name(gear.name, object.path("name"), /*is_body=*/false);
  gear.first = read_body_name(object, "first", body_index, /*world_allowed=*/false);
  gear.second = read_body_name(object, "second", body_index, /*world_allowed=*/false);
  if (gear.first == gear.second) {
    fail(object.path("second"), "must differ from first, both are " + in_quotes(bodies[gear.first].body.name));
  }
  gear.first_axis = object.direction("first_axis");
  gear.second_axis = object.direction("second_axis");
  gear.ratio = object.number("ratio");
  if (gear.ratio == 0) fail(object.path("ratio"), "must not be 0 (the second gear would be held still)");
  return gear;
}


std::vector<Actuator> read_actuators(const Json& value, const std::string& path, const std::vector<Joint>& joints) {
  if (!value.is_array()) wrong_type(value, path, "an array");
  std::vector<Actuator> actuators;
  for (std::size_t i = 0; i < value.size(); ++i) {
    const Object object(value[i], indexed(path, i));
    object.allow_only({"name", "joint", "axis", "kind", "gear", "gain", "reference", "control_range"});
    Actuator actuator;
    actuator.name = object.string("name");
    require_name(actuator.name, object.path("name"), /*is_body=*/false);
    const std::string joint_name = object.string("joint");
    const auto joint = std::find_if(joints.begin(), joints.end(), [&](const Joint& j) { return j.name == joint_name; });
    if (joint == joints.end()) fail(object.path("joint"), "no joint named " + in_quotes(joint_name));
    actuator.joint = static_cast<int>(joint - joints.begin());
    if (joint->type == JointType::serial) {
      const std::string axis_name = object.string("axis");
      const auto axis = std::find_if(joint->serial_axes.begin(), joint->serial_axes.end(), [&](const SerialAxis& a) { return a.name == axis_name; });
      if (axis == joint->serial_axes.end()) fail(object.path("axis"), "joint " + in_quotes(joint_name) + " has no axis named " + in_quotes(axis_name));
      actuator.axis = static_cast<int>(axis - joint->serial_axes.begin());
    } else if (object.find("axis")) {
      fail(object.path("axis"), "names a serial joint's axis; joint " + in_quotes(joint_name) + " is " + std::string(joint_type_name(joint->type)));
    }
    actuator.gear = object.number("gear");
    object.optional_choice("kind", actuator.kind,
                           {{"motor", ActuatorKind::motor}, {"position", ActuatorKind::position}, {"velocity", ActuatorKind::velocity}});
    if (actuator.kind == ActuatorKind::motor) {
      for (const char* key : {"gain", "reference"}) {
        if (object.find(key)) fail(object.path(key), "a motor has none (its force is gear x control)");
      }
    } else {
      actuator.gain = object.number("gain");
      if (actuator.kind == ActuatorKind::velocity && object.find("reference")) fail(object.path("reference"), "a velocity actuator has none");
      object.optional("reference", actuator.reference);
    }
    if (const Json* range = object.find("control_range")) actuator.control_range = read_range(*range, object.path("control_range"));
    actuators.push_back(std::move(actuator));
  }
  return actuators;
}

}  // namespace limber::scene_json
