#include "tools/fuzz/scene_fuzzing.hpp"

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/world/world.hpp"

namespace limber::fuzz {
namespace {

[[noreturn]] void broken_promise(const std::string& what) {
  std::fprintf(stderr, "scene fuzzer: broken promise: %s\n", what.c_str());
  std::abort();
}

/// The kConfigurations stepped: every method, and the particle method's two precisions and two
/// kinds of solver (the sweeps and the global Newton projection).
std::vector<WorldOptions> configurations(const Scene& scene) {
  std::vector<WorldOptions> all;
  for (Method method : {Method::particles, Method::springs, Method::lagrange, Method::featherstone}) {
    all.push_back(world_options(method, scene.methods));
  }
  WorldOptions single = all.front();
  single.single_precision = true;
  all.push_back(single);
  WorldOptions direct = all.front();
  direct.particles.solver = RelaxationSolver::direct;
  all.push_back(direct);
  for (WorldOptions& options : all) {
    RelaxationSettings& relaxation = options.particles.relaxation;
    relaxation.iterations = std::min(relaxation.iterations, kSweepCap);
    relaxation.substeps = std::min(relaxation.substeps, kSubstepCap);
    relaxation.budget_us = 0;  // wall-clock stops are not deterministic
  }
  return all;
}

/// Whether everything the World reports of its state is a finite number.
bool finite_state(const World& world) {
  for (BodyId body : world.bodies()) {
    const Pose pose = world.pose(body);
    const Motion motion = world.motion(body);
    if (!pose.position.allFinite() || !pose.orientation.coeffs().allFinite() || !motion.linear.allFinite() ||
        !motion.angular.allFinite()) {
      return false;
    }
  }
  const Observation seen = world.observe();
  return std::isfinite(seen.energy()) && seen.linear_momentum.allFinite() && seen.body_centre_of_mass.allFinite() &&
         std::isfinite(seen.max_joint_gap);
}

void step_under(const Scene& scene, const WorldOptions& options) {
  std::optional<World> world;
  try {
    world.emplace(scene.model, options);
  } catch (const ModelError&) {
    return;  // the method cannot represent this model (a loop under Featherstone, ...), and said so
  } catch (const std::invalid_argument&) {
    return;  // options that do not go together (a scene's settings with this configuration)
  }
  for (int k = 0; k < kSteps; ++k) {
    const StepStatus status = world->step();
    if (status != StepStatus::ok) return;  // reported, as promised
    if (!finite_state(*world)) {
      broken_promise("step " + std::to_string(k) + " under " + std::string(method_name(options.method)) +
                     " reported ok over a non-finite state");
    }
  }
}

}  // namespace

void load_and_step(std::string_view bytes, std::optional<std::size_t> only) {
  std::optional<Scene> scene;
  SceneOptions options;
  options.max_bodies = kMaxBodies;
  options.max_triangles = kMaxTriangles;
  try {
    scene.emplace(load_scene_text(bytes, "fuzz", options));
  } catch (const ModelError&) {
    return;  // refused with one line, as promised
  }
  if (scene->model.bodies.size() > kMaxSteppedBodies) return;
  const std::vector<WorldOptions> all = configurations(*scene);
  if (only) {
    step_under(*scene, all.at(*only));
  } else {
    for (const WorldOptions& configuration : all) step_under(*scene, configuration);
  }
}

}  // namespace limber::fuzz
