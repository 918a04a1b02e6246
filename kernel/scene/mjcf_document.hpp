// MJCF (MuJoCo's XML model format) read into a plain document: bodies, joints, geoms and
// actuators with every default, include, angle unit and orientation resolved, and each body's mass
// properties computed as MuJoCo's compiler does. No limber Model yet: the conversion
// (kernel/scene/MJCF.md §3) reads this document.
//
// Semantics are MuJoCo 2.2.2's (the XML reference, doc/XMLreference.rst, and its compiler,
// src/user/user_objects.cc), checked against mj_loadXML of the same files
// (tests/scene/mjcf_mujoco_test.cpp). MJCF.md §2 lists the rules that matter; the ones a reader
// may not expect:
// - include: `<include file>` is resolved against the MAIN file's directory; the included file's
//   root element is dropped and its children take the include's place. Including a file twice
//   (or in a cycle) is an error. Every file is read as scene_file.hpp's load_scene_file says: a
//   regular file only (a FIFO or /dev/zero is refused at the <include>), the main file and its
//   includes within kMaxModelFileBytes together, each nested at most kMaxXmlDepth elements deep,
//   includes inside includes' roots too. Names and every other attribute must be UTF-8.
// - A value whose derived quantity overflows (a geom's size, fromto or density whose volume,
//   mass or inertia is not finite; geoms whose sum is not) is refused at that attribute; what
//   only the assembled Model shows names the element the body or joint came from.
// - Sections apply in MuJoCo's order whatever their order in the file (compiler and option,
//   defaults, worldbody, actuator), as mj_loadXML reads them.
// - Defaults: a nested class copies its parent when it is read; several top-level <default>s
//   all write into `main`; an element takes its `class`, else its body's `childclass` (inherited
//   down the tree), else main. `<freejoint>` takes no defaults. A partial `size`, `friction` or
//   `gear` overwrites only the leading numbers of its class's value.
// - Angles (`<compiler angle>`, default degree): euler, axisangle, hinge and ball ranges (only
//   when the joint is limited, as MuJoCo), hinge ref and springref. Never ctrlrange.
// - `range` without `limited` (and ctrlrange without ctrllimited, forcerange without
//   forcelimited) is an error unless `<compiler autolimits="true">` (MuJoCo 2.2.2).
//
// Ignored, with a line in Document::notes (they do not change the dynamics limber simulates):
// asset, visual, statistic, size, custom, light, camera, site, sensor, keyframe; rendering
// attributes (material, rgba, ...); option integrator/solver/iterations/tolerance; the soft
// constraint parameters (solref, solimp, solreflimit, solimplimit, margin, gap, ...).
// Refused with one line "FILE:LINE: <element>: not supported: reason" (a ModelError):
// composite, tendon, equality, contact, general and muscle actuators, non-joint transmissions,
// mesh and hfield geoms, coordinate="global", and any element or attribute outside MuJoCo's
// schema (it is closed). Malformed values (bad numbers, unknown types, missing sizes, two
// orientations) are errors of the same form: "model.xml:12: <joint range>: expected 2 numbers,
// got 'a b'".
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/kernel/model/model.hpp"  // ModelError

