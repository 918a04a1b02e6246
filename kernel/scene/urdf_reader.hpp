// The URDF reader's first half: the XML of a <robot> read into plain links and joints, every
// attribute checked and every number parsed, nothing interpreted yet (urdf.cpp turns them into
// a Model). Internal to kernel/scene; pugixml stays inside urdf_reader.cpp.
//
// The format is the URDF specification (wiki.ros.org/urdf/XML: link, joint and their children);
// where it leaves a choice, MuJoCo's URDF importer (src/xml/xml_urdf.cc) is followed.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber::urdf {

/// Where an element starts: the file as named and its 1-based line.
struct Source {
  std::string file;
  int line = 0;
};

/// "FILE:LINE: " for messages.
std::string where(const Source& at);

/// A rigid transform read from <origin xyz rpy>: child frame → parent frame (m, rad).
using Isometry = Eigen::Isometry3d;

/// URDF's roll-pitch-yaw: R = R_z(yaw)·R_y(pitch)·R_x(roll) (about the fixed x, then y, then z),
/// rad (the spec's <origin rpy>; MuJoCo's URDF reader builds the same rotation).
Eigen::Matrix3d rpy_rotation(const Eigen::Vector3d& roll_pitch_yaw);

enum class GeometryType { box, cylinder, sphere };

/// A <collision> of a link. Mesh geometry is refused while reading.
struct Collision {
  Source at;
  Source shape_at;                ///< the <box>, <cylinder> or <sphere> element
  std::string name;               ///< the collision's name attribute, or empty
  Isometry origin = Isometry::Identity();  ///< collision frame → link frame
  GeometryType type = GeometryType::sphere;
  double radius = 0;              ///< cylinder, sphere: m, > 0
  double length = 0;              ///< cylinder: m along the collision frame's z, > 0
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  ///< box: FULL extents along x, y, z, m, > 0
};

/// A link's <inertial>: mass and the inertia tensor about the centre of mass, in the inertial
/// frame (its origin is the centre of mass).
struct Inertial {
  Source at;
  Isometry origin = Isometry::Identity();  ///< inertial frame → link frame
  double mass = 0;                         ///< kg, ≥ 0
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();  ///< kg·m², symmetric, inertial frame
};

struct Link {
  Source at;
  std::string name;
  std::optional<Inertial> inertial;
  std::vector<Collision> collisions;  ///< file order
};

enum class JointType { revolute, continuous, prismatic, fixed, floating };

/// A <limit>: lower and upper as written (rad or m), both required for revolute and prismatic.
struct Limit {
  Source at;
  std::optional<double> lower, upper;
};

struct Joint {
  Source at;
  std::string name;
  JointType type = JointType::fixed;
  std::string parent, child;  ///< link names
  Source parent_at, child_at;
  Isometry origin = Isometry::Identity();   ///< child link frame → parent link frame at q = 0
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();  ///< unit, the joint (= child link) frame
  std::optional<Limit> limit;
  double damping = 0;   ///< <dynamics damping>: N·m·s/rad or N·s/m, ≥ 0
  double friction = 0;  ///< <dynamics friction>: N·m or N, ≥ 0
};

struct Robot {
  Source at;  ///< the <robot> element
  std::string name;
  std::vector<Link> links;    ///< file order
  std::vector<Joint> joints;  ///< file order
};

/// Reads the XML of a URDF file named `file` (in messages). Throws ModelError
/// "FILE:LINE: <element attr>: problem" at the first malformed or unsupported element or
/// attribute; appends "FILE:LINE: <element>: ignored: reason" to `notes`, once per kind.
Robot read_robot(std::string_view xml, const std::string& file, std::vector<std::string>& notes);

}  // namespace limber::urdf
