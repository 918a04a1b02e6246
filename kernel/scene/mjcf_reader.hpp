// The MJCF reader's internals, shared by its files: the XML files and their lines
// (mjcf_reader.cpp), frames (mjcf_frames.cpp), mass properties (mjcf_inertia.cpp), one element at
// a time (mjcf_elements.cpp) and the sections and body tree (mjcf_document.cpp). Internal to
// kernel/scene: it includes pugixml, which limber keeps private, so no public header may include
// this one.
//
// Every problem is a ModelError of one line, "FILE:LINE: <element attr>: problem", FILE the file
// the element was read from (an included file names itself, not the main one).
#pragma once

#include <array>
#include <deque>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <pugixml.hpp>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "limber/kernel/scene/mjcf_document.hpp"

namespace limber::mjcf::detail {

/// MuJoCo 2.2.2's mjMINVAL (include/mujoco/mjtnum.h: the least denominator, here the least total
/// mass of several geoms) and mjEPS (src/user/user_util.h: the "too small" threshold of axes).
inline constexpr double mj_minval = 1e-15;
inline constexpr double mj_eps = 1e-14;

/// One parsed file: its text (pugixml's offsets point into it), its tree and where its lines start.
struct Buffer {
  std::string file;
  std::string text;
  pugi::xml_document tree;
  std::vector<std::size_t> line_starts;  // offsets of each line's first character
};

/// An element and the file it was read from.
struct Node {
  pugi::xml_node xml;
  const Buffer* buffer = nullptr;
  std::string_view name() const { return xml.name(); }
};

/// An attribute the reader accepts and drops, and why (the note's reason).
struct Ignored {
  std::string_view attribute;
  std::string_view reason;
};

/// The files, their lines, includes, attribute reading and the notes.
class Reader {
 public:
  explicit Reader(const std::filesystem::path& main_file);
  /// Parses the main file's text; returns its root element (which must be <mujoco>).
  Node parse_main(std::string_view xml);
  /// The element children of `element` in order, each <include> replaced by the children of
  /// its file's root. Call once per element: an include met twice is an error.
  std::vector<Node> children(const Node& element);
  Source source(const Node& element) const;
  /// Throws ModelError "FILE:LINE: <what>: problem".
  [[noreturn]] void fail(const Node& element, std::string_view what, std::string_view problem) const;
  /// Adds "FILE:LINE: <what>: ignored: reason" unless `what` was already noted in that file.
  void note(const Node& element, std::string_view what, std::string_view reason);
  /// Fails on an attribute neither read nor ignored (MuJoCo's schema is closed); notes the ignored.
  void check_attributes(const Node& element, std::initializer_list<std::string_view> read,
                        std::initializer_list<Ignored> ignored = {});
  void refuse_children(const Node& element);  ///< fails on any child element

  std::optional<std::string_view> text(const Node& element, const char* attribute) const;
  /// Reads numbers into the leading entries of `values`: exactly values.size() if `exact`, else
  /// 1 to values.size() (the rest keep their value, as MuJoCo's partial defaults). False: absent.
  bool numbers(const Node& element, const char* attribute, std::span<double> values, bool exact) const;
  std::optional<double> number(const Node& element, const char* attribute) const;
  std::optional<int> integer(const Node& element, const char* attribute) const;
  std::optional<bool> boolean(const Node& element, const char* attribute) const;
  /// The index of the attribute's value in `words`; fails naming them when it is none.
  std::optional<int> keyword(const Node& element, const char* attribute,
                             std::initializer_list<std::string_view> words) const;

  std::vector<std::string> take_notes() { return std::move(notes_); }

 private:
  const Buffer& parse(std::string file, std::string text);
  const Buffer& include(const Node& element);

  std::filesystem::path main_file_;
  std::filesystem::path directory_;        // the main file's: includes are relative to it
  std::deque<Buffer> buffers_;             // stable addresses: Nodes point at them
  std::set<std::string> included_;         // canonical paths of the files read
  std::size_t bytes_ = 0;                  // the files' bytes so far, against kMaxModelFileBytes
  int include_depth_ = 0;                  // includes being spliced inside one another
  std::set<std::string> noted_;            // "file\n<what>" already in notes_
  std::vector<std::string> notes_;
};

/// "<element attr>" or "<element>" for messages.
std::string tag(const Node& element, std::string_view attribute = {});

// ---- compiler settings and default classes (MuJoCo's mjCDef) ----

/// <compiler>: what changes how the rest reads.
struct Compiler {
  bool degree = true;                       // angle="degree" (MuJoCo's default)
  std::array<char, 3> eulerseq{'x', 'y', 'z'};
  int inertiafromgeom = 2;                  // 0 false, 1 true, 2 auto
  std::array<double, 2> inertiagroups{0, 5};
  bool autolimits = false;                  // MuJoCo 2.2.2's default
};

enum Tristate { tri_false = 0, tri_true = 1, tri_auto = 2 };

struct JointDefaults {
  JointType type = JointType::hinge;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  int limited = tri_auto;
  std::array<double, 2> range{0, 0};
  double ref = 0, springref = 0, stiffness = 0, damping = 0, armature = 0, frictionloss = 0;
};

struct GeomDefaults {
  GeomType type = GeomType::sphere;
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  std::optional<double> mass;
  double density = 1000;
  int contype = 1, conaffinity = 1, condim = 3, group = 0;
  Eigen::Vector3d friction{1, 0.005, 0.0001};
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector4d quat{1, 0, 0, 0};  // w x y z, as written
};

/// One default record for every actuator kind, as MuJoCo keeps: gain is gainprm[0] (a motor
/// sets it to 1, a position's kp or a velocity's kv to theirs).
struct ActuatorDefaults {
  double gain = 1, gear = 1;
  int ctrllimited = tri_auto, forcelimited = tri_auto;
  std::array<double, 2> ctrlrange{0, 0}, forcerange{0, 0};
};

struct DefaultClass {
  std::string name;
  JointDefaults joint;
  GeomDefaults geom;
  ActuatorDefaults actuator;
};

/// What the element readers share: the reader, the compiler settings and the default classes
/// (classes[0] is main).
struct Context {
  explicit Context(Reader& r) : reader(r) {}
  Reader& reader;
  Compiler compiler;
  std::vector<DefaultClass> classes{DefaultClass{"main", {}, {}, {}}};
  std::unordered_map<std::string, int> class_index{{"main", 0}};
  /// Joint names to (body index, index in the body's joints), for the actuators.
  std::unordered_map<std::string, std::pair<int, int>> joints_by_name;

