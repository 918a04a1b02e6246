// The exact joint-tree solve (VerletSettings::joint_solve = JointSolve::tree,
// kernel/relaxation/joint_trees.hpp): a ragdoll's joints and limits close in one solve whatever
// its mass ratios, momentum is kept, and the solve changes no bits between the scalar and SIMD
// paths or one and two threads.
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "limber/kernel/metrics/divergence.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/relaxation/joint_trees.hpp"
#include "limber/kernel/relaxation/relaxation.hpp"
#include "limber/kernel/relaxation/tree_packs.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "limber/kernel/world/world.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

// ragdoll.json's ragdoll in the air (no ground, no stairs, no ball), every limb 1 kg but the
// upper torso, `heavy` kg: the mass ratio across its joints is `heavy`:1.
Model ragdoll(double heavy, bool gravity = false) {
  Model model = testing::load_shipped_scene("ragdoll.json");
  model.colliders.clear();
  model.balls.clear();
  model.ground.reset();
  model.settings.sleep.enabled = false;
  if (!gravity) model.settings.gravity.setZero();
  for (Body& body : model.bodies) {
    body.mass = body.name == "upper_torso" ? heavy : 1.0;
    body.point_masses.clear();
  }
  return model;
}

VerletOptions tree_options() {
  VerletOptions options;
  options.verlet.joint_solve = JointSolve::tree;
  options.relaxation.iterations = 4;
  return options;
}

// Moves every particle by up to `size` m in each coordinate: joints open and limbs bend.
template <typename Scalar>
void shake(VerletState<Scalar>& state, double size, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> offset(-size, size);
  for (std::size_t p = 0; p < state.particles.size(); ++p) {
    if (!(state.particles.inverse_mass[p] > 0)) continue;
    const Eigen::Vector3d moved = state.particles.position(p).template cast<double>() + Eigen::Vector3d(offset(random), offset(random), offset(random));
    state.particles.set_position(p, moved.template cast<Scalar>());
  }
}

template <typename Scalar>
Eigen::Vector3d centre_of_mass(const VerletState<Scalar>& state) {
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  double mass = 0;
  for (std::size_t p = 0; p < state.particles.size(); ++p) {
    const double m = 1.0 / static_cast<double>(state.particles.inverse_mass[p]);
    moment += m * state.particles.position(p).template cast<double>(), mass += m;
  }
  return moment / mass;
}

// Each call takes Newton steps until one moves no particle by 1e-5 m (leaving ~1e-9 m): the
// next call's steps converge quadratically from there, so two calls close the joints to rounding.
TEST(JointTrees, TwoSolvesCloseARagdollsJointsAndLimitsToRoundingWhateverItsMassRatios) {
  for (const double heavy : {1.0, 10.0, 100.0, 1000.0}) {
    SCOPED_TRACE("mass ratio " + std::to_string(heavy) + ":1");
    VerletState<double> state = compile<double>(ragdoll(heavy), tree_options());
    ASSERT_TRUE(state.plan.joint_trees.active());
    state.awake_islands = {0};
    shake(state, 0.01, 7);
    const Observation before = observe(state);
    ASSERT_GT(before.max_joint_gap, 1e-2);  // the shake opened the joints by a tenth of a link or so
    project_joint_trees(state);
    EXPECT_LT(observe(state).max_joint_gap, 1e-6);  // 1e-7 m of a 0.1 m link: one solve is nearly there
    project_joint_trees(state);
    const Observation after = observe(state);
    EXPECT_LT(after.max_joint_gap, 1e-10);
    EXPECT_LT(after.joints.limit_violation, 1e-9);
  }
}

