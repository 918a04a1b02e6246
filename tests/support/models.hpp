// Small models built in C++ for tests, and access to the shipped scene files.
#pragma once

#include <string>
#include <vector>

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/particles/verlet_state.hpp"
#include "limber/kernel/scene/scene_file.hpp"

namespace limber::testing {

inline std::string scene_path(const std::string& file) { return std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/" + file; }

/// A shipped scene file: its Model and the method settings it gives.
inline Scene shipped_scene(const std::string& file, const SceneOptions& options = {}) {
  return load_scene_file(scene_path(file), options);
}

/// A shipped scene file's Model alone: for the rigid-body methods, or a test that gives the
/// particle method its settings itself.
inline Model load_shipped_scene(const std::string& file, const SceneOptions& options = {}) {
  return shipped_scene(file, options).model;
}

/// `options` with the scene's particle settings (relaxation, limb masses, joints).
inline VerletOptions with_scene_settings(const Scene& scene, VerletOptions options = {}) {
  options.relaxation = scene.methods.relaxation;
  options.verlet = scene.methods.verlet;
  return options;
}

/// The relaxation the thesis ran (the pbd rule in one step), `iterations` sweeps and
/// over-relaxation ω — for tests of pbd's facts on shipped scenes, whatever rule and substeps
/// the files now choose.
inline RelaxationSettings thesis_relaxation(int iterations, double over_relaxation) {
  RelaxationSettings relaxation;
  relaxation.iterations = iterations;
  relaxation.over_relaxation = over_relaxation;
  return relaxation;
}

/// A straight chain along +x of capsule links with the given masses (kg), each `link_length` m,
/// link 0's head at `start`; joints link k−1 tail → link k head; optionally pinned to the world.
inline Model make_chain(const std::vector<double>& masses, double link_length, bool pinned,
                        const Vector3& start = Vector3(0, 0, 1)) {
  Model model;
  model.name = "test_chain";
  for (std::size_t k = 0; k < masses.size(); ++k) {
    Body body;
    body.name = "link_" + std::to_string(k);
    body.shape = {ShapeType::capsule, link_length, 0.01};
    body.mass = masses[k];
    body.axis = -Vector3::UnitX();  // tail → head points back towards the start
    body.position = start + Vector3((k + 0.5) * link_length, 0, 0);
    body.collision = {2, ~2u};  // links do not meet links, as the generators' (generators.hpp)
    model.bodies.push_back(body);
  }
  const Vector3 head(0, 0, 0.5 * link_length), tail(0, 0, -0.5 * link_length);
  if (pinned) model.joints.push_back(spherical_joint("pin", kWorld, 0, start, head));
  for (std::size_t k = 1; k < masses.size(); ++k) {
    model.joints.push_back(spherical_joint("joint_" + std::to_string(k), static_cast<int>(k - 1), static_cast<int>(k), tail, head));
  }
  model.settings.sleep.enabled = false;
  return model;
}

/// The joint-control tests' pendulum: one rod (cylinder, 1 kg, 1 m, `radius` m) lying along +x,
/// its head held at the origin by a joint of `type` about `axis` (world), sleep off.
inline Model rod_held_at_head(JointType type, const Vector3& axis = Vector3::UnitY(), double radius = 0.01) {
  Model model;
  model.name = "rod";
  Body rod;
  rod.name = "rod";
  rod.shape = {ShapeType::cylinder, 1, radius};
  rod.mass = 1;
  rod.axis = -Vector3::UnitX();  // head at the anchor
  rod.position = Vector3(0.5, 0, 0);
  model.bodies.push_back(rod);
  Joint joint = spherical_joint("hinge", kWorld, 0, Vector3::Zero(), Vector3(0, 0, 0.5));
  joint.type = type;
  joint.axis = axis;
  model.joints.push_back(joint);
  model.settings.sleep.enabled = false;
  return model;
}

}  // namespace limber::testing