  /// The class an element takes: its `class` attribute, else `inherited`.
  int element_class(const Node& element, int inherited) const;
};

// ---- frames (mjcf_frames.cpp) ----

/// The orientation attributes of one element, as written.
struct OrientationSpec {
  std::optional<Eigen::Vector4d> quat;       // w x y z
  std::optional<Eigen::Vector4d> axisangle;  // axis, angle
  std::optional<Eigen::Vector3d> euler;
  std::optional<Eigen::Matrix<double, 6, 1>> xyaxes;
  std::optional<Eigen::Vector3d> zaxis;
};

/// A problem with a frame attribute, for the caller to report with the element's place.
struct FrameError {
  std::string attribute;
  std::string problem;
};

/// Reads pos-less orientation attributes (quat, axisangle, euler, xyaxes, zaxis) of `element`;
/// fails when more than one is given.
OrientationSpec read_orientation(const Reader& reader, const Node& element);
/// The rotation (element frame -> parent frame) as MuJoCo's mjCAlternative::Set and
/// user_util.cc compute it; `fallback` (w x y z, normalized) when no attribute is given.
/// Throws FrameError (axisangle, xyaxes or zaxis too small).
Eigen::Quaterniond resolve_orientation(const OrientationSpec& spec, const Eigen::Vector4d& fallback,
                                       const Compiler& compiler);
/// MuJoCo's mjuu_z2quat: the shortest arc taking +z to `direction` (x for a direction along -z).
Eigen::Quaterniond z_axis_to_quaternion(const Eigen::Vector3d& direction);
/// `quat` normalized (MuJoCo's mjuu_normvec; a zero quaternion stays as it is).
Eigen::Quaterniond normalized_quaternion(const Eigen::Vector4d& wxyz);

// ---- mass properties (mjcf_inertia.cpp) ----

/// m³; 0 for a plane.
double geom_volume(GeomType type, const Eigen::Vector3d& size);
/// Principal moments about the geom's centre in its frame, kg m² (MuJoCo's mjCGeom::SetInertia).
Eigen::Vector3d geom_principal_moments(GeomType type, const Eigen::Vector3d& size, double mass);
/// The geom's mass from its `mass` attribute or density, as mjCGeom::Compile.
double geom_mass(GeomType type, const Eigen::Vector3d& size, std::optional<double> mass, double density);
/// R diag(moments) Rᵀ.
Eigen::Matrix3d rotated_inertia(const Eigen::Quaterniond& rotation, const Eigen::Vector3d& moments);

struct MassProperties {
  int geoms = 0;  // how many were summed
  double mass = 0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
};
/// The geoms whose group lies in `groups` summed as MuJoCo's mjCBody::GeomFrame: masses and
/// centres, then the parallel-axis theorem about the mass-weighted centre. Empty: no geoms. The
/// caller reports a total mass of several geoms below 1e-15 kg (MuJoCo's error).
std::optional<MassProperties> geoms_mass_properties(const std::vector<Geom>& geoms,
                                                    const std::array<double, 2>& groups);

// ---- elements (mjcf_elements.cpp) ----


/// A body's <joint> (class `inherited` unless it names one) and <freejoint>.
Joint make_joint(Context& context, const Node& element, int inherited);
Joint make_free_joint(Context& context, const Node& element);
/// A <geom>; `moving`: its body is not welded to the world (planes are refused there).
Geom make_geom(Context& context, const Node& element, int inherited, bool moving);
/// A body's <inertial>: sets explicit_inertial, mass, centre_of_mass and inertia.
void read_inertial(Context& context, const Node& element, Body& body);
/// An <actuator> child: motor, position or velocity (the caller refuses the others).
Actuator make_actuator(Context& context, const Node& element);
/// One child of a <default>: its fields into `into` (joint, geom, motor, position, velocity),
/// noted (site, camera, light, material, mesh, pair, equality, tendon) or refused.
void read_default_element(Context& context, const Node& element, DefaultClass& into);

}  // namespace limber::mjcf::detail
