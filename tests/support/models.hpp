// Small models built in C++ for tests, and access to the shipped scene files.
#pragma once

#include <string>
#include <vector>

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/scene/scene_file.hpp"

namespace limber::testing {

inline std::string scene_path(const std::string& file) { return std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/" + file; }

inline Model load_shipped_scene(const std::string& file, const SceneOptions& options = {}) {
  return load_scene_file(scene_path(file), options);
}

/// `model` with the relaxation the thesis ran (settings.relaxation back to its defaults: the pbd
/// rule in one step), `iterations` sweeps and over-relaxation ω — for tests of pbd's facts on
/// shipped scenes, whatever rule and substeps the files now choose.
inline Model with_thesis_relaxation(Model model, int iterations, double over_relaxation) {
  model.settings.relaxation = RelaxationSettings{};
  model.settings.relaxation.iterations = iterations;
  model.settings.relaxation.over_relaxation = over_relaxation;
  return model;
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

}  // namespace limber::testing
