// compile_featherstone(Model, FeatherstoneOptions) -> FeatherstoneState: the Model's bodies as a
// kinematic tree in reduced coordinates (Featherstone 2008, chapter 4).
#pragma once

#include "limber/kernel/featherstone/featherstone_state.hpp"
#include "limber/kernel/model/model.hpp"

namespace limber {

/// Builds the Featherstone state of `model`:
/// - the rigid scene (compile_rigid_scene, kernel/rigid/rigid_scene.hpp) the state derives from;
/// - the tree: each island (bodies joined by joints; the ball is its own) becomes a subtree,
///   rooted at its joint to the world where it has one (the first in joint order), else at its
///   lowest-index body on a 6-DOF floating joint (so is the ball). Bodies are ordered island by
///   island, breadth first from the root, so parents come before children; a joint may connect
///   its Model outboard body as the tree parent (spherical, revolute, prismatic and fixed joints
///   are symmetric). Joint types map one to one (Table 4.1); axes, given in world coordinates at
///   the initial poses, are carried into the child's frame. X_tree places the child's frame at
///   its initial pose in its parent's, so q = 0 (quaternions 1) is the Model's initial pose.
///   Frames: featherstone_state.hpp. A non-prismatic joint whose anchors do not coincide at the
///   initial poses is placed at the child's anchor, and the gap it starts with is kept (the
///   joint-gap observer reports it); the Model documents such a gap as an error.
/// - each body's spatial inertia (eq. 2.63) from the rigid scene's mass properties
///   (body_mass_properties, with its floor on principal moments), in the tree body's frame;
/// - velocities: a floating root gets the Model body's full spatial velocity; every other joint
///   the relative velocity of its two bodies projected on its motion subspace (least squares,
///   exact when the Model's velocities are consistent with the joints). The rigid bodies are
///   then refreshed from (q, v), so they carry the projected velocities.
/// Throws ModelError when the model is invalid, for universal joints and gears ("the featherstone
/// method does not support ..."), and for a joint that closes a kinematic loop — one between two
/// bodies already connected, or a second joint to the world in one island:
/// "joints[7] 'x': closes a kinematic loop, which reduced coordinates cannot express; use
/// --method lagrange".
FeatherstoneState compile_featherstone(const Model& model, const FeatherstoneOptions& options = {});

}  // namespace limber
