// step() allocates nothing after its first call: the Verlet method's (every solver), the explicit
// spring method's and the Lagrange tree solve's. (The implicit springs and Lagrange's sparse path
// allocate inside Eigen's sparse factorization, kernel/springs/step.hpp.) Counted by
// tests/support/allocation_counter.cpp, which replaces this program's allocation functions.
#include <algorithm>
#include <cstdint>
#include <new>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/lagrange/compile.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "limber/kernel/springs/compile.hpp"
#include "limber/kernel/springs/step.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"
#include "limber/kernel/world/world.hpp"
#include "tests/support/allocation_counter.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

template <typename Scalar>
long allocations_while_stepping(const Model& model, int steps, bool push, const VerletOptions& options = {}) {
  auto state = compile<Scalar>(model, options);
  step(state);  // the first call may allocate
  const long before = testing::allocation_count();
  for (int s = 0; s < steps; ++s) {
    if (push && s % 50 == 0) apply_force(state, 0, Eigen::Vector3d(0, 5, 0));
    step(state);
  }
  return testing::allocation_count() - before;
}

TEST(Allocation, StepAllocatesNothingAfterItsFirstCall) {
  // The humanoid wakes, hits the ground and falls asleep again; the box bounces a stick; the
  // chain takes applied forces.
  const Model humanoid = testing::load_shipped_scene("humanoid.json");
  const Scene box = testing::shipped_scene("stick_in_box.json");
  Scene chain = testing::shipped_scene("chain.json");
  chain.model.settings.damping = 3;
  chain.model.settings.sleep = {true, false, 0.01, 0.2};  // sleeps, then the pushes wake it
  EXPECT_EQ(allocations_while_stepping<float>(humanoid, 1200, false), 0);
  EXPECT_EQ(allocations_while_stepping<double>(humanoid, 1200, false), 0);
  EXPECT_EQ(allocations_while_stepping<double>(box.model, 1200, false, testing::with_scene_settings(box)), 0);
  EXPECT_EQ(allocations_while_stepping<double>(chain.model, 1200, true, testing::with_scene_settings(chain)), 0);
}

TEST(Allocation, JointRowsAllocateNothing) {
  // The armed ragdoll: frames, hinges, cone-twists and friction rows, batches rebuilt as it
  // wakes on impact and falls asleep; the active ragdoll's drives, released on impact.
  const Scene ragdoll = testing::shipped_scene("ragdoll.json");
  EXPECT_EQ(allocations_while_stepping<float>(ragdoll.model, 1200, false, testing::with_scene_settings(ragdoll)), 0);
  EXPECT_EQ(allocations_while_stepping<double>(ragdoll.model, 1200, false, testing::with_scene_settings(ragdoll)), 0);
  VerletOptions rattle = testing::with_scene_settings(ragdoll);
  rattle.relaxation.projection = ProjectionRule::rattle, rattle.relaxation.substeps = 2, rattle.threads = 2;
  rattle.parallel_minimum_slots = 1;
  EXPECT_EQ(allocations_while_stepping<double>(ragdoll.model, 600, false, rattle), 0);
  // Joint trees (joint_trees.hpp), both rules: factors, active sets and Newton steps.
  VerletOptions trees = testing::with_scene_settings(ragdoll);
  trees.verlet.joint_solve = JointSolve::tree, trees.relaxation.substeps = 2;
  EXPECT_EQ(allocations_while_stepping<float>(ragdoll.model, 600, false, trees), 0);
  trees.relaxation.projection = ProjectionRule::rattle;
  EXPECT_EQ(allocations_while_stepping<double>(ragdoll.model, 600, false, trees), 0);
  const Scene active = testing::shipped_scene("active_ragdoll.json");
  World world(active.model, world_options(Method::particles, active.methods));
  world.step();
  const long before = testing::allocation_count();
  for (int s = 0; s < 240; ++s) world.step();
  EXPECT_EQ(testing::allocation_count() - before, 0);
}

TEST(Allocation, EveryRelaxationPathAllocatesNothing) {
  // Threads on every colour, the AoS copy with contacts between sweeps, Jacobi's sums, and
  // batches rebuilt as the humanoid wakes and sleeps.
  const Model humanoid = testing::load_shipped_scene("humanoid.json");
  for (const RelaxationSolver solver : {RelaxationSolver::gauss_seidel, RelaxationSolver::jacobi}) {
    for (const ParticleLayout layout : {ParticleLayout::soa, ParticleLayout::aos, ParticleLayout::aosoa}) {
      VerletOptions options;
      options.solver = solver, options.layout = layout;
      options.threads = 2, options.threading = Threading::workers, options.parallel_minimum_slots = 1;
      EXPECT_EQ(allocations_while_stepping<float>(humanoid, 600, false, options), 0)
          << "solver " << int(solver) << " layout " << int(layout);
    }
  }
}

