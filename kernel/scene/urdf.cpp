// A URDF robot's links and joints (urdf_reader.hpp) into limber's Model (urdf.hpp): the tree
// checks, the world frames at q = 0, one body per link, the frame links folded away, the joints.
#include "limber/kernel/scene/urdf.hpp"

#include <algorithm>
#include <numbers>
#include <sstream>
#include <unordered_map>

#include <Eigen/Eigenvalues>

#include "limber/kernel/scene/inertial_import.hpp"
#include "limber/kernel/scene/input_file.hpp"
#include "limber/kernel/scene/model_origins.hpp"
#include "limber/kernel/scene/urdf_reader.hpp"

namespace limber {
namespace {

using urdf::Isometry;

[[noreturn]] void refuse(const urdf::Source& at, const std::string& element, const std::string& problem) {
  throw ModelError(urdf::where(at) + element + ": " + problem);
}

std::string link_tag(const urdf::Link& link) { return "<link name='" + link.name + "'>"; }
std::string joint_tag(const urdf::Joint& joint) { return "<joint name='" + joint.name + "'>"; }

std::string type_name(urdf::JointType type) {
  static constexpr const char* kNames[] = {"revolute", "continuous", "prismatic", "fixed", "floating"};
  return kNames[static_cast<int>(type)];
}

// The links as a tree: each link's parent joint and child joints, the root, and an order that
// puts every parent before its children.
struct Tree {
  std::vector<int> parent_joint;               // per link; -1: the root
  std::vector<std::vector<int>> child_joints;  // per link, file order
  std::vector<int> link_of_child, link_of_parent;  // per joint
  int root = -1;
  std::vector<int> order;
};

// Unique names, and each joint's parent and child links (refused when unknown).
std::unordered_map<std::string, int> index_names(const urdf::Robot& robot) {
  std::unordered_map<std::string, int> links;
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    const urdf::Link& link = robot.links[l];
    auto [found, inserted] = links.emplace(link.name, static_cast<int>(l));
    if (!inserted) {
      refuse(link.at, link_tag(link), "a second link of this name (the first is at line " +
                                          std::to_string(robot.links[static_cast<std::size_t>(found->second)].at.line) + ")");
    }
  }
  std::unordered_map<std::string, int> joints;
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    const urdf::Joint& joint = robot.joints[j];
    auto [found, inserted] = joints.emplace(joint.name, static_cast<int>(j));
    if (!inserted) {
      refuse(joint.at, joint_tag(joint), "a second joint of this name (the first is at line " +
                                             std::to_string(robot.joints[static_cast<std::size_t>(found->second)].at.line) + ")");
    }
  }
  return links;
}

Tree build_tree(const urdf::Robot& robot) {
  if (robot.links.empty()) refuse(robot.at, "<robot>", "no <link>: nothing to simulate");
  const std::unordered_map<std::string, int> links = index_names(robot);
  Tree tree;
  tree.parent_joint.assign(robot.links.size(), -1);
  tree.child_joints.resize(robot.links.size());
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    const urdf::Joint& joint = robot.joints[j];
    const auto parent = links.find(joint.parent), child = links.find(joint.child);
    if (parent == links.end()) refuse(joint.parent_at, "<parent link>", "joint '" + joint.name + "' names unknown link '" + joint.parent + "'");
    if (child == links.end()) refuse(joint.child_at, "<child link>", "joint '" + joint.name + "' names unknown link '" + joint.child + "'");
    if (parent->second == child->second) refuse(joint.at, joint_tag(joint), "joins link '" + joint.child + "' to itself (a loop)");
    int& parent_joint = tree.parent_joint[static_cast<std::size_t>(child->second)];
    if (parent_joint >= 0) {
      const urdf::Joint& first = robot.joints[static_cast<std::size_t>(parent_joint)];
      refuse(joint.at, joint_tag(joint), "link '" + joint.child + "' has two parent joints, '" + first.name + "' (line " +
                                             std::to_string(first.at.line) + ") and '" + joint.name +
                                             "': a closed loop (a URDF robot is a tree)");
    }
    parent_joint = static_cast<int>(j);
    tree.child_joints[static_cast<std::size_t>(parent->second)].push_back(static_cast<int>(j));
    tree.link_of_parent.push_back(parent->second);
    tree.link_of_child.push_back(child->second);
  }
  std::string roots;
  int root_count = 0;
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    if (tree.parent_joint[l] >= 0) continue;
    if (root_count < 3) roots += (roots.empty() ? "'" : ", '") + robot.links[l].name + "'";
    if (root_count++ == 0) tree.root = static_cast<int>(l);
  }
  if (root_count == 0) refuse(robot.at, "<robot>", "no root link: every link has a parent joint, so the joints close a loop");
  if (root_count > 3) roots += ", ... (" + std::to_string(root_count) + " in all)";
  if (root_count > 1) refuse(robot.at, "<robot>", "several root links (" + roots + "): a URDF robot is one tree");
  // Depth first from the root with an explicit stack: any depth.
  std::vector<int> stack{tree.root};
  while (!stack.empty()) {
    const int link = stack.back();
    stack.pop_back();
    tree.order.push_back(link);
    const std::vector<int>& children = tree.child_joints[static_cast<std::size_t>(link)];
    for (auto j = children.rbegin(); j != children.rend(); ++j) stack.push_back(tree.link_of_child[static_cast<std::size_t>(*j)]);
  }
  if (tree.order.size() < robot.links.size()) {
    std::vector<bool> reached(robot.links.size(), false);
    for (int link : tree.order) reached[static_cast<std::size_t>(link)] = true;
    const auto unreached = static_cast<std::size_t>(std::find(reached.begin(), reached.end(), false) - reached.begin());
    const urdf::Joint& joint = robot.joints[static_cast<std::size_t>(tree.parent_joint[unreached])];
    refuse(joint.at, joint_tag(joint), "a closed loop: link '" + robot.links[unreached].name + "' is not reached from the root link '" +
                                           robot.links[static_cast<std::size_t>(tree.root)].name + "'");
  }
  return tree;
}

