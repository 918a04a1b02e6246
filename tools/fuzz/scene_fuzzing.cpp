#include "tools/fuzz/scene_fuzzing.hpp"

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <stdlib.h>  // mkdtemp

#include <pugixml.hpp>

#include "limber/kernel/scene/mjcf_document.hpp"
#include "limber/kernel/scene/mjcf_model.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/scene/urdf.hpp"
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

// The file a fuzzed MJCF input may include, spliced in place of <include file="part.xml"/>.
constexpr const char* kIncludedPart = R"(<mujoco>
  <body name="included" pos="0 0 1"><joint type="hinge" axis="0 1 0"/><geom type="capsule" size="0.05 0.1"/></body>
</mujoco>
)";

// A temporary directory holding part.xml alone, made on first use, removed at exit: fuzzed MJCF
// inputs are named as files in it, so their includes resolve there.
class IncludeDirectory {
 public:
  IncludeDirectory() {
    std::string pattern = (std::filesystem::temp_directory_path() / "limber-mjcf-fuzz-XXXXXX").string();
    if (!mkdtemp(pattern.data())) broken_promise("cannot make a temporary directory for MJCF includes");
    path_ = pattern;
    std::ofstream(path_ / "part.xml") << kIncludedPart;
  }
  ~IncludeDirectory() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  IncludeDirectory(const IncludeDirectory&) = delete;
  IncludeDirectory& operator=(const IncludeDirectory&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

const std::filesystem::path& include_directory() {
  static const IncludeDirectory directory;
  return directory.path();
}

// Whether every <include file> of an MJCF input is a plain name (no directory part), read as
// the MJCF reader reads it (pugixml, the same options: character references decoded). An input
// pugixml refuses is refused by the reader too, before any include: it loads nothing.
bool includes_are_plain_names(std::string_view bytes) {
  if (bytes.find("<include") == std::string_view::npos) return true;
  pugi::xml_document document;
  if (!document.load_buffer(bytes.data(), bytes.size(), pugi::parse_default, pugi::encoding_utf8)) return false;
  std::vector<pugi::xml_node> stack{document.document_element()};
  while (!stack.empty()) {
    const pugi::xml_node node = stack.back();
    stack.pop_back();
    if (std::string_view(node.name()) == "include") {
      const std::string_view file = node.attribute("file").value();
      if (file.find_first_of("/\\") != std::string_view::npos || file == "." || file == "..") return false;
    }
    for (pugi::xml_node child = node.first_child(); child; child = child.next_sibling()) {
      if (child.type() == pugi::node_element) stack.push_back(child);
    }
  }
  return true;
}

// The Model of an MJCF or URDF input, or nullopt when the loader refuses it (a ModelError).
std::optional<Scene> load_model_file(Target target, std::string_view bytes) {
  Scene scene;
  try {
    if (target == Target::mjcf) {
      if (!includes_are_plain_names(bytes)) return std::nullopt;
      scene.model = model_from_mjcf(mjcf::parse_mjcf(bytes, include_directory() / "fuzz.xml"), scene.notes);
    } else {
      const bool floating_base = std::hash<std::string_view>{}(bytes) % 2 == 1;
      scene.model = parse_urdf(bytes, "fuzz.urdf", scene.notes, floating_base);
    }
  } catch (const ModelError&) {
    return std::nullopt;  // refused with one line, as promised
  }
  return scene;
}

}  // namespace

Target target_of_file(std::string_view file_name) {
  const auto ends_with = [&](std::string_view end) { return file_name.size() >= end.size() && file_name.substr(file_name.size() - end.size()) == end; };
  return ends_with(".xml") ? Target::mjcf : ends_with(".urdf") ? Target::urdf : Target::scene;
}

std::optional<Target> target_named(std::string_view name) {
  if (name == "scene") return Target::scene;
  if (name == "mjcf") return Target::mjcf;
  if (name == "urdf") return Target::urdf;
  return std::nullopt;
}

void load_and_step(Target target, std::string_view bytes, std::optional<std::size_t> only) {
  if (target == Target::scene) return load_and_step(bytes, only);
  const std::optional<Scene> scene = load_model_file(target, bytes);
  if (!scene || scene->model.bodies.size() > kMaxSteppedBodies) return;
  const std::vector<WorldOptions> all = configurations(*scene);
  constexpr std::size_t kFeatherstone = 3;  // configurations()' order
  step_under(*scene, all[kFeatherstone]);
  for (std::size_t k = 0; k < all.size(); ++k) {
    if (k != kFeatherstone && (!only || *only == k)) step_under(*scene, all[k]);
  }
}

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
