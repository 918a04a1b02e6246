// How a step ended and what it did, the same for every method, and the guard every method's
// step() runs inside.
#pragma once

#include <chrono>
#include <cmath>
#include <cstdint>
#include <utility>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

/// Outcome of one step. step() never throws; divergence is reported here.
enum class StepStatus : std::uint8_t {
  ok,
  diverged_non_finite,  ///< a position became NaN or infinite
  diverged_speed,       ///< a particle or body exceeded Settings::divergence_speed
  diverged_energy,      ///< the energy rose past its bound (kernel/metrics/divergence.hpp)
  diverged_joint_gap,   ///< a joint came apart, or a particle limb stretched, past its bound (kernel/metrics/divergence.hpp)
  invalid_time_step,    ///< Δt was not a finite number ≥ the method's minimum (kMinimumTimeStep); nothing was done
};

/// The status as an identifier: "ok", "diverged_non_finite", … (Python's, a sweep's column).
inline const char* name(StepStatus status) {
  switch (status) {
    case StepStatus::ok: return "ok";
    case StepStatus::diverged_non_finite: return "diverged_non_finite";
    case StepStatus::diverged_speed: return "diverged_speed";
    case StepStatus::diverged_energy: return "diverged_energy";
    case StepStatus::diverged_joint_gap: return "diverged_joint_gap";
    case StepStatus::invalid_time_step: return "invalid_time_step";
  }
  return "unknown";
}

/// The status as the run summary says it: "ok", "DIVERGED (a non-finite number in the state)", …
inline const char* describe(StepStatus status) {
  switch (status) {
    case StepStatus::ok: return "ok";
    case StepStatus::diverged_non_finite: return "DIVERGED (a non-finite number in the state)";
    case StepStatus::diverged_speed: return "DIVERGED (speed above settings.divergence_speed)";
    case StepStatus::diverged_energy: return "DIVERGED (energy gained past 100 energy scales of the scene)";
    case StepStatus::diverged_joint_gap: return "DIVERGED (a joint gap or a link's stretch past a whole link)";
    case StepStatus::invalid_time_step: return "invalid time step";
  }
  return "unknown";
}

/// The shortest step any method takes, s. Below it a step is refused (invalid_time_step): a
/// subnormal Δt is zero once denormals are flushed, and steps this short carry a body's motion
/// in the last digits of its coordinates (a particle moving at 1 m/s moves 10⁻⁹ m, 10⁷ ulps of
/// a double at 1 m; a float has 10⁻⁷ of a metre there, which is why float particle states
/// take their own minimum, VerletState's minimum_time_step).
inline constexpr double kMinimumTimeStep = 1e-9;

/// Whether step() can take a step of dt seconds: a finite number ≥ `minimum` (s).
inline bool valid_time_step(double dt, double minimum = kMinimumTimeStep) { return dt >= minimum && std::isfinite(dt); }

/// Why the particle method's relaxation stopped in a step (thesis 3.2.3 lists the three).
enum class RelaxationStop : std::uint8_t {
  iterations,  ///< ran the configured number of sweeps
  tolerance,   ///< the largest correction of a sweep fell below the tolerance
  budget,      ///< the wall-clock budget ran out (hard real-time stop)
  idle,        ///< nothing awake to relax
};

/// Where one step's time went, and what it did (StepReport::profile), on the model of Box2D
/// v3's b2Profile. Filled only when the method's options ask for it (VerletOptions::profile,
/// SpringOptions::profile, LagrangeOptions::profile, FeatherstoneOptions::profile); otherwise
/// every field is 0 and no clock is read. Times are seconds of std::chrono::steady_clock, the
/// stages consecutive and in the order they run, so their sum is at most `step`; times and
/// counts are sums over the step's substeps. A field a method has no such stage for stays 0.
///
/// The particle method (verlet/step.cpp, step.hpp's passes) fills every field. Under rattle the
/// contacts' restitution passes run inside the velocity sweeps and count as `velocity`
/// (`restitution` stays 0). The rigid methods (springs, lagrange, featherstone) fill `step`,
/// `integrate` (the integrator, with the forces and any joint solve it makes: springs'
/// backward-Euler solve, Lagrange's multipliers, Featherstone's articulated-body algorithm),
/// `detect`, `substeps` (1), `candidate_pairs` and `contacts`; the rest of their step, contact
/// response, projections and sleep, is `step` less those.
struct StepProfile {
  double integrate = 0;    ///< s: prediction (pbd Verlet, or rattle's kick and drift), forces, kinematic moves
  double detect = 0;       ///< s: contacts with the ball, the planes, and between limbs (broadphase and narrowphase)
  double colour = 0;       ///< s: the contact rows' colouring into batches (and the interleaved layouts' contact particles)
  double relax = 0;        ///< s: the position sweeps (or Newton steps) with their contact projections
  double velocity = 0;     ///< s: rattle's velocity stage; pbd: the shortened substep's velocity (else nothing)
  double restitution = 0;  ///< s: pbd's contact restitution passes (under rattle: inside `velocity`)
  double sleep = 0;        ///< s: sleep and divergence checks, and the step's bookkeeping after its stages
  double step = 0;         ///< s: the whole step, guard included
  int substeps = 0;
  int position_sweeps = 0;   ///< = StepReport::iterations
  int velocity_sweeps = 0;   ///< rattle's velocity sweeps (0 under pbd)
  int contact_rows = 0;      ///< limb–limb, limb–static and ball–static rows detected
  int contact_colours = 0;   ///< colours of those rows (the overflow not counted)
  int candidate_pairs = 0;   ///< pairs of limbs (and balls) the sweep-and-prune broadphase gave
  int limb_searches = 0;     ///< broadphase searches for the limbs' contacts (the other substeps reuse their pairs)
  int contacts = 0;          ///< StepReport::contacts' count, summed over the substeps (≥ StepReport::contacts)
  int tree_solves = 0;       ///< exact joint trees (JointSolve::tree): one component's position solves
  int tree_newton_steps = 0; ///< their Newton steps (a fresh or reused factor and a solve each)
  int tree_capped = 0;       ///< solves that stopped at the cap of Newton steps unconverged
  /// The trees' elimination work, position and velocity stages: factors (one a component and
  /// Newton step), inverse diagonals (the contacts' mobilities), whole back-substitutions, and
  /// path solves (a loop contact's mobility); and the SIMD lanes the factors ran in (the packs'
  /// factors × lanes per pack: tree_factors / tree_lane_slots is the lanes' occupancy).
  int tree_factors = 0, tree_inverse_diagonals = 0, tree_substitutions = 0, tree_path_solves = 0, tree_lane_slots = 0;
  /// s: the trees' share of `relax` and `velocity`, by what it does — staging (limb loads, joint
  /// assembly, limit measures), elimination (gathers into SIMD lanes, factors, solves, path
  /// solves, scatters), moves (the limbs' rigid moves) and contacts (gathering, impulses, loads).
  /// Thread time: on more than one thread their sum can exceed the stages' wall time.
  double tree_staging = 0, tree_elimination = 0, tree_moves = 0, tree_contacts = 0;