// Whether a link has neither mass nor collision geometry: a frame, not a body.
bool is_frame(const urdf::Link& link) { return link.collisions.empty() && !(link.inertial && link.inertial->mass > 0); }

// A physical inertia tensor (as validate() requires), refused at its <inertia> otherwise.
void check_inertia(const urdf::Link& link) {
  const urdf::Inertial& inertial = *link.inertial;
  const Eigen::Vector3d moments = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(inertial.inertia, Eigen::EigenvaluesOnly).eigenvalues();
  std::ostringstream text;
  text << moments.transpose();
  if (!(moments[0] > 0)) refuse(inertial.at, "<inertial> of link '" + link.name + "'", "the inertia tensor must be positive definite, principal moments " + text.str());
  if (moments[0] + moments[1] < moments[2] * (1 - 1e-12)) {
    refuse(inertial.at, "<inertial> of link '" + link.name + "'",
           "principal moments " + text.str() + " break the triangle inequality I1 + I2 >= I3 (no body has them)");
  }
}

// Link `link` as a limber body at its collision pose (`frame`: the link's world frame), with
// the link's <inertial> moved exactly into the body's frame.
Body link_body(const urdf::Link& link, const Isometry& frame) {
  if (link.collisions.empty()) refuse(link.at, link_tag(link), "a link without collision geometry is not supported yet: limber's bodies have shapes");
  if (!link.inertial || !(link.inertial->mass > 0)) {
    refuse(link.at, link_tag(link), "a link with collision geometry needs an <inertial> with mass > 0 (limber does not compute mass from geometry)");
  }
  if (link.collisions.size() > 1) {
    refuse(link.collisions[1].at, "<collision> of link '" + link.name + "'",
           "several collision shapes on one link are not supported yet (one limber body takes the link's whole inertial)");
  }
  const urdf::Collision& collision = link.collisions.front();
  Body body;
  body.name = link.name;
  int along = 2;  // the collision frame's axis that is the body's
  if (collision.type == urdf::GeometryType::box) {
    // Its body axis is its longest side (the particle method's capsule proxy lies along it,
    // capsule_proxy.hpp), its own frame the collision frame.
    body.shape.type = ShapeType::box;
    body.shape.half_extents = collision.size / 2;
    collision.size.maxCoeff(&along);
  } else {
    body.shape = collision.type == urdf::GeometryType::cylinder ? Shape{ShapeType::cylinder, collision.length, collision.radius}
                                                                  : Shape{ShapeType::capsule, 0, collision.radius};
  }
  if (!frame.translation().allFinite()) {
    refuse(link.at, link_tag(link), "its frame's position is not finite: the joints' <origin xyz> from the root overflow when added up");
  }
  const Isometry world = frame * collision.origin;
  body.position = world.translation();
  body.axis = world.linear().col(along).normalized();
  if (has_half_extents(body.shape)) body.shape.rotation = (body.orientation().conjugate() * Eigen::Quaterniond(world.linear())).normalized();
  check_inertia(link);
  const urdf::Inertial& source = *link.inertial;
  body.mass = source.mass;
  body.inertial = inertial_in_body_frame(body, frame * source.origin.translation(), frame.linear() * source.origin.linear(), source.inertia);
  if (!body.inertial->inertia.allFinite() || !body.inertial->centre_of_mass.allFinite()) {
    refuse(source.at, "<inertial> of link '" + link.name + "'",
           "its <inertia> or <origin> is not finite in the body's frame: the values overflow when turned into it");
  }
  return body;
}

