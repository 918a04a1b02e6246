// Scene files: JSON in, a validated Scene out (its Model, and the settings it gives the methods
// that may step it), or one clear error line.
//
// Format (version 1). All numbers SI (m, kg, s). "required" fields missing, unknown fields,
// wrong types and non-finite numbers (e.g. 1e999) are errors. Optional fields and their
// defaults are listed here and in README.md; no other value is ever filled in silently.
//
// {
//   "limber_scene": 1,                         required, must be 1
//   "name": "humanoid",                        required, non-empty string
//   "description": "...",                      optional string
//   "settings": {                              required
//     "gravity": [0, 0, -9.81],                required, m/s²
//     "time_step": 0.004166667,                required, s, > 0
//     "duration": 5,                           required, s, > 0
//     "damping": 0,                            optional (0), 1/s, ≥ 0
//     "divergence_speed": 1000,                optional (1000), m/s, > 0
//     "contact_recovery_speed": 0.5,           optional (0.5), m/s, ≥ 0: push-out speed of old penetration
//     "release_drives_on_impact": false,       optional (false): every joint drive goes limp once the
//                                              ball has touched a limb (an active ragdoll's switch)
//     "limb_friction": 0.5,                    optional (0.5), ≥ 0: Coulomb friction between limbs that touch
//     "tolerances": {                          optional; each field optional, ≥ 0: what a run's verdict
//                                              calls accurate, over every step (model.hpp's Tolerances)
//       "joint_gap": 0.01,                     (0.01) of a link: a joint's gap, a particle limb's stretch
//       "penetration": 0.03,                   (the thinnest limb's radius) m: the deepest overlap
//       "limit": 0.1,                          (0.1) rad (m for a prismatic range) past a joint's limit
//       "energy_gain": 0.01 },                 (0.01; 1 with actuators or drives) of the energy scale
//     "relaxation": {                          optional; each field optional
//       "iterations": 100,                     (100) integer ≥ 1
//       "tolerance": 0,                        (0) m, ≥ 0; 0 disables
//       "budget_us": 0,                        (0) µs, ≥ 0; 0 disables
//       "over_relaxation": 1,                  (1) in (0, 2): successive over-relaxation factor
//       "projection": "pbd",                   ("pbd": end-of-step gradient, the thesis's) or "rattle":
//                                              start-of-step gradient and a velocity stage (SHAKE/RATTLE)
//       "substeps": 1 },                       (1) integer in [1, 10000]: each step runs as this many
//     "sleep": {                               optional; each field optional
//       "enabled": true,                       (true)
//       "start_asleep": false,                 (false)
//       "speed_threshold": 0.05,               (0.05) m/s, ≥ 0
//       "time_to_sleep": 0.5 },                (0.5) s, ≥ 0
//     "verlet": {                              optional; each field optional
//       "joints": "zero_length_constraint",    ("zero_length_constraint") or "shared_particle"
//       "limb_masses": "ends",                 ("ends": half each end, the thesis), "inertia": three
//                                              particles keeping mass, centre of mass, transverse inertia,
//                                              or "lumps": each point mass (on the axis) to head and tail
//                                              by the lever rule
//       "joint_solve": "rows",                 ("rows": projected in the sweeps) or "tree": each ragdoll's
//                                              joints, limits and contacts solved exactly per limb tree
//       "drag_factor": 1.99 } },               (absent) in (1, 2]
//   "ground": { "height": 0, "restitution": 0.1, "friction": 0.6 },      optional object; all fields required;
//                                              restitution in [0, 1], friction ≥ 0
//   "bounds": { "min": [0,0,0], "max": [5,5,5], "restitution": 0.5, "friction": 0.3 },
//                                              optional object; all required; max > min on every axis
//   "ball": { "radius": 0.05, "mass": 2.268, "restitution": 0.8,
//             "position": [0.8, 0, 0.25], "speed": 6, "direction": [-1, 0, 0] },
//                                              optional object; all required; radius, mass > 0;
//                                              restitution in [0, 1]; speed ≥ 0; direction non-zero
//                                              (normalized); velocity = speed · direction
//   "balls": [ { ...as "ball"... }, ... ]      optional: several balls (a volley), in place of "ball"
//   "bodies": [ {                              required unless "chain" is given
//       "name": "neck",                        required, unique, non-empty, not "world"
//       "shape": { "type": "cylinder", "length": 0.05, "radius": 0.02 },
//                                              required; type "cylinder" | "capsule" | "box" | "ellipsoid"
//                                              (model.hpp's Shape). cylinder, capsule: length and radius,
//                                              both required; length > 0 (a capsule: ≥ 0, a sphere of
//                                              length 0 and radius > 0); radius ≥ 0
//       "shape": { "type": "box", "half_extents": [0.1, 0.05, 0.2], "rotation": [1, 0, 0, 0] },
//                                              box, ellipsoid: "half_extents" required, m, each > 0 (a
//                                              box's half-sizes, an ellipsoid's semi-axes, along the shape
//                                              frame's x, y, z); "rotation" optional ([1, 0, 0, 0], the
//                                              identity): the unit quaternion [w, x, y, z] (norm 1 within
//                                              1e-9) turning the shape frame into the body frame (a
//                                              collider's "rotation" is a rotation vector instead). Either
//                                              family's fields on the other are refused by name
//       "mass": 2.268,                         exactly one of "mass" (kg, > 0),
//       "density": 1000,                       "density" (kg/m³, > 0; mass = density × volume(shape)) or
//       "point_masses": [ {"position": [0, 0, 0.01], "mass": 1.2, "radius": 0.02}, ... ],
//                                              lumps in the body frame (m; kg > 0; radius m ≥ 0, optional
//                                              0; a solid sphere); mass = their sum (thesis eq. 4.1)
//       "inertial": {"centre_of_mass": [0, 0, 0.02],  optional, with "mass": the distribution given
//                    "inertia": [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]},  directly (body frame; kg·m² about
//                                              the centre of mass; symmetric, positive, a physical body)
//       "position": [0, 0, 1.02],              required, m, centre
//       "axis": [0, 0, 1],                     required, non-zero (normalized), tail → head
//       "linear_velocity": [0, 0, 0],          optional ([0,0,0]), m/s
//       "angular_velocity": [0, 0, 0],         optional ([0,0,0]), rad/s
//       "collision": {"group": 1, "mask": 4294967295} } ],
//                                              optional; each field optional (these defaults): integers
//                                              in [0, 2^32), bits; two things collide when each one's
//                                              group shares a bit with the other's mask (model.hpp's
//                                              CollisionFilter)
//   "joints": [ {                              optional (none)
//       "name": "head-neck",                   required, unique, non-empty
//       "type": "spherical",                   required: "spherical" | "revolute" | "prismatic" |
//                                              "universal" | "fixed" | "serial" (model.hpp's JointType)
//       "inboard": "head",                     required: a body name, or "world"
//       "outboard": "neck",                    required: a body name, different from inboard
//       "inboard_anchor": "tail",              required: "head" | "tail" (the axis end points,
//       "outboard_anchor": "head",             local (0,0,±length/2); not on a box or ellipsoid) or a
//                                              local [x,y,z] in m; with inboard "world", a world [x,y,z] in m
//       "axis": [1, 0, 0],                     revolute, prismatic, universal: required, world at rest
//       "second_axis": [0, 1, 0],              universal: required, perpendicular to axis
//       "stiffness": 2e4, "damping": 20,       optional: the stiff-spring method's spring (N/m, N·s/m)
//       "limits": {                            optional; each field optional (model.hpp's JointLimits)
//         "swing": 1.2,                        spherical: cone half-angle, rad, in (0, pi)
//         "swing_axis": [0, 0, -1],            spherical: the cone's axis, world at rest, fixed in the
//                                              inboard body (default: the outboard's axis at rest)
//         "twist": [-0.5, 0.5],                spherical: roll about the outboard's axis from the cone's axis, rad, min <= 0 <= max
//         "range": [0, 2.6] },                 revolute: hinge angle, rad; prismatic: slide, m; min <= 0 <= max
//       "friction": 0,                         optional (0): largest resisting torque, N·m (force, N, prismatic)
//       "drive": {                             optional: a PD drive toward a target (spherical, revolute,
//         "stiffness": 300, "damping": 30,     prismatic); each field optional (0): N·m/rad, N·m·s/rad
//         "target": 0.5, "target_velocity": 0, revolute: rad, rad/s; prismatic: m, m/s
//         "target_rotation": [0, 0.3, 0],      spherical: rotation vector from rest, rad, world axes at rest
//         "target_angular_velocity": [0, 0, 0] },      spherical: rad/s
//       "armature": 0.01,                      optional (0): revolute, prismatic: kg·m² or kg on the
//                                              coordinate's diagonal of the mass matrix
//       "serial_axes": [ {                     serial: required, 1 to 6, in order from the inboard body
//         "name": "hip_x",                     required, unique among the Model's axes
//         "slide": false,                      optional (false): a hinge; true: a slide
//         "axis": [1, 0, 0], "point": [0, 0, 1],  required, world at rest: the axis and a point on it
//         "range": [-0.5, 0.5],                optional: rad (m for a slide), min <= 0 <= max
//         "drive": { ...as above... },         optional: the coordinate's spring and damper
//         "friction": 0, "armature": 0 } ] } ],  optional (0 each)
//   "actuators": [ {                           optional (none): model.hpp's Actuator, u the control
//       "name": "hip",                         required, unique
//       "joint": "right_hip",                  required: a revolute, prismatic or serial joint's name
//       "axis": "hip_x",                       serial joints only, required: the axis's name
//       "kind": "motor",                       optional ("motor"): force gear·u; "position":
//                                              gear·gain·(u − gear·(q + reference)); "velocity": gear·gain·(u − gear·q̇)
//       "gear": 40,                            required: N·m (or N) per unit of control; position and
//                                              velocity: actuator length per unit of q
//       "gain": 100,                           position, velocity: required, ≥ 0 (MuJoCo's kp, kv)
//       "reference": 0,                        position: optional (0): q's value at the initial pose (MuJoCo's ref)
//       "control_range": [-1, 1] } ],          optional: controls outside are clamped to it
//   "chain": {                                 optional generator of a straight chain of links
//       "links": 5,                            required integer ≥ 1 (SceneOptions::links overrides)
//       "shape": "capsule",                    required: "cylinder" | "capsule" (not "box" or "ellipsoid")
//       "link_length": 0.2, "link_radius": 0.015,     required; > 0 and ≥ 0
//       "link_mass": 2.268, "end_mass": 4.536,        required, kg, > 0 (end_mass: the last link)
//       "anchor": [0, 0, 1.5],                 required: world point of link_0's head
//       "direction": [1, 0, 0],                required, non-zero: from each link's head to its tail
//       "pinned": true },                      required: joint "joint_0" holds link_0's head to the world
//     It appends bodies "link_0" … "link_{N−1}" (after any explicit ones), laid head to tail from
//     the anchor, and spherical joints "joint_k" (k ≥ 1) from link_{k−1}'s tail to link_k's head.
//   "tree": {                                  optional generator (at most one of chain, tree, grid):
//       "branching": 2,                        required integer ≥ 1: children per link
//       "links": 127, or "depth": 6,           exactly one: links in all, or levels below the root
//       "link_length": 0.1, "link_mass": 1,    required, > 0
//       "anchor": [0, 0, 2], "pinned": true }, required: the root's head, held to the world or not
//     Bodies "link_0" … (link k hangs from link (k−1)/branching; generators.hpp's make_tree_model).
//   "grid": {                                  optional generator: a cloth-like sheet
//       "columns": 20, "rows": 20,             required integers ≥ 2: nodes
//       "spacing": 0.05, "link_mass": 0.01,    required, > 0 (each edge a capsule link)
//       "anchor": [0, 0, 2],                   required: node (0, 0); rows go down (−z), columns +x
//       "pin_top_corners": true },             required
//   "copies": { "count": 16, "spacing": 1.5 }, optional: everything above count times on a square
//                                              lattice in x, y, spacing m apart, names "c<k>.<name>";
//                                              SceneOptions::copies (--copies) overrides the count
//     "layers": 2, "layer_height": 1.4         optional, together: the copies in `layers` (integer in
//                                              [1, count]) lattices of ⌈count/layers⌉, each layer_height
//                                              m above the one below (≥ the bodies' height), odd ones
//                                              half a spacing across (a pile to drop; generators.hpp's
//                                              copies_of). Colliders, ground and balls stay as given.
//     "per_layer": 100, "layer_height": 1.4    optional, together, in place of layers: lattices of
//                                              per_layer (integer ≥ 1) copies, as many as the count
//                                              needs, so --copies grows the crowd upward (copies_in_layers_of)
//     A scene may generate at most 10⁷ bodies (chain, tree, grid and copies together; SceneOptions::max_bodies).
//   "colliders": [ {                           optional (none): static level geometry (model.hpp's StaticCollider)
//       "name": "bar",                         required, unique, non-empty, no body's name
//       "type": "box",                         required: "box" | "capsule" | "mesh" | "stairs" (a generator
//                                              of a mesh); a field another type takes is refused
//       "restitution": 0, "friction": 0.5,     optional (these): in [0, 1]; ≥ 0
//       "collision": {"group": 1, "mask": 4294967295},   optional, as a body's
//     box:      "position": [x, y, z],         required, m, its centre
//               "half_extents": [hx, hy, hz],  required, m, each > 0
//               "rotation": [rx, ry, rz],      optional ([0,0,0]): rotation vector (axis × angle, rad, as a
//                                              drive's target_rotation), box frame → world
//     capsule:  "position", "rotation"         as the box's; position is the middle of its core segment,
//               "axis": [0, 1, 0],             or instead of rotation: the core's direction (local +z), non-zero
//               "length": 1, "radius": 0.05,   required, m: the core segment (≥ 0) and the radius (> 0)
//     mesh:     "vertices": [[x, y, z], ...],  required, m
//               "triangles": [[0, 1, 2], ...], required, ≥ 1: vertex indices, counter-clockwise seen from
//                                              outside (the front; one-sided). Dropped at load, and
//                                              counted in Scene::notes: a degenerate triangle (twice
//                                              its area ≤ 1e-10 × its longest edge squared: repeated
//                                              or collinear vertices) and a duplicate (the same three
//                                              points, in the same turn, as an earlier triangle: it
//                                              would cost a step its time and add nothing). A mesh
//                                              left with none is refused.
//               "position", "rotation",        optional (none): the frame the vertices are given in (the
//                                              Model holds them in world coordinates)
//               "thickness": 0.1,              optional (0.1), m, > 0: how far behind a triangle counts as inside
//     stairs:   "steps": 6,                    required integer ≥ 1: risers (generators.hpp's make_stairs_mesh)
//               "rise": 0.15, "run": 0.3,      required, m, > 0: each riser's height, each tread's depth
//               "width": 2,                    required, m, > 0
//               "landing": 0.3,                optional (run), m, > 0: the top's depth beyond the last riser
//               "position": [x, y, z],         required: the first riser's foot, mid-width
//               "direction": [1, 0, 0],        required, horizontal, non-zero (normalized): uphill
//               "thickness": 0.1 } ],          optional (0.1), as a mesh's
//     The stairs are a closed mesh: risers, treads, landing, back, sides and bottom, facing out.
//     The meshes and stairs may have at most 10⁶ triangles in all (SceneOptions::max_triangles).
//   "variants": {                              optional: named sets of per-body overrides
//       "thin": { "head": { "radius": 0.04, "mass": 9.07 }, ... }, ... },
//                                              each override may give "radius" and/or "mass" (or
//                                              "density") for a body that exists; only "radius"
//                                              for a body with "point_masses" (their sum is its mass);
//                                              no "radius" for a box or an ellipsoid
//   "variant": "medium"                        required when "variants" is given: the default one
// }
//
// A scene that wraps a model file: limber's settings over an MJCF or URDF file's.
// {
//   "limber_scene": 1,                         required, must be 1
//   "model": "humanoid.xml",                   required: an MJCF (.xml) or URDF (.urdf) file, relative
//                                              to this file's directory
//   "name": "...", "description": "...",       optional: the name replaces the model file's
//   "floating_base": false,                    optional (false), URDF only: SceneOptions::floating_base
//   "settings": { ... }                        optional: any of the settings above, each replacing
//                                              the model file's (or the import's default for the
//                                              methods: load_scene_file); nothing else is allowed
// }
//
// Errors: ModelError whose what() is one line "<source>: <path>: <problem>", the path in JSON
// terms (e.g. "bodies[3].shape.radius", "joints[1].outboard", "colliders[2].triangles[5]",
// "variants.thin.neck.mass"). A malformed file reports "<source>:<line>:<column>: malformed
// JSON: <detail>", and arrays and objects nested deeper than kMaxJsonDepth (64) report
// "<source>:<line>:<column>: arrays and objects nested deeper than 64" at the first too deep,
// before anything is parsed.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "limber/kernel/model/method_settings.hpp"
#include "limber/kernel/model/model.hpp"

