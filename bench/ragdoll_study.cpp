// The armed ragdoll under every method (bench/accuracy.md, "Limits after a hard fall"):
//  1. limits after a hard fall: the ragdoll dropped from 1.5 m above its standing pose onto
//     the ground, without the ball, at 1/60 and 1/240 s: the largest limit violation in 3 s;
//  2. the thesis's experiment with arms: the ball hits the standing ragdoll; the knock (the
//     centre of mass's travel along the ball's path in the 0.3 s after contact,
//     kernel/metrics/knock.hpp), the final pose, and whether a knee ever bent backwards.
//
//   build/bench/ragdoll_study [tools/scenes/ragdoll.json]
//
// Every method steps through the World, the same calls an engine makes.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "limber/kernel/metrics/knock.hpp"
#include "limber/kernel/model/joint_coordinates.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/world/world_internals.hpp"

namespace limber {
namespace {

struct MethodChoice {
  const char* name;
  Method method;
};
constexpr MethodChoice kMethods[] = {
    {"weighted", Method::particles}, {"springs", Method::springs}, {"lagrange", Method::lagrange}, {"featherstone", Method::featherstone}};

bool ball_touched(const World& world) {
  return std::visit(
      [](const auto& state) {
        if constexpr (requires { state.ball_touched; }) {
          return state.ball_touched;
        } else {
          return state.ball_touching;
        }
      },
      world.internals().state);
}

FramePose frame_pose(const World& world, std::size_t body) {
  const Pose pose = world.pose(world.bodies()[body]);
  return {pose.orientation, pose.position};
}

// How far the knees went past their range's lower or upper end the wrong way, rad (the largest).
double knee_overbend(const World& world, const std::vector<JointFrame>& frames) {
  const Model& model = world.model();
  double worst = 0;
  for (std::size_t k = 0; k < model.joints.size(); ++k) {
    const Joint& joint = model.joints[k];
    if (joint.name.find("knee") == std::string::npos || !joint.limits.range) continue;
    const JointCoordinates q = joint_coordinates(joint, frames[k], frame_pose(world, static_cast<std::size_t>(joint.inboard)),
                                                 frame_pose(world, static_cast<std::size_t>(joint.outboard)));
    worst = std::max({worst, joint.limits.range->min - q.angle, q.angle - joint.limits.range->max});
  }
  return worst;
}

void hard_fall(const Scene& scene) {
  std::printf("## Limits after a hard fall (dropped from 1.5 m, no ball, 3 s)\n\n");
  std::printf("| method | dt (s) | largest limit violation in run (rad) | at end (rad) | largest joint gap | status |\n|---|---|---|---|---|---|\n");
  for (const MethodChoice& choice : kMethods) {
    for (const double dt : {1.0 / 60, 1.0 / 240}) {
      Model model = scene.model;
      model.balls.clear();
      model.settings.sleep.start_asleep = false;
      model.settings.time_step = dt;
      for (Body& body : model.bodies) body.position.z() += 1.5;
      for (Joint& joint : model.joints) {
        if (joint.inboard == kWorld) joint.inboard_anchor.z() += 1.5;
      }
      try {
        World world(model, world_options(choice.method, scene.methods));
        double worst = 0, gap = 0;
        StepStatus status = StepStatus::ok;
        for (int s = 0; s < static_cast<int>(std::lround(3 / dt)) && status == StepStatus::ok; ++s) {
          status = world.step();
          const Observation o = world.observe();
          worst = std::max(worst, o.joints.limit_violation), gap = std::max(gap, o.max_joint_gap);
        }
        std::printf("| %s | 1/%.0f | %.3g | %.3g | %.3g | %s |\n", choice.name, 1 / dt, worst, world.observe().joints.limit_violation, gap,
                    status == StepStatus::ok ? "ok" : "diverged");
      } catch (const ModelError& error) {
        std::printf("| %s | 1/%.0f | refused: %s | | | |\n", choice.name, 1 / dt, error.what());
      }
    }
  }
}

void knock(const Scene& scene) {
  std::printf("\n## The ball against the armed humanoid (the scene's ball and step, 3 s)\n\n");
  std::printf("| method | knock (m, 0.3 s) | centre of mass travel (m) | final height (m) | knees bent backwards (rad past range) | "
              "largest limit violation (rad) | largest joint gap | status |\n|---|---|---|---|---|---|---|---|\n");
  for (const MethodChoice& choice : kMethods) {
    try {
      World world(scene.model, world_options(choice.method, scene.methods));
      const std::vector<JointFrame> frames = joint_frames(scene.model);
      const Observation start = world.observe();
      KnockMeter meter(scene.model.balls.front().velocity, start.body_centre_of_mass);
      double overbend = 0, worst = 0, gap = 0;
      StepStatus status = StepStatus::ok;
      const int steps = static_cast<int>(std::lround(3 / scene.model.settings.time_step));
      for (int s = 0; s < steps && status == StepStatus::ok; ++s) {
        status = world.step();
        const Observation o = world.observe();
        meter.update(world.time(), ball_touched(world), o.body_centre_of_mass);
        overbend = std::max(overbend, knee_overbend(world, frames));
        worst = std::max(worst, o.joints.limit_violation), gap = std::max(gap, o.max_joint_gap);
      }
      const Observation end = world.observe();
      const Eigen::Vector3d travel = end.body_centre_of_mass - start.body_centre_of_mass;
      std::printf("| %s | %.3f | %.3f | %.3f | %.3g | %.3g | %.3g | %s |\n", choice.name, meter.distance(),
                  Eigen::Vector2d(travel.x(), travel.y()).norm(), end.body_centre_of_mass.z(), overbend, worst, gap,
                  status == StepStatus::ok ? "ok" : "diverged");
    } catch (const ModelError& error) {
      std::printf("| %s | refused: %s | | | | | | |\n", choice.name, error.what());
    }
  }
}

}  // namespace
}  // namespace limber

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/ragdoll.json";
  try {
    const limber::Scene scene = limber::load_scene_file(path);
    limber::hard_fall(scene);
    limber::knock(scene);
  } catch (const limber::ModelError& error) {
    std::fprintf(stderr, "ragdoll_study: %s\n", error.what());
    return 2;
  }
  return 0;
}
