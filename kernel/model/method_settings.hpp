// What a scene says about the methods that may step it: the particle method's relaxation and
// particles, the stiff-spring method's default spring. These are method settings, not facts of
// the scene, so they live outside the Model: a scene file returns them beside its Model
// (kernel/scene/scene_file.hpp), and each method takes its part through its options
// (VerletOptions::relaxation and ::verlet, SpringOptions::defaults; methods/method.hpp copies
// them all into WorldOptions).
#pragma once

#include <cstdint>
#include <optional>

#include "limber/kernel/model/model.hpp"

namespace limber {

/// Along which gradient a distance constraint's projection moves its particles
/// (kernel/relaxation/README.md derives both).
enum class ProjectionRule : std::uint8_t {
  /// The gradient at the end of the step: the nearest point on the constraint manifold. The
  /// thesis's and Jakobsen's rule (position-based dynamics), state (x, x*). First order in Δt,
  /// and it damps fast rotation.
  pbd,
  /// The gradient at the start of the (sub)step (SHAKE, Ryckaert, Ciccotti & Berendsen 1977),
  /// then a velocity stage that projects velocities onto the constraints' tangent space (RATTLE,
  /// Andersen 1983); state (x, v). Second order and symplectic (Leimkuhler & Skeel 1994). The
  /// same inverse-mass weights, the same sweeps.
  rattle,
};

/// Most substeps a step may be split into (a guard against hostile input, not a physical limit).
inline constexpr int kMaxSubsteps = 10000;
/// Most relaxation sweeps per substep (a guard against hostile input: 1e5 sweeps of the pile are
/// minutes per step; the thesis used 100).
inline constexpr int kMaxIterations = 100000;

/// When relaxation stops (thesis 3.2.3): after `iterations` sweeps, or earlier when the largest
/// correction of a sweep falls below `tolerance`, or when `budget_us` of wall-clock time has
/// passed (the hard real-time stop; not deterministic). Each step of Δt runs as `substeps` steps
/// of Δt/substeps (Macklin et al. 2019, "Small steps in physics simulation"), each with its own
/// sweeps (and, for rattle, as many velocity sweeps).
struct RelaxationSettings {
  int iterations = 100;    ///< in [1, kMaxIterations] sweeps per substep; the thesis's program used 100
  double tolerance = 0;    ///< m; 0 disables
  double budget_us = 0;    ///< µs per step; 0 disables
  /// Successive over-relaxation factor ω in (0, 2) for distance constraints: each projection
  /// moves ω times the plain correction (thesis 3.2.3, "over-relaxation techniques"). 1 is the
  /// thesis's Gauss-Seidel; > 1 converges faster along chains. Contacts are never over-relaxed,
  /// nor is the first sweep of a step (it starts far from the solution and would overshoot).
  /// The projections are nonlinear, so the linear theory's (0, 2) is not all safe: on chain.json
  /// ω ≤ 1.8 never gained energy, ω = 1.9 did below 10 sweeps (bench/accuracy.md, "Relaxation").
  double over_relaxation = 1;
  ProjectionRule projection = ProjectionRule::pbd;
  int substeps = 1;        ///< in [1, kMaxSubsteps]
};


/// How the particle (Verlet) methods build a spherical joint (thesis 3.2.5).
enum class ParticleJoints {
  zero_length_constraint,  ///< inboard and outboard anchor particles joined by a distance constraint with d = 0
  shared_particle,         ///< the two limbs share one particle carrying both mass shares
};

/// Where the particle (Verlet) methods put a limb's mass (thesis 4.1).
enum class LimbMasses {
  ends,     ///< half at each end: the thesis's program; a uniform rod's inertia is 3× too large
  inertia,  ///< three particles (tail, centre, head) whose masses reproduce the limb's mass, centre
            ///< of mass along the axis and inertia about a transverse axis (uniform rod: m/6, 2m/3, m/6)
  lumps,    ///< the body's point masses, each shared between head and tail by the lever rule
            ///< (exact for lumps at the ends; every lump must lie on the axis, between the ends)
};

/// How the particle (Verlet) methods hold the joints of a limb tree.
enum class JointSolve : std::uint8_t {
  rows,  ///< every joint's constraint and rows are projected one by one in the sweeps
  tree,  ///< each island's joints solved exactly after every sweep, limbs as rigid bodies, by tree
         ///< elimination (kernel/relaxation/joint_trees.hpp); limits join while reached; friction
         ///< and drives stay rows; under pbd the tree limbs' contacts go through the trees
};

struct VerletSettings {
  ParticleJoints joints = ParticleJoints::zero_length_constraint;
  LimbMasses limb_masses = LimbMasses::ends;
  /// Rows, or the exact trees (the weighted rule, Gauss-Seidel in colours, zero-length joints;
  /// other options are refused by name). A scene file's "settings.verlet.joint_solve".
  JointSolve joint_solve = JointSolve::rows;
  /// The thesis's drag (3.2.1, [Jak03]): x' = f·x − (f − 1)·x* + a·Δt², e.g. f = 1.99. Depends on
  /// Δt; prefer Settings::damping. When set it replaces the damping.
  std::optional<double> drag_factor;
};

/// The stiff-spring method (thesis 3.3, 4.4.1): each spherical joint becomes a zero-length
/// spring with damping between its two anchor points, f = −k·d − c·ḋ (eq. 3.11 with damping),
/// d the inboard anchor minus the outboard anchor. Joint::stiffness / damping override these.
struct SpringSettings {
  double stiffness = 2e4;  ///< k, N/m, > 0
  double damping = 20;     ///< c, N·s/m, ≥ 0
};

/// The method settings a scene file may carry (its "settings.relaxation", "settings.verlet" and
/// "settings.springs").
struct MethodSettings {
  RelaxationSettings relaxation;
  VerletSettings verlet;
  SpringSettings springs;
};

/// Each throws ModelError naming the first bad field as the scene file spells it, e.g.
/// "settings.relaxation.substeps: must be <= 10000, got 20000".
void validate(const RelaxationSettings& relaxation);
void validate(const VerletSettings& verlet);
void validate(const SpringSettings& springs);
void validate(const MethodSettings& settings);

}  // namespace limber