// The profile's tree counts (joint_tree_counts): a shaken ragdoll's first solve takes Newton
// steps until one moves less than 1e-5 m or the cap of 4 is reached (a shake of 1 cm needs at
// least two), each a fresh factor and one back-substitution; the next call one step; a substep
// starts them from zero, and a profiled step counts one solve a sweep. In the air there is no
// contact: no inverse diagonal or path solve.
TEST(JointTrees, TheProfileCountsEachSolveAndItsNewtonSteps) {
  VerletState<double> state = compile<double>(ragdoll(100), tree_options());
  state.awake_islands = {0};
  shake(state, 0.01, 13);
  begin_joint_trees(state, 1.0 / 240);
  project_joint_trees(state);
  const JointTreeCounts first = joint_tree_counts(state);
  EXPECT_EQ(first.solves, 1);
  EXPECT_GE(first.newton_steps, 2);
  EXPECT_LE(first.newton_steps, 4);
  EXPECT_LE(first.capped, 1);
  if (first.capped == 1) {
    EXPECT_EQ(first.newton_steps, 4);  // only a solve at the cap is capped
  }
  EXPECT_EQ(first.factors, first.newton_steps);
  EXPECT_EQ(first.substitutions, first.newton_steps);
  EXPECT_EQ(first.inverse_diagonals + first.path_solves, 0);
  project_joint_trees(state);
  const JointTreeCounts second = joint_tree_counts(state);
  EXPECT_EQ(second.solves, 2);
  EXPECT_EQ(second.newton_steps, first.newton_steps + 1);
  EXPECT_EQ(second.factors, first.factors + 1);
  EXPECT_EQ(second.substitutions, second.newton_steps);
  begin_joint_trees(state, 1.0 / 240);
  EXPECT_EQ(joint_tree_counts(state).newton_steps, 0);

  VerletOptions options = tree_options();
  options.profile = true;
  options.relaxation.substeps = 2;
  VerletState<double> stepped = compile<double>(ragdoll(100, true), options);
  const StepReport report = step(stepped);
  EXPECT_EQ(report.profile.tree_solves, 2 * options.relaxation.iterations);
  EXPECT_GE(report.profile.tree_newton_steps, report.profile.tree_solves);
  EXPECT_GE(report.profile.tree_factors, 1);
  EXPECT_LE(report.profile.tree_factors, report.profile.tree_newton_steps);
  EXPECT_GE(report.profile.tree_substitutions, report.profile.tree_newton_steps);
  // The trees' times are parts of the relax stage (one ragdoll: one thread, whose time is the
  // stage's), each a stage that ran; an unprofiled step reads no clock.
  const StepProfile& profile = report.profile;
  EXPECT_GT(profile.tree_staging, 0);
  EXPECT_GT(profile.tree_elimination, 0);
  EXPECT_GT(profile.tree_moves, 0);
  EXPECT_LT(profile.tree_staging + profile.tree_elimination + profile.tree_moves + profile.tree_contacts, profile.relax);
  VerletState<double> unprofiled = compile<double>(ragdoll(100, true), tree_options());
  step(unprofiled);
  const TreeStageSeconds seconds = joint_tree_counts(unprofiled).seconds;
  EXPECT_EQ(seconds.staging + seconds.elimination + seconds.moves + seconds.contacts, 0);
}

TEST(JointTrees, APositionSolveKeepsTheCentreOfMass) {
  VerletState<double> state = compile<double>(ragdoll(100), tree_options());
  state.awake_islands = {0};
  shake(state, 0.01, 11);
  const Eigen::Vector3d before = centre_of_mass(state);
  ASSERT_GT(project_joint_trees(state), 1e-3);
  EXPECT_LT((centre_of_mass(state) - before).norm(), 1e-12);
}

