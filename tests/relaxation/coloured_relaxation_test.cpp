// The coloured relaxation paths: batches hold what they should, every variant (scalar, SIMD,
// threads, layouts) gives the same bits, Jacobi and Gauss-Seidel agree where they must.
#include <cmath>
#include <map>
#include <set>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/sleeping/sleeping.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "limber/layouts/graph/constraint_colouring.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

using testing::load_shipped_scene;
using testing::make_chain;

template <typename Scalar>
class ColouredRelaxation : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(ColouredRelaxation, Scalars);

// A chain of `links` with a heavy end (670× a link: the mass ratio), horizontal, pinned.
// Relaxed by 20 sweeps a step.
Scene heavy_end_chain(std::size_t links) {
  std::vector<double> masses(links, 0.01);
  masses.back() = 6.7;
  Scene scene{make_chain(masses, 0.05, true), {}, {}};
  scene.methods.relaxation.iterations = 20;
  return scene;
}

// Two chains and a Y-shaped tree of capsules: several islands, a particle with three
// constraints (the fork), one pinned chain and one free. Relaxed by 15 sweeps a step.
Scene mixed_scene() {
  Model model = make_chain({1, 2, 1, 3, 1, 2, 5}, 0.1, true);
  Model free_chain = make_chain({1, 1, 1, 1}, 0.1, false, Vector3(0, 1, 1));
  for (Body body : free_chain.bodies) {
    body.name = "free_" + body.name;
    body.linear_velocity = Vector3(0.3, -0.2, 1.0);
    model.bodies.push_back(body);
  }
  for (Joint joint : free_chain.joints) {
    joint.name = "free_" + joint.name;
    joint.inboard += 7, joint.outboard += 7;
    model.joints.push_back(joint);
  }
  // A branch from link_2's tail: two bodies hanging from the same particle as link_3's head.
  Body branch = model.bodies[3];
  branch.name = "branch";
  branch.position += Vector3(0, 0, -0.05);
  model.bodies.push_back(branch);
  model.joints.push_back(spherical_joint("branch_joint", 2, static_cast<int>(model.bodies.size() - 1),
                          Vector3(0, 0, -0.05), Vector3(0, 0, 0.05)));
  Scene scene{model, {}, {}};
  scene.methods.relaxation.iterations = 15;
  return scene;
}

// The worst relative constraint error: link stretch or joint gap.
template <typename Scalar>
double worst_error(const VerletState<Scalar>& state) {
  const Observation observation = observe(state);
  return std::max(observation.max_link_stretch, observation.max_joint_gap);
}

template <typename Scalar>
std::vector<std::uint64_t> trajectory_hashes(const Scene& scene, const VerletOptions& options, int steps) {
  VerletState<Scalar> state = compile<Scalar>(scene.model, testing::with_scene_settings(scene, options));
  std::vector<std::uint64_t> hashes;
  for (int s = 0; s < steps; ++s) {
    EXPECT_EQ(step(state).status, StepStatus::ok);
    hashes.push_back(hash_live_elements(state.particles));
  }
  return hashes;
}

TYPED_TEST(ColouredRelaxation, BatchesHoldEachMovableConstraintOnceAndNeverAPin) {
  const Scene scene = mixed_scene();
  VerletState<TypeParam> state = compile<TypeParam>(scene.model, testing::with_scene_settings(scene));
  step(state);
  const auto& batches = state.plan.batches;
  const auto null_particle = state.particles.null_particle();
  std::multiset<std::pair<std::uint32_t, std::uint32_t>> expected, found;
  for (std::uint32_t c = 0; c < state.constraints.size(); ++c) {
    const auto i = state.constraints.particle_i[c], j = state.constraints.particle_j[c];
    if (state.particles.inverse_mass[i] > 0 || state.particles.inverse_mass[j] > 0) expected.insert({i, j});
  }
  for (std::size_t k = 0; k < batches.colour_count(); ++k) {
    EXPECT_EQ((batches.colour_begin[k + 1] - batches.colour_begin[k]) % batches.kBlockLanes, 0u);
    std::set<std::uint32_t> touched;
    for (std::size_t slot = batches.colour_begin[k]; slot < batches.colour_begin[k + 1]; ++slot) {
      const auto i = static_cast<std::uint32_t>(batches.particle_i[slot]);
      const auto j = static_cast<std::uint32_t>(batches.particle_j[slot]);
      if (i == null_particle && j == null_particle) continue;  // padding
      EXPECT_GT(state.particles.inverse_mass[i], 0) << "a pinned particle in a batch";
      EXPECT_GT(state.particles.inverse_mass[j], 0) << "a pinned particle in a batch";
      EXPECT_TRUE(touched.insert(i).second && touched.insert(j).second) << "colour " << k << " shares a particle";
      found.insert({i, j});
    }
  }
  for (std::size_t slot = batches.overflow_begin(); slot < batches.slot_count(); ++slot) {
    found.insert({static_cast<std::uint32_t>(batches.particle_i[slot]), static_cast<std::uint32_t>(batches.particle_j[slot])});
  }
  EXPECT_EQ(found, expected);
  EXPECT_EQ(state.colour_count, 3u);  // the fork particle has three constraints
}

