// The thesis's Verlet experiments, redone: prints the README's tables (markdown) to stdout.
//
//   build/bench/thesis_experiments                   every table
//   build/bench/thesis_experiments TABLE             one: sweeps, rules, humanoid, verlet-rk2, chain-methods
//   build/bench/thesis_experiments verlet-rk2-csv    figure 3.12's series as CSV (tools/plot_thesis.py)
//
// Physics only — joint gaps, how far bodies move, integration error. Timings are in verlet_bench
// and thesis_speed (Google Benchmark).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "limber/kernel/featherstone/compile.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/metrics/knock.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/rigid/rigid_integration.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/springs/compile.hpp"
#include "limber/kernel/springs/step.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"

namespace limber {
namespace {

Model scene(const std::string& file, const SceneOptions& options = {}) {
  return load_scene_file(std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/" + file, options).model;
}

// chain.json's own particle settings (its rule and substeps), with the relaxation rule `rule`.
VerletOptions chain_json_options(RelaxationRule rule) {
  const Scene chain = load_scene_file(std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/chain.json");
  VerletOptions options;
  options.rule = rule;
  options.relaxation = chain.methods.relaxation;
  options.verlet = chain.methods.verlet;
  return options;
}

// Thesis 3.2.3 / 4.4.2: more sweeps, smaller gaps; over-relaxation gets there sooner.
void relaxation_sweeps() {
  std::printf("### Joint gap against relaxation sweeps (chain.json: 5 links, heavy end, released horizontally)\n\n");
  std::printf("| sweeps per step | joint gap, ω = 1 (thesis) | joint gap, ω = 1.5 (chain.json) | link stretch, shared-particle joints, ω = 1 |\n|---|---|---|---|\n");
  // Largest joint gap (or, with shared particles, link stretch) over 5 s, relative to the link length.
  const auto largest_error = [](int sweeps, double omega, bool shared) {
    const Model model = scene("chain.json");
    VerletOptions options = chain_json_options(RelaxationRule::weighted);
    options.relaxation.iterations = sweeps;
    options.relaxation.over_relaxation = omega;
    if (shared) options.verlet.joints = ParticleJoints::shared_particle;
    auto state = compile<double>(model, options);
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
    Model model = scene("humanoid.json", {.variant = std::string(body), .links = {}, .copies = {}});
    adjust(model.balls.front());
    auto state = compile<double>(model);
    const Eigen::Vector3d start = observe(state).body_centre_of_mass;
    KnockMeter knock(model.balls.front().velocity, start);
    const long steps = std::lround(model.settings.duration / model.settings.time_step);
    for (long s = 0; s < steps; ++s) {
      step(state);
      knock.update(state.time, state.ball_touched, observe(state).body_centre_of_mass);
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


// --- Thesis 3.2.6, figure 3.12: Verlet against a 2nd-order Runge-Kutta on one particle ---------
//
// The thesis plots the particle's *velocity* under each integrator and finds RK2's "more precise"
// without naming the force or the step. We integrate two forces, per unit mass, with the kernel's
// own steps: a constant one (gravity, a thrown particle) and a spring to the origin (ω = 2π,
// period 1 s), whose exact solutions are known.
struct ParticleProblem {
  const char* name;
  Eigen::Vector3d gravity;             // m/s²
  double spring_rate;                  // ω² = k/m, 1/s²; 0: no spring
  Eigen::Vector3d position, velocity;  // at t = 0

  Eigen::Vector3d acceleration(const Eigen::Vector3d& x) const { return gravity - spring_rate * x; }
  Eigen::Vector3d exact_position(double t) const {
    if (spring_rate == 0) return position + velocity * t + 0.5 * gravity * t * t;
    const double omega = std::sqrt(spring_rate);
    const Eigen::Vector3d rest = gravity / spring_rate;
    return rest + (position - rest) * std::cos(omega * t) + velocity / omega * std::sin(omega * t);
  }
  Eigen::Vector3d exact_velocity(double t) const {
    if (spring_rate == 0) return velocity + gravity * t;
    const double omega = std::sqrt(spring_rate);
    const Eigen::Vector3d rest = gravity / spring_rate;
    return -(position - rest) * omega * std::sin(omega * t) + velocity * std::cos(omega * t);
  }
};

const ParticleProblem kThrownParticle{"gravity", Eigen::Vector3d(0, 0, -9.81), 0, Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 5)};
const ParticleProblem kSpringParticle{"spring", Eigen::Vector3d::Zero(), 4 * std::numbers::pi * std::numbers::pi,
                                      Eigen::Vector3d(1, 0, 0), Eigen::Vector3d::Zero()};

// The kernel's Verlet step (eq. 3.6) on one free particle: a Model with one short limb and no
// joints. Both of the limb's particles get the same acceleration, so its link constraint never
// acts and its centre moves as a lone particle. compile() starts from x(−Δt) = x0 − v0·Δt, which
// is first order (the first step then adds a·Δt² where the Taylor series has ½·a·Δt²); the
// consistent start adds ½·a0·Δt² to x(−Δt), after which Verlet's positions are second order.
struct VerletParticle {
  const ParticleProblem* problem;
  VerletState<double> state;

  VerletParticle(const ParticleProblem& p, double dt, bool consistent_start) : problem(&p), state(compile<double>(model(p, dt), one_sweep())) {
    if (!consistent_start) return;
    const Eigen::Vector3d shift = 0.5 * p.acceleration(p.position) * dt * dt;
    for (std::size_t i = 0; i < state.particles.size(); ++i) {
      state.particles.previous_x[i] += shift.x(), state.particles.previous_y[i] += shift.y(), state.particles.previous_z[i] += shift.z();
    }
  }
  static Model model(const ParticleProblem& p, double dt) {
    Model model;
    model.name = "particle";
    Body body;
    body.name = "particle";
    body.shape = {ShapeType::capsule, 0.01, 0.005};
    body.mass = 1;
    body.position = p.position, body.linear_velocity = p.velocity;
    model.bodies.push_back(body);
    model.settings.gravity = p.gravity;
    model.settings.time_step = dt;
    model.settings.sleep.enabled = false;
    return model;
  }
  static VerletOptions one_sweep() {
    VerletOptions options;
    options.relaxation.iterations = 1;
    return options;
  }
  Eigen::Vector3d position() const {
    return 0.5 * (state.particles.position(state.limbs.head[0]) + state.particles.position(state.limbs.tail[0]));
  }
  // The velocity the kernel uses (observe(): kinetic energy), v = (x − x*)/Δt: a backward
  // difference, first order at t (second order at t − Δt/2).
  Eigen::Vector3d velocity() const {
    const auto& p = state.particles;
    const std::uint32_t head = state.limbs.head[0], tail = state.limbs.tail[0];
    const Eigen::Vector3d previous = 0.5 * Eigen::Vector3d(p.previous_x[head] + p.previous_x[tail], p.previous_y[head] + p.previous_y[tail],
                                                           p.previous_z[head] + p.previous_z[tail]);
    return (position() - previous) / state.settings.time_step;
  }
  void advance() {
    // The spring's force at x(t) enters this step's a·Δt² (gravity is the scene's).
    const double mass = 1;
    if (problem->spring_rate != 0) apply_force(state, 0, Eigen::Vector3d(-mass * problem->spring_rate * position()));
    step(state);
  }
};

// The kernel's rigid-body RK2 (midpoint) step, Integrator::rk2, on one body of 1 kg: its
// velocity is part of the state, so it is as accurate as its position.
struct RungeKuttaParticle {
  const ParticleProblem* problem;
  double dt;
  RigidBodyBuffer bodies;
  RigidIntegratorScratch scratch;

  RungeKuttaParticle(const ParticleProblem& p, double step) : problem(&p), dt(step) {
    bodies.resize(1), scratch.resize(1);
    bodies.mass[0] = bodies.inverse_mass[0] = 1;
    bodies.body_inertia[0] = bodies.body_inverse_inertia[0] = Eigen::Matrix3d::Identity();
    bodies.state.position[0] = p.position, bodies.state.linear_momentum[0] = p.velocity;
  }
  Eigen::Vector3d position() const { return bodies.state.position[0]; }
  Eigen::Vector3d velocity() const { return bodies.linear_velocity(bodies.state, 0); }
  void advance() {
    integrate_rigid_bodies(bodies, dt, Integrator::rk2, scratch, [this](const RigidBodyState& y, RigidForces& forces) {
      forces.force[0] += bodies.mass[0] * problem->acceleration(y.position[0]);
    });
  }
};

// Largest errors over 2 s against the exact solution.
struct IntegrationErrors {
  double rk2_position = 0, rk2_velocity = 0;
  double verlet_position_kernel_start = 0, verlet_position = 0;
  double verlet_velocity = 0, verlet_central_velocity = 0;
};

IntegrationErrors integration_errors(const ParticleProblem& problem, double dt) {
  IntegrationErrors e;
  RungeKuttaParticle rk2(problem, dt);
  VerletParticle verlet(problem, dt, true), kernel_start(problem, dt, false);
  const long steps = std::lround(2.0 / dt);
  Eigen::Vector3d before_previous = problem.exact_position(-dt);  // x(t − 2Δt) for the central difference
  for (long n = 1; n <= steps; ++n) {
    const Eigen::Vector3d previous = verlet.position();
    rk2.advance(), verlet.advance(), kernel_start.advance();
    const double t = n * dt;
    e.rk2_position = std::max(e.rk2_position, (rk2.position() - problem.exact_position(t)).norm());
    e.rk2_velocity = std::max(e.rk2_velocity, (rk2.velocity() - problem.exact_velocity(t)).norm());
    e.verlet_position = std::max(e.verlet_position, (verlet.position() - problem.exact_position(t)).norm());
    e.verlet_position_kernel_start = std::max(e.verlet_position_kernel_start, (kernel_start.position() - problem.exact_position(t)).norm());
    e.verlet_velocity = std::max(e.verlet_velocity, (verlet.velocity() - problem.exact_velocity(t)).norm());
    // (x(t) − x(t − 2Δt)) / 2Δt estimates v(t − Δt) to second order.
    if (n >= 2) {
      const Eigen::Vector3d central = (verlet.position() - before_previous) / (2 * dt);
      e.verlet_central_velocity = std::max(e.verlet_central_velocity, (central - problem.exact_velocity(t - dt)).norm());
    }
    before_previous = previous;
  }
  return e;
}

void verlet_against_rk2() {
  std::printf("### Verlet against 2nd-order Runge-Kutta on one particle (thesis figure 3.12)\n\n");
  std::printf("Largest error over 2 s against the exact solution. gravity: thrown up at 5 m/s under g; spring: released\n"
              "1 m from the origin on a spring of period 1 s. RK2 is the kernel's rigid-body midpoint step; Verlet is the\n"
              "kernel's Verlet step on a one-limb model, from compile()'s start x(−Δt) = x0 − v0Δt or the consistent one\n"
              "(+½a0Δt²). Velocities: RK2's own; Verlet's (x − x*)/Δt (the kernel's) and the central (x₊ − x₋)/2Δt.\n\n");
  std::printf("| force | Δt | RK2 position | RK2 velocity | Verlet position, compile()'s start | Verlet position, consistent start "
              "| Verlet velocity (x − x*)/Δt | Verlet velocity, central |\n|---|---|---|---|---|---|---|---|\n");
  for (const ParticleProblem* problem : {&kThrownParticle, &kSpringParticle}) {
    for (int per_second : {30, 60, 120, 240}) {
      const IntegrationErrors e = integration_errors(*problem, 1.0 / per_second);
      std::printf("| %s | 1/%d s | %.1e m | %.1e m/s | %.1e m | %.1e m | %.1e m/s | %.1e m/s |\n", problem->name, per_second, e.rk2_position,
                  e.rk2_velocity, e.verlet_position_kernel_start, e.verlet_position, e.verlet_velocity, e.verlet_central_velocity);
    }
  }
  std::printf("\n");
}

// The spring's series at Δt = 1/30 s (a game's frame) for the figure: x components.
void verlet_against_rk2_series() {
  const ParticleProblem& problem = kSpringParticle;
  const double dt = 1.0 / 30;
  RungeKuttaParticle rk2(problem, dt);
  VerletParticle verlet(problem, dt, true), kernel_start(problem, dt, false);
  const long steps = std::lround(2.0 / dt);
  std::vector<double> verlet_x{verlet.position().x()};
  std::printf("time,exact_position,exact_velocity,rk2_position,rk2_velocity,verlet_position,verlet_position_kernel_start,"
              "verlet_velocity,verlet_central_velocity\n");
  std::vector<std::array<double, 8>> rows;
  for (long n = 1; n <= steps; ++n) {
    rk2.advance(), verlet.advance(), kernel_start.advance();
    const double t = n * dt;
    verlet_x.push_back(verlet.position().x());
    rows.push_back({t, problem.exact_position(t).x(), problem.exact_velocity(t).x(), rk2.position().x(), rk2.velocity().x(),
                    verlet.position().x(), kernel_start.position().x(), verlet.velocity().x()});
  }
  for (long n = 1; n <= steps; ++n) {
    const auto& r = rows[n - 1];
    // Central difference at t_n needs x(t_{n+1}); the last row has none.
    const double central = n < steps ? (verlet_x[n + 1] - verlet_x[n - 1]) / (2 * dt) : NAN;
    std::printf("%.6f,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], central);
  }
}

// --- Thesis 4.4.2–4.4.3: weighted, midpoint and stiff springs on the heavy-end chain -----------
//
// Measured on chain.json as shipped (5 links, the end double mass, released horizontally from
// the pivot at (0, 0, 1.5) along +x; Verlet: 100 sweeps, ω = 1.5):
//  - joint gap: the largest over 5 s, relative to the link length;
//  - end under the pivot: the time the chain's free end first swings under the pivot (x ≤ 0),
//    a quarter swing: the heavier the end relative to the chain, the more the chain swings as
//    one pendulum and the sooner its end arrives;
//  - end's lead: at 0.3 s, the angle of pivot → end below the horizontal minus that of pivot →
//    the chain's middle (half its length): > 0 the end leads the chain down, < 0 it trails (whips);
//  - settling: chain.json has no damping, so we add settings.damping = 0.5 /s for every method
//    (the thesis damped Verlet with the 1.99 factor of eq. 4.5; the damping rate is that idea in
//    units that do not depend on Δt). Settled: the time after which the kinetic energy stays
//    below 1 % of its peak, over 30 s.
struct ChainSample {
  Eigen::Vector3d end, middle;
  double gap = 0, kinetic = 0;
};

struct ChainRun {
  double largest_gap = 0, end_under_pivot = NAN, end_lead_degrees = NAN, settled = NAN;
};

// advance(): one step of a method, then what it shows. `make` builds a fresh run from a model.
using ChainStepper = std::function<ChainSample()>;
using ChainMethod = std::function<ChainStepper(const Model&)>;

ChainStepper verlet_stepper(const Model& model, VerletOptions options) {
  auto state = std::make_shared<VerletState<double>>(compile<double>(model, options));
  return [state] {
    step(*state);
    const auto& p = state->particles;
    const auto& limbs = state->limbs;
    const std::uint32_t middle = state->body_limb[limbs.size() / 2], last = state->body_limb[limbs.size() - 1];
    const Observation o = observe(*state);
    return ChainSample{p.position(limbs.tail[last]).cast<double>(),
                       (0.5 * (p.position(limbs.head[middle]) + p.position(limbs.tail[middle]))).cast<double>(), o.max_joint_gap,
                       o.kinetic_energy};
  };
}

template <typename State>
ChainSample rigid_sample(const State& state, double link_length) {
  const std::size_t links = state.bodies.size();
  const Observation o = observe(state);
  return ChainSample{world_point(state, links - 1, Eigen::Vector3d(0, 0, -0.5 * link_length)), world_point(state, links / 2, Eigen::Vector3d::Zero()),
                     o.max_joint_gap, o.kinetic_energy};
}

ChainStepper spring_stepper(const Model& model, SpringOptions options) {
  auto state = std::make_shared<SpringState>(compile_springs(model, options));
  const double length = model.bodies.front().shape.length;
  return [state, length] { return step(*state), rigid_sample(*state, length); };
}

ChainStepper featherstone_stepper(const Model& model) {
  auto state = std::make_shared<FeatherstoneState>(compile_featherstone(model));
  const double length = model.bodies.front().shape.length;
  return [state, length] { return step(*state), rigid_sample(*state, length); };
}

ChainRun run_chain(const Model& shipped, const ChainMethod& method) {
  ChainRun run;
  const Eigen::Vector3d pivot(0, 0, 1.5);
  const double dt = shipped.settings.time_step;
  const auto below_horizontal = [&](const Eigen::Vector3d& point) { return std::atan2(pivot.z() - point.z(), point.x() - pivot.x()); };
  // The scene as shipped: gaps, the quarter swing, the lead.
  ChainStepper undamped = method(shipped);
  for (long n = 1; n <= std::lround(5 / dt); ++n) {
    const ChainSample s = undamped();
    run.largest_gap = std::max(run.largest_gap, s.gap);
    if (std::isnan(run.end_under_pivot) && s.end.x() <= pivot.x()) run.end_under_pivot = n * dt;
    if (n == std::lround(0.3 / dt)) run.end_lead_degrees = (below_horizontal(s.end) - below_horizontal(s.middle)) * 180 / std::numbers::pi;
  }
  // With damping: when the chain comes to rest.
  Model damped_model = shipped;
  damped_model.settings.damping = 0.5;
  ChainStepper damped = method(damped_model);
  std::vector<double> kinetic;
  for (long n = 1; n <= std::lround(30 / dt); ++n) kinetic.push_back(damped().kinetic);
  const double peak = *std::max_element(kinetic.begin(), kinetic.end());
  for (std::size_t n = kinetic.size(); n-- > 0;) {
    if (kinetic[n] >= 0.01 * peak) {
      run.settled = n + 1 < kinetic.size() ? (n + 1) * dt : NAN;  // NAN: still moving at 30 s
      break;
    }
  }
  return run;
}

void chain_methods() {
  std::printf("### Weighted, midpoint and stiff springs on the heavy-end chain (chain.json)\n\n");
  std::printf("Joint gap: largest over 5 s / link length. End under pivot: when the free end first swings under the pivot.\n"
              "End's lead: at 0.3 s, the end's angle below the horizontal about the pivot minus the chain middle's (> 0: the end\n"
              "leads). Settled: with damping 0.5 /s added, when the kinetic energy stays below 1 %% of its peak (30 s run).\n\n");
  std::printf("| method | end link | joint gap | end under pivot | end's lead at 0.3 s | settled |\n|---|---|---|---|---|---|\n");
  const Model heavy_end = scene("chain.json");
  Model equal = heavy_end;
  equal.bodies.back().mass = equal.bodies.front().mass;
  Model heavier = heavy_end;  // a 10× end makes the rules' difference plain
  heavier.bodies.back().mass = 10 * heavier.bodies.front().mass;
  struct Row { const char* name; const char* end; const Model* model; ChainMethod method; };
  const Row rows[] = {
      {"weighted Verlet (eq. 4.7)", "2 × link", &heavy_end, [](const Model& m) { return verlet_stepper(m, chain_json_options(RelaxationRule::weighted)); }},
      {"midpoint Verlet (eq. 4.6)", "2 × link", &heavy_end, [](const Model& m) { return verlet_stepper(m, chain_json_options(RelaxationRule::unweighted)); }},
      {"weighted = midpoint Verlet", "1 × link", &equal, [](const Model& m) { return verlet_stepper(m, chain_json_options(RelaxationRule::weighted)); }},
      {"stiff springs, explicit, k = 2·10⁴ N/m (the thesis's step)", "2 × link", &heavy_end,
       [](const Model& m) { return spring_stepper(m, {.integrator = Integrator::semi_implicit_euler}); }},
      {"stiff springs, implicit, k = 10⁶ N/m", "2 × link", &heavy_end,
       [](const Model& m) { return spring_stepper(m, {.integrator = Integrator::backward_euler, .stiffness = 1e6}); }},
      {"weighted Verlet, three-particle limbs (rigid-limb inertia)", "2 × link", &heavy_end,
       [](const Model& m) {
         VerletOptions options = chain_json_options(RelaxationRule::weighted);
         options.verlet.limb_masses = LimbMasses::inertia;
         return verlet_stepper(m, options);
       }},
      {"Featherstone (exact rigid chain, reference)", "2 × link", &heavy_end, [](const Model& m) { return featherstone_stepper(m); }},
      {"Featherstone (exact rigid chain, reference)", "1 × link", &equal, [](const Model& m) { return featherstone_stepper(m); }},
      {"weighted Verlet (eq. 4.7)", "10 × link", &heavier, [](const Model& m) { return verlet_stepper(m, chain_json_options(RelaxationRule::weighted)); }},
      {"midpoint Verlet (eq. 4.6)", "10 × link", &heavier, [](const Model& m) { return verlet_stepper(m, chain_json_options(RelaxationRule::unweighted)); }},
      {"Featherstone (exact rigid chain, reference)", "10 × link", &heavier, [](const Model& m) { return featherstone_stepper(m); }},
  };
  for (const Row& row : rows) {
    const ChainRun run = run_chain(*row.model, row.method);
    std::printf("| %s | %s | %.1e | %.3f s | %+.1f° | %.2f s |\n", row.name, row.end, run.largest_gap, run.end_under_pivot, run.end_lead_degrees,
                run.settled);
  }
  std::printf("\n");
}

}  // namespace
}  // namespace limber

int main(int argc, char** argv) {
  const std::string only = argc > 1 ? argv[1] : "";
  if (only == "verlet-rk2-csv") return limber::verlet_against_rk2_series(), 0;
  const bool all = only.empty();
  if (!all && only != "sweeps" && only != "rules" && only != "humanoid" && only != "verlet-rk2" && only != "chain-methods") {
    std::fprintf(stderr, "usage: thesis_experiments [sweeps|rules|humanoid|verlet-rk2|chain-methods|verlet-rk2-csv]\n");
    return 2;
  }
  if (all || only == "sweeps") limber::relaxation_sweeps();
  if (all || only == "rules") limber::weighted_against_midpoint();
  if (all || only == "humanoid") limber::humanoid_knocks();
  if (all || only == "verlet-rk2") limber::verlet_against_rk2();
  if (all || only == "chain-methods") limber::chain_methods();
  return 0;
}
