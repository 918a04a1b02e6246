// URDF's XML into plain links and joints (urdf_reader.hpp): pugixml, lines from element offsets
// (xml_text.hpp), attribute checks, number parsing and the notes.
#include "limber/kernel/scene/urdf_reader.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <pugixml.hpp>
#include <set>
#include <span>

#include "limber/kernel/model/model.hpp"  // ModelError
#include "limber/kernel/scene/scene_file.hpp"  // kMaxXmlDepth
#include "limber/kernel/scene/xml_text.hpp"

namespace limber::urdf {

std::string where(const Source& at) { return at.file + ":" + std::to_string(at.line) + ": "; }

Eigen::Matrix3d rpy_rotation(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

namespace {

using Node = pugi::xml_node;

/// An attribute accepted and dropped, and why (the note's reason).
struct Ignored {
  std::string_view attribute;
  std::string_view reason;
};

// "<element attr>" or "<element name='x'>" for messages.
std::string tag(Node element, std::string_view attribute = {}) {
  std::string out(1, '<');
  out.append(element.name());
  if (!attribute.empty()) {
    out.append(1, ' ').append(attribute);
  } else if (element.attribute("name")) {
    out.append(" name='").append(element.attribute("name").value()).append("'");
  }
  out.append(1, '>');
  return out;
}

// The parsed file, its lines, attribute reading and the notes.
class Reader {
 public:
  Reader(std::string file, std::string_view xml, std::vector<std::string>& notes)
      : file_(std::move(file)), text_(xml), starts_(xml::line_starts(text_)), notes_(notes) {
    const pugi::xml_parse_result result = tree_.load_buffer(text_.data(), text_.size(), pugi::parse_default, pugi::encoding_utf8);
    if (!result) throw ModelError(file_ + ":" + std::to_string(xml::line_of(starts_, result.offset)) + ": XML error: " + result.description());
    if (!tree_.document_element()) throw ModelError(file_ + ": XML error: no root element");
    if (auto problem = xml::check_tree(tree_, kMaxXmlDepth)) fail(problem->node, problem->what, problem->problem);
  }
  Node root() const { return tree_.document_element(); }
  Source source(Node element) const { return {file_, xml::line_of(starts_, element.offset_debug())}; }

  [[noreturn]] void fail(Node element, std::string_view what, std::string_view problem) const {
    throw ModelError(where(source(element)) + std::string(what) + ": " + std::string(problem));
  }
  // "FILE:LINE: <what>: ignored: reason", once per <what> in the file.
  void note(Node element, std::string_view what, std::string_view reason) {
    if (!noted_.insert(std::string(what)).second) return;
    notes_.push_back(where(source(element)) + std::string(what) + ": ignored: " + std::string(reason));
  }
  // Fails on an attribute neither read nor ignored; notes the ignored.
  void check_attributes(Node element, std::initializer_list<std::string_view> read, std::initializer_list<Ignored> ignored = {}) {
    for (pugi::xml_attribute attribute : element.attributes()) {
      const std::string_view name = attribute.name();
      if (std::find(read.begin(), read.end(), name) != read.end()) continue;
      auto drop = std::find_if(ignored.begin(), ignored.end(), [&](const Ignored& i) { return i.attribute == name; });
      if (drop == ignored.end()) fail(element, tag(element, name), "not supported: unknown attribute (not in the URDF specification here)");
      note(element, tag(element, name), drop->reason);
    }
  }
  std::optional<std::string_view> text(Node element, const char* attribute) const {
    const pugi::xml_attribute found = element.attribute(attribute);
    if (!found) return std::nullopt;
    return std::string_view(found.value());
  }
  std::string required_text(Node element, const char* attribute) const {
    auto value = text(element, attribute);
    if (!value || value->empty()) fail(element, tag(element, attribute), "missing (required by the URDF specification)");
    return std::string(*value);
  }
  // Exactly values.size() numbers; false when the attribute is absent.
  bool numbers(Node element, const char* attribute, std::span<double> values) const {
    auto written = text(element, attribute);
    if (!written) return false;
    const std::vector<std::string_view> parts = xml::words(*written);
    bool ok = parts.size() == values.size();
    for (std::size_t k = 0; ok && k < parts.size(); ++k) {
      auto value = xml::parse_double(parts[k]);
      ok = value.has_value();
      if (ok) values[k] = *value;
    }
    if (!ok) {
      fail(element, tag(element, attribute), "expected " + std::to_string(values.size()) + (values.size() == 1 ? " number" : " numbers") +
                                                 ", got '" + std::string(*written) + "'");
    }
    return true;
  }
  std::optional<double> number(Node element, const char* attribute) const {
    double value = 0;
    if (!numbers(element, attribute, std::span<double>(&value, 1))) return std::nullopt;
    return value;
  }
  double required_number(Node element, const char* attribute) const {
    auto value = number(element, attribute);
    if (!value) fail(element, tag(element, attribute), "missing (required by the URDF specification)");
    return *value;
  }
  double non_negative(Node element, const char* attribute) const {
    const double value = number(element, attribute).value_or(0);
    if (value < 0) fail(element, tag(element, attribute), "must be >= 0, got " + std::string(*text(element, attribute)));
    return value;
  }
  double positive(Node element, const char* attribute) const {
    const double value = required_number(element, attribute);
    if (!(value > 0)) fail(element, tag(element, attribute), "must be > 0, got " + std::string(*text(element, attribute)));
    return value;
  }
  // The element children of `element`.
  static std::vector<Node> children(Node element) {
    std::vector<Node> out;
    for (Node child = element.first_child(); child; child = child.next_sibling()) {
      if (child.type() == pugi::node_element) out.push_back(child);
    }
    return out;
  }
  // Fails when `element` has a second child named like `child`.
  void once(Node parent, Node child) const {
    if (parent.child(child.name()) != child) fail(child, tag(child), "given twice in " + tag(parent));
  }

 private:
  std::string file_;
  std::string text_;  // pugixml's offsets point into it
  std::vector<std::size_t> starts_;
  pugi::xml_document tree_;
  std::set<std::string> noted_;
  std::vector<std::string>& notes_;
};

// <origin xyz rpy>: the child frame in the parent's. Absent: the identity (the spec's default).
Isometry read_origin(Reader& reader, Node parent) {
  Isometry pose = Isometry::Identity();
  const Node element = parent.child("origin");
  if (!element) return pose;
  reader.once(parent, element);
  reader.check_attributes(element, {"xyz", "rpy"});
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero(), rpy = Eigen::Vector3d::Zero();
  reader.numbers(element, "xyz", std::span<double>(xyz.data(), 3));
  reader.numbers(element, "rpy", std::span<double>(rpy.data(), 3));
  pose.linear() = rpy_rotation(rpy);
  pose.translation() = xyz;
  return pose;
}

Inertial read_inertial(Reader& reader, Node element) {
  reader.check_attributes(element, {});
  Inertial inertial;
  inertial.at = reader.source(element);
  for (Node child : Reader::children(element)) {
    const std::string_view name = child.name();
    if (name != "origin" && name != "mass" && name != "inertia") {
      reader.fail(child, tag(child), "not supported: unknown element (an <inertial> holds origin, mass and inertia)");
    }
    reader.once(element, child);
  }
  inertial.origin = read_origin(reader, element);
  const Node mass = element.child("mass");
  if (!mass) reader.fail(element, tag(element), "missing <mass> (required by the URDF specification)");
  reader.check_attributes(mass, {"value"});
  inertial.mass = reader.required_number(mass, "value");
  if (inertial.mass < 0) reader.fail(mass, tag(mass, "value"), "must be >= 0");
  const Node inertia = element.child("inertia");
  if (!inertia) reader.fail(element, tag(element), "missing <inertia> (required by the URDF specification)");
  reader.check_attributes(inertia, {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"});
  const double ixx = reader.required_number(inertia, "ixx"), ixy = reader.required_number(inertia, "ixy");
  const double ixz = reader.required_number(inertia, "ixz"), iyy = reader.required_number(inertia, "iyy");
  const double iyz = reader.required_number(inertia, "iyz"), izz = reader.required_number(inertia, "izz");
  inertial.inertia << ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz;
  return inertial;
}

// A <collision>'s <geometry>: one of box, cylinder, sphere; a mesh is refused by name.
void read_geometry(Reader& reader, Node element, Collision& collision) {
  reader.check_attributes(element, {});
  const std::vector<Node> shapes = Reader::children(element);
  if (shapes.size() != 1) reader.fail(element, tag(element), "must hold exactly one shape (box, cylinder, sphere or mesh)");
  const Node shape = shapes.front();
  const std::string_view kind = shape.name();
  collision.shape_at = reader.source(shape);
  if (!Reader::children(shape).empty()) {
    reader.fail(Reader::children(shape).front(), tag(Reader::children(shape).front()), "not supported: unknown element");
  }
  if (kind == "mesh") {
    const std::string file(reader.text(shape, "filename").value_or(""));
    reader.fail(shape, "<mesh filename='" + file + "'>", "meshes are not supported yet (limber's bodies are capsules, cylinders and spheres)");
  }
  if (kind == "box") {
    reader.check_attributes(shape, {"size"});
    if (!reader.numbers(shape, "size", std::span<double>(collision.size.data(), 3))) {
      reader.fail(shape, tag(shape, "size"), "missing (required by the URDF specification)");
    }
    if (!(collision.size.minCoeff() > 0)) reader.fail(shape, tag(shape, "size"), "every extent must be > 0");
    collision.type = GeometryType::box;
  } else if (kind == "cylinder") {
    reader.check_attributes(shape, {"radius", "length"});
    collision.type = GeometryType::cylinder;
    collision.radius = reader.positive(shape, "radius");
    collision.length = reader.positive(shape, "length");
  } else if (kind == "sphere") {
    reader.check_attributes(shape, {"radius"});
    collision.type = GeometryType::sphere;
    collision.radius = reader.positive(shape, "radius");
  } else {
    reader.fail(shape, tag(shape), "not supported: unknown shape (URDF's are box, cylinder, sphere and mesh)");
  }
}

Collision read_collision(Reader& reader, Node element) {
  reader.check_attributes(element, {"name"});
  Collision collision;
  collision.at = reader.source(element);
  collision.name = std::string(reader.text(element, "name").value_or(""));
  for (Node child : Reader::children(element)) {
    const std::string_view name = child.name();
    if (name != "origin" && name != "geometry") {
      reader.fail(child, tag(child), "not supported: unknown element (a <collision> holds origin and geometry)");
    }
    reader.once(element, child);
  }
  collision.origin = read_origin(reader, element);
  const Node geometry = element.child("geometry");
  if (!geometry) reader.fail(element, tag(element), "missing <geometry> (required by the URDF specification)");
  read_geometry(reader, geometry, collision);
  return collision;
}

Link read_link(Reader& reader, Node element) {
  reader.check_attributes(element, {"name"});
  Link link;
  link.at = reader.source(element);
  link.name = reader.required_text(element, "name");
  for (Node child : Reader::children(element)) {
    const std::string_view name = child.name();
    if (name == "inertial") {
      reader.once(element, child);
      link.inertial = read_inertial(reader, child);
    } else if (name == "collision") {
      link.collisions.push_back(read_collision(reader, child));
    } else if (name == "visual") {
      reader.note(child, "<visual>", "rendering only");
    } else {
      reader.fail(child, tag(child), "not supported: unknown element (a <link> holds inertial, visual and collision)");
    }
  }
  return link;
}

// A joint's <limit>; effort and velocity are noted (limber applies neither).
Limit read_limit(Reader& reader, Node element) {
  reader.check_attributes(element, {"lower", "upper"},
                          {{"effort", "limber applies no actuator effort limit"}, {"velocity", "limber applies no joint speed limit"}});
  return Limit{reader.source(element), reader.number(element, "lower"), reader.number(element, "upper")};
}

// Reads the children of a <joint> other than origin.
void read_joint_children(Reader& reader, Node element, Joint& joint) {
  for (Node child : Reader::children(element)) {
    const std::string_view name = child.name();
    reader.once(element, child);
    if (name == "origin") continue;
    if (name == "parent" || name == "child") {
      reader.check_attributes(child, {"link"});
      (name == "parent" ? joint.parent : joint.child) = reader.required_text(child, "link");
      (name == "parent" ? joint.parent_at : joint.child_at) = reader.source(child);
    } else if (name == "axis") {
      reader.check_attributes(child, {"xyz"});
      Eigen::Vector3d axis = Eigen::Vector3d::UnitX();
      reader.numbers(child, "xyz", std::span<double>(axis.data(), 3));
      if (!(axis.stableNorm() > 1e-12)) reader.fail(child, tag(child, "xyz"), "must not be zero");
      joint.axis = axis.stableNormalized();
    } else if (name == "limit") {
      joint.limit = read_limit(reader, child);
    } else if (name == "dynamics") {
      reader.check_attributes(child, {"damping", "friction"});
      joint.damping = reader.non_negative(child, "damping");
      joint.friction = reader.non_negative(child, "friction");
    } else if (name == "mimic") {
      reader.fail(child, tag(child), "not supported: a mimic joint couples two joints' coordinates (an equality constraint)");
    } else if (name == "calibration") {
      reader.note(child, "<calibration>", "encoder reference positions (not dynamics)");
    } else if (name == "safety_controller") {
      reader.note(child, "<safety_controller>", "a controller's soft limits (not dynamics)");
    } else {
      reader.fail(child, tag(child), "not supported: unknown element (not a child of <joint> in the URDF specification)");
    }
  }
}

Joint read_joint(Reader& reader, Node element) {
  reader.check_attributes(element, {"name", "type"});
  Joint joint;
  joint.at = reader.source(element);
  joint.name = reader.required_text(element, "name");
  const std::string type = reader.required_text(element, "type");
  constexpr std::pair<std::string_view, JointType> kTypes[] = {{"revolute", JointType::revolute}, {"continuous", JointType::continuous},
                                                               {"prismatic", JointType::prismatic}, {"fixed", JointType::fixed},
                                                               {"floating", JointType::floating}};
  auto found = std::find_if(std::begin(kTypes), std::end(kTypes), [&](const auto& entry) { return entry.first == type; });
  if (type == "planar") {
    reader.fail(element, tag(element), "a planar joint is not supported yet (it would be a serial slide, slide and hinge)");
  }
  if (found == std::end(kTypes)) {
    reader.fail(element, tag(element, "type"), "expected one of revolute, continuous, prismatic, fixed, floating, planar, got '" + type + "'");
  }
  joint.type = found->second;
  joint.origin = read_origin(reader, element);
  read_joint_children(reader, element, joint);
  if (joint.parent.empty()) reader.fail(element, tag(element), "missing <parent link> (required by the URDF specification)");
  if (joint.child.empty()) reader.fail(element, tag(element), "missing <child link> (required by the URDF specification)");
  return joint;
}

}  // namespace

Robot read_robot(std::string_view xml, const std::string& file, std::vector<std::string>& notes) {
  Reader reader(file, xml, notes);
  const Node root = reader.root();
  if (std::string_view(root.name()) != "robot") reader.fail(root, tag(root), "not a URDF file: its root element must be <robot>");
  Robot robot;
  robot.at = reader.source(root);
  robot.name = std::string(reader.text(root, "name").value_or(""));
  for (pugi::xml_attribute attribute : root.attributes()) {
    const std::string_view name = attribute.name();
    if (name != "name" && name != "version" && name.substr(0, 5) != "xmlns") {
      reader.note(root, tag(root, name), "not in the URDF specification");
    }
  }
  for (Node child : Reader::children(root)) {
    const std::string_view name = child.name();
    if (name == "link") {
      robot.links.push_back(read_link(reader, child));
    } else if (name == "joint") {
      robot.joints.push_back(read_joint(reader, child));
    } else if (name == "material") {
      reader.note(child, "<material>", "rendering only");
    } else if (name == "transmission") {
      reader.note(child, "<transmission>", "actuator transmissions (limber's drives are its own)");
    } else if (name == "gazebo") {
      reader.note(child, "<gazebo>", "Gazebo's simulator settings");
    } else {
      reader.note(child, tag(child), "not an element of the URDF specification");
    }
  }
  return robot;
}

}  // namespace limber::urdf