namespace limber::mjcf {

/// Where an element starts: the file it was read from (the main file or an included one, as
/// its path was given or resolved) and its 1-based line.
struct Source {
  std::string file;
  int line = 0;
};

enum class GeomType { plane, sphere, capsule, cylinder, box, ellipsoid };

/// A `<geom>`, defaults applied. Frame: the geom's local z is a capsule's or cylinder's axis.
struct Geom {
  std::string name;
  GeomType type = GeomType::sphere;
  Source at;
  /// MuJoCo's compiled geom_size, m: sphere (radius, 0, 0); capsule and cylinder (radius,
  /// half-length, 0); box and ellipsoid (half-sizes x, y, z); plane (x and y half-sizes, 0 for
  /// infinite, grid spacing). With fromto, the half-length along z is |to - from|/2 (a box's or
  /// ellipsoid's y half-size then equals its x half-size, as MuJoCo).
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  /// The geom's centre in its body's frame, m (fromto: the midpoint).
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  /// Geom frame -> body frame (fromto: the shortest arc taking +z to from - to, as MuJoCo).
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  /// kg: the `mass` attribute, else density (default 1000 kg/m³) times the volume; planes 0.
  double mass = 0;
  int contype = 1, conaffinity = 1, condim = 3;
  /// Sliding, torsional, rolling friction coefficients (MuJoCo's defaults).
  Eigen::Vector3d friction{1, 0.005, 0.0001};
  int group = 0;
};

enum class JointType { hinge, slide, ball, free };

/// A `<joint>` or `<freejoint>`, defaults applied (a freejoint takes none).
struct Joint {
  std::string name;
  JointType type = JointType::hinge;
  Source at;
  /// A point on the axis in the body frame, m (0 for a free joint).
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  /// Body frame, unit (normalized as MuJoCo does; +z for ball and free joints).
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  /// Resolved: explicit `limited`, else (autolimits) whether a range was given. Free: false.
  bool limited = false;
  /// rad for hinge and ball (converted from degrees when limited and compiler angle=degree, as
  /// MuJoCo), m for slide. Absolute coordinates (MuJoCo's q), meaningful when `limited`.
  double range_min = 0, range_max = 0;
  /// The coordinate at the XML pose (qpos0) and the spring's rest coordinate: rad for a hinge
  /// (converted from degrees), m for a slide; MuJoCo leaves a ball's as given.
  double ref = 0, springref = 0;
  /// N m/rad or N/m; N m s/rad or N s/m; kg m² or kg; N m or N (per degree of freedom).
  double stiffness = 0, damping = 0, armature = 0, frictionloss = 0;
};

/// A `<body>`, its frame, joints, geoms and mass properties.
struct Body {
  std::string name;
  int parent = -1;  ///< index into Document::bodies; -1: the worldbody
  Source at;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();               ///< in the parent's frame, m
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< body frame -> parent frame
  /// In file order; they compose in order, the first next to the parent (MuJoCo's kinematics).
  std::vector<Joint> joints;
  std::vector<Geom> geoms;
  bool explicit_inertial = false;  ///< an <inertial> element was given
  /// kg: from <inertial>, or (inertiafromgeom true, or auto without <inertial>) the geoms' sum.
  double mass = 0;
  /// Body frame, m. A body with no mass keeps 0 (MuJoCo's body_ipos is then no centre of mass).
  Eigen::Vector3d centre_of_mass = Eigen::Vector3d::Zero();
  /// kg m², about the centre of mass in the body frame: the full symmetric tensor, not
  /// diagonalized (MuJoCo's R diag(body_inertia) Rᵀ, R from body_iquat).
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
};

enum class ActuatorType { motor, position, velocity };

/// A joint actuator (MuJoCo's motor, position or velocity shortcut). Force on the joint:
/// gear · (motor: ctrl; position: kp (ctrl - gear q); velocity: kv (ctrl - gear q̇)), ctrl
/// clamped to ctrlrange when ctrllimited, the actuator force to forcerange when forcelimited.
struct Actuator {
  std::string name;
  ActuatorType type = ActuatorType::motor;
  Source at;
  int joint = -1;       ///< index in Document::bodies[joint_body].joints
  int joint_body = -1;  ///< index in Document::bodies of the joint's body
  double gear = 1;      ///< gear[0]; the other five do not act on a joint
  double kp = 0;        ///< position: N m/rad (or N/m) per unit ctrl; 0 for the others
  double kv = 0;        ///< velocity: N m s/rad (or N s/m); 0 for the others
  bool ctrllimited = false, forcelimited = false;
  double ctrl_min = 0, ctrl_max = 0, force_min = 0, force_max = 0;  ///< ctrl units; N m or N
};

/// A whole MJCF file, includes spliced.
struct Document {
  std::string model_name;  ///< <mujoco model>
  std::string file;        ///< the main file, as given
  /// Parents before children, depth first in file order: MuJoCo's body ids minus one (its body
  /// 0 is the world).
  std::vector<Body> bodies;
  std::vector<Geom> world_geoms;     ///< the worldbody's own geoms (their body frame is the world)
  std::vector<Actuator> actuators;   ///< file order (MuJoCo's actuator ids)
  double timestep = 0.002;           ///< s, <option timestep>
  Eigen::Vector3d gravity{0, 0, -9.81};  ///< m/s², <option gravity>
  /// "FILE:LINE: <element>: ignored: reason", one per ignored element or attribute per file.
  std::vector<std::string> notes;
};

/// Reads an MJCF file and the files it includes. Throws ModelError, one line
/// "FILE:LINE: <element attr>: problem", at the first problem (an unreadable file: "FILE: ...").
Document load_mjcf(const std::filesystem::path& file);

/// Reads MJCF text. `file_name` names it in messages and locates its includes (relative to its
/// directory). Throws ModelError as load_mjcf.
Document parse_mjcf(std::string_view xml, const std::filesystem::path& file_name);

}  // namespace limber::mjcf
