// MJCF's top level: the sections in MuJoCo's order, <compiler>, <option>, the <default> classes
// and the body tree (an explicit stack: a chain of any depth loads), then the actuators.
#include <algorithm>
#include <cmath>

#include "limber/kernel/scene/input_file.hpp"
#include "limber/kernel/scene/mjcf_reader.hpp"

namespace limber::mjcf {

namespace detail {
namespace {

void read_compiler(Context& context, const Node& element) {
  Reader& reader = context.reader;
  reader.check_attributes(element,
                          {"autolimits", "angle", "eulerseq", "inertiafromgeom", "inertiagrouprange", "coordinate",
                           "boundmass", "boundinertia", "settotalmass", "balanceinertia", "fusestatic"},
                          {{"meshdir", "asset files (no meshes)"}, {"texturedir", "rendering only"},
                           {"strippath", "asset file paths (no assets)"}, {"discardvisual", "rendering only"},
                           {"convexhull", "mesh collision (no meshes)"}, {"usethread", "MuJoCo's compiler threads"},
                           {"fitaabb", "mesh fitting (no meshes)"}, {"exactmeshinertia", "mesh inertia (no meshes)"}});
  Compiler& compiler = context.compiler;
  if (auto autolimits = reader.boolean(element, "autolimits")) compiler.autolimits = *autolimits;
  if (auto angle = reader.keyword(element, "angle", {"radian", "degree"})) compiler.degree = *angle == 1;
  if (auto sequence = reader.text(element, "eulerseq")) {
    if (sequence->size() != 3 || sequence->find_first_not_of("xyzXYZ") != std::string_view::npos) {
      reader.fail(element, tag(element, "eulerseq"), "expected 3 of x, y, z, X, Y, Z, got '" + std::string(*sequence) + "'");
    }
    std::copy(sequence->begin(), sequence->end(), compiler.eulerseq.begin());
  }
  if (auto from_geoms = reader.keyword(element, "inertiafromgeom", {"false", "true", "auto"})) {
    compiler.inertiafromgeom = *from_geoms;
  }
  reader.numbers(element, "inertiagrouprange", compiler.inertiagroups, true);
  if (reader.keyword(element, "coordinate", {"local", "global"}).value_or(0) == 1) {
    reader.fail(element, tag(element, "coordinate"), "not supported: global coordinates (frames must be local)");
  }
  for (const char* bound : {"boundmass", "boundinertia"}) {
    if (reader.number(element, bound).value_or(0) != 0) {
      reader.fail(element, tag(element, bound), "not supported: it changes the bodies' mass properties");
    }
  }
  if (reader.number(element, "settotalmass").value_or(-1) > 0) {
    reader.fail(element, tag(element, "settotalmass"), "not supported: it rescales the bodies' masses");
  }
  if (reader.boolean(element, "balanceinertia").value_or(false)) {
    reader.fail(element, tag(element, "balanceinertia"), "not supported: it changes the bodies' inertia");
  }
  if (reader.boolean(element, "fusestatic").value_or(false)) {
    reader.fail(element, tag(element, "fusestatic"), "not supported: it merges bodies");
  }
  for (const Node& child : reader.children(element)) {
    if (child.name() != "lengthrange") {
      reader.fail(child, tag(child), "not supported: unknown element (not a child of <compiler> in MuJoCo's schema)");
    }
    reader.note(child, tag(child), "actuator length ranges (muscles only)");
  }
}

void read_option(Context& context, const Node& element, Document& document) {
  Reader& reader = context.reader;
  constexpr std::string_view solver = "MuJoCo's solver settings (each limber method has its own)";
  constexpr std::string_view soft = "soft-constraint settings (limber's constraints are hard)";
  reader.check_attributes(element, {"timestep", "gravity", "density", "viscosity", "collision"},
                          {{"integrator", "MuJoCo's integrator (each limber method has its own)"}, {"solver", solver},
                           {"iterations", solver}, {"tolerance", solver}, {"noslip_iterations", solver},
                           {"noslip_tolerance", solver}, {"mpr_iterations", solver}, {"mpr_tolerance", solver},
                           {"jacobian", solver}, {"cone", solver}, {"apirate", "MuJoCo's remote API"},
                           {"impratio", soft}, {"o_margin", soft}, {"o_solref", soft}, {"o_solimp", soft},
                           {"wind", "fluid forces (density and viscosity 0)"},
                           {"magnetic", "magnetometer sensors only"}});
  if (auto timestep = reader.number(element, "timestep")) {
    if (*timestep <= 0) reader.fail(element, tag(element, "timestep"), "must be positive");
    document.timestep = *timestep;
  }
  reader.numbers(element, "gravity", std::span<double>(document.gravity.data(), 3), true);
  for (const char* fluid : {"density", "viscosity"}) {
    if (reader.number(element, fluid).value_or(0) != 0) reader.fail(element, tag(element, fluid), "not supported: fluid forces");
  }
  if (reader.keyword(element, "collision", {"all", "predefined", "dynamic"}).value_or(0) != 0) {
    reader.fail(element, tag(element, "collision"), "not supported: only collision=\"all\"");
  }
  for (const Node& child : reader.children(element)) {
    if (child.name() != "flag") {
      reader.fail(child, tag(child), "not supported: unknown element (not a child of <option> in MuJoCo's schema)");
    }
    reader.fail(child, tag(child), "not supported: flags change which forces and constraints apply");
  }
}

// Nested classes copy their parent when read; top-level <default>s all write into main. Each
// default's own elements are read before its nested classes, as MuJoCo does.
void read_defaults(Context& context, const Node& top) {
  Reader& reader = context.reader;
  std::vector<std::pair<Node, int>> stack{{top, -1}};  // element, parent class (-1: top level)
  while (!stack.empty()) {
    auto [element, parent] = stack.back();
    stack.pop_back();
    reader.check_attributes(element, {"class"});
    auto name = reader.text(element, "class");
    int index = 0;
    if (parent < 0 && name && *name != "main") {
      reader.fail(element, tag(element, "class"), "a top-level default is class main, not '" + std::string(*name) + "'");
    }
    if (parent >= 0) {
      if (!name || name->empty()) reader.fail(element, tag(element, "class"), "missing: a nested default needs a class name");
      if (context.class_index.contains(std::string(*name))) {
        reader.fail(element, tag(element, "class"), "repeated default class '" + std::string(*name) + "'");
      }
      DefaultClass copy = context.classes[parent];
      copy.name = std::string(*name);
      index = static_cast<int>(context.classes.size());
      context.classes.push_back(std::move(copy));
      context.class_index.emplace(std::string(*name), index);
    }
    std::vector<Node> nested;
    for (const Node& child : reader.children(element)) {
      if (child.name() == "default") {
        nested.push_back(child);
      } else {
        read_default_element(context, child, context.classes[index]);
      }
    }
    for (auto child = nested.rbegin(); child != nested.rend(); ++child) stack.emplace_back(*child, index);
  }
}

struct PendingBody {
  Node element;
  int parent = -1;          // index in Document::bodies, -1: the world
  int childclass = 0;       // the class its elements take by default
  bool parent_moving = false;  // the parent is not welded to the world
};

// One body's frame and children; its child bodies go on `stack` (last pushed is read next).
// A child of <body> or <worldbody> (`parent`) that is not a geom, joint or body: sites, cameras
// and lights are noted, a composite and anything outside MuJoCo's schema refused.
void other_body_child(Reader& reader, const Node& child, std::string_view parent) {
  const std::string_view kind = child.name();
  if (kind == "site" || kind == "camera" || kind == "light") {
    reader.note(child, tag(child), kind == "site" ? "sites (markers for sensors and tendons)" : "rendering only");
  } else if (kind == "composite") {
    reader.fail(child, tag(child), "not supported: composite objects (particles, grids, ropes, cloth)");
  } else {
    reader.fail(child, tag(child), "not supported: unknown element (not a child of <" + std::string(parent) + "> in MuJoCo's schema)");
  }
}

void read_body_children(Context& context, const PendingBody& pending, Body& body, int index,
                        std::vector<Node>& geoms, std::vector<Node>& bodies) {
  Reader& reader = context.reader;
  bool inertial = false;
  for (const Node& child : reader.children(pending.element)) {
    const std::string_view kind = child.name();
    if (kind == "inertial") {
      if (inertial) reader.fail(child, tag(child), "a body has at most one <inertial>");
      inertial = true;
      read_inertial(context, child, body);
    } else if (kind == "joint") {
      body.joints.push_back(make_joint(context, child, pending.childclass));
    } else if (kind == "freejoint") {
      body.joints.push_back(make_free_joint(context, child));
    } else if (kind == "geom") {
      geoms.push_back(child);
    } else if (kind == "body") {
      bodies.push_back(child);
    } else {
      other_body_child(reader, child, "body");
    }
  }
  for (std::size_t j = 0; j < body.joints.size(); ++j) {
    const std::string& name = body.joints[j].name;
    if (name.empty()) continue;
    if (!context.joints_by_name.emplace(name, std::pair{index, static_cast<int>(j)}).second) {
      reader.fail(pending.element, "<joint name>", "repeated joint name '" + name + "'");
    }
  }
}

// MuJoCo's mjCBody::Compile checks: at most 6 degrees of freedom, no rotation after a ball.
void check_joint_list(const Reader& reader, const Node& element, const Body& body) {
  int dofs = 0;
  bool ball = false;
  for (const Joint& joint : body.joints) {
    dofs += joint.type == JointType::free ? 6 : joint.type == JointType::ball ? 3 : 1;
    if (ball && (joint.type == JointType::ball || joint.type == JointType::hinge)) {
      reader.fail(element, tag(element), "a ball joint followed by a rotation (MuJoCo's rule)");
    }
    ball = ball || joint.type == JointType::ball;
  }
  if (dofs > 6) reader.fail(element, tag(element), "more than 6 degrees of freedom in one body");
}

void resolve_mass(Context& context, const Node& element, Body& body) {
  const int from_geoms = context.compiler.inertiafromgeom;
  if (!(from_geoms == 1 || (from_geoms == 2 && !body.explicit_inertial))) return;
  auto summed = geoms_mass_properties(body.geoms, context.compiler.inertiagroups);
  if (!summed) return;
  if (summed->geoms > 1 && summed->mass < mj_minval) {
    context.reader.fail(element, tag(element), "the geoms' total mass is too small to place a centre of mass");
  }
  if (!std::isfinite(summed->mass) || !summed->centre.allFinite() || !summed->inertia.allFinite()) {
    context.reader.fail(element, tag(element), "its geoms' total mass, centre of mass or inertia is not finite: their sizes, "
                                               "masses or positions overflow when summed");
  }
  body.mass = summed->mass;
  body.centre_of_mass = summed->centre;
  body.inertia = summed->inertia;
}

void read_body(Context& context, const PendingBody& pending, Document& document, std::vector<PendingBody>& stack) {
  Reader& reader = context.reader;
  const Node& element = pending.element;
  reader.check_attributes(element, {"name", "childclass", "pos", "quat", "axisangle", "xyaxes", "zaxis", "euler", "mocap"},
                          {{"user", "user data"}});
  if (reader.boolean(element, "mocap").value_or(false)) {
    reader.fail(element, tag(element, "mocap"), "not supported: bodies moved by the user (mocap)");
  }
  const int index = static_cast<int>(document.bodies.size());
  Body& body = document.bodies.emplace_back();
  body.name = std::string(reader.text(element, "name").value_or(""));
  body.parent = pending.parent;
  body.at = reader.source(element);
  int childclass = pending.childclass;
  if (auto name = reader.text(element, "childclass")) {
    auto found = context.class_index.find(std::string(*name));
    if (found == context.class_index.end()) {
      reader.fail(element, tag(element, "childclass"), "unknown default class '" + std::string(*name) + "'");
    }
    childclass = found->second;
  }
  reader.numbers(element, "pos", std::span<double>(body.position.data(), 3), true);
  try {
    body.orientation = resolve_orientation(read_orientation(reader, element), Eigen::Vector4d(1, 0, 0, 0), context.compiler);
  } catch (const FrameError& error) {
    reader.fail(element, tag(element, error.attribute), error.problem);
  }
  std::vector<Node> geoms, bodies;
  read_body_children(context, {element, pending.parent, childclass, pending.parent_moving}, body, index, geoms, bodies);
  const bool moving = pending.parent_moving || !body.joints.empty();
  for (const Node& geom : geoms) body.geoms.push_back(make_geom(context, geom, childclass, moving));
  check_joint_list(reader, element, body);
  resolve_mass(context, element, body);
  for (auto child = bodies.rbegin(); child != bodies.rend(); ++child) stack.push_back({*child, index, childclass, moving});
}

// Bodies depth first in file order (MuJoCo's body ids): parents before children.
void read_world(Context& context, const Node& world, Document& document) {
  Reader& reader = context.reader;
  reader.check_attributes(world, {});
  std::vector<Node> bodies;
  for (const Node& child : reader.children(world)) {
    const std::string_view kind = child.name();
    if (kind == "geom") {
      document.world_geoms.push_back(make_geom(context, child, 0, false));
    } else if (kind == "body") {
      bodies.push_back(child);
    } else {
      other_body_child(reader, child, "worldbody");
    }
  }
  std::vector<PendingBody> stack;
  for (auto child = bodies.rbegin(); child != bodies.rend(); ++child) stack.push_back({*child, -1, 0, false});
  while (!stack.empty()) {
    PendingBody pending = stack.back();
    stack.pop_back();
    read_body(context, pending, document, stack);
  }
}

void read_actuators(Context& context, const Node& section, Document& document) {
  Reader& reader = context.reader;
  reader.check_attributes(section, {});
  for (const Node& child : reader.children(section)) {
    const std::string_view kind = child.name();
    if (kind == "motor" || kind == "position" || kind == "velocity") {
      document.actuators.push_back(make_actuator(context, child));
    } else if (kind == "general" || kind == "intvelocity" || kind == "damper" || kind == "cylinder" ||
               kind == "muscle" || kind == "adhesion") {
      reader.fail(child, tag(child), "not supported: only motor, position and velocity actuators");
    } else {
      reader.fail(child, tag(child), "not supported: unknown element (not a child of <actuator> in MuJoCo's schema)");
    }
  }
}

// A section limber refuses when it holds anything.
void refuse_section(Reader& reader, const Node& section, std::string_view what) {
  std::vector<Node> children = reader.children(section);
  if (!children.empty()) reader.fail(children.front(), tag(children.front()), "not supported: " + std::string(what));
}

Document read_document(Reader& reader, const Node& root) {
  Context context(reader);
  Document document;
  reader.check_attributes(root, {"model"});
  document.model_name = std::string(reader.text(root, "model").value_or(""));
  const std::vector<Node> sections = reader.children(root);
  // mj_loadXML reads the sections kind by kind in this order, wherever they are in the file.
  constexpr std::string_view order[] = {"compiler", "option", "size", "visual", "statistic", "default", "custom", "asset",
                                        "worldbody", "contact", "equality", "tendon", "actuator", "sensor", "keyframe"};
  for (const Node& section : sections) {
    if (std::find(std::begin(order), std::end(order), section.name()) == std::end(order)) {
      reader.fail(section, tag(section), "not supported: unknown element (not a section of <mujoco> in MuJoCo's schema)");
    }
  }
  for (std::string_view kind : order) {
    for (const Node& section : sections) {
      if (section.name() != kind) continue;
      if (kind == "compiler") read_compiler(context, section);
      if (kind == "option") read_option(context, section, document);
      if (kind == "default") read_defaults(context, section);
      if (kind == "worldbody") read_world(context, section, document);
      if (kind == "actuator") read_actuators(context, section, document);
      if (kind == "contact") refuse_section(reader, section, "contact pairs and exclusions");
      if (kind == "equality") refuse_section(reader, section, "equality constraints");
      if (kind == "tendon") refuse_section(reader, section, "tendons");
      if (kind == "size") reader.note(section, tag(section), "MuJoCo's memory sizes");
      if (kind == "visual" || kind == "asset") reader.note(section, tag(section), "rendering only (textures, materials, meshes)");
      if (kind == "statistic") reader.note(section, tag(section), "rendering only (the viewer's scale)");
      if (kind == "custom") reader.note(section, tag(section), "user data");
      if (kind == "sensor") reader.note(section, tag(section), "sensors (limber's observers are its own)");
      if (kind == "keyframe") reader.note(section, tag(section), "keyframes (limber starts at the XML pose, qpos0)");
    }
  }
  return document;
}

}  // namespace
}  // namespace detail

Document parse_mjcf(std::string_view xml, const std::filesystem::path& file_name) {
  detail::Reader reader(file_name);
  const detail::Node root = reader.parse_main(xml);
  Document document = detail::read_document(reader, root);
  document.file = file_name.string();
  document.notes = reader.take_notes();
  return document;
}

Document load_mjcf(const std::filesystem::path& file) {
  return parse_mjcf(scene_input::read_file(file, scene_input::FileKind::model), file);
}

}  // namespace limber::mjcf
