#include "limber/kernel/study/simulation.hpp"

#include <stdexcept>
#include <type_traits>

#include "limber/kernel/rigid/rigid_scene.hpp"
#include "limber/kernel/scene/capsule_proxy.hpp"
#include "limber/kernel/world/world_internals.hpp"

namespace limber::study {

WorldOptions configure(const MethodSettings& scene, const Method& method) {
  WorldOptions options{.method = method.family, .single_precision = false, .particles = method.verlet,
                       .springs = method.springs, .lagrange = method.lagrange, .featherstone = method.featherstone,
                       .divergence_check = false};
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
    : time_step_(method.time_step), world_(at_time_step(scene.model, method.time_step), configure(scene.methods, method)) {}

StepStatus Simulation::step() {
  const StepStatus status = world_.step(time_step_);
  fallbacks_ += world_.last_report().fallbacks;
  return status;
}

Observation Simulation::observe() const { return world_.observe(); }

double Simulation::time() const { return world_.time(); }

void Simulation::limb_points(std::vector<Eigen::Vector3d>& points) const {
  points.clear();
  const Model& model = world_.model();
  const MethodState& state = world_.internals().state;
  if (const auto* verlet = std::get_if<VerletState<double>>(&state)) {
    for (std::size_t body = 0; body < model.bodies.size(); ++body) {
      const std::uint32_t limb = verlet->body_limb[body];
      points.push_back(verlet->particles.position(verlet->limbs.head[limb]));
      points.push_back(verlet->particles.position(verlet->limbs.tail[limb]));
    }
    return;
  }
  const RigidScene& rigid = std::visit(
      [](const auto& s) -> const RigidScene& {
        if constexpr (std::is_base_of_v<RigidScene, std::decay_t<decltype(s)>>) return s;
        else throw std::logic_error("unreachable: the Verlet state was handled above");
      },
      state);
  for (std::size_t body = 0; body < model.bodies.size(); ++body) {
    const double half = 0.5 * capsule_proxy(model.bodies[body].shape).length;  // a box: its proxy's ends, the particles' limb ends
    points.push_back(world_point(rigid, body, Eigen::Vector3d(0, 0, half)));
    points.push_back(world_point(rigid, body, Eigen::Vector3d(0, 0, -half)));
  }
}

}  // namespace limber::study