// A point (world, m) in body `index`'s frame, or in the world's for kWorld.
Eigen::Vector3d anchor(const Model& model, int index, const Eigen::Vector3d& point) {
  if (index == kWorld) return point;
  const Body& body = model.bodies[static_cast<std::size_t>(index)];
  return body.orientation().conjugate() * (point - body.position);
}

// A revolute or prismatic joint's range from its <limit>: both ends given, holding 0, a
// revolute's inside (−π, π).
Range joint_range(const urdf::Joint& joint) {
  const std::string type = type_name(joint.type);
  if (!joint.limit) refuse(joint.at, joint_tag(joint), "a " + type + " joint needs a <limit lower upper> (required by the URDF specification)");
  const urdf::Limit& limit = *joint.limit;
  for (const auto& [end, name] : {std::pair{limit.lower, "lower"}, std::pair{limit.upper, "upper"}}) {
    if (!end) {
      refuse(limit.at, std::string("<limit ") + name + ">",
             "missing: joint '" + joint.name + "' is " + type + " (URDF's default 0 for both ends would lock it)");
    }
  }
  const Range range{*limit.lower, *limit.upper};
  std::string text(1, '[');  // appended: GCC 12 warns falsely (-Wrestrict) on "[" + std::string
  text.append(std::to_string(range.min)).append(", ").append(std::to_string(range.max)).append("]");
  if (!(range.min < range.max)) refuse(limit.at, "<limit>", "lower must be below upper, got " + text);
  if (!(range.min <= 0 && range.max >= 0)) {
    refuse(limit.at, "<limit>", "range " + text + " does not hold 0, the file's pose (limber's joint coordinate is 0 there)");
  }
  if (joint.type == urdf::JointType::revolute && !(range.min > -std::numbers::pi && range.max < std::numbers::pi)) {
    refuse(limit.at, "<limit>", "a revolute range reaching ±π (±180°) is not supported (use continuous for an unlimited hinge)");
  }
  return range;
}

// URDF joint `source` from body `inboard` (or kWorld) to body `outboard`, `frame` the child
// link's world frame at q = 0 (its origin is the joint's anchor).
Joint make_joint(const urdf::Joint& source, const Isometry& frame, const Model& model, int inboard, int outboard,
                 std::vector<std::string>& notes) {
  Joint joint;
  joint.name = source.name;
  joint.inboard = inboard, joint.outboard = outboard;
  joint.inboard_anchor = anchor(model, inboard, frame.translation());
  joint.outboard_anchor = anchor(model, outboard, frame.translation());
  if (source.type == urdf::JointType::fixed) {
    joint.type = JointType::fixed;
    if (source.damping > 0 || source.friction > 0) notes.push_back(urdf::where(source.at) + joint_tag(source) + ": <dynamics>: ignored: a fixed joint");
    return joint;
  }
  joint.type = source.type == urdf::JointType::prismatic ? JointType::prismatic : JointType::revolute;
  joint.axis = (frame.linear() * source.axis).normalized();
  if (source.type == urdf::JointType::continuous) {
    if (source.limit && (source.limit->lower || source.limit->upper)) {
      notes.push_back(urdf::where(source.limit->at) + "<limit lower upper>: ignored: joint '" + source.name + "' is continuous (unlimited)");
    }
  } else {
    joint.limits.range = joint_range(source);
  }
  if (source.damping > 0) joint.drive = JointDrive{.damping = source.damping};
  joint.friction = source.friction;
  return joint;
}

