// The direct solver (RelaxationSolver::direct): Newton steps of an exact global projection of the
// distance constraints, solved by tree elimination. Converged, it satisfies every constraint to
// rounding; it is the mass-weighted projection Gauss-Seidel converges to (to first order); it
// keeps momentum; compliance obeys Hooke's law; loops converge; options are checked.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/relaxation/relaxation.hpp"
#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"

namespace limber {
namespace {

template <typename Scalar>
class DirectProjection : public ::testing::Test {
 protected:
  static constexpr bool kFloat = std::is_same_v<Scalar, float>;
};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(DirectProjection, Scalars);

constexpr double kLinkLength = 0.1;

// The direct solver; the generated models' joints as one particle each unless `joints` says not.
VerletOptions direct_options(int newton_iterations = 2, ParticleJoints joints = ParticleJoints::shared_particle) {
  VerletOptions options;
  options.verlet.joints = joints;
  options.solver = RelaxationSolver::direct;
  options.newton_iterations = newton_iterations;
  options.warm_start = false;  // set explicitly: the default may change
  return options;
}

// The largest constraint error over all constraints, m, computed from the particles directly:
// |x_i − x_j| for a zero-length joint, ||x_i − x_j| − d| for a link.
template <typename Scalar>
double largest_constraint_error(const VerletState<Scalar>& state) {
  double largest = 0;
  for (std::size_t c = 0; c < state.constraints.size(); ++c) {
    const Eigen::Vector3d x_i = state.particles.position(state.constraints.particle_i[c]).template cast<double>();
    const Eigen::Vector3d x_j = state.particles.position(state.constraints.particle_j[c]).template cast<double>();
    const double rest = state.constraints.rest_length[c];
    largest = std::max(largest, std::abs((x_i - x_j).norm() - rest));
  }
  return largest;
}

// Moves every movable particle by amplitude · u, u uniform in [−1, 1]³ drawn from `seed` (the
// same u for the same seed, so amplitudes can be compared). Pinned particles stay.
template <typename Scalar>
void perturb(VerletState<Scalar>& state, double amplitude, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(-1, 1);
  for (std::size_t p = 0; p < state.particles.size(); ++p) {
    const Eigen::Vector3d u(unit(random), unit(random), unit(random));
    if (state.particles.inverse_mass[p] == Scalar(0)) continue;
    state.particles.set_position(p, (state.particles.position(p).template cast<double>() + amplitude * u).template cast<Scalar>());
  }
}

// One step's projection alone, without integration: `sweeps` Newton steps of the direct solver
// (or sweeps of whichever solver the options chose).
template <typename Scalar>
void project(VerletState<Scalar>& state, int sweeps) {
  begin_relaxation(state, state.settings.time_step);
  for (int k = 0; k < sweeps; ++k) relaxation_sweep(state, 1.0);
  end_relaxation(state);
}

template <typename Scalar>
std::vector<Eigen::Vector3d> positions(const VerletState<Scalar>& state) {
  std::vector<Eigen::Vector3d> out;
  for (std::size_t p = 0; p < state.particles.size(); ++p) out.push_back(state.particles.position(p).template cast<double>());
  return out;
}

// Random trees: sizes and branchings from a chain to a wide hub, link masses from 0.2 to 5 kg,
// pinned and free, both joint kinds.
std::vector<std::pair<Model, ParticleJoints>> random_trees() {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> mass(0.2, 5.0);
  std::vector<std::pair<Model, ParticleJoints>> trees;
  for (const ParticleJoints joints : {ParticleJoints::shared_particle, ParticleJoints::zero_length_constraint}) {
    for (const std::size_t links : {1, 2, 7, 20, 60}) {
      for (const std::size_t branching : {1, 2, 3, 6}) {
        TreeSpec spec;
        spec.links = links, spec.branching = branching, spec.link_length = kLinkLength;
        spec.pinned = (links + branching) % 2 == 0 || links == 60;
        Model model = make_tree_model(spec);
        for (Body& body : model.bodies) body.mass = mass(random);
        trees.emplace_back(model, joints);
      }
    }
  }
  return trees;
}

TYPED_TEST(DirectProjection, ConvergedProjectionSatisfiesEveryConstraintOnRandomTrees) {
  // Each Newton step solves the linearized system exactly, so from a few-percent perturbation
  // the error falls quadratically to rounding: no sweep count to tune, whatever the tree's size.
  const double tolerance = (this->kFloat ? 1e-5 : 1e-12) * kLinkLength;
  int most_steps = 0;
  unsigned seed = 1;
  for (const auto& [model, joints] : random_trees()) {
    VerletState<TypeParam> state = compile<TypeParam>(model, direct_options(2, joints));
    perturb(state, 0.03 * kLinkLength, seed++);
    ASSERT_GT(largest_constraint_error(state), 1e-3 * kLinkLength) << "the perturbation must violate the constraints";
    int steps = 0;
    begin_relaxation(state, model.settings.time_step);
    while (largest_constraint_error(state) > tolerance && steps < 30) relaxation_sweep(state, 1.0), ++steps;
    end_relaxation(state);
    EXPECT_LE(largest_constraint_error(state), tolerance) << model.bodies.size() << " links, seed " << seed - 1;
    most_steps = std::max(most_steps, steps);
  }
  // Quadratic convergence: 3 % → 1e-3 → 1e-6 → 1e-12 relative, a handful of steps.
  // A linearly convergent solver (Gauss-Seidel) needs far more sweeps on the larger trees.
  EXPECT_LE(most_steps, 8);
}

TEST(DirectProjectionAgreement, TheConstraintSpaceSolveFollowsTheParticleBlocks) {
  // The trees are solved in constraint space; the same trees through the particle blocks
  // (in_constraint_space cleared) are the same projection, so 50 steps of a falling, swinging
  // tree end at the same positions to rounding (1e-9 m; the two orders of operations differ in
  // the last bits, and a chaotic branching tree could amplify that over many more steps).
  int compared = 0;
  for (const auto& [model, joints] : random_trees()) {
    VerletState<double> fast = compile<double>(model, direct_options(3, joints));
    VerletState<double> blocks = compile<double>(model, direct_options(3, joints));
    bool any = false;
    for (std::uint8_t& flag : blocks.plan.direct.in_constraint_space) any = any || flag, flag = 0;
    compared += any ? 1 : 0;
    for (int k = 0; k < 50; ++k) step(fast), step(blocks);
    const auto a = positions(fast), b = positions(blocks);
    for (std::size_t p = 0; p < a.size(); ++p) EXPECT_LE((a[p] - b[p]).norm(), 1e-9) << model.bodies.size() << " links, particle " << p;
  }
  // Every tree: the busiest particle, a hub's, carries its link and six joints (19 rows, the
  // limit), or seven links.
  EXPECT_EQ(compared, 40);
}

TEST(DirectProjectionAgreement, AKeptFactorGivesTheBitsOfAFreshOne) {
  // Under rattle a rigid chain's factor passes from the velocity stage to the next step's Newton
  // steps (the same positions' gradients). Forgetting it before every step (a compliance of NaN
  // matches nothing) must change no bit: a factor is kept only for the same inputs.
  ChainSpec spec;
  spec.links = 40, spec.link_length = kLinkLength, spec.end_mass_ratio = 20;
  Model model = make_chain_model(spec);
  model.settings.sleep.enabled = false;
  VerletOptions options = direct_options(3);
  options.relaxation.projection = ProjectionRule::rattle;
  VerletState<double> kept = compile<double>(model, options), fresh = compile<double>(model, options);
  ASSERT_TRUE(kept.plan.direct.in_constraint_space.at(0));
  for (int k = 0; k < 100; ++k) {
    step(kept);
    for (double& alpha : fresh.plan.direct.factored_compliance) alpha = std::numeric_limits<double>::quiet_NaN();
    step(fresh);
  }
  const auto a = positions(kept), b = positions(fresh);
  for (std::size_t p = 0; p < a.size(); ++p) {
    for (int i = 0; i < 3; ++i) EXPECT_EQ(a[p][i], b[p][i]) << "particle " << p;
  }
}

TEST(DirectProjectionAgreement, GaussSeidelReachesTheSamePointToSecondOrder) {
  // Converged, both solvers land on the constraint manifold. Linearized, both are the
  // mass-weighted (M-metric) projection of the start onto it: Newton's step is W·Jᵀ(J W Jᵀ)⁻¹C,
  // and sequential weighted projections (Kaczmarz in the M-metric) converge to the M-closest
  // point of an affine set. The constraints are not linear, so the two maps may differ, but only
  // by O(ε²) for a perturbation of size ε: halving ε must quarter the difference (first order
  // would only halve it).
  for (const ParticleJoints joints : {ParticleJoints::shared_particle, ParticleJoints::zero_length_constraint}) {
    for (const std::size_t links : {3, 6}) {
      TreeSpec spec;
      spec.links = links, spec.branching = 2, spec.link_length = kLinkLength;
      Model model = make_tree_model(spec);
      for (std::size_t k = 0; k < model.bodies.size(); ++k) model.bodies[k].mass = 0.5 + double(k % 3);
      VerletOptions gauss_seidel;
      gauss_seidel.solver = RelaxationSolver::gauss_seidel;
      gauss_seidel.order = SweepOrder::sequential;
      gauss_seidel.rule = RelaxationRule::weighted;
      gauss_seidel.verlet.joints = joints;
      std::vector<double> difference, displacement;
      for (const double epsilon : {0.04, 0.02, 0.01, 0.005}) {
        VerletState<double> direct = compile<double>(model, direct_options(2, joints));
        VerletState<double> sequential = compile<double>(model, gauss_seidel);
        perturb(direct, epsilon * kLinkLength, 5);
        perturb(sequential, epsilon * kLinkLength, 5);
        const auto start = positions(direct);
        project(direct, 20);
        project(sequential, 5000);
        ASSERT_LT(largest_constraint_error(direct), 1e-13) << "direct did not converge";
        ASSERT_LT(largest_constraint_error(sequential), 1e-13) << "Gauss-Seidel did not converge";
        double largest = 0, moved = 0;
        for (std::size_t p = 0; p < start.size(); ++p) {
          largest = std::max(largest, (direct.particles.position(p) - sequential.particles.position(p)).norm());
          moved = std::max(moved, (direct.particles.position(p) - start[p]).norm());
        }
        difference.push_back(largest), displacement.push_back(moved);
      }
      for (std::size_t k = 0; k + 1 < difference.size(); ++k) {
        EXPECT_GT(difference[k] / difference[k + 1], 3.0) << "ε halved " << k + 1 << " times; " << links << " links";
        EXPECT_LT(difference[k + 1], 0.1 * displacement[k + 1]) << "the two must agree to first order";
      }
    }
  }
}

// Σ m_i x_i, kg·m, of a state without pinned particles (m_i = 1/w_i).
template <typename Scalar>
Eigen::Vector3d weighted_sum(const VerletState<Scalar>& state, const std::vector<Eigen::Vector3d>& x) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t p = 0; p < x.size(); ++p) sum += x[p] / double(state.particles.inverse_mass[p]);
  return sum;
}

