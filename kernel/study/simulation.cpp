#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"  // GCC 12 false positives in Eigen's AVX-512 paths
#include "limber/kernel/study/simulation.hpp"

#include <stdexcept>
#include <type_traits>

#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "limber/kernel/rigid/rigid_scene.hpp"
#include "limber/kernel/springs/step.hpp"
#include "limber/kernel/verlet/step.hpp"

namespace limber::study {

Model configure(const Model& scene, const Method& method) {
  Model model = scene;
  model.settings.time_step = method.time_step;
  if (method.family == Family::particles) {
    model.settings.relaxation.iterations = method.sweeps;
    model.settings.relaxation.over_relaxation = method.over_relaxation;
    model.settings.relaxation.tolerance = method.relaxation_tolerance;
    model.settings.relaxation.projection = method.projection;
    model.settings.relaxation.substeps = method.substeps;
    if (method.limb_masses) model.settings.verlet.limb_masses = *method.limb_masses;
    if (method.joints) model.settings.verlet.joints = *method.joints;
  }
  return model;
}

namespace {

// The study's method as the one dispatch's options (kernel/methods/), double precision.
WorldOptions method_options(const Method& method) {
  return {.method = method.family, .single_precision = false, .particles = method.verlet, .springs = method.springs,
          .lagrange = method.lagrange, .featherstone = method.featherstone};
}

}  // namespace

Simulation::Simulation(const Model& scene, const Method& method)
    : model_(configure(scene, method)), time_step_(method.time_step), state_(compile_method(model_, method_options(method))) {}

StepStatus Simulation::step() {
  return std::visit(
      [&](auto& state) {
        const auto report = limber::step(state, time_step_);
        if constexpr (requires { report.fallbacks; }) fallbacks_ += report.fallbacks;
        return report.status;
      },
      state_);
}

Observation Simulation::observe() const {
  return std::visit([](const auto& state) { return limber::observe(state); }, state_);
}

double Simulation::time() const {
  return std::visit([](const auto& state) { return state.time; }, state_);
}

void Simulation::limb_points(std::vector<Eigen::Vector3d>& points) const {
  points.clear();
  if (const auto* verlet = std::get_if<VerletState<double>>(&state_)) {
    for (std::size_t body = 0; body < model_.bodies.size(); ++body) {
      const std::uint32_t limb = verlet->body_limb[body];
      points.push_back(verlet->particles.position(verlet->limbs.head[limb]));
      points.push_back(verlet->particles.position(verlet->limbs.tail[limb]));
    }
    return;
  }
  const RigidScene& rigid = std::visit(
      [](const auto& state) -> const RigidScene& {
        if constexpr (std::is_base_of_v<RigidScene, std::decay_t<decltype(state)>>) return state;
        else throw std::logic_error("unreachable: the Verlet state was handled above");
      },
      state_);
  for (std::size_t body = 0; body < model_.bodies.size(); ++body) {
    const double half = 0.5 * model_.bodies[body].shape.length;
    points.push_back(world_point(rigid, body, Eigen::Vector3d(0, 0, half)));
    points.push_back(world_point(rigid, body, Eigen::Vector3d(0, 0, -half)));
  }
}

}  // namespace limber::study