TEST(Allocation, TheDirectSolverAllocatesNothing) {
  // Its Newton steps over the humanoid (contacts, sleep and wake) and the chain, warm-started
  // and with long-range attachments.
  const Model humanoid = testing::load_shipped_scene("humanoid.json");
  const Scene chain = testing::shipped_scene("chain.json");
  VerletOptions options = testing::with_scene_settings(chain);
  options.solver = RelaxationSolver::direct;
  options.newton_iterations = 3;
  EXPECT_EQ(allocations_while_stepping<float>(humanoid, 600, false, options), 0);
  options.warm_start = true, options.long_range_attachments = true;
  EXPECT_EQ(allocations_while_stepping<double>(chain.model, 600, true, options), 0);
}

TEST(Allocation, TheRattleRuleAllocatesNothing) {
  // Substeps, start gradients, velocity sweeps with restitution, fallbacks counted from the
  // threads; every solver and the sequential sweep.
  const Model humanoid = testing::load_shipped_scene("humanoid.json");
  VerletOptions rattle;
  rattle.relaxation.projection = ProjectionRule::rattle;
  rattle.relaxation.substeps = 3;
  rattle.relaxation.iterations = 10;
  for (const RelaxationSolver solver : {RelaxationSolver::gauss_seidel, RelaxationSolver::jacobi, RelaxationSolver::direct}) {
    VerletOptions options = rattle;
    options.solver = solver;
    options.threads = 2, options.threading = Threading::workers, options.parallel_minimum_slots = 1;
    EXPECT_EQ(allocations_while_stepping<float>(humanoid, 600, false, options), 0) << "solver " << int(solver);
  }
  VerletOptions sequential = rattle;
  sequential.order = SweepOrder::sequential;
  EXPECT_EQ(allocations_while_stepping<double>(humanoid, 600, false, sequential), 0);
}

TEST(Allocation, AWorldStepWithLoadsAllocatesNothing) {
  // Every method behind the World, a force, a torque and an impulse each step, and a moving
  // held point (particles): after the first step, nothing is allocated.
  Model model = testing::load_shipped_scene("humanoid.json");
  model.settings.sleep.start_asleep = false;
  for (const Method method : {Method::particles, Method::springs, Method::lagrange, Method::featherstone}) {
    World world(model, WorldOptions{.method = method});
    const BodyId head = world.body("head"), basin = world.body("basin");
    world.step();
    const long before = testing::allocation_count();
    for (int s = 0; s < 200; ++s) {
      world.apply_force(head, Eigen::Vector3d(1, 0, 0), world.pose(head).position);
      world.apply_torque(basin, Eigen::Vector3d(0, 0, 0.1));
      world.apply_impulse(basin, Eigen::Vector3d(0, 0.01, 0), world.pose(basin).position);
      world.step();
    }
    EXPECT_EQ(testing::allocation_count() - before, 0) << method_name(method);
  }
  Model rope = testing::make_chain({0.1, 0.1, 0.1}, 0.1, false);
  WorldOptions shared;
  shared.particles.verlet.joints = ParticleJoints::shared_particle;
  World held(rope, shared);
  const PinId hand = held.pin(held.body("link_0"), Eigen::Vector3d(0, 0, 0.05));
  held.move_pin(hand, held.pin_position(hand));
  held.step(1.0 / 60);
  const long before = testing::allocation_count();
  for (int s = 0; s < 100; ++s) {
    held.move_pin(hand, held.pin_position(hand) + Eigen::Vector3d(0.001, 0, 0));
    held.step(1.0 / 60);
  }
  EXPECT_EQ(testing::allocation_count() - before, 0);
}

TEST(Allocation, TheCounterSeesAllocations) {  // so the test above can fail
  // (A new-expression may be elided by the compiler; std::allocator calls operator new itself.)
  const long before = testing::allocation_count();
  std::vector<int> vector(100, 1);
  EXPECT_EQ(vector[99], 1);
  EXPECT_GE(testing::allocation_count() - before, 1);
}