TEST(JointTrees, AVelocitySolveKeepsLinearAndAngularMomentumAndLeavesTheJointsNoRate) {
  VerletState<double> state = compile<double>(ragdoll(100), tree_options());
  state.awake_islands = {0};
  // Each limb a random rigid motion: v + ω × r on its particles.
  std::mt19937 random(3);
  std::uniform_real_distribution<double> draw(-1, 1);
  const JointTrees& trees = state.plan.joint_trees;
  for (std::size_t limb = 0; limb < trees.limb_particles.size(); ++limb) {
    const Eigen::Vector3d v(draw(random), draw(random), draw(random)), omega(3 * draw(random), 3 * draw(random), 3 * draw(random));
    const Eigen::Vector3d centre = state.particles.position(state.limbs.head[limb]);
    for (const std::uint32_t p : trees.limb_particles[limb]) {
      if (p == state.particles.null_particle()) break;
      state.particles.set_velocity(p, v + omega.cross(state.particles.position(p) - centre));
    }
  }
  const auto momenta = [&] {
    Eigen::Vector3d linear = Eigen::Vector3d::Zero(), angular = Eigen::Vector3d::Zero();
    for (std::size_t p = 0; p < state.particles.size(); ++p) {
      const double m = 1.0 / state.particles.inverse_mass[p];
      linear += m * state.particles.velocity(p), angular += m * state.particles.position(p).cross(state.particles.velocity(p));
    }
    return std::make_pair(linear, angular);
  };
  // Rounding's scale: Σ m|v| and Σ m|x||v|.
  double linear_scale = 0, angular_scale = 0;
  for (std::size_t p = 0; p < state.particles.size(); ++p) {
    const double m = 1.0 / state.particles.inverse_mass[p], speed = state.particles.velocity(p).norm();
    linear_scale += m * speed, angular_scale += m * speed * state.particles.position(p).norm();
  }
  const auto [linear, angular] = momenta();
  ASSERT_GT(project_joint_tree_velocities(state), 0.1);
  const auto [linear_after, angular_after] = momenta();
  EXPECT_LT((linear_after - linear).norm(), 1e-13 * linear_scale);
  EXPECT_LT((angular_after - angular).norm(), 1e-11 * angular_scale);
  // Every zero-length joint's two particles now move alike.
  for (const auto& [c, reference] : state.joint_constraints) {
    const Eigen::Vector3d rate = state.particles.velocity(state.constraints.particle_i[c]) - state.particles.velocity(state.constraints.particle_j[c]);
    EXPECT_LT(rate.norm(), 1e-12) << "constraint " << c;
  }
}

TEST(JointTrees, AFallingRagdollFallsFreelyUnderBothRules) {
  for (const ProjectionRule rule : {ProjectionRule::pbd, ProjectionRule::rattle}) {
    SCOPED_TRACE(rule == ProjectionRule::pbd ? "pbd" : "rattle");
    VerletOptions options = tree_options();
    options.relaxation.projection = rule;
    const Model model = ragdoll(30, true);
    VerletState<double> state = compile<double>(model, options);
    const Eigen::Vector3d start = observe(state).linear_momentum;
    const int steps = 120;
    for (int k = 0; k < steps; ++k) ASSERT_EQ(step(state, model.settings.time_step).status, StepStatus::ok);
    const Observation seen = observe(state);
    double mass = 0;
    for (const Body& body : model.bodies) mass += body.mass;
    const Eigen::Vector3d expected = start + mass * model.settings.gravity * steps * model.settings.time_step;
    EXPECT_LT((seen.linear_momentum - expected).norm(), 1e-3 * expected.norm()) << seen.linear_momentum.transpose() << " vs " << expected.transpose();
    EXPECT_LT(seen.max_joint_gap, 1e-9);
  }
}

// A pile of four ragdolls for the bit tests: two layers falling onto the ground.
Model four_ragdolls() {
  SceneOptions scene;
  scene.copies = 4;
  Model model = testing::load_shipped_scene("ragdoll_pile.json", scene);
  model.settings.sleep.enabled = false;
  return model;
}

template <typename Scalar>
std::vector<Scalar> run_positions(const Model& model, VerletOptions options, int steps) {
  VerletState<Scalar> state = compile<Scalar>(model, options);
  for (int k = 0; k < steps; ++k) step(state, model.settings.time_step);
  std::vector<Scalar> out;
  for (std::size_t p = 0; p < state.particles.size(); ++p) {
    for (int i = 0; i < 3; ++i) out.push_back(state.particles.position(p)[i]);
  }
  return out;
}