TYPED_TEST(DirectProjection, WeightedProjectionOfAFreeTreeKeepsItsMomentum) {
  // Δx = W·Jᵀ·Δλ, so Σ m_i Δx_i = Σ (Jᵀ Δλ)_i = 0: every row of a distance constraint or joint
  // pushes its two particles equally and oppositely. Verlet's momentum Σ m (x − x*)/Δt changes
  // by Σ m Δx / Δt, so the projection keeps it — after one Newton step and after convergence.
  // With unequal masses the unweighted rule (w = 1 for every particle) does not.
  const double tolerance = this->kFloat ? 1e-5 : 1e-12;
  for (const ParticleJoints joints : {ParticleJoints::shared_particle, ParticleJoints::zero_length_constraint}) {
    TreeSpec spec;
    spec.links = 15, spec.branching = 3, spec.link_length = kLinkLength, spec.pinned = false;
    Model model = make_tree_model(spec);
    std::mt19937 random(4);
    std::uniform_real_distribution<double> mass(0.2, 5.0);
    for (Body& body : model.bodies) body.mass = mass(random);
    for (const RelaxationRule rule : {RelaxationRule::weighted, RelaxationRule::unweighted}) {
      for (const int newton_steps : {1, 10}) {
        VerletOptions options = direct_options(2, joints);
        options.rule = rule;
        VerletState<TypeParam> state = compile<TypeParam>(model, options);
        perturb(state, 0.05 * kLinkLength, 9);
        const auto before = positions(state);
        project(state, newton_steps);
        const auto after = positions(state);
        double moved = 0;  // Σ m |Δx|, the scale the sum is measured against
        for (std::size_t p = 0; p < before.size(); ++p) moved += (after[p] - before[p]).norm() / double(state.particles.inverse_mass[p]);
        const double change = (weighted_sum(state, after) - weighted_sum(state, before)).norm() / moved;
        if (rule == RelaxationRule::weighted) {
          EXPECT_LT(change, tolerance) << "Newton steps " << newton_steps;
        } else {
          EXPECT_GT(change, 1e-3) << "unequal masses: the unweighted rule must move the centre of mass";
        }
      }
    }
  }
}

