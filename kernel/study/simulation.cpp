#include "limber/kernel/study/simulation.hpp"

#include <stdexcept>
#include <type_traits>

#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "limber/kernel/rigid/rigid_scene.hpp"
#include "limber/kernel/springs/step.hpp"
#include "limber/kernel/verlet/step.hpp"

namespace limber::study {

WorldOptions configure(const MethodSettings& scene, const Method& method) {
  WorldOptions options{.method = method.family, .single_precision = false, .particles = method.verlet,
                       .springs = method.springs, .lagrange = method.lagrange, .featherstone = method.featherstone};
  options.particles.relaxation = {.iterations = method.sweeps, .tolerance = method.relaxation_tolerance, .budget_us = 0,
                                  .over_relaxation = method.over_relaxation, .projection = method.projection,
                                  .substeps = method.substeps};
  options.particles.verlet = scene.verlet;
  if (method.limb_masses) options.particles.verlet.limb_masses = *method.limb_masses;
  if (method.joints) options.particles.verlet.joints = *method.joints;
  options.springs.defaults = scene.springs;
  return options;
}

namespace {

Model at_time_step(Model model, double time_step) {
  model.settings.time_step = time_step;
  return model;
}

}  // namespace

Simulation::Simulation(const Scene& scene, const Method& method)
    : model_(at_time_step(scene.model, method.time_step)),
      time_step_(method.time_step),
      state_(compile_method(model_, configure(scene.methods, method))) {}

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