  /// Adds `part` (a substep's) field by field.
  StepProfile& operator+=(const StepProfile& part) {
    integrate += part.integrate, detect += part.detect, colour += part.colour, relax += part.relax;
    velocity += part.velocity, restitution += part.restitution, sleep += part.sleep, step += part.step;
    substeps += part.substeps, position_sweeps += part.position_sweeps, velocity_sweeps += part.velocity_sweeps;
    contact_rows += part.contact_rows, contact_colours += part.contact_colours;
    candidate_pairs += part.candidate_pairs, limb_searches += part.limb_searches, contacts += part.contacts;
    tree_solves += part.tree_solves, tree_newton_steps += part.tree_newton_steps, tree_capped += part.tree_capped;
    tree_factors += part.tree_factors, tree_inverse_diagonals += part.tree_inverse_diagonals;
    tree_substitutions += part.tree_substitutions, tree_path_solves += part.tree_path_solves;
    tree_lane_slots += part.tree_lane_slots;
    tree_staging += part.tree_staging, tree_elimination += part.tree_elimination;
    tree_moves += part.tree_moves, tree_contacts += part.tree_contacts;
    return *this;
  }
};

/// Laps of a step's stages for StepProfile: lap() is the seconds since the last lap (or the
/// start), 0 without reading the clock when the profile is off.
class StageClock {
 public:
  explicit StageClock(bool on) : on_(on) {
    if (on_) last_ = std::chrono::steady_clock::now();
  }
  double lap() {
    if (!on_) return 0;
    const auto now = std::chrono::steady_clock::now();
    const double seconds = std::chrono::duration<double>(now - last_).count();
    last_ = now;
    return seconds;
  }

 private:
  bool on_;
  std::chrono::steady_clock::time_point last_{};
};

/// What one step did, under any method: the status, and what the method's solvers say (a field
/// another method fills stays 0). A particle step of `substeps` substeps sums their sweeps and
/// fallbacks; `stop` and `largest_correction` are the last substep's.
struct StepReport {
  StepStatus status = StepStatus::ok;
  int contacts = 0;  ///< contacts found this step (particles: the most in any one of its substeps)

  // Particles: the relaxation.
  RelaxationStop stop = RelaxationStop::idle;
  int iterations = 0;             ///< sweeps run (position sweeps; rattle runs as many velocity sweeps)
  double largest_correction = 0;  ///< largest particle displacement in the last sweep, m
  int substeps = 0;               ///< substeps run (VerletOptions::relaxation.substeps, or fewer on a divergence)
  /// Rattle: constraint projections that fell back to pbd because their start gradient had
  /// turned too far from the current one (kStartGradientMinimumCosine), once per constraint and
  /// substep.
  std::uint64_t fallbacks = 0;

  // Springs, backward Euler with conjugate gradients: the linear solve.
  int linear_solver_iterations = 0;
  double linear_solver_error = 0;  ///< its relative residual

  // Lagrange: how well the joints hold after the step.
  double constraint_error = 0;  ///< largest |C| of a joint's point and slide rows, m
  double angular_error = 0;     ///< largest |u·v| of a joint's angular rows (≈ rad)

  StepProfile profile;  ///< where the step's time went; all 0 unless the method's options ask (`profile`)
};

/// The shortest step `state` takes, s: kMinimumTimeStep, unless an overload for its type (found
/// by argument-dependent lookup) says more.
template <typename State>
double minimum_time_step(const State&) {
  return kMinimumTimeStep;
}

}  // namespace limber