TYPED_TEST(DirectProjection, SpinningFreeTreeConservesMomentumOverManySteps) {
  // No gravity, no pin, no contact: only the projections act, and each keeps the momentum, with
  // or without the warm start (its impulse W·Jᵀ·λ is one more such projection).
  TreeSpec spec;
  spec.links = 13, spec.branching = 3, spec.link_length = kLinkLength, spec.pinned = false;
  Model model = make_tree_model(spec);
  model.settings.gravity.setZero();
  std::mt19937 random(8);
  std::uniform_real_distribution<double> mass(0.2, 5.0);
  for (Body& body : model.bodies) body.mass = mass(random);
  const Vector3 spin(3, 17, -5);  // rad/s about the root link's centre: links swing through large angles
  const Vector3 drift(0.2, -0.1, 0.3);
  const Vector3 centre = model.bodies.front().position;
  for (Body& body : model.bodies) {
    body.angular_velocity = spin;
    body.linear_velocity = drift + spin.cross(body.position - centre);
  }
  for (const bool warm_start : {false, true}) {
    VerletOptions options = direct_options(3, ParticleJoints::zero_length_constraint);
    options.warm_start = warm_start;
    VerletState<TypeParam> state = compile<TypeParam>(model, options);
    step(state);  // turns the initial velocities into ones the constraints allow
    const Eigen::Vector3d p0 = observe(state).linear_momentum;
    double drift_seen = 0;
    for (int s = 0; s < 300; ++s) {
      ASSERT_EQ(step(state).status, StepStatus::ok);
      drift_seen = std::max(drift_seen, (observe(state).linear_momentum - p0).norm());
    }
    // Double: rounding. Float: Verlet's velocity is a difference of positions, each rounded to
    // ulp(x) ≈ 6e-8 m at 0.5 m, i.e. m·ulp/Δt ≈ 1e-4 kg·m/s a particle and step at random.
    EXPECT_LT(drift_seen, (this->kFloat ? 1e-3 : 1e-10) * p0.norm()) << "warm start " << warm_start;
  }
}

