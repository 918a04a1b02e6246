// One Model under any of limber's methods, behind one interface: what the run-time-against-error
// studies, the stability stress runs and the peer comparisons step and observe.
//
// A Method names a family (weighted or unweighted Verlet relaxation, stiff springs, Lagrange
// multipliers, Featherstone) and that family's settings; configure() turns them and the scene's
// method settings into the one dispatch's options, and Simulation steps the Model with them
// through a World (the one step path). Nothing here changes the physics of a method: a
// Simulation steps exactly what `limber run` with the same flags steps. It turns the World's
// shared divergence check off (WorldOptions::divergence_check): a study runs on past such a step
// and classifies the run itself (run_metrics.hpp).
#pragma once

#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/step_status.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/world/world.hpp"

namespace limber::study {

/// The method family (kernel/methods/): particles, springs, lagrange or featherstone.
using Family = limber::Method;

/// A method and its settings. Only the fields of `family` are read.
struct Method {
  std::string series{};   ///< the method as plots name it, e.g. "verlet gauss-seidel"
  std::string setting{};  ///< this point of the series, e.g. "20 sweeps"
  Family family = Family::particles;
  double time_step = 1.0 / 240;  ///< s

  // Verlet (thesis 3.2, 4.2): the rule and solver, sweeps (VerletOptions::relaxation.iterations) or
  // Newton steps (verlet.newton_iterations), over-relaxation, the projection rule and substeps,
  // and the particle model.
  VerletOptions verlet{};
  int sweeps = 100;                           ///< per substep
  double over_relaxation = 1;
  ProjectionRule projection = ProjectionRule::pbd;
  int substeps = 1;
  double relaxation_tolerance = 0;            ///< m; 0: run every sweep / Newton step
  std::optional<LimbMasses> limb_masses{};    ///< unset: the scene's
  std::optional<ParticleJoints> joints{};     ///< unset: the scene's

  SpringOptions springs{};            ///< stiffness unset: the scene's
  LagrangeOptions lagrange{};
  FeatherstoneOptions featherstone{};
};

/// `method` as the one dispatch's options (double precision): the scene's method settings, then
/// the relaxation and particle settings `method` gives; the World's divergence check off.
WorldOptions configure(const MethodSettings& scene, const Method& method);

/// A compiled Model stepping under one method (double precision).
class Simulation {
 public:
  /// Compiles scene.model at `method`'s time step with configure(scene.methods, method). Throws
  /// ModelError when the model is invalid for the method (as the method's own compile does).
  Simulation(const Scene& scene, const Method& method);
  /// A Model without method settings of its own (the methods' defaults).
  Simulation(const Model& model, const Method& method) : Simulation(Scene{model, {}, {}}, method) {}

  /// One step of the method's time step.
  StepStatus step();
  /// Rattle projections that fell back to pbd over every step so far (StepReport::fallbacks;
  /// 0 for the other methods).
  std::uint64_t fallbacks() const { return fallbacks_; }
  Observation observe() const;
  double time() const;
  double time_step() const { return time_step_; }
  const Model& model() const { return world_.model(); }
  const World& world() const { return world_; }

  /// Every limb's head and tail, world, m: 2 points per Model body that is a limb (Model order,
  /// head first; the ball is left out). The particle methods' head and tail particles, the rigid
  /// methods' body points at ±length/2 on the axis — the same points of the same body model,
  /// so trajectories of different methods can be compared point by point. `points` is resized.
  void limb_points(std::vector<Eigen::Vector3d>& points) const;

 private:
  double time_step_ = 0;
  std::uint64_t fallbacks_ = 0;
  World world_;
};

}  // namespace limber::study