TEST(JointTrees, ThePileGivesTheSameBitsScalarAndSimdAndOnOneAndTwoThreads) {
  const Model model = four_ragdolls();
  VerletOptions options = tree_options();
  options.relaxation.substeps = 2;
  ASSERT_TRUE(compile<float>(model, options).plan.joint_trees.active());  // the trees are what is compared
  const std::vector<float> reference = run_positions<float>(model, options, 150);
  VerletOptions scalar = options;
  scalar.simd = false;
  EXPECT_EQ(run_positions<float>(model, scalar, 150), reference);
  VerletOptions threads = options;
  threads.threads = 2;  // each island's trees a task (joint_trees_on_threads)
  threads.parallel_minimum_slots = 1;  // and every colour split, so the second thread works
  ASSERT_TRUE(joint_trees_on_threads(compile<float>(model, threads).plan));
  EXPECT_EQ(run_positions<float>(model, threads, 150), reference);
  // The rattle rule's velocity stage solves the trees on the threads too.
  VerletOptions rattle = options, rattle_threads = threads;
  rattle.relaxation.projection = rattle_threads.relaxation.projection = ProjectionRule::rattle;
  EXPECT_EQ(run_positions<float>(model, rattle_threads, 150), run_positions<float>(model, rattle, 150));
}

// The ragdolls of one skeleton share SIMD lanes (tree_packs.hpp), and each lane's bits are its
// own: eight ragdolls of the pile landing on the stairs and on one another — each with its own
// contacts, active limits and Newton steps — step to the same bits packed as many to a pack as
// the lanes hold as one to a pack, in float with the pbd rule and in double with the rattle
// rule's velocity stage.
template <typename Scalar>
std::vector<Scalar> run_packed(const Model& model, const VerletOptions& options, std::size_t lanes, int steps) {
  VerletState<Scalar> state = compile<Scalar>(model, options);
  build_tree_packs<Scalar>(state.plan.joint_trees, lanes);
  const std::size_t packs = state.plan.joint_trees.packs->template packs<Scalar>().size();
  EXPECT_EQ(packs, lanes == 1 ? 8 : (8 + kTreeLanes<Scalar> - 1) / kTreeLanes<Scalar>);  // eight ragdolls, one shape
  for (int k = 0; k < steps; ++k) step(state, model.settings.time_step);
  std::vector<Scalar> out;
  for (std::size_t p = 0; p < state.particles.size(); ++p) {
    for (int i = 0; i < 3; ++i) out.push_back(state.particles.position(p)[i]), out.push_back(state.particles.velocity(p)[i]);
  }
  return out;
}

TEST(JointTrees, EveryLaneOfAPackGivesTheBitsOfItsRagdollInAPackOfItsOwn) {
  SceneOptions scene;
  scene.copies = 8;
  Model model = testing::load_shipped_scene("ragdoll_pile.json", scene);
  model.settings.sleep.enabled = false;
  VerletOptions options = tree_options();
  options.relaxation.substeps = 2;
  options.relaxation.iterations = 1;
  EXPECT_EQ(run_packed<float>(model, options, kTreeLanes<float>, 200), run_packed<float>(model, options, 1, 200));
  options.relaxation.projection = ProjectionRule::rattle;
  EXPECT_EQ(run_packed<double>(model, options, kTreeLanes<double>, 200), run_packed<double>(model, options, 1, 200));
}

// Substeps × sweeps from 1 × 1 to 16 × 4 on four ragdolls of the pile, trees on, for 1 s (they
// land, and one layer lands on the other): every setting holds — no bound of the World's
// divergence check is passed (a non-finite number, the speed, the energy, a joint gap of a whole
// link) — and ends with its joints closed under kAccuracyJointGap, where the command line would
// flag the run. (The whole pile of 32 holds at every setting from 1 × 1 to 16 × 2 since contacts
// go through the trees: bench/ragdolls.md, "Exact limits and contacts with the trees".)
TEST(JointTrees, EverySubstepsBySweepsSettingHoldsFourRagdollsOfThePile) {
  const Model model = four_ragdolls();
  for (const int substeps : {1, 2, 4, 8, 16}) {
    for (const int sweeps : {1, 2, 4}) {
      SCOPED_TRACE(std::to_string(substeps) + " substeps × " + std::to_string(sweeps) + " sweeps");
      WorldOptions options{.method = Method::particles};
      options.particles = tree_options();
      options.particles.relaxation.substeps = substeps;
      options.particles.relaxation.iterations = sweeps;
      World world(model, options);
      StepStatus status = StepStatus::ok;
      int steps = 0;
      for (; steps < 240 && status == StepStatus::ok; ++steps) status = world.step();
      EXPECT_EQ(status, StepStatus::ok) << "at step " << steps;
      EXPECT_LT(world.observe().max_joint_gap, kAccuracyJointGap);
    }
  }
}