// A chain of `masses.size()` links hanging straight down from a pin at the origin, at rest.
Model hanging_chain(const std::vector<double>& masses) {
  ChainSpec spec;
  spec.links = masses.size(), spec.link_length = kLinkLength, spec.direction = Vector3(0, 0, -1);
  Model model = make_chain_model(spec);
  for (std::size_t k = 0; k < masses.size(); ++k) model.bodies[k].mass = masses[k];
  return model;
}

TYPED_TEST(DirectProjection, CompliantLinksStretchByComplianceTimesTheWeightTheyCarry) {
  // XPBD's converged step solves M(x − x̃) = ∇Cᵀλ, C + (α/Δt²)λ = 0. At rest x̃ = x + g·Δt², so λ
  // is the weight below a link times Δt², and its stretch C = α·(weight): Hooke's law, whatever
  // Δt. With the limb mass at its ends (LimbMasses::ends), link k carries its own lower half and
  // every link below it.
  const std::vector<double> masses{1.0, 2.0, 0.5};
  const double alpha = 2e-5, g = 9.81;  // m/N: stretches of ~1 % of a link
  // The same under the rattle rule, whose positions the same equations give (its velocity
  // stage leaves compliant constraints alone).
  Model model = hanging_chain(masses);
  model.settings.damping = 20;  // settle the bounce in well under the 2 s run
  for (const auto& [warm_start, projection] : {std::pair{false, ProjectionRule::pbd}, std::pair{true, ProjectionRule::pbd},
                                               std::pair{false, ProjectionRule::rattle}}) {
    for (const double compliance : {alpha, 0.0}) {
      VerletOptions options = direct_options(6);
      options.relaxation.projection = projection;
      options.compliance = compliance, options.warm_start = warm_start;
      VerletState<TypeParam> state = compile<TypeParam>(model, options);
      for (int s = 0; s < 480; ++s) ASSERT_EQ(step(state).status, StepStatus::ok);
      for (std::size_t k = 0; k < masses.size(); ++k) {
        const std::uint32_t c = state.limbs.link_constraint[k];
        const double length = (state.particles.position(state.constraints.particle_i[c]) -
                               state.particles.position(state.constraints.particle_j[c])).template cast<double>().norm();
        double carried = 0.5 * masses[k];
        for (std::size_t j = k + 1; j < masses.size(); ++j) carried += masses[j];
        const double expected = compliance * carried * g;
        if (compliance > 0) {
          // Double: to rounding, once the bounce has died out. Float resolves positions near
          // 0.3 m only to ulp ≈ 3e-8 m, a part in 10³ of the lowest link's 5e-5 m stretch.
          const double tolerance = this->kFloat ? 1e-6 * kLinkLength : 1e-8 * expected;
          EXPECT_NEAR(length - kLinkLength, expected, tolerance) << "link " << k << " warm " << warm_start << " projection " << int(projection);
        } else {
          EXPECT_NEAR(length, kLinkLength, (this->kFloat ? 1e-6 : 1e-12) * kLinkLength) << "rigid link " << k;
        }
      }
    }
  }
}