// `scene` under a projection rule, in two substeps for rattle (its velocity stage runs too).
Scene with_projection(Scene scene, ProjectionRule projection) {
  scene.methods.relaxation.projection = projection;
  if (projection == ProjectionRule::rattle) scene.methods.relaxation.substeps = 2;
  return scene;
}

TYPED_TEST(ColouredRelaxation, ScalarSimdLayoutsAndThreadsGiveTheSameBits) {
  // Every variant of the coloured sweep runs the same arithmetic on the same constraints in the
  // same order within each particle, so each step's positions (and, under rattle, velocities)
  // must match bit for bit. parallel_minimum_slots = 1 splits even these small colours across
  // threads.
  for (const RelaxationSolver solver : {RelaxationSolver::gauss_seidel, RelaxationSolver::jacobi}) {
    for (const auto& [rule, projection] : {std::pair{RelaxationRule::weighted, ProjectionRule::pbd},
                                           std::pair{RelaxationRule::unweighted, ProjectionRule::pbd},
                                           std::pair{RelaxationRule::weighted, ProjectionRule::rattle},
                                           std::pair{RelaxationRule::unweighted, ProjectionRule::rattle}}) {
      for (const Scene& model : {with_projection(mixed_scene(), projection), with_projection(heavy_end_chain(300), projection)}) {
        VerletOptions reference;
        reference.solver = solver, reference.rule = rule, reference.simd = false, reference.threads = 1;
        const auto expected = trajectory_hashes<TypeParam>(model, reference, 60);
        for (const ParticleLayout layout : {ParticleLayout::soa, ParticleLayout::aos, ParticleLayout::aosoa}) {
          for (const Threading threading : {Threading::parallel_for, Threading::workers}) {
            for (const bool simd : {false, true}) {
              VerletOptions options = reference;
              options.layout = layout, options.threading = threading, options.simd = simd;
              options.threads = 2, options.parallel_minimum_slots = 1;
              EXPECT_EQ(trajectory_hashes<TypeParam>(model, options, 60), expected)
                  << "layout " << int(layout) << " threading " << int(threading) << " simd " << simd << " solver "
                  << int(solver) << " rule " << int(rule) << " projection " << int(projection);
            }
          }
        }
      }
    }
  }
}

// An engine's task system for the test: each stage's blocks split in two halves, run backwards on
// two threads of its own.
TaskSystem reversed_two_thread_tasks() {
  TaskSystem system;
  system.enqueue = [](TaskSystem::Work work, std::size_t count, void* work_context, void*) -> void* {
    const auto backwards = [=](std::size_t begin, std::size_t end) {
      for (std::size_t block = end; block-- > begin;) work(block, block + 1, work_context);
    };
    std::thread second(backwards, count / 2, count);
    backwards(0, count / 2);
    second.join();
    return nullptr;
  };
  system.finish = [](void*, void*) {};
  return system;
}