namespace limber {

/// Most bodies a scene may generate by default (chain, tree, grid and copies together): a guard
/// against a file asking for terabytes. Not a promise that so many fit: a 10⁷-link chain needs
/// about 25 GB under the particle method and up to 95 GB under the implicit springs
/// (bench/speed.md, "Linear costs"), more than most machines have — `limber run` refuses a
/// scene whose bodies would not fit in the memory available, before generating them
/// (SceneOptions::before_generating).
inline constexpr std::size_t kMaxSceneBodies = 10'000'000;

/// Most triangles a scene's mesh and stairs colliders may have in all, by default: a guard
/// against a few bytes of "stairs" asking for gigabytes (a mesh file of 10⁶ triangles would
/// already be past kMaxSceneFileBytes).
inline constexpr std::size_t kMaxSceneTriangles = 1'000'000;

/// Choices made when loading, for scenes that offer them.
struct SceneOptions {
  std::optional<std::string> variant;  ///< select one of "variants" (e.g. the humanoid's "thin")
  std::optional<long> links;           ///< number of links of the "chain" or "tree" generator
  std::optional<long> copies;          ///< copies of the scene's bodies (its "copies" count, or laid out by their extent)
  /// A generator (or copies) asking for more bodies is refused before anything is allocated:
  /// lower it to load untrusted files within a memory and time budget.
  std::size_t max_bodies = kMaxSceneBodies;
  /// Likewise for the triangles of the mesh and stairs colliders, all together.
  std::size_t max_triangles = kMaxSceneTriangles;
  /// Called with the number of bodies a generator (or copies) is about to make and its path in
  /// the file (e.g. "chain.links"), after the max_bodies check and before anything is allocated:
  /// a caller refuses sizes it cannot hold (the command line: the memory available) by throwing.
  std::function<void(double bodies, const std::string& path)> before_generating = nullptr;
  /// A URDF robot only (kernel/scene/urdf.hpp): its root link floats (a free body) instead of
  /// being welded to the world. Refused for any other file.
  bool floating_base = false;
};

/// A loaded scene: the solver-independent Model, and what the file says about the methods
/// ("settings.relaxation", "settings.verlet", "settings.springs"), which each method takes
/// through its options (methods/method.hpp: world_options(method, scene.methods)).
struct Scene {
  Model model;
  MethodSettings methods;
  /// What the loader dropped or approximated, one line each ("file:line: <element>: reason"):
  /// a model file's elements limber does not simulate (kernel/scene/mjcf_model.hpp,
  /// kernel/scene/urdf.hpp); in a JSON scene, the triangles a mesh collider dropped
  /// ("<source>: colliders[k].triangles: ...", the format above).
  std::vector<std::string> notes;
};

/// Parses and validates a scene. `source` names it in error messages (usually the file path).
/// Throws ModelError (one line naming source, field and problem) on any bad input, including
/// an option the scene cannot honour (a variant it lacks, links without a "chain").
Scene load_scene_text(std::string_view json_text, std::string_view source, const SceneOptions& options = {});

/// Most bytes a JSON scene file may have (64 MiB: the largest shipped scene is ~30 kB; a mesh of
/// 10⁵ triangles is ~10 MB): a guard against reading a wrong file whole.
inline constexpr std::size_t kMaxSceneFileBytes = std::size_t(64) << 20;

/// Most bytes an MJCF or URDF model file may have, an MJCF file's includes counted with it
/// (16 MiB: the largest shipped model, MuJoCo's 22_humanoids.xml, is 133 kB).
inline constexpr std::size_t kMaxModelFileBytes = std::size_t(16) << 20;

/// Deepest nesting of arrays and objects in a JSON scene (the format needs 6: a serial axis's
/// drive's target_rotation). Deeper text is refused before it is parsed.
inline constexpr int kMaxJsonDepth = 64;

/// Deepest nesting of elements in an MJCF or URDF file, the root element at depth 1, and of
/// MJCF includes in one another. In MJCF a chain of bodies nests: MuJoCo 2.2.2's XML parser
/// (tinyxml2 9) stops at 99 elements, 96 bodies below <worldbody>; limber reads chains ten times
/// deeper, without recursion, and refuses past this, at the first element too deep, by name.
inline constexpr int kMaxXmlDepth = 1000;

/// Reads and loads a scene file: JSON; MuJoCo's MJCF when its name ends in ".xml"
/// (kernel/scene/mjcf_model.hpp); a URDF robot when it ends in ".urdf" (kernel/scene/urdf.hpp:
/// welded to the world at its root link unless options.floating_base). Model files take no
/// SceneOptions but the limits (and floating_base, URDF only). Every file is read the same way
/// (the scene, a model file, an MJCF include, the model file a scene wraps): only a regular
/// file, never a directory, FIFO or device, which would hang or never end. Throws ModelError
/// (one line naming the file) when it cannot be read, is not a regular file, is empty, is
/// larger than kMaxSceneFileBytes (JSON) or kMaxModelFileBytes (a model file with its
/// includes), nests deeper than kMaxJsonDepth or kMaxXmlDepth, or is invalid.
Scene load_scene_file(const std::filesystem::path& path, const SceneOptions& options = {});

/// The text of tools/scenes/humanoid.json, compiled into the library: the default scene.
std::string_view embedded_humanoid_scene();

}  // namespace limber
