// MuJoCo's humanoid.xml as shipped, falling for 2 s onto its floor under every method that
// accepts it (the import's settings, scene.methods): the widest joint gap World::observe()
// reports (of a link), the widest in metres (the rigid methods: each joint's anchors from the
// bodies' poses, against their rest distance, which a serial joint's first and last axis points
// keep; not the particles, whose joints hold particles, not anchors placed by a pose: observe()
// gives theirs), the
// deepest penetration and the largest limit violation. Prints the landing table of
// bench/models.md; MuJoCo's own penetration on the same fall is bench/mjcf_race's.
//
//   build/bench/mjcf_landing [model file (humanoid.xml)] [time step s ... (the file's)]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/world/world.hpp"

using namespace limber;

namespace {

struct Landing {
  double relative_gap = 0, gap = 0, penetration = 0, limit = 0;
  std::string widest;
  std::string failure;
};

// The largest distance a joint's anchors moved apart from their rest distance, m.
double widest_anchor_gap(const World& world, const Model& model, std::vector<double>& rest) {
  double widest = 0;
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const Joint& joint = model.joints[j];
    const auto point = [&](int body, const Eigen::Vector3d& anchor) {
      if (body < 0) return anchor;
      const Pose pose = world.pose(world.body(model.bodies[static_cast<std::size_t>(body)].name));
      return Eigen::Vector3d(pose.position + pose.orientation * anchor);
    };
    const double distance = (point(joint.inboard, joint.inboard_anchor) - point(joint.outboard, joint.outboard_anchor)).norm();
    if (rest[j] < 0) rest[j] = distance;
    widest = std::max(widest, std::abs(distance - rest[j]));
  }
  return widest;
}

Landing land(const Scene& scene, Method method, double dt) {
  Landing out;
  World world(scene.model, world_options(method, scene.methods));
  std::vector<double> rest(scene.model.joints.size(), -1.0);
  widest_anchor_gap(world, scene.model, rest);
  for (long n = 0, steps = std::lround(2.0 / dt); n < steps; ++n) {
    if (const StepStatus status = world.step(dt); status != StepStatus::ok) {
      out.failure = std::string(name(status)) + " at t = " + std::to_string(world.time()) + " s";
      return out;
    }
    const Observation now = world.observe();
    if (now.max_joint_gap > out.relative_gap) {
      out.relative_gap = now.max_joint_gap;
      out.widest = now.widest_joint >= 0 ? scene.model.joints[static_cast<std::size_t>(now.widest_joint)].name : "";
    }
    out.penetration = std::max(out.penetration, now.penetration.depth);
    out.limit = std::max(out.limit, now.joints.limit_violation);
    if (method != Method::particles) out.gap = std::max(out.gap, widest_anchor_gap(world, scene.model, rest));
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  const std::filesystem::path file = argc > 1 ? argv[1] : "/usr/share/mujoco/model/humanoid/humanoid.xml";
  if (!std::filesystem::exists(file)) {
    std::fprintf(stderr, "mjcf_landing: %s is missing (Debian's libmujoco-samples)\n", file.c_str());
    return 1;
  }
  const Scene scene = load_scene_file(file);
  std::vector<double> steps;
  for (int a = 2; a < argc; ++a) steps.push_back(std::atof(argv[a]));
  if (steps.empty()) steps.push_back(scene.model.settings.time_step);
  std::printf("%s as shipped, 2 s of its fall\n\n", file.filename().c_str());
  std::printf("| method | dt s | widest joint gap (observe, of a link) | widest joint gap m | deepest penetration m | largest limit violation rad |\n");
  std::printf("|---|---:|---|---:|---:|---:|\n");
  for (const Method method : {Method::particles, Method::springs, Method::lagrange, Method::featherstone}) {
    for (const double dt : steps) {
      Landing landing;
      try {
        landing = land(scene, method, dt);
      } catch (const ModelError& error) {
        std::printf("| %s | | refused: %s | | | |\n", std::string(method_name(method)).c_str(), error.what());
        break;
      }
      if (!landing.failure.empty()) {
        std::printf("| %s | %g | %s | | | |\n", std::string(method_name(method)).c_str(), dt, landing.failure.c_str());
        continue;
      }
      const std::string metres = method == Method::particles ? "—" : [&] {
        char text[32];
        std::snprintf(text, sizeof text, "%.3g", landing.gap);
        return std::string(text);
      }();
      std::printf("| %s | %g | %.3g (%s) | %s | %.3g | %.3g |\n", std::string(method_name(method)).c_str(), dt, landing.relative_gap,
                  landing.widest.c_str(), metres.c_str(), landing.penetration, landing.limit);
      std::fflush(stdout);
    }
  }
  return 0;
}
