// URDF robots into limber's Model: a ROS robot description runs under the methods that can
// represent it. Sources: the URDF specification (wiki.ros.org/urdf/XML) for the format; MuJoCo's
// URDF importer (src/xml/xml_urdf.cc) for its conventions; kernel/scene/MJCF.md §3 for the design.
//
// The mapping, at the file's pose (every joint coordinate 0, limber's zero):
// - Frames: a joint's <origin xyz rpy> is its child link's frame in the parent link's frame,
//   rpy = R_z(yaw)·R_y(pitch)·R_x(roll) (about the fixed x, then y, then z), m and rad.
// - A link with one <collision> shape and an <inertial> of mass > 0 is one limber body at the
//   collision pose: a <cylinder radius length> along the collision frame's z is a cylinder, a
//   <sphere radius> a capsule of length 0. Its mass and inertia are the <inertial>'s (origin,
//   mass, the full tensor ixx…izz in the inertial frame), moved exactly into the body's frame
//   (Body::inertial), never computed from the geometry.
// - A link without mass and without collision geometry is a frame: the root one is the world
//   (the robot is welded there, and its child links' joints are joints to the world); one
//   reached by a fixed joint is folded into its parent, so the joints after it compose with it
//   (its children hang from the parent's body at the composed poses).
// - Joints: revolute → revolute with its <limit lower upper> (rad) as the range; continuous →
//   revolute without a range; prismatic → prismatic with its range (m); fixed → fixed;
//   floating → none (the child is a free body; only for a child of the root link). The anchors
//   are the joint's origin (the child link frame's origin) in each body's frame; the axis
//   (<axis xyz>, default 1 0 0, in the child link frame) is carried to world. <dynamics damping>
//   is a JointDrive of damping only (target velocity 0); <dynamics friction> is Joint::friction.
// - The root link is welded to the world by a fixed joint at its frame, unless `floating_base`:
//   then it is a free body (with a root frame, its one child by a fixed joint floats instead).
// - Settings (URDF has none): limber's defaults, gravity (0, 0, −9.81) m/s² and time step
//   1/240 s; sleep off (MuJoCo, whose conventions URDF models are written for, never sleeps a
//   body). No ground: URDF describes the robot alone.
//
// Refused, "FILE:LINE: <element attr>: problem" (a ModelError) at the first: mesh geometry (not
// yet), a box on a link (limber's bodies are capsules, cylinders and spheres: not yet), several
// collision shapes on one link (one limber body needs the link's whole inertial: not yet), a
// link with mass but no collision geometry, a link with geometry but no mass, a moving joint into
// a massless frame link, planar and mimic joints, a revolute or prismatic joint without <limit
// lower upper>, a range not holding 0 (the file's pose) or, for a revolute, reaching ±π, a
// floating joint below the root's children, a link with two parent joints (a loop: both named),
// a joint naming an unknown link, no root or several roots, unknown elements or attributes in
// <link> and <joint> and their children, malformed numbers. Noted (Scene::notes): visual,
// material, transmission, gazebo, calibration, safety_controller, limit effort and velocity,
// other top-level elements, folded frame links.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "limber/kernel/model/model.hpp"

namespace limber {

/// Reads a URDF robot file (a regular file of at most kMaxModelFileBytes, elements nested at
/// most kMaxXmlDepth deep, attributes UTF-8: scene_file.hpp). Throws ModelError "FILE:LINE:
/// <element attr>: problem" (an unreadable file: "FILE: cannot read file: reason"; what only the
/// assembled Model shows, such as frames that overflow down the tree, names the link or joint
/// it came from). Appends to `notes` what it dropped, one line
/// each ("FILE:LINE: <element>: ignored: reason"). `floating_base`: the root link floats.
Model load_urdf(const std::filesystem::path& file, std::vector<std::string>& notes, bool floating_base = false);

/// Reads URDF text; `file_name` names it in messages. Otherwise as load_urdf.
Model parse_urdf(std::string_view xml, const std::filesystem::path& file_name, std::vector<std::string>& notes,
                 bool floating_base = false);

}  // namespace limber