TEST(DirectProjectionOptions, ComplianceNeedsTheDirectSolver) {
  const Model model = hanging_chain({1.0, 1.0});
  for (const RelaxationSolver solver : {RelaxationSolver::gauss_seidel, RelaxationSolver::jacobi}) {
    VerletOptions options;
    options.solver = solver, options.compliance = 1e-4;
    EXPECT_THROW(compile<double>(model, options), std::invalid_argument) << "solver " << int(solver);
  }
  VerletOptions options = direct_options();
  options.compliance = 1e-4;
  EXPECT_NO_THROW(compile<double>(model, options));
}

TYPED_TEST(DirectProjection, GridLoopsConvergeAsNewtonStepsGrow) {
  // A grid's constraints close loops: the tree part is solved exactly each Newton step, the
  // loop-closing constraints by a Gauss-Seidel pass after it, so the whole converges like a
  // block Gauss-Seidel — not in one step, but more steps must leave less error.
  GridSpec spec;
  spec.columns = 6, spec.rows = 6, spec.spacing = kLinkLength;
  Model model = make_grid_model(spec);
  // Hung from one corner: pinned at both top corners, the top row is a string pulled straight
  // between pins exactly its length apart — a degenerate configuration (its rows' gradients are
  // dependent), where no solver converges (Gauss-Seidel stalls as well) and gravity cannot be held.
  std::erase_if(model.joints, [](const Joint& joint) { return joint.name == "pin_top_right"; });
  std::vector<double> errors;
  for (const int newton_steps : {1, 4, 16, 64, 256}) {
    VerletState<TypeParam> state = compile<TypeParam>(model, direct_options());
    ASSERT_FALSE(state.plan.direct.island_loop_constraints.row(0).empty()) << "a grid must have loops";
    perturb(state, 0.03 * kLinkLength, 3);
    project(state, newton_steps);
    errors.push_back(largest_constraint_error(state));
  }
  // Until rounding: float's positions near 0.5 m resolve ~3e-8 m.
  const double rounding = (this->kFloat ? 1e-6 : 1e-14) * kLinkLength;
  for (std::size_t k = 0; k + 1 < errors.size(); ++k) EXPECT_LT(errors[k + 1], std::max(errors[k], rounding)) << "run " << k + 1;
  EXPECT_LT(errors.back(), (this->kFloat ? 1e-5 : 1e-12) * kLinkLength);

  // Simulated: the sheet swings down from its corner and stays finite and closed.
  VerletState<TypeParam> state = compile<TypeParam>(model, direct_options(8));
  double worst = 0;
  for (int s = 0; s < 240; ++s) {
    ASSERT_EQ(step(state).status, StepStatus::ok) << "step " << s;
    for (std::size_t p = 0; p < state.particles.size(); ++p) ASSERT_TRUE(state.particles.position(p).allFinite());
    worst = std::max(worst, largest_constraint_error(state));
  }
  // Loop closures converge linearly: 8 steps a step leave errors of ~1 % while the sheet swings.
  EXPECT_LT(worst, 0.02 * kLinkLength);
}