TYPED_TEST(ColouredRelaxation, AnEnginesTaskSystemOrTbbArenaGivesTheSameBits) {
  // Threading::tasks hands each colour to the engine's scheduler: whoever runs the blocks, in
  // whatever order, each step's state must be the bits of the serial sweep.
  tbb::task_arena arena(2);
  for (const RelaxationSolver solver : {RelaxationSolver::gauss_seidel, RelaxationSolver::jacobi}) {
    for (const ProjectionRule projection : {ProjectionRule::pbd, ProjectionRule::rattle}) {
      for (const Scene& model : {with_projection(mixed_scene(), projection), with_projection(heavy_end_chain(300), projection)}) {
        VerletOptions reference;
        reference.solver = solver;
        const auto expected = trajectory_hashes<TypeParam>(model, reference, 40);
        for (const TaskSystem& tasks : {reversed_two_thread_tasks(), tbb_task_system(arena)}) {
          VerletOptions options = reference;
          options.threading = Threading::tasks, options.tasks = tasks, options.threads = 2, options.parallel_minimum_slots = 1;
          EXPECT_EQ(trajectory_hashes<TypeParam>(model, options, 40), expected) << "solver " << int(solver) << " projection " << int(projection);
        }
      }
    }
  }
}

TYPED_TEST(ColouredRelaxation, ParticleOrderingRenumbersButChangesNoBit) {
  // Renumbering particles changes where they are stored, not which constraints meet in which
  // colour or in which order: every particle must end with the same bits under its new index.
  const Model model = load_shipped_scene("humanoid.json");
  const auto final_positions = [&](ParticleOrder ordering, RelaxationSolver solver) {
    VerletOptions options;
    options.ordering = ordering, options.solver = solver;
    VerletState<TypeParam> state = compile<TypeParam>(model, options);
    for (int s = 0; s < 200; ++s) step(state);
    std::map<std::pair<int, std::uint32_t>, Eigen::Matrix<TypeParam, 3, 1>> by_origin;
    for (std::size_t p = 0; p < state.particles.size(); ++p) {
      const ParticleOrigin origin = state.particle_origins[p];
      by_origin[{int(origin.kind), origin.index}] = state.particles.position(p);
    }
    return by_origin;
  };
  for (const RelaxationSolver solver : {RelaxationSolver::gauss_seidel, RelaxationSolver::jacobi}) {
    const auto expected = final_positions(ParticleOrder::breadth_first, solver);
    EXPECT_EQ(final_positions(ParticleOrder::reverse_cuthill_mckee, solver), expected);
    EXPECT_EQ(final_positions(ParticleOrder::depth_parity, solver), expected);
    EXPECT_EQ(final_positions(ParticleOrder::shuffled, solver), expected);
  }
}

TYPED_TEST(ColouredRelaxation, HumanoidWithContactsIsTheSameInEveryLayout) {
  // The ball and ground contacts move particles between sweeps; the interleaved layouts copy
  // exactly those particles out and back.
  for (const ProjectionRule projection : {ProjectionRule::pbd, ProjectionRule::rattle}) {
    const Scene model = with_projection(testing::shipped_scene("humanoid.json"), projection);
    VerletOptions reference;
    reference.threads = 1;
    const auto expected = trajectory_hashes<TypeParam>(model, reference, 150);
    for (const ParticleLayout layout : {ParticleLayout::aos, ParticleLayout::aosoa}) {
      VerletOptions options = reference;
      options.layout = layout, options.threads = 2, options.parallel_minimum_slots = 1;
      EXPECT_EQ(trajectory_hashes<TypeParam>(model, options, 150), expected) << "layout " << int(layout) << " projection " << int(projection);
    }
  }
}

