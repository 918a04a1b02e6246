// The thesis's Verlet experiments, redone: prints the README's tables (markdown) to stdout.
//
//   build/bench/thesis_experiments
//
// Physics only — joint gaps, how far bodies move. Timings are in verlet_bench (Google Benchmark).
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>

#include "kernel/metrics/knock.hpp"
#include "kernel/metrics/observers.hpp"
#include "kernel/scene/scene_file.hpp"
#include "kernel/verlet/compile.hpp"
#include "kernel/verlet/step.hpp"

namespace limber {
namespace {

Model scene(const std::string& file, const SceneOptions& options = {}) {
  return load_scene_file(std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/" + file, options);
}

// Thesis 3.2.3 / 4.4.2: more sweeps, smaller gaps; over-relaxation gets there sooner.
void relaxation_sweeps() {
  std::printf("### Joint gap against relaxation sweeps (chain.json: 5 links, heavy end, released horizontally)\n\n");
  std::printf("| sweeps per step | joint gap, ω = 1 (thesis) | joint gap, ω = 1.5 (chain.json) | link stretch, shared-particle joints, ω = 1 |\n|---|---|---|---|\n");
  // Largest joint gap (or, with shared particles, link stretch) over 5 s, relative to the link length.
  const auto largest_error = [](int sweeps, double omega, bool shared) {
    Model model = scene("chain.json");
    model.settings.relaxation.iterations = sweeps;
    model.settings.relaxation.over_relaxation = omega;
    if (shared) model.settings.verlet.joints = ParticleJoints::shared_particle;
    auto state = compile<double>(model);
    double largest = 0;
    for (int s = 0; s < 1200; ++s) {
      step(state);
      const Observation o = observe(state);
      largest = std::max(largest, shared ? o.max_link_stretch : o.max_joint_gap);
    }
    return largest;
  };
  for (int sweeps : {1, 5, 10, 20, 50, 100, 1000}) {
    std::printf("| %d | %.1e | %.1e | %.1e |\n", sweeps, largest_error(sweeps, 1.0, false), largest_error(sweeps, 1.5, false),
                largest_error(sweeps, 1.0, true));
  }
  std::printf("\nLargest over 5 s, relative to the link length.\n\n");
}

// Thesis 4.4.2: with the weighted rule the heavy end "has more control over the global motion";
// with the midpoint rule mass makes no difference.
void weighted_against_midpoint() {
  std::printf("### Weighted against midpoint relaxation (chain.json, 2 s)\n\n");
  std::printf("| end link mass | largest distance between the two rules' chain ends | end height at 1 s, weighted | midpoint |\n|---|---|---|---|\n");
  for (double factor : {1.0, 2.0, 10.0}) {
    Model model = scene("chain.json");
    model.bodies.back().mass = factor * model.bodies.front().mass;
    auto weighted = compile<double>(model, {RelaxationRule::weighted});
    auto midpoint = compile<double>(model, {RelaxationRule::unweighted});
    const std::uint32_t end = weighted.limbs.tail.back();  // the chain's free end
    double largest = 0, weighted_height = 0, midpoint_height = 0;
    for (int s = 0; s < 480; ++s) {
      step(weighted), step(midpoint);
      largest = std::max(largest, double((weighted.particles.position(end) - midpoint.particles.position(end)).norm()));
      if (s == 239) weighted_height = weighted.particles.position_z[end], midpoint_height = midpoint.particles.position_z[end];
    }
    std::printf("| %g × link | %.3f m | %.3f m | %.3f m |\n", factor, largest, weighted_height, midpoint_height);
  }
  std::printf("\n");
}

// Thesis 4.5.4, figures 4.11–4.14.
void humanoid_knocks() {
  std::printf("### The humanoid and the ball (humanoid.json)\n\n");
  std::printf("Knock: how far the body's centre of mass moves along the ball's path in the 0.3 s after first\n"
              "contact. Rest: its horizontal distance from the start at 5 s, when the passive body lies on the ground.\n\n");
  std::printf("| body | ball | knock | rest |\n|---|---|---|---|\n");
  const auto row = [](const char* body, const char* label, const std::function<void(Ball&)>& adjust) {
    Model model = scene("humanoid.json", {.variant = std::string(body), .links = {}});
    adjust(*model.ball);
    auto state = compile<double>(model);
    const Eigen::Vector3d start = observe(state).body_centre_of_mass;
    KnockMeter knock(model.ball->velocity, start);
    const long steps = std::lround(model.settings.duration / model.settings.time_step);
    for (long s = 0; s < steps; ++s) {
      step(state);
      knock.update(state.time, !state.ball_contacts.empty(), observe(state).body_centre_of_mass);
    }
    const Eigen::Vector3d moved = observe(state).body_centre_of_mass - start;
    std::printf("| %s | %s | %.3f m | %.3f m |\n", body, label, knock.distance(), std::hypot(moved.x(), moved.y()));
  };
  const auto speed = [](double v) { return [v](Ball& b) { b.velocity = v * b.velocity.normalized(); }; };
  for (double v : {4.0, 10.0, 16.0}) row("medium", (std::to_string(int(v)) + " m/s").c_str(), speed(v));
  for (double e : {0.05, 0.5, 1.0}) {
    row("medium", ("restitution " + std::to_string(e).substr(0, 4)).c_str(), [e](Ball& b) { b.restitution = e; });
  }
  for (double m : {1.0, 2.268, 10.0}) {
    row("medium", ("mass " + std::to_string(m).substr(0, 5) + " kg").c_str(), [m](Ball& b) { b.mass = m; });
  }
  for (const char* body : {"thin", "medium", "wide"}) row(body, "default (10 m/s, e 0.8, 5 lb)", [](Ball&) {});
  std::printf("\n");
}

}  // namespace
}  // namespace limber

int main() {
  limber::relaxation_sweeps();
  limber::weighted_against_midpoint();
  limber::humanoid_knocks();
}