TEST(Allocation, TheCounterCountsEveryFormOnceAndFreesItsOwn) {
  // Each replaceable allocation function counts one allocation and its memory goes back through
  // the matching delete (called directly: unlike a new-expression, a call is never elided).
  // std::stable_partition's temporary buffer takes the nothrow new: AddressSanitizer reported
  // alloc-dealloc-mismatch when that form was left to the runtime and freed here.
  const auto counted = [](auto allocate_and_free) {
    const long before = testing::allocation_count();
    allocate_and_free();
    return testing::allocation_count() - before;
  };
  const auto wide = std::align_val_t{64};
  const std::nothrow_t& nothrow = std::nothrow;
  EXPECT_EQ(counted([] { ::operator delete(::operator new(24)); }), 1);
  EXPECT_EQ(counted([] { ::operator delete[](::operator new[](24)); }), 1);
#if defined(__cpp_sized_deallocation)  // clang declares the sized forms only with -fsized-deallocation
  EXPECT_EQ(counted([] { ::operator delete(::operator new(24), 24); }), 1);
  EXPECT_EQ(counted([] { ::operator delete[](::operator new[](24), 24); }), 1);
#endif
  EXPECT_EQ(counted([&] { ::operator delete(::operator new(24, nothrow), nothrow); }), 1);
  EXPECT_EQ(counted([&] { ::operator delete[](::operator new[](24, nothrow), nothrow); }), 1);
  for (const std::size_t size : {std::size_t{0}, std::size_t{24}, std::size_t{200}}) {
    EXPECT_EQ(counted([&] {
                void* p = ::operator new(size, wide);
                EXPECT_EQ(reinterpret_cast<std::uintptr_t>(p) % 64, 0u);
                ::operator delete(p, wide);
              }),
              1);
#if defined(__cpp_sized_deallocation)
    EXPECT_EQ(counted([&] { ::operator delete(::operator new(size, wide), size, wide); }), 1);
    EXPECT_EQ(counted([&] { ::operator delete[](::operator new[](size, wide), size, wide); }), 1);
#endif
    EXPECT_EQ(counted([&] { ::operator delete[](::operator new[](size, wide), wide); }), 1);
    EXPECT_EQ(counted([&] { ::operator delete(::operator new(size, wide, nothrow), wide, nothrow); }), 1);
    EXPECT_EQ(counted([&] { ::operator delete[](::operator new[](size, wide, nothrow), wide, nothrow); }), 1);
  }
  std::vector<int> values(1000);
  for (int k = 0; k < 1000; ++k) values[static_cast<std::size_t>(k)] = (k * 7919) % 1000;
  EXPECT_GE(counted([&] { std::stable_partition(values.begin(), values.end(), [](int v) { return v % 2 == 0; }); }), 1);
  EXPECT_TRUE(std::is_partitioned(values.begin(), values.end(), [](int v) { return v % 2 == 0; }));
}

TEST(Allocation, ExplicitSpringStepAllocatesNothingAfterItsFirstCall) {
  // Every explicit integrator, on the three shipped scenes: contacts, impulses, sleeping.
  for (const char* file : {"humanoid.json", "chain.json", "stick_in_box.json"}) {
    const Model model = testing::load_shipped_scene(file);
    for (Integrator integrator : {Integrator::euler, Integrator::semi_implicit_euler, Integrator::rk2,
                                        Integrator::rk4}) {
      SpringState state = compile_springs(model, {.integrator = integrator, .damping = 50.0});
      step(state);
      const long before = testing::allocation_count();
      for (int s = 0; s < 600; ++s) step(state);
      EXPECT_EQ(testing::allocation_count() - before, 0) << file << ", integrator " << integrator_name(integrator);
    }
  }
}

TEST(Allocation, LagrangeTreeStepAllocatesNothingAfterItsFirstCall) {
  // Baraff's tree solve with every stabilization and integrator, contacts and projections
  // included; the sparse path (loops, gears) allocates inside Eigen's factorization.
  for (const char* file : {"humanoid.json", "chain.json", "stick_in_box.json"}) {
    const Model model = testing::load_shipped_scene(file);
    for (Stabilization stabilization : {Stabilization::baumgarte, Stabilization::projection}) {
      for (Integrator integrator : {Integrator::semi_implicit_euler, Integrator::rk4}) {
        LagrangeState state = compile_lagrange(model, {.integrator = integrator, .stabilization = stabilization});
        ASSERT_TRUE(state.uses_tree);
        step(state, model.settings.time_step);
        const long before = testing::allocation_count();
        for (int s = 0; s < 600; ++s) step(state, model.settings.time_step);
        EXPECT_EQ(testing::allocation_count() - before, 0) << file << ", integrator " << integrator_name(integrator)
                                                  << ", stabilization " << static_cast<int>(stabilization);
      }
    }
  }
}

}  // namespace
}  // namespace limber