// The deepest overlap now of the state's limbs with the stairs, the ground and one another, m
// (what the command line's summary measures: observers.hpp).
template <typename Scalar>
double deepest_penetration(VerletState<Scalar>& state, const Model& model) {
  std::vector<LimbSegment> segments;
  limb_segments(state, segments);
  return deepest_penetration(model, state.collisions, segments).depth;
}

// The trees push each contact of their limbs with the mobility the whole tree gives it
// (tree_contacts.hpp): four ragdolls of the pile landing on the stairs and on one another stay
// out of the stairs, the ground and each other to within 1 mm at few sweeps (contact rows that
// pushed a limb's own particles let them sink 3.2, 11 and 0.5 cm at 2 × 2, 4 × 1 and 8 × 2),
// and within 1 cm with torsos ten times heavier, 635 kg on 1.6 kg forearms (rows: 12.5, 12.6
// and 9.6 cm).
TEST(JointTrees, TheTreesHoldTheirContactsAtFewSweepsWhateverTheMassRatio) {
  for (const double torso : {1.0, 10.0}) {
    Model model = four_ragdolls();
    for (Body& body : model.bodies) {
      if (body.name.find("upper_torso") != std::string::npos) body.mass *= torso;
    }
    for (const auto& [substeps, sweeps] : {std::pair{2, 2}, std::pair{4, 1}, std::pair{8, 2}}) {
      SCOPED_TRACE("torso × " + std::to_string(torso) + ", " + std::to_string(substeps) + " substeps × " + std::to_string(sweeps) + " sweeps");
      VerletOptions options = tree_options();
      options.relaxation.substeps = substeps, options.relaxation.iterations = sweeps;
      VerletState<double> state = compile<double>(model, options);
      ASSERT_TRUE(state.plan.joint_trees.with_contacts);
      double deepest = 0;
      for (int k = 0; k < 360; ++k) {
        ASSERT_EQ(step(state, model.settings.time_step).status, StepStatus::ok) << "step " << k;
        deepest = std::max(deepest, deepest_penetration(state, model));
      }
      EXPECT_LT(deepest, torso == 1 ? 0.001 : 0.01) << "m";
      EXPECT_LT(observe(state).max_joint_gap, kAccuracyJointGap);
    }
  }
}

TEST(JointTrees, TheSweepsProjectNothingTheTreesHold) {
  // The ragdolls' links, limb centres and joints are all the trees': the work counter of the
  // sweeps (constraint projections) stays at zero while the trees keep the joints.
  const Model model = four_ragdolls();
  VerletState<double> state = compile<double>(model, tree_options());
  for (int k = 0; k < 20; ++k) step(state, model.settings.time_step);
  EXPECT_EQ(state.counters.constraint_projections, 0u);
  EXPECT_LT(observe(state).max_joint_gap, 1e-6);
}

TEST(JointTrees, OptionsItCannotRunWithAreRefusedByName) {
  const Model model = ragdoll(10);
  for (const RelaxationSolver solver : {RelaxationSolver::jacobi, RelaxationSolver::direct}) {
    VerletOptions options = tree_options();
    options.solver = solver;
    try {
      compile<double>(model, options);
      ADD_FAILURE() << "accepted";
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(std::string(error.what()).find("Gauss-Seidel"), std::string::npos) << error.what();
    }
  }
}

}  // namespace
}  // namespace limber
