// What a method takes besides the Model: each method's options and the World's choice of
// method, in one header that includes no state type (no SIMD, oneTBB or sparse-solver
// header), so that an engine naming an option compiles none of the kernel. Each method's state
// keeps a copy of its options (verlet_state.hpp, spring_state.hpp, lagrange_state.hpp,
// featherstone_state.hpp); kernel/methods/method.hpp compiles a Model under WorldOptions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "limber/kernel/model/method_settings.hpp"
#include "limber/kernel/numerics/integrator.hpp"
#include "limber/kernel/threading/task_system.hpp"
#include "limber/layouts/layout_choices.hpp"

namespace limber {

// --- The particle method (Verlet integration and relaxation: kernel/verlet/) ---

/// How a distance constraint's correction is shared between its two particles.
enum class RelaxationRule {
  weighted,    ///< inverse-mass weights w_i/(w_i+w_j), w_j/(w_i+w_j) — thesis eq. 4.7, the thesis's contribution
  unweighted,  ///< ½ and ½ (the whole gap to the free end when the other is pinned) — thesis eq. 4.6 [Jak03]
};

/// How one relaxation sweep visits the constraints.
enum class RelaxationSolver : std::uint8_t {
  gauss_seidel,  ///< each projection sees the positions the previous ones left (thesis 3.2.2)
  jacobi,        ///< every projection reads the same positions; corrections are averaged per particle
  direct,        ///< Newton steps of an exact global projection, linear time on trees
                 ///< (kernel/relaxation/direct_projection.hpp)
};

/// The order of a Gauss-Seidel sweep.
enum class SweepOrder : std::uint8_t {
  coloured,    ///< colour after colour, SIMD lanes and threads inside a colour (the default)
  sequential,  ///< storage order (breadth-first from the pinned root), one constraint at a time:
               ///< the thesis's loop, scalar and single-threaded
};

/// Which end of the sweep holds the constraints at pinned particles.
enum class SweepDirection : std::uint8_t {
  pinned_first,  ///< coloured: pinned and overflow constraints, then colours 0, 1, …; sequential: root first
  pinned_last,   ///< the reverse
};

/// Most threads VerletOptions::threads may ask for (a guard: asking for 1e5 threads failed to
/// start them and ended the program).
inline constexpr int kMaxThreads = 256;
/// Islands of trees (a ragdoll is one) from which automatic threads (threads = 0) start for the
/// particles' joint trees and Featherstone's contacts: an island is a task.
inline constexpr std::size_t kParallelMinimumTreeIslands = 8;
/// Most Newton steps of the direct solver per time step (a guard, as kMaxIterations).
inline constexpr int kMaxNewtonIterations = 1000;

/// Choices the Verlet method takes besides the Model. None changes the physics model; the
/// solver, order and direction change how relaxation converges, the rest only how fast it runs
/// (results are the same bits for every thread count, lane width, layout and ordering).
struct VerletOptions {
  RelaxationRule rule = RelaxationRule::weighted;
  RelaxationSolver solver = RelaxationSolver::gauss_seidel;
  SweepOrder order = SweepOrder::coloured;
  SweepDirection direction = SweepDirection::pinned_first;
  bool simd = true;                          ///< false: the scalar path (one lane)
  ParticleLayout layout = ParticleLayout::automatic;  ///< of the relaxation's particle copy
  ParticleOrder ordering = ParticleOrder::depth_parity;  ///< particle numbering inside islands
  /// Threads for relaxation, the calling one included, in [0, kMaxThreads]: 1 (the default)
  /// starts none; 0 takes the hardware's, and only when some colour is big enough to pay for them
  /// (parallel_minimum_slots) or the joint trees have 8 islands or more (a crowd: an island is a
  /// task); a small scene then starts none either.
  int threads = 1;
  Threading threading = Threading::workers;  ///< how a colour is split across threads
  /// Threading::tasks: the engine's task system (or tbb_task_system(arena)); `threads` then only
  /// says whether to split (≥ 2, or 0 with a colour big enough) and limber starts no thread.
  TaskSystem tasks{};
  /// Colours a stage must have at least this many constraint slots to be split across threads;
  /// 0 picks the crossover measured on the reference machine (bench/speed.md, "The data-oriented core:
  /// SIMD, threads, layouts").
  std::uint32_t parallel_minimum_slots = 0;
  std::uint32_t max_colours = 16;            ///< beyond it, constraints go to the scalar overflow
  /// RelaxationSolver::direct: Newton steps per time step (in [1, kMaxNewtonIterations]; replaces
  /// relaxation.iterations), whether they start from the previous step's multipliers,
  /// and the compliance α of every distance constraint, m/N (0: rigid; XPBD, Macklin et al.
  /// 2016 — the other solvers treat every constraint as rigid and refuse α > 0).
  int newton_iterations = 2;
  bool warm_start = false;
  double compliance = 0;
  /// Long-range attachments (Kim, Chentanez, Müller 2012): after every sweep, each particle
  /// joined to a pinned one is pulled back within the rest length of the path between them.
  bool long_range_attachments = false;
  /// Sweeps, tolerance, over-relaxation, projection rule and substeps (a scene file's
  /// "settings.relaxation"), and how limbs become particles and joints are held
  /// ("settings.verlet").
  RelaxationSettings relaxation{};
  VerletSettings verlet{};
  /// Time the step's stages into StepReport::profile (step_status.hpp): a few steady_clock reads
  /// a substep, the same bits as without; false leaves the profile all zeros and reads no clock.
  bool profile = false;
};

// --- The stiff springs (kernel/springs/) ---

/// The sparse solver of the implicit step.
enum class SpringLinearSolver : std::uint8_t {
  ldlt,                ///< Eigen::SimplicialLDLT with an AMD ordering: exact, no fill on chains and trees, O(n)
  conjugate_gradient,  ///< Eigen::ConjugateGradient, Jacobi preconditioner, warm-started
};

/// Choices the spring method takes besides the Model.
struct SpringOptions {
  /// Any of the five: euler is stable only for small h·k (eq. 3.15), semi_implicit_euler for
  /// h·ω < 2 (ω² = k/m_effective); backward_euler is one linearized solve over the whole system
  /// (eq. 3.16–3.22; Baraff & Witkin 1998), stable for every h·k.
  Integrator integrator = Integrator::semi_implicit_euler;
  SpringLinearSolver linear_solver = SpringLinearSolver::ldlt;
  std::optional<double> stiffness{};  ///< N/m: overrides every joint's and the scene's
  std::optional<double> damping{};    ///< N·s/m: likewise
  double solver_tolerance = 1e-10;  ///< conjugate gradient: relative residual
  /// Backward Euler: 1 is the linearized step (eq. 3.16–3.22); each further iteration is a
  /// Newton step on the nonlinear equations with the same matrix (implicit_step.hpp).
  int newton_iterations = 2;
  /// The spring of a joint that names none (Joint::stiffness, ::damping; a scene file's
  /// "settings.springs"). `stiffness` and `damping` above override both.
  SpringSettings defaults{};
  /// Time the step's stages into StepReport::profile (step_status.hpp): a few steady_clock reads
  /// a step, the same bits as without; false leaves the profile all zeros and reads no clock.
  bool profile = false;
};

// --- Lagrange multipliers (kernel/lagrange/) ---

/// How the joints' drift (the constraint error integration leaves) is held down.
enum class Stabilization : std::uint8_t {
  baumgarte,   ///< C̈ = −2ω_b·Ċ − ω_b²·C in the acceleration solve (Baumgarte 1972)
  projection,  ///< after each step, positions then velocities projected back onto C = 0, Ċ = 0
               ///< through the mass matrix (post-stabilization, Cline & Pai 2003)
};

/// Which solve gives the multipliers.
enum class MultiplierSolver : std::uint8_t {
  automatic,  ///< tree when the joint graph has no loop, else sparse
  tree,       ///< Baraff's linear-time factorization of the tree-ordered system (1996)
  sparse,     ///< J M⁻¹ Jᵀ assembled and factored by Eigen's sparse LDLᵀ: any graph
};

struct LagrangeOptions {
  Integrator integrator = Integrator::semi_implicit_euler;
  Stabilization stabilization = Stabilization::baumgarte;
  MultiplierSolver solver = MultiplierSolver::automatic;
  /// ω_b of Baumgarte stabilization, 1/s; 0: 1/(4Δt), critically damped and four steps to
  /// correct an error — with Δt no shorter than the Model's Settings::time_step, so that a short
  /// step does not turn a longer step's error C into a velocity C/(4Δt).
  double baumgarte_frequency = 0;
  int projection_iterations = 2;  ///< Newton iterations of the position projection
  /// Time the step's stages into StepReport::profile (step_status.hpp): a few steady_clock reads
  /// a step, the same bits as without; false leaves the profile all zeros and reads no clock.
  bool profile = false;
};

// --- Featherstone's articulated-body algorithm (kernel/featherstone/) ---

struct FeatherstoneOptions {
  /// The core's integrators (integration.hpp). RK4 by default: the semi-implicit Euler step
  /// (v ← v + h·v̇(q, v), then q) takes the velocity-product terms of v̇ — the gyroscopic
  /// torque, and a floating body's body-frame velocity turning as −ω × v — explicitly, so a
  /// body or joint turning at Ω (rad/s, in its own frame) gains |v| by a factor
  /// √(1 + (hΩ)²) every step. That is unstable at any Δt: a thin limb spinning about its axis,
  /// or the humanoid's short neck spinning between two spherical joints after the ball's impact
  /// (Ω ≈ 100 rad/s), diverges within a few dozen steps at Δt = 1/240 s (measured on every
  /// humanoid.json body and ball speed, and on stick_in_box.json). RK4 damps such motion
  /// slightly instead (|amplification| = 1 − (hΩ)⁶/144 + …, stable while hΩ < 2.8); the step
  /// splits into substeps where a body turns fast (step.hpp). The integrator also sets when the
  /// contacts and limits are solved: under RK4 after the move (the thesis's loop), under
  /// semi-implicit Euler before it, on the velocity update (MuJoCo's order; joint_space_contacts.hpp,
  /// "Before the move"), where static friction holds and a landing limb does not overlap.
  Integrator integrator = Integrator::rk4;
  /// Threads for the contacts and limits, the calling one included, in [0, kMaxThreads]: each
  /// group of islands the step's contacts join is a task (joint_space_contacts.hpp, "Groups"),
  /// the same bits for any count. 1 (the default) starts none; 0 takes the hardware's when the
  /// tree has kParallelMinimumTreeIslands islands or more.
  int threads = 1;
  Threading threading = Threading::workers;  ///< how the groups are split across threads
  /// Threading::tasks: the engine's task system (or tbb_task_system(arena)); limber starts no thread.
  TaskSystem tasks{};
  /// Time the step's stages into StepReport::profile (step_status.hpp): a few steady_clock reads
  /// a step, the same bits as without; false leaves the profile all zeros and reads no clock.
  bool profile = false;
};

// --- The World's choice ---

/// The method a Model is stepped with.
enum class Method : std::uint8_t {
  particles,     ///< Verlet integration and relaxation (thesis 3.2, 4.2): WorldOptions::particles
  springs,       ///< rigid limbs joined by stiff springs (thesis 3.3): WorldOptions::springs
  lagrange,      ///< rigid limbs and joint constraints (thesis 3.4): WorldOptions::lagrange
  featherstone,  ///< reduced coordinates, the articulated-body algorithm (thesis 3.5)
};

/// The method's name in messages and tables ("particles", "springs", "lagrange",
/// "featherstone"); the command line spells the particle method "weighted" or "unweighted"
/// (its limb masses) and the springs "springs-explicit" or "springs-implicit".
std::string_view method_name(Method method);

/// A method and its options (each method reads only its own).
struct WorldOptions {
  Method method = Method::particles;
  bool single_precision = false;  ///< particles only: a float state (other methods refuse it)
  VerletOptions particles{};      ///< threads default to 1: a world starts no threads unless asked
  SpringOptions springs{};
  LagrangeOptions lagrange{};
  FeatherstoneOptions featherstone{};
  /// After each step, the checks every method shares (metrics/divergence.hpp: a non-finite
  /// number, energy gained past its bound, a joint come apart) turn an ok status into a
  /// divergence. The studies turn them off: they run on past such a step and classify the run
  /// themselves (study/run_metrics.hpp). The method's own guard runs either way.
  bool divergence_check = true;
};

/// Default options for `method` that carry a scene's method settings (a scene file's
/// relaxation, particle and spring settings: Scene::methods); change any field after.
/// Defined with the dispatch (kernel/methods/method.cpp).
WorldOptions world_options(Method method, const MethodSettings& scene);

}  // namespace limber
