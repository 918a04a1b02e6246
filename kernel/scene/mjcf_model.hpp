// MuJoCo's MJCF into limber's Model: what a parsed model file (kernel/scene/mjcf_document.hpp)
// becomes, so a model written for MuJoCo runs under the methods that can represent it.
//
// The mapping (kernel/scene/MJCF.md is the design; MuJoCo 2.2.2's semantics):
// - Bodies: every geom of an MJCF body is one limber body (capsule; cylinder; sphere: a capsule
//   of length 0) at the geom's pose with the geom's mass spread over its shape, so a body of
//   several geoms (a torso of two capsules) is a compound of limber bodies welded by fixed joints,
//   its mass, centre and inertia MuJoCo's sum exactly. The first geom's body is the MJCF body's
//   own: its joints join it. An explicit <inertial> is taken on a body of one geom (moved into
//   that body's frame); with several geoms it is refused (not yet).
// - Joints (at the file's pose, MuJoCo's qpos0, every limber joint's zero): no joint: welded to
//   the parent (fixed); free: a floating body (no joint); one hinge: revolute; one slide:
//   prismatic; one ball: spherical; 2–6 hinges and slides: one serial joint, axes in file order.
//   range → limits (minus ref), stiffness and damping → a drive toward springref − ref,
//   frictionloss → friction, armature → armature.
// - The world: a plane with normal +z is the Ground (friction the largest geom friction, as
//   MuJoCo mixes them); world capsules and boxes are static colliders.
// - Contacts: contype and conaffinity are a body's collision group and mask (the same pairs as
//   MuJoCo's rule whenever contype = conaffinity; other files are refused). Limb–limb friction is
//   0 when every body geom has condim 1 (MuJoCo: frictionless), else the largest friction.
// - Settings: timestep and gravity from <option>; sleep off (MuJoCo never sleeps a body).
// What it cannot represent is refused with "FILE:LINE: <element>: problem"; what it drops or
// approximates is listed in `notes`, one line each.
#pragma once

#include <string>
#include <vector>

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/scene/mjcf_document.hpp"

namespace limber {

/// The Model of a parsed MJCF document. Appends to `notes` what it dropped or approximated
/// ("FILE:LINE: <element>: reason"). Throws ModelError, one line naming file, line and element.
Model model_from_mjcf(const mjcf::Document& document, std::vector<std::string>& notes);

}  // namespace limber
