// MJCF elements one at a time: joints, geoms, <inertial>, actuators, and the same fields in
// <default> classes. Each follows MuJoCo 2.2.2's reader (src/xml/xml_native_reader.cc) for what
// an attribute means and its compiler (src/user/user_objects.cc, mjCJoint/mjCGeom/mjCActuator
// ::Compile) for what is resolved and refused.
#include <cmath>
#include <numbers>

#include <Eigen/Eigenvalues>

#include "limber/kernel/scene/mjcf_reader.hpp"

namespace limber::mjcf::detail {

namespace {

constexpr double degree = std::numbers::pi / 180;

constexpr Ignored soft_joint[] = {
    {"solreflimit", "soft-limit parameters (limber's joint limits are hard)"},
    {"solimplimit", "soft-limit parameters (limber's joint limits are hard)"},
    {"solreffriction", "soft dry-friction parameters (limber's dry friction is hard)"},
    {"solimpfriction", "soft dry-friction parameters (limber's dry friction is hard)"},
    {"margin", "the limit margin (limber's joint limits act at the limit)"},
    {"user", "user data"}};

// Fails on `name` and `class` inside <default> (not in MuJoCo's schema there).
void refuse_naming_in_default(const Reader& reader, const Node& element) {
  for (const char* attribute : {"name", "class"}) {
    if (reader.text(element, attribute)) {
      reader.fail(element, tag(element, attribute), "not supported: unknown attribute (not allowed in a <default> class)");
    }
  }
}

// MuJoCo 2.2.2: a range without `limited` is an error unless autolimits; returns whether limited.
bool resolve_limited(const Context& context, const Node& element, int limited, const std::array<double, 2>& range,
                     const char* range_attribute, const char* limited_attribute) {
  if (limited != tri_auto) return limited == tri_true;
  const bool has_range = !(range[0] == 0 && range[1] == 0);
  if (has_range && !context.compiler.autolimits) {
    context.reader.fail(element, tag(element, range_attribute),
                        std::string("given without `") + limited_attribute + "`: MuJoCo 2.2.2 requires " +
                            limited_attribute + "=\"true\" or \"false\", or <compiler autolimits=\"true\">");
  }
  return has_range;
}

const char* size_meaning(GeomType type) {
  switch (type) {
    case GeomType::sphere: return "1 positive number (radius)";
    case GeomType::capsule: return "2 positive numbers (radius, half-length), or a radius and fromto";
    case GeomType::cylinder: return "2 positive numbers (radius, half-length), or a radius and fromto";
    case GeomType::box: return "3 positive numbers (half-sizes), or 1 and fromto";
    case GeomType::ellipsoid: return "3 positive numbers (semi-axes), or 1 and fromto";
    case GeomType::plane: return "a positive third number (grid spacing; 0 0 spacing: infinite)";
  }
  return "";
}

// MuJoCo's checksize: a plane's spacing, else each size the type uses must be positive.
void check_geom_size(const Reader& reader, const Node& element, const Geom& geom) {
  const int used = geom.type == GeomType::sphere ? 1
                   : geom.type == GeomType::capsule || geom.type == GeomType::cylinder ? 2 : 3;
  bool ok = true;
  if (geom.type == GeomType::plane) {
    ok = geom.size(2) > 0;
  } else {
    for (int i = 0; i < used; ++i) ok = ok && geom.size(i) > 0;
  }
  if (ok) return;
  auto written = reader.text(element, "size");
  constexpr const char* names[] = {"a plane", "a sphere", "a capsule", "a cylinder", "a box", "an ellipsoid"};
  reader.fail(element, tag(element, "size"),
              std::string(written ? "" : "missing: ") + names[static_cast<int>(geom.type)] + " needs " + size_meaning(geom.type) +
                  (written ? ", got '" + std::string(*written) + "'" : std::string()));
}

// fromto: the centre at the midpoint, local z along from - to, half-length |to - from|/2.
void place_from_to(const Reader& reader, const Node& element, const Eigen::Matrix<double, 6, 1>& from_to, Geom& geom) {
  const bool fits = geom.type == GeomType::capsule || geom.type == GeomType::cylinder ||
                    geom.type == GeomType::box || geom.type == GeomType::ellipsoid;
  if (!fits) reader.fail(element, tag(element, "fromto"), "needs a capsule, cylinder, box or ellipsoid");
  if (geom.position != Eigen::Vector3d::Zero()) {
    reader.fail(element, tag(element, "fromto"), "pos is given too (fromto places the geom): give one");
  }
  Eigen::Vector3d along = from_to.head<3>() - from_to.tail<3>();
  const double length = along.norm();
  if (length / 2 < mj_eps) reader.fail(element, tag(element, "fromto"), "the two points coincide");
  along /= length;
  geom.size(1) = length / 2;
  if (geom.type == GeomType::box || geom.type == GeomType::ellipsoid) {
    geom.size(2) = geom.size(1);
    geom.size(1) = geom.size(0);  // MuJoCo: the second half-size repeats the first
  }
  geom.position = (from_to.head<3>() + from_to.tail<3>()) / 2;
  geom.orientation = z_axis_to_quaternion(along);
}

// A geom's derived size, volume, mass and inertia, each finite, or refused at the attribute that
// made it overflow (a size or fromto near 1e308, a density that large times a volume, a mass
// that large times a size squared): the element's line names it, where the Model's checks could
// only name a mass of inf or nan.
void check_geom_finite(const Reader& reader, const Node& element, const Geom& geom, bool from_to, bool explicit_mass) {
  const char* shape = from_to ? "fromto" : "size";
  const auto refuse = [&](const char* attribute, const std::string& problem) {
    reader.fail(element, tag(element, attribute), problem + ": it overflows (no geom is that large)");
  };
  if (!geom.size.allFinite()) refuse(shape, "gives a size that is not finite");
  if (!geom.position.allFinite()) refuse(shape, "gives a centre that is not finite");
  const double volume = geom_volume(geom.type, geom.size);
  if (!std::isfinite(volume)) refuse(shape, "gives a volume that is not finite");
  if (!std::isfinite(geom.mass)) refuse("density", "density × volume, the geom's mass, is not finite");
  if (!geom_principal_moments(geom.type, geom.size, geom.mass).allFinite()) {
    refuse(explicit_mass ? "mass" : shape, "gives a moment of inertia (mass × size²) that is not finite");
  }
}

}  // namespace

static void read_joint_fields(Context& context, const Node& element, JointDefaults& joint) {
  Reader& reader = context.reader;
  if (auto type = reader.keyword(element, "type", {"hinge", "slide", "ball", "free"})) {
    joint.type = static_cast<JointType>(*type);
  }
  reader.integer(element, "group");  // a display group: read to check it
  reader.numbers(element, "pos", std::span<double>(joint.position.data(), 3), true);
  reader.numbers(element, "axis", std::span<double>(joint.axis.data(), 3), true);
  if (auto limited = reader.keyword(element, "limited", {"false", "true", "auto"})) joint.limited = *limited;
  reader.numbers(element, "range", joint.range, true);
  std::array<double, 2> spring_damper{0, 0};
  if (reader.numbers(element, "springdamper", spring_damper, true) && (spring_damper[0] != 0 || spring_damper[1] != 0)) {
    reader.fail(element, tag(element, "springdamper"), "not supported: give stiffness and damping");
  }
  for (auto [attribute, field] : {std::pair{"ref", &joint.ref}, {"springref", &joint.springref},
                                  {"stiffness", &joint.stiffness}, {"damping", &joint.damping},
                                  {"armature", &joint.armature}, {"frictionloss", &joint.frictionloss}}) {
    if (auto value = reader.number(element, attribute)) *field = *value;
  }
}

Joint make_joint(Context& context, const Node& element, int inherited) {
  Reader& reader = context.reader;
  reader.check_attributes(element, {"name", "class", "type", "group", "pos", "axis", "springdamper", "limited",
                                    "stiffness", "range", "ref", "springref", "armature", "damping", "frictionloss"},
                          {soft_joint[0], soft_joint[1], soft_joint[2], soft_joint[3], soft_joint[4], soft_joint[5]});
  reader.refuse_children(element);
  JointDefaults fields = context.classes[context.element_class(element, inherited)].joint;
  read_joint_fields(context, element, fields);
  Joint joint;
  joint.name = std::string(reader.text(element, "name").value_or(""));
  joint.type = fields.type;
  joint.at = reader.source(element);
  joint.stiffness = fields.stiffness, joint.damping = fields.damping;
  joint.armature = fields.armature, joint.frictionloss = fields.frictionloss;
  const bool rotation = joint.type == JointType::hinge || joint.type == JointType::ball;
  // mjCJoint::Compile: limits, then angle units (ranges only when limited), axis, pivot.
  joint.limited = joint.type != JointType::free &&
                  resolve_limited(context, element, fields.limited, fields.range, "range", "limited");
  if (joint.limited && joint.type != JointType::ball && fields.range[0] >= fields.range[1]) {
    reader.fail(element, tag(element, "range"), "the lower limit must be below the upper");
  }
  if (joint.limited && joint.type == JointType::ball && fields.range[0] != 0) {
    reader.fail(element, tag(element, "range"), "a ball joint's range must start at 0 (it limits the rotation angle)");
  }
  const double unit = context.compiler.degree && rotation && joint.limited ? degree : 1;
  joint.range_min = fields.range[0] * unit, joint.range_max = fields.range[1] * unit;
  const Eigen::Vector3d axis = joint.type == JointType::ball || joint.type == JointType::free ? Eigen::Vector3d::UnitZ() : fields.axis;
  if (axis.norm() < mj_eps) reader.fail(element, tag(element, "axis"), "the axis is too small");
  joint.axis = axis / axis.norm();
  joint.position = joint.type == JointType::free ? Eigen::Vector3d::Zero() : fields.position;
  const double angle_unit = context.compiler.degree && joint.type == JointType::hinge ? degree : 1;
  joint.ref = fields.ref * angle_unit, joint.springref = fields.springref * angle_unit;
  return joint;
}

Joint make_free_joint(Context& context, const Node& element) {
  context.reader.check_attributes(element, {"name", "group"});
  context.reader.refuse_children(element);
  context.reader.integer(element, "group");
  Joint joint;
  joint.name = std::string(context.reader.text(element, "name").value_or(""));
  joint.type = JointType::free;
  joint.at = context.reader.source(element);
  return joint;
}

static void read_geom_fields(Context& context, const Node& element, GeomDefaults& geom) {
  Reader& reader = context.reader;
  if (auto type = reader.keyword(element, "type", {"plane", "hfield", "sphere", "capsule", "ellipsoid", "cylinder", "box", "mesh"})) {
    constexpr GeomType types[] = {GeomType::plane, GeomType::plane, GeomType::sphere, GeomType::capsule,
                                  GeomType::ellipsoid, GeomType::cylinder, GeomType::box, GeomType::plane};
    if (*type == 1 || *type == 7) reader.fail(element, tag(element, "type"), "not supported: mesh and hfield geoms");
    geom.type = types[*type];
  }
  for (const char* attribute : {"mesh", "hfield"}) {
    if (reader.text(element, attribute)) reader.fail(element, tag(element, attribute), "not supported: mesh and hfield geoms");
  }
  if (reader.boolean(element, "shellinertia").value_or(false)) {
    reader.fail(element, tag(element, "shellinertia"), "not supported: inertia of a hollow shell");
  }
  reader.numbers(element, "size", std::span<double>(geom.size.data(), 3), false);
  reader.numbers(element, "friction", std::span<double>(geom.friction.data(), 3), false);
  for (auto [attribute, field] : {std::pair{"contype", &geom.contype}, {"conaffinity", &geom.conaffinity},
                                  {"condim", &geom.condim}, {"group", &geom.group}}) {
    if (auto value = reader.integer(element, attribute)) *field = *value;
  }
  if (auto mass = reader.number(element, "mass")) geom.mass = *mass;
  if (auto density = reader.number(element, "density")) geom.density = *density;
  reader.numbers(element, "pos", std::span<double>(geom.position.data(), 3), true);
  reader.numbers(element, "quat", std::span<double>(geom.quat.data(), 4), true);
}

constexpr Ignored geom_ignored[] = {
    {"priority", "contact parameter priority (limber mixes friction by the maximum)"},
    {"material", "rendering only"}, {"rgba", "rendering only"},
    {"solmix", "soft-contact parameters (limber's contacts are hard)"},
    {"solref", "soft-contact parameters (limber's contacts are hard)"},
    {"solimp", "soft-contact parameters (limber's contacts are hard)"},
    {"margin", "contact margin (limber's contacts act at touch)"},
    {"gap", "contact gap (limber's contacts act at touch)"},
    {"user", "user data"}, {"fitscale", "mesh fitting (no meshes)"},
    {"fluidshape", "fluid forces (limber has no fluid)"}, {"fluidcoef", "fluid forces (limber has no fluid)"}};

Geom make_geom(Context& context, const Node& element, int inherited, bool moving) {
  Reader& reader = context.reader;
  const auto& ig = geom_ignored;
  reader.check_attributes(element, {"name", "class", "type", "contype", "conaffinity", "condim", "group", "size",
                                    "friction", "mass", "density", "shellinertia", "fromto", "pos", "quat",
                                    "axisangle", "xyaxes", "zaxis", "euler", "hfield", "mesh"},
                          {ig[0], ig[1], ig[2], ig[3], ig[4], ig[5], ig[6], ig[7], ig[8], ig[9], ig[10], ig[11]});
  reader.refuse_children(element);
  GeomDefaults fields = context.classes[context.element_class(element, inherited)].geom;
  read_geom_fields(context, element, fields);
  Geom geom;
  geom.name = std::string(reader.text(element, "name").value_or(""));
  geom.type = fields.type, geom.at = reader.source(element), geom.size = fields.size;
  geom.contype = fields.contype, geom.conaffinity = fields.conaffinity, geom.condim = fields.condim;
  geom.friction = fields.friction, geom.group = fields.group, geom.position = fields.position;
  if (geom.condim != 1 && geom.condim != 3 && geom.condim != 4 && geom.condim != 6) {
    reader.fail(element, tag(element, "condim"), "must be 1, 3, 4 or 6");
  }
  const OrientationSpec spec = read_orientation(reader, element);
  Eigen::Matrix<double, 6, 1> from_to;
  const bool placed = reader.numbers(element, "fromto", std::span<double>(from_to.data(), 6), true);
  if (placed) {
    if (spec.quat || spec.axisangle || spec.euler || spec.xyaxes || spec.zaxis) {
      reader.fail(element, tag(element, "fromto"), "an orientation is given too (fromto orients the geom): give one");
    }
    place_from_to(reader, element, from_to, geom);
  } else {
    try {
      geom.orientation = resolve_orientation(spec, fields.quat, context.compiler);
    } catch (const FrameError& error) {
      reader.fail(element, tag(element, error.attribute), error.problem);
    }
  }
  check_geom_size(reader, element, geom);
  if (geom.type == GeomType::plane && moving) {
    reader.fail(element, tag(element, "type"), "a plane must be in the worldbody or a body welded to it (MuJoCo's rule)");
  }
  if (fields.density < 0 || fields.mass.value_or(0) < 0) {
    reader.fail(element, tag(element, fields.mass ? "mass" : "density"), "must not be negative");
  }
  geom.mass = geom_mass(geom.type, geom.size, fields.mass, fields.density);
  check_geom_finite(reader, element, geom, placed, fields.mass.has_value());
  return geom;
}

void read_inertial(Context& context, const Node& element, Body& body) {
  Reader& reader = context.reader;
  reader.check_attributes(element, {"pos", "quat", "mass", "diaginertia", "axisangle", "xyaxes", "zaxis", "euler", "fullinertia"});
  reader.refuse_children(element);
  const OrientationSpec spec = read_orientation(reader, element);
  const bool oriented = spec.quat || spec.axisangle || spec.euler || spec.xyaxes || spec.zaxis;
  Eigen::Vector3d centre;
  if (!reader.numbers(element, "pos", std::span<double>(centre.data(), 3), true)) {
    reader.fail(element, tag(element, "pos"), "missing: the centre of mass is required");
  }
  auto mass = reader.number(element, "mass");
  if (!mass) reader.fail(element, tag(element, "mass"), "missing: the mass is required");
  if (*mass < 0) reader.fail(element, tag(element, "mass"), "must not be negative");
  Eigen::Vector3d moments = Eigen::Vector3d::Zero();
  Eigen::Matrix<double, 6, 1> full;
  const bool diagonal = reader.numbers(element, "diaginertia", std::span<double>(moments.data(), 3), true);
  if (reader.numbers(element, "fullinertia", std::span<double>(full.data(), 6), true)) {
    if (diagonal) reader.fail(element, tag(element, "fullinertia"), "diaginertia is given too: give one");
    if (oriented) reader.fail(element, tag(element, "fullinertia"), "an orientation is given too (fullinertia is in the body frame): give one");
    body.inertia << full(0), full(3), full(4), full(3), full(1), full(5), full(4), full(5), full(2);
    moments = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(body.inertia).eigenvalues();
    if (moments.minCoeff() < mj_eps) reader.fail(element, tag(element, "fullinertia"), "must be positive definite");
  } else {
    try {
      body.inertia = rotated_inertia(resolve_orientation(spec, Eigen::Vector4d(1, 0, 0, 0), context.compiler), moments);
    } catch (const FrameError& error) {
      reader.fail(element, tag(element, error.attribute), error.problem);
    }
    if (moments.minCoeff() < 0) reader.fail(element, tag(element, "diaginertia"), "must not be negative");
  }
  if (!body.inertia.allFinite() || !moments.allFinite()) {
    reader.fail(element, tag(element, diagonal ? "diaginertia" : "fullinertia"), "the inertia overflows (not finite once turned into the body frame)");
  }
  if (moments(0) + moments(1) < moments(2) || moments(0) + moments(2) < moments(1) || moments(1) + moments(2) < moments(0)) {
    reader.fail(element, tag(element, diagonal ? "diaginertia" : "fullinertia"),
                "the principal moments break the triangle inequality A + B >= C");
  }
  body.explicit_inertial = true;
  body.mass = *mass;
  body.centre_of_mass = centre;
}

static void read_actuator_fields(Context& context, const Node& element, ActuatorDefaults& actuator) {
  Reader& reader = context.reader;
  if (auto limited = reader.keyword(element, "ctrllimited", {"false", "true", "auto"})) actuator.ctrllimited = *limited;
  if (auto limited = reader.keyword(element, "forcelimited", {"false", "true", "auto"})) actuator.forcelimited = *limited;
  reader.numbers(element, "ctrlrange", actuator.ctrlrange, true);
  reader.numbers(element, "forcerange", actuator.forcerange, true);
  std::array<double, 6> gear{actuator.gear, 0, 0, 0, 0, 0};
  if (reader.numbers(element, "gear", gear, false)) actuator.gear = gear[0];
  reader.integer(element, "group");
  // MuJoCo's shortcuts write gainprm[0]: a motor 1, a position kp, a velocity kv.
  const std::string_view kind = element.name();
  if (reader.text(element, "kp") && kind != "position") {
    reader.fail(element, tag(element, "kp"), "not supported: unknown attribute (only a position actuator has kp)");
  }
  if (reader.text(element, "kv") && kind != "velocity") {
    reader.fail(element, tag(element, "kv"), "not supported: unknown attribute (only a velocity actuator has kv)");
  }
  // MuJoCo's shortcuts write gainprm[0]: a motor 1, a position its kp, a velocity its kv.
  if (kind == "motor") actuator.gain = 1;
  if (auto kp = reader.number(element, "kp")) actuator.gain = *kp;
  if (auto kv = reader.number(element, "kv")) actuator.gain = *kv;
}

Actuator make_actuator(Context& context, const Node& element) {
  Reader& reader = context.reader;
  reader.check_attributes(element, {"name", "class", "group", "ctrllimited", "forcelimited", "ctrlrange", "forcerange",
                                    "gear", "joint", "jointinparent", "tendon", "slidersite", "cranksite", "site",
                                    "refsite", "body", "kp", "kv"},
                          {{"lengthrange", "actuator length range (muscles only)"},
                           {"cranklength", "slider-crank length (joint transmissions only)"}, {"user", "user data"}});
  reader.refuse_children(element);
  for (const char* other : {"jointinparent", "tendon", "slidersite", "cranksite", "site", "refsite", "body"}) {
    if (reader.text(element, other)) reader.fail(element, tag(element, other), "not supported: only joint transmissions");
  }
  ActuatorDefaults fields = context.classes[context.element_class(element, 0)].actuator;
  read_actuator_fields(context, element, fields);
  Actuator actuator;
  actuator.name = std::string(reader.text(element, "name").value_or(""));
  actuator.type = element.name() == "motor" ? ActuatorType::motor
                  : element.name() == "position" ? ActuatorType::position : ActuatorType::velocity;
  actuator.at = reader.source(element);
  auto joint = reader.text(element, "joint");
  if (!joint) reader.fail(element, tag(element, "joint"), "missing: the joint it drives (the only transmission supported)");
  auto found = context.joints_by_name.find(std::string(*joint));
  if (found == context.joints_by_name.end()) reader.fail(element, tag(element, "joint"), "unknown joint '" + std::string(*joint) + "'");
  actuator.joint_body = found->second.first, actuator.joint = found->second.second;
  actuator.gear = fields.gear;
  if (actuator.type == ActuatorType::position) actuator.kp = fields.gain;
  if (actuator.type == ActuatorType::velocity) actuator.kv = fields.gain;
  actuator.ctrllimited = resolve_limited(context, element, fields.ctrllimited, fields.ctrlrange, "ctrlrange", "ctrllimited");
  actuator.forcelimited = resolve_limited(context, element, fields.forcelimited, fields.forcerange, "forcerange", "forcelimited");
  if (actuator.ctrllimited && fields.ctrlrange[0] >= fields.ctrlrange[1]) {
    reader.fail(element, tag(element, "ctrlrange"), "the lower limit must be below the upper");
  }
  if (actuator.forcelimited && fields.forcerange[0] >= fields.forcerange[1]) {
    reader.fail(element, tag(element, "forcerange"), "the lower limit must be below the upper");
  }
  actuator.ctrl_min = fields.ctrlrange[0], actuator.ctrl_max = fields.ctrlrange[1];
  actuator.force_min = fields.forcerange[0], actuator.force_max = fields.forcerange[1];
  return actuator;
}

void read_default_element(Context& context, const Node& element, DefaultClass& into) {
  Reader& reader = context.reader;
  const std::string_view kind = element.name();
  refuse_naming_in_default(reader, element);
  const auto& ig = geom_ignored;
  if (kind == "joint") {
    reader.check_attributes(element, {"type", "group", "pos", "axis", "springdamper", "limited", "stiffness", "range",
                                      "ref", "springref", "armature", "damping", "frictionloss"},
                            {soft_joint[0], soft_joint[1], soft_joint[2], soft_joint[3], soft_joint[4], soft_joint[5]});
    read_joint_fields(context, element, into.joint);
  } else if (kind == "geom") {
    reader.check_attributes(element, {"type", "contype", "conaffinity", "condim", "group", "size", "friction", "mass",
                                      "density", "shellinertia", "pos", "quat", "fromto", "axisangle", "xyaxes",
                                      "zaxis", "euler", "hfield", "mesh"},
                            {ig[0], ig[1], ig[2], ig[3], ig[4], ig[5], ig[6], ig[7], ig[8], ig[9], ig[10], ig[11]});
    for (const char* attribute : {"fromto", "axisangle", "xyaxes", "zaxis", "euler"}) {
      if (reader.text(element, attribute)) {
        reader.fail(element, tag(element, attribute), "not supported in a default class: give it on the geom");
      }
    }
    read_geom_fields(context, element, into.geom);
  } else if (kind == "motor" || kind == "position" || kind == "velocity") {
    reader.check_attributes(element, {"ctrllimited", "forcelimited", "ctrlrange", "forcerange", "gear", "group", "kp", "kv"},
                            {{"cranklength", "slider-crank length (joint transmissions only)"}, {"user", "user data"}});
    read_actuator_fields(context, element, into.actuator);
  } else if (kind == "site" || kind == "camera" || kind == "light" || kind == "material" || kind == "mesh" ||
             kind == "pair" || kind == "equality" || kind == "tendon") {
    reader.note(element, tag(element), "defaults of elements limber ignores or refuses where they appear");
    return;
  } else if (kind == "general" || kind == "intvelocity" || kind == "damper" || kind == "cylinder" ||
             kind == "muscle" || kind == "adhesion") {
    reader.fail(element, tag(element), "not supported: only motor, position and velocity actuators");
  } else {
    reader.fail(element, tag(element), "not supported: unknown element (not a child of <default> in MuJoCo's schema)");
  }
  reader.refuse_children(element);
}

}  // namespace limber::mjcf::detail