TYPED_TEST(ColouredRelaxation, JacobiAndGaussSeidelSettleOnTheSameHangingChain) {
  // A heavy-end chain hanging straight down from its pin, released at rest: the static solution
  // is the straight chain at rest length. Both solvers must find it; Jacobi needs more sweeps.
  Model model = make_chain({1, 1, 1, 1, 1, 1, 1, 5}, 0.1, true);
  for (Body& body : model.bodies) {
    const double depth = body.position.x();
    body.position = Vector3(0, 0, 1 - depth);
    body.axis = Vector3::UnitZ();
  }
  for (Joint& joint : model.joints) {
    if (joint.inboard == kWorld) joint.inboard_anchor = Vector3(0, 0, 1);
  }
  model.settings.damping = 5;
  // Relax each step until the largest correction is negligible, so that both reach the static
  // solution, not just their own per-step balance with gravity.
  std::vector<Vector3> settled[2];
  for (const RelaxationSolver solver : {RelaxationSolver::gauss_seidel, RelaxationSolver::jacobi}) {
    VerletOptions options;
    options.relaxation.iterations = 20000;
    options.relaxation.tolerance = std::is_same_v<TypeParam, float> ? 1e-7 : 1e-12;
    options.solver = solver;
    VerletState<TypeParam> state = compile<TypeParam>(model, options);
    for (int s = 0; s < 300; ++s) ASSERT_EQ(step(state).status, StepStatus::ok);
    for (std::size_t p = 0; p < state.particles.size(); ++p) {
      settled[int(solver)].push_back(state.particles.position(p).template cast<double>());
    }
    EXPECT_LT(worst_error(state), (std::is_same_v<TypeParam, float> ? 1e-4 : 1e-7));
  }
  const double tolerance = std::is_same_v<TypeParam, float> ? 1e-4 : 1e-7;
  for (std::size_t p = 0; p < settled[0].size(); ++p) {
    EXPECT_LT((settled[0][p] - settled[1][p]).norm(), tolerance) << "particle " << p;
    EXPECT_NEAR(settled[0][p].x(), 0, tolerance);  // hangs straight
  }
}

TYPED_TEST(ColouredRelaxation, GaussSeidelConvergesFasterThanJacobiPerSweep) {
  // The convergence difference the README plots: after the same sweeps, Jacobi leaves more stretch.
  const Scene chain = heavy_end_chain(100);
  double stretch[2];
  for (const RelaxationSolver solver : {RelaxationSolver::gauss_seidel, RelaxationSolver::jacobi}) {
    VerletOptions options = testing::with_scene_settings(chain);
    options.solver = solver;
    VerletState<TypeParam> state = compile<TypeParam>(chain.model, options);
    for (int s = 0; s < 120; ++s) step(state);
    stretch[int(solver)] = worst_error(state);
  }
  EXPECT_LT(stretch[0], stretch[1]);
}

TYPED_TEST(ColouredRelaxation, SleepingIslandLeavesTheBatchesWithoutRecolouring) {
  Scene scene = mixed_scene();
  scene.model.settings.sleep.enabled = true;
  VerletState<TypeParam> state = compile<TypeParam>(scene.model, testing::with_scene_settings(scene));
  const std::vector<std::uint8_t> colours = state.constraint_colour;
  step(state);
  const std::size_t all_slots = state.plan.batches.slot_count();
  state.islands[0].sleeping = true;  // the pinned chain with its branch
  rebuild_awake_islands(state);
  step(state);
  EXPECT_LT(state.plan.batches.slot_count(), all_slots);
  const Island& asleep = state.islands[0];
  for (std::size_t slot = 0; slot < state.plan.batches.slot_count(); ++slot) {
    const auto i = static_cast<std::uint32_t>(state.plan.batches.particle_i[slot]);
    EXPECT_FALSE(i >= asleep.particle_begin && i < asleep.particle_end) << "a sleeping particle in a batch";
  }
  EXPECT_EQ(state.constraint_colour, colours);
}

TEST(ColouredRelaxationOptions, IncompatibleOptionsAreRejected) {
  const Model model = make_chain({1, 1}, 0.1, true);
  VerletOptions options;
  options.order = SweepOrder::sequential, options.layout = ParticleLayout::aos;
  EXPECT_THROW(compile<float>(model, options), std::invalid_argument);
  options.layout = ParticleLayout::soa, options.solver = RelaxationSolver::jacobi;
  EXPECT_THROW(compile<float>(model, options), std::invalid_argument);
  options = {};
  options.threads = -1;
  EXPECT_THROW(compile<float>(model, options), std::invalid_argument);
  options = {};
  options.max_colours = 0;
  EXPECT_THROW(compile<float>(model, options), std::invalid_argument);
}

}  // namespace
}  // namespace limber
