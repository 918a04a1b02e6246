// Long-run soak: the humanoid and its ball under every method,
// and a long chain under every Verlet solver at Δt = 1/30 s, stepped through World and checked
// after every step against what the physics allows, measured here from World::observe(),
// pose(), motion(), ball() and segments() — not by the kernel's own divergence check:
// - a step reported ok leaves every number finite, no joint open and no limb stretched past a
//   whole link, and no more energy than the run started with, plus a stated tolerance: nothing
//   in these scenes pushes, drives or moves a pin, and the ball's kinetic energy is already in
//   the start's;
// - a step reported diverged leaves a state that is bad by the same measures (the report is no
//   false alarm), and the run stops there;
// - the humanoid, lying on the ground, never gains energy beyond a stated tolerance. Its
//   contacts never end (it rests on the ground, the ball rolls on), so "after the last contact"
//   is read as "at rest": from 10 s on, energy stays below its lowest since plus the tolerance.
//
// Short form (soak_tests, label stress, in every ctest run): 6000 humanoid steps per method
// (25 s: the ball, the fall and the rest) and a 10³-link chain for up to 400 steps (13 s).
// Long form (soak_long_tests, compiled with LIMBER_SOAK_LONG, label stress, ctest
// configuration "soak" so a plain ctest leaves it out): 10⁵ humanoid steps per method (417 s)
// and the 10⁴-link chain for up to 10⁴ steps (333 s):
//   ninja -C build soak_long_tests && ctest --test-dir build -C soak -R soak_long --output-on-failure
// Each case prints its steps, largest energy gain and how it ended.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/geometry/limb_collisions.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/world/world.hpp"