// Per particle, the rest length of the constraint path to the pinned particle of its island
// (a chain: one path), found breadth first; infinity where no pin is reached.
template <typename Scalar>
std::vector<double> path_rest_lengths(const VerletState<Scalar>& state, std::uint32_t& pin) {
  std::vector<double> length(state.particles.size(), std::numeric_limits<double>::infinity());
  for (std::uint32_t p = 0; p < state.particles.size(); ++p) {
    if (state.particles.inverse_mass[p] == Scalar(0)) length[p] = 0, pin = p;
  }
  for (bool changed = true; changed;) {  // Bellman-Ford: a chain of tens of constraints
    changed = false;
    for (std::size_t c = 0; c < state.constraints.size(); ++c) {
      const std::uint32_t i = state.constraints.particle_i[c], j = state.constraints.particle_j[c];
      const double d = state.constraints.rest_length[c];
      if (length[i] + d < length[j]) length[j] = length[i] + d, changed = true;
      if (length[j] + d < length[i]) length[i] = length[j] + d, changed = true;
    }
  }
  return length;
}

TYPED_TEST(DirectProjection, LongRangeAttachmentsKeepAChainWithinItsLength) {
  // Two Gauss-Seidel sweeps a step at 60 Hz cannot hold a 20-link chain released horizontally:
  // it stretches, the end falling past the length of the chain. The attachments (Kim et al.
  // 2012) put every particle back within the rest length of its path from the pin after each
  // sweep, so none is ever farther — a tether, which allows a slack chain but not a long one.
  ChainSpec spec;
  spec.links = 20, spec.link_length = kLinkLength, spec.direction = Vector3(1, 0, 0);
  Model model = make_chain_model(spec);
  model.settings.time_step = 1.0 / 60;
  for (const ProjectionRule projection : {ProjectionRule::pbd, ProjectionRule::rattle}) {
  double overshoot[2] = {0, 0};
  for (const bool attachments : {false, true}) {
    VerletOptions options;
    options.verlet.joints = ParticleJoints::shared_particle;
    options.relaxation.iterations = 2;
    options.relaxation.projection = projection;
    options.solver = RelaxationSolver::gauss_seidel;
    options.long_range_attachments = attachments;
    VerletState<TypeParam> state = compile<TypeParam>(model, options);
    std::uint32_t pin = 0;
    const std::vector<double> allowed = path_rest_lengths(state, pin);
    for (int s = 0; s < 120; ++s) {
      ASSERT_EQ(step(state).status, StepStatus::ok);
      for (std::size_t p = 0; p < state.particles.size(); ++p) {
        if (p == pin) continue;
        const double distance = (state.particles.position(p) - state.particles.position(pin)).template cast<double>().norm();
        overshoot[attachments] = std::max(overshoot[attachments], (distance - allowed[p]) / allowed[p]);
      }
    }
  }
  EXPECT_GT(overshoot[false], 0.01) << "without attachments the stretched chain must overshoot its length";
  EXPECT_LE(overshoot[true], this->kFloat ? 1e-6 : 1e-14) << "projection " << int(projection);
  }
}

TEST(DirectProjectionOptions, BadNewtonIterationsAndComplianceAreRejectedByName) {
  const Model model = hanging_chain({1.0, 1.0});
  const auto message = [&](const VerletOptions& options) -> std::string {
    try {
      compile<double>(model, options);
    } catch (const std::invalid_argument& error) {
      return error.what();
    }
    return "no exception";
  };
  for (const int iterations : {0, -3}) {
    VerletOptions options = direct_options(iterations);
    EXPECT_THAT(message(options), ::testing::HasSubstr("newton_iterations")) << iterations;
  }
  for (const double compliance : {-1e-4, std::nan("")}) {
    VerletOptions options = direct_options();
    options.compliance = compliance;
    EXPECT_THAT(message(options), ::testing::HasSubstr("compliance")) << compliance;
  }
}

}  // namespace
}  // namespace limber