// The link whose body floats with `floating_base`: the root, or a root frame's one child by a
// fixed joint. -1 without floating_base.
int floating_link(const urdf::Robot& robot, const Tree& tree, bool floating_base) {
  if (!floating_base) return -1;
  const urdf::Link& root = robot.links[static_cast<std::size_t>(tree.root)];
  if (!is_frame(root)) return tree.root;
  const std::vector<int>& children = tree.child_joints[static_cast<std::size_t>(tree.root)];
  if (children.size() == 1) {
    const auto joint = static_cast<std::size_t>(children.front());
    const int child = tree.link_of_child[joint];
    if (robot.joints[joint].type == urdf::JointType::fixed && !is_frame(robot.links[static_cast<std::size_t>(child)])) return child;
  }
  refuse(root.at, link_tag(root),
         "a floating base needs a root link with mass and geometry, or a root frame holding one such link by a fixed joint");
}

// Every link in tree order: its world frame, its body (or the body it folds into), its joint.
void add_links(const urdf::Robot& robot, const Tree& tree, bool floating_base, Model& model, std::vector<std::string>& notes,
               ModelOrigins& origins) {
  const int floats = floating_link(robot, tree, floating_base);
  std::vector<Isometry> frame(robot.links.size(), Isometry::Identity());
  std::vector<int> body_of(robot.links.size(), kWorld);
  for (const int l : tree.order) {
    const auto index = static_cast<std::size_t>(l);
    const urdf::Link& link = robot.links[index];
    const int j = tree.parent_joint[index];
    const urdf::Joint* joint = j < 0 ? nullptr : &robot.joints[static_cast<std::size_t>(j)];
    const int parent = joint ? tree.link_of_parent[static_cast<std::size_t>(j)] : -1;
    if (joint) frame[index] = frame[static_cast<std::size_t>(parent)] * joint->origin;
    const int inboard = joint ? body_of[static_cast<std::size_t>(parent)] : kWorld;
    if (is_frame(link)) {
      if (!joint) continue;  // the root frame: the world
      if (joint->type != urdf::JointType::fixed) {
        refuse(joint->at, joint_tag(*joint), "a " + type_name(joint->type) + " joint into link '" + link.name +
                                                 "', a frame (no mass, no collision geometry), is not supported yet: it would move nothing");
      }
      body_of[index] = inboard;
      notes.push_back(urdf::where(link.at) + link_tag(link) + ": a frame (no mass, no collision geometry), folded into " +
                      (inboard == kWorld ? std::string("the world") : "'" + model.bodies[static_cast<std::size_t>(inboard)].name + "'"));
      continue;
    }
    model.bodies.push_back(link_body(link, frame[index]));
    origins.bodies.push_back(urdf::where(link.at) + link_tag(link));
    const int own = static_cast<int>(model.bodies.size()) - 1;
    body_of[index] = own;
    if (l == floats) continue;
    if (joint && joint->type == urdf::JointType::floating) {
      if (parent != tree.root) refuse(joint->at, joint_tag(*joint), "a floating joint is only supported for a child of the root link");
      continue;  // a free body
    }
    if (!joint) {
      urdf::Joint weld;
      weld.name = link.name + ".weld";
      model.joints.push_back(make_joint(weld, frame[index], model, kWorld, own, notes));
      origins.joints.push_back(urdf::where(link.at) + link_tag(link));
    } else {
      model.joints.push_back(make_joint(*joint, frame[index], model, inboard, own, notes));
      origins.joints.push_back(urdf::where(joint->at) + joint_tag(*joint));
    }
  }
}

}  // namespace

Model parse_urdf(std::string_view xml, const std::filesystem::path& file_name, std::vector<std::string>& notes, bool floating_base) {
  const std::string file = file_name.string();
  const urdf::Robot robot = urdf::read_robot(xml, file, notes);
  const Tree tree = build_tree(robot);
  Model model;
  model.name = robot.name.empty() ? "urdf" : robot.name;
  model.settings.sleep.enabled = false;  // MuJoCo's convention: no body sleeps
  ModelOrigins origins;
  add_links(robot, tree, floating_base, model, notes, origins);
  if (model.bodies.empty()) refuse(robot.at, "<robot>", "no link has mass and collision geometry: nothing to simulate");
  validate_model_from(model, origins, file);
  return model;
}

Model load_urdf(const std::filesystem::path& file, std::vector<std::string>& notes, bool floating_base) {
  return parse_urdf(scene_input::read_file(file, scene_input::FileKind::model), file, notes, floating_base);
}

}  // namespace limber