namespace limber {
namespace {

#ifdef LIMBER_SOAK_LONG
constexpr long kHumanoidSteps = 100000;
constexpr long kChainLinks = 10000, kChainSteps = 10000;
#else
constexpr long kHumanoidSteps = 6000;
constexpr long kChainLinks = 1000, kChainSteps = 400;
#endif

// The bound past which energy has run away, as divergence.hpp states it but computed here from
// the Model: 100 × (M·|g|·max(extent, 1 m) + the start's kinetic energy).
double runaway_energy(const Model& model, const Observation& start) {
  Eigen::Vector3d low = Eigen::Vector3d::Constant(1e300), high = -low;
  double mass = 0;
  for (const Body& body : model.bodies) {
    low = low.cwiseMin(body.position), high = high.cwiseMax(body.position);
    mass += body.mass;
  }
  for (const Ball& ball : model.balls) {
    low = low.cwiseMin(ball.position), high = high.cwiseMax(ball.position);
    mass += ball.mass;
  }
  const double extent = std::max((high - low).norm(), 1.0);
  return 100 * (mass * model.settings.gravity.norm() * extent + start.kinetic_energy);
}

// What is wrong with the world's state now, measured from its public reads; empty when nothing.
std::string bad_state(const World& world, const Observation& now, double start_energy, double runaway) {
  for (const BodyId body : world.bodies()) {
    const Pose pose = world.pose(body);
    const Motion motion = world.motion(body);
    if (!pose.position.allFinite() || !pose.orientation.coeffs().allFinite() || !motion.linear.allFinite() ||
        !motion.angular.allFinite()) {
      return "body " + world.body_description(body).name + " is not finite";
    }
  }
  for (const BallId ball : world.balls()) {
    const BallMotion motion = world.ball(ball);
    if (!motion.position.allFinite() || !motion.velocity.allFinite()) return "a ball is not finite";
  }
  if (!std::isfinite(now.energy()) || !now.linear_momentum.allFinite() || !now.body_centre_of_mass.allFinite() ||
      !std::isfinite(now.max_joint_gap)) {
    return "an observed quantity is not finite";
  }
  if (now.energy() - start_energy > runaway) return "energy ran away: gained " + std::to_string(now.energy() - start_energy) + " J";
  if (now.max_joint_gap > 1) return "a joint is open by " + std::to_string(now.max_joint_gap) + " links";
  // Each limb's length as collision sees it (World::segments), against its Model length.
  std::vector<LimbSegment> segments;
  world.segments(segments);
  for (std::size_t b = 0; b < world.model().bodies.size(); ++b) {
    const double length = world.model().bodies[b].shape.length;
    const double stretch = std::abs((segments[b].head - segments[b].tail).norm() - length) / length;
    if (!(stretch <= 1)) return "limb " + world.model().bodies[b].name + " is stretched by " + std::to_string(stretch) + " of its length";
  }
  return {};
}

struct SoakCase {
  std::string name;
  WorldOptions options;
};

struct SoakResult {
  long steps = 0;                 // steps reported ok
  StepStatus status = StepStatus::ok;  // the first status other than ok, or ok
  double largest_gain = 0;        // J: max over ok steps of E − E(0)
  double largest_rise_at_rest = 0;  // J: max over ok steps after `rest_from` of E − (lowest E since rest_from)
  double end_energy = 0;
};

// Steps `world` up to `steps` times at `dt`, checking every step as the file's head says; stops
// at the first status other than ok. ok steps must keep E ≤ E(0) + energy_tolerance.
SoakResult soak(World& world, double dt, long steps, double energy_tolerance, double rest_from) {
  const Observation start = world.observe();
  const double start_energy = start.energy(), runaway = runaway_energy(world.model(), start);
  SoakResult result;
  double lowest_at_rest = 1e300;
  for (long n = 1; n <= steps; ++n) {
    const StepStatus status = world.step(dt);
    const Observation now = world.observe();
    const std::string bad = bad_state(world, now, start_energy, runaway);
    const double energy = now.energy();
    if (status != StepStatus::ok) {
      result.status = status;
      EXPECT_FALSE(bad.empty()) << "step " << n << " reported status " << int(status) << " but the state is sound: E − E(0) = "
                                << energy - start_energy << " J, gap " << now.max_joint_gap << ", stretch " << now.max_link_stretch;
      std::printf("  step %ld: status %d (%s), E − E(0) = %.4g J\n", n, int(status), bad.c_str(), energy - start_energy);
      break;
    }
    EXPECT_TRUE(bad.empty()) << "step " << n << " reported ok but " << bad;
    EXPECT_LE(energy, start_energy + energy_tolerance) << "step " << n << " reported ok with energy gained";
    if (!bad.empty() || energy > start_energy + energy_tolerance) break;  // one failure is enough to read
    result.steps = n;
    result.largest_gain = std::max(result.largest_gain, energy - start_energy);
    if (n * dt >= rest_from) {
      lowest_at_rest = std::min(lowest_at_rest, energy);
      result.largest_rise_at_rest = std::max(result.largest_rise_at_rest, energy - lowest_at_rest);
    }
    result.end_energy = energy;
  }
  return result;
}

// --- The humanoid and its ball -----------------------------------------------------------------

Scene humanoid() { return load_scene_text(embedded_humanoid_scene(), "humanoid"); }

// Every method and Verlet solver, with the scene's settings (GS: 100 sweeps, pbd) unless named.
std::vector<SoakCase> humanoid_cases(const Scene& scene) {
  std::vector<SoakCase> cases;
  const auto add = [&](std::string name, Method method, auto&& change) {
    WorldOptions options = world_options(method, scene.methods);
    change(options);
    cases.push_back({std::move(name), options});
  };
  add("particles, Gauss-Seidel coloured, 100 sweeps", Method::particles, [](WorldOptions&) {});
  add("particles, Gauss-Seidel sequential, 100 sweeps", Method::particles,
      [](WorldOptions& o) { o.particles.order = SweepOrder::sequential; });
  add("particles, Jacobi, 100 sweeps", Method::particles, [](WorldOptions& o) { o.particles.solver = RelaxationSolver::jacobi; });
  add("particles, direct, 2 Newton steps", Method::particles, [](WorldOptions& o) { o.particles.solver = RelaxationSolver::direct; });
  add("particles, unweighted Gauss-Seidel, 100 sweeps", Method::particles,
      [](WorldOptions& o) { o.particles.rule = RelaxationRule::unweighted; });
  add("springs, semi-implicit Euler", Method::springs, [](WorldOptions&) {});
  add("springs, backward Euler", Method::springs, [](WorldOptions& o) { o.springs.integrator = Integrator::backward_euler; });
  add("lagrange", Method::lagrange, [](WorldOptions&) {});
  add("featherstone, RK4", Method::featherstone, [](WorldOptions&) {});
  return cases;
}

// E ≤ E(0) + 0.1 J: E(0) (1159 J) holds the ball's 113 J; the largest gain measured is 5 mJ
// (Featherstone, awake, the feet settling onto the ground in the first steps). At rest (from
// 10 s on: the body is down by 4 s under every method) energy may not rise more than 0.05 J
// above its lowest since: contact rows and push-out jitter put in at most 15 mJ (Lagrange),
// and 0.05 J is the whole 180 kg body lifted by 28 µm.
constexpr double kHumanoidGain = 0.1, kHumanoidRise = 0.05, kHumanoidRestFrom = 10;

void soak_humanoid(bool sleeping) {
  Scene scene = humanoid();
  scene.model.settings.sleep.enabled = sleeping;
  const double dt = scene.model.settings.time_step;
  for (const SoakCase& c : humanoid_cases(scene)) {
    SCOPED_TRACE(c.name);
    World world(scene.model, c.options);
    const SoakResult result = soak(world, dt, kHumanoidSteps, kHumanoidGain, kHumanoidRestFrom);
    std::printf("humanoid%s, %s: %ld steps ok, largest gain %.3g J, largest rise at rest %.3g J, end energy %.3f J\n",
                sleeping ? "" : " (awake)", c.name.c_str(), result.steps, result.largest_gain, result.largest_rise_at_rest,
                result.end_energy);
    EXPECT_EQ(result.steps, kHumanoidSteps);
    EXPECT_EQ(result.status, StepStatus::ok);
    // The thesis's unweighted rule (½ and ½, eq. 4.6) does not keep the centre of mass. Lying awake
    // on the ground it creeps upward in a propped pose and gains energy with no kinetic energy to
    // speak of (< 3·10⁻⁶ J): measured 229.452 J at 2·10⁴ steps, 229.748 J at 10⁵ (centre of mass
    // +0.17 mm), 0.456 J above its lowest at step 120503 (502 s), when the body tips over into a
    // lower pose (178.10 J) and lies still to 4·10⁵ steps. The weighted rule under the same
    // conditions rises less than 1 mJ. Not asserted for it (the creep is bounded by the tip-over, and
    // is what the thesis's weighting removes); everything else is.
    if (c.options.method == Method::particles && c.options.particles.rule == RelaxationRule::unweighted && !sleeping) continue;
    EXPECT_LE(result.largest_rise_at_rest, kHumanoidRise);
  }
}

// The scene as shipped: it falls, and sleeps once it lies still.
TEST(HumanoidSoak, EveryMethodStaysFiniteAndGainsNoEnergy) { soak_humanoid(true); }

// Sleeping off: it lies on the ground awake for the rest of the run, every contact solved every
// step, which is where slow creep would show.
TEST(HumanoidSoak, EveryMethodLyingAwakeStaysFiniteAndGainsNoEnergy) { soak_humanoid(false); }

// --- The long chain at 1/30 s -------------------------------------------------------------------

// tools/scenes/chain.json (pinned, released from horizontal, no ground, links do not meet
// links: no contacts at all) with `links` links, its own relaxation settings (rattle, 16
// substeps × 2 sweeps, over-relaxation 1.5), the solver swapped — what `limber run
// tools/scenes/chain.json --links N --dt 0.0333 --solver S` runs — and, as a long rope would
// use them, long-range attachments. At 1/30 s none of them holds the released 10⁴-link chain
// (2 km) for long: a joint or a link opens past a whole link at step 125 (Gauss-Seidel
// coloured), 146 (sequential), 312 (Jacobi), 141 (direct), 279 (Gauss-Seidel with
// attachments) or 1243 (Jacobi with attachments); at 10³ links Jacobi with attachments holds
// the short form's 400 steps and the others stop at steps 125–321. Each stop must be reported
// and verified bad (the test's second fact), never called ok: before check_divergence read the
// links' stretch, the direct solver and sequential Gauss-Seidel were (divergence.hpp).
std::vector<SoakCase> chain_cases(const Scene& scene) {
  std::vector<SoakCase> cases;
  WorldOptions options = world_options(Method::particles, scene.methods);
  cases.push_back({"Gauss-Seidel coloured", options});
  WorldOptions sequential = options;
  sequential.particles.order = SweepOrder::sequential;
  cases.push_back({"Gauss-Seidel sequential", sequential});
  WorldOptions jacobi = options;
  jacobi.particles.solver = RelaxationSolver::jacobi;
  cases.push_back({"Jacobi", jacobi});
  WorldOptions direct = options;
  direct.particles.solver = RelaxationSolver::direct;  // 2 Newton steps per substep (the default)
  cases.push_back({"direct", direct});
  // What a long rope asks for: long-range attachments (Kim, Chentanez & Müller 2012).
  WorldOptions attached = options;
  attached.particles.long_range_attachments = true;
  cases.push_back({"Gauss-Seidel coloured, long-range attachments", attached});
  jacobi.particles.long_range_attachments = true;
  cases.push_back({"Jacobi, long-range attachments", jacobi});
  return cases;
}

// No contacts: energy may only fall (pbd dissipates; rattle conserves it to O(Δt²) and the
// sweeps left unconverged only take it out), so E ≤ E(0) + 10⁻⁶·M·|g|·L, L the chain's length.
TEST(ChainSoak, EveryVerletSolverAt30HzStaysFiniteAndGainsNoEnergy) {
  SceneOptions options;
  options.links = kChainLinks;
  const Scene scene = load_scene_file(std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/chain.json", options);
  double mass = 0, length = 0;
  for (const Body& body : scene.model.bodies) mass += body.mass, length += body.shape.length;
  const double tolerance = 1e-6 * mass * scene.model.settings.gravity.norm() * length;
  for (const SoakCase& c : chain_cases(scene)) {
    SCOPED_TRACE(c.name);
    World world(scene.model, c.options);
    const SoakResult result = soak(world, 1.0 / 30, kChainSteps, tolerance, 1e300);
    std::printf("chain of %ld, %s: %ld steps ok, then status %d; largest gain %.3g J\n", kChainLinks, c.name.c_str(), result.steps,
                int(result.status), result.largest_gain);
  }
}

}  // namespace
}  // namespace limber
