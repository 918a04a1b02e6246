// Time per call of the articulated-body algorithm (Featherstone 2008, Table 7.1) against the
// number of links: a chain of revolute joints (axes turning from link to link) or of spherical
// joints, 0.1 m slender links, at a fixed pseudo-random state. ns_per_link staying flat from 10 to
// 10⁵ links shows the algorithm is O(n); the workspace is sized before timing, so the loop
// allocates nothing.
//
// The Humanoid rows time, on MuJoCo's humanoid.xml (its tree as limber compiles it: 27
// velocity coordinates), one articulated-body pass against the constraint-space work a step's
// contacts cost: the composite-rigid-body H, its LᵀDL factor in the tree's sparsity, the
// Delassus matrix of 18 rows (6 contacts × 3, each on a foot's or hand's path to the root) and
// one solve (kernel/featherstone/joint_space_factor.hpp).
//
// The Chain rows time a whole step of a hanging chain against one articulated-body pass of its
// tree (bench/chains.md: the step's cost in passes).
//   build/bench/featherstone_bench --benchmark_min_time=0.2
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <vector>

#include "limber/kernel/featherstone/compile.hpp"
#include "limber/kernel/featherstone/dynamics.hpp"
#include "limber/kernel/featherstone/joint_space_factor.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/scene/scene_file.hpp"

namespace {

using namespace limber;

ArticulatedTree chain(std::size_t links, ArticulatedJoint joint) {
  ArticulatedTree tree;
  const SpatialInertia link = SpatialInertia::from_mass_properties(0.1, Eigen::Vector3d(0, 0, -0.05), Eigen::Vector3d(1e-4, 1e-4, 1e-5).asDiagonal());
  for (std::size_t i = 0; i < links; ++i) {
    ArticulatedBody body;
    body.parent = static_cast<int>(i) - 1;
    body.joint = joint;
    const double turn = 0.7 * static_cast<double>(i);
    body.joint_axis = Eigen::Vector3d(std::cos(turn), std::sin(turn), 0);
    if (i > 0) body.tree_transform.translation = Eigen::Vector3d(0, 0, -0.1);
    body.inertia = link;
    tree.add_body(body);
  }
  return tree;
}

void forward_dynamics_on_chain(benchmark::State& bench, ArticulatedJoint joint) {
  const auto links = static_cast<std::size_t>(bench.range(0));
  const ArticulatedTree tree = chain(links, joint);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> small(-0.3, 0.3);
  Eigen::VectorXd q = tree.neutral_positions();
  for (int i = 0; i < tree.body_count(); ++i) {
    const int p = tree.position_offset(i);
    if (joint == ArticulatedJoint::revolute) {
      q[p] = small(rng);
    } else {
      const Eigen::Quaterniond turn = Eigen::Quaterniond(1, small(rng), small(rng), small(rng)).normalized();
      q.segment<4>(p) << turn.w(), turn.x(), turn.y(), turn.z();
    }
  }
  const Eigen::VectorXd v = Eigen::VectorXd::NullaryExpr(tree.velocity_count(), [&] { return small(rng); });
  const Eigen::VectorXd tau = Eigen::VectorXd::NullaryExpr(tree.velocity_count(), [&] { return 0.01 * small(rng); });
  DynamicsWorkspace workspace;
  workspace.resize(tree);
  Eigen::VectorXd accelerations(tree.velocity_count());
  const Eigen::Vector3d gravity(0, 0, -9.81);
  for (auto _ : bench) {
    forward_dynamics(tree, q, v, tau, gravity, workspace, accelerations);
    benchmark::DoNotOptimize(accelerations.data());
    benchmark::ClobberMemory();
  }
  bench.counters["links"] = static_cast<double>(links);
  bench.counters["ns_per_link"] = benchmark::Counter(static_cast<double>(links), benchmark::Counter::kIsIterationInvariantRate |
                                                                                    benchmark::Counter::kInvert);
  bench.SetItemsProcessed(static_cast<std::int64_t>(bench.iterations()) * static_cast<std::int64_t>(links));
}

void BM_ArticulatedBodyRevoluteChain(benchmark::State& bench) { forward_dynamics_on_chain(bench, ArticulatedJoint::revolute); }
void BM_ArticulatedBodySphericalChain(benchmark::State& bench) { forward_dynamics_on_chain(bench, ArticulatedJoint::spherical); }

// humanoid.xml's tree (Debian's libmujoco-samples), or an empty tree when it is not installed.
ArticulatedTree humanoid_tree() {
  const std::filesystem::path file = "/usr/share/mujoco/model/humanoid/humanoid.xml";
  if (!std::filesystem::exists(file)) return {};
  return compile_featherstone(load_scene_file(file).model).tree;
}

void BM_HumanoidArticulatedBodyPass(benchmark::State& bench) {
  const ArticulatedTree tree = humanoid_tree();
  if (tree.body_count() == 0) return bench.SkipWithError("humanoid.xml not found (libmujoco-samples)");
  const Eigen::VectorXd q = tree.neutral_positions(), v = Eigen::VectorXd::Constant(tree.velocity_count(), 0.1);
  const Eigen::VectorXd tau = Eigen::VectorXd::Zero(tree.velocity_count());
  DynamicsWorkspace workspace;
  workspace.resize(tree);
  Eigen::VectorXd accelerations(tree.velocity_count());
  for (auto _ : bench) {
    forward_dynamics(tree, q, v, tau, Eigen::Vector3d(0, 0, -9.81), workspace, accelerations);
    benchmark::DoNotOptimize(accelerations.data());
  }
}

// The articulated-body pass's answer the other way (MuJoCo's, and the step's for an island a
// contact touches before the move): the poses and body velocities, the bias forces by recursive
// Newton–Euler, H by the composite-rigid-body algorithm, its LᵀDL factor and one solve; the
// factor then serves the contacts.
void BM_HumanoidBiasForcesAndFactorSolve(benchmark::State& bench) {
  const ArticulatedTree tree = humanoid_tree();
  if (tree.body_count() == 0) return bench.SkipWithError("humanoid.xml not found (libmujoco-samples)");
  const int nv = tree.velocity_count();
  const Eigen::VectorXd q = tree.neutral_positions(), v = Eigen::VectorXd::Constant(nv, 0.1);
  DynamicsWorkspace poses, workspace;
  poses.resize(tree), workspace.resize(tree);
  JointSpaceFactor factor;
  factor.assign(tree);
  Eigen::VectorXd accelerations = Eigen::VectorXd::Zero(nv);
  for (auto _ : bench) {
    forward_kinematics(tree, q, v, poses);
    bias_forces(tree, poses, Eigen::Vector3d(0, 0, -9.81), workspace, accelerations, tree.all_bodies());
    mass_matrix(tree, poses, workspace, factor);
    factor.factor(0, nv);
    accelerations = -accelerations;  // τ = 0
    factor.solve(accelerations, 0, nv);
    benchmark::DoNotOptimize(accelerations.data());
  }
}

// The composite-rigid-body algorithm alone, into the factor's sparsity, at given poses.
void BM_HumanoidMassMatrix(benchmark::State& bench) {
  const ArticulatedTree tree = humanoid_tree();
  if (tree.body_count() == 0) return bench.SkipWithError("humanoid.xml not found (libmujoco-samples)");
  DynamicsWorkspace poses, workspace;
  poses.resize(tree), workspace.resize(tree);
  body_poses(tree, tree.neutral_positions(), poses);
  JointSpaceFactor factor;
  factor.assign(tree);
  for (auto _ : bench) {
    mass_matrix(tree, poses, workspace, factor);
    benchmark::ClobberMemory();
  }
}

void BM_HumanoidFactorAndDelassus(benchmark::State& bench) {
  const ArticulatedTree tree = humanoid_tree();
  if (tree.body_count() == 0) return bench.SkipWithError("humanoid.xml not found (libmujoco-samples)");
  const int nv = tree.velocity_count();
  const Eigen::VectorXd q = tree.neutral_positions();
  // Rows on the paths of the tree's leaves' coordinates (the feet and hands), dense there.
  JointSpaceFactor factor;
  factor.assign(tree);
  std::vector<int> leaves;
  for (int i = nv - 1; i >= 0; --i) {
    bool leaf = true;
    for (int k = i + 1; k < nv; ++k) leaf = leaf && factor.parent(k) != i;
    if (leaf) leaves.push_back(i);
  }
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> entry(-1, 1);
  constexpr int kContacts = 6;  // a leaf may take more than one (the humanoid has 4 leaves)
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(3 * kContacts, nv);
  for (int c = 0; c < kContacts; ++c) {
    for (int row = 0; row < 3; ++row) {
      for (int k = leaves[static_cast<std::size_t>(c) % leaves.size()]; k >= 0; k = factor.parent(k)) jacobian(3 * c + row, k) = entry(rng);
    }
  }
  DynamicsWorkspace workspace;
  workspace.resize(tree);
  Eigen::MatrixXd h, a, half;
  Eigen::VectorXd x(nv);
  for (auto _ : bench) {
    mass_matrix(tree, q, workspace, h);
    factor.factor(h);
    factor.delassus(jacobian, a, half);
    x.setOnes();
    factor.solve(x);
    benchmark::DoNotOptimize(a.data());
    benchmark::DoNotOptimize(x.data());
  }
  bench.counters["rows"] = static_cast<double>(jacobian.rows());
  bench.counters["coordinates"] = nv;
}

// A whole step of the method against one articulated-body pass of the same tree: a chain of N
// links (the scene file's chain generator: ball joints) hanging straight down from its pin, awake,
// stepped by semi-implicit Euler at 1/240 s (one pass a step). ChainStep / ChainPass is the
// step's cost in passes.
Model hanging_chain(std::size_t links) {
  ChainSpec spec;
  spec.links = links;
  spec.direction = Vector3(0, 0, -1);
  Model model = make_chain_model(spec);
  model.settings.sleep.enabled = false;
  return model;
}

void BM_ChainStep(benchmark::State& bench) {
  FeatherstoneState state = compile_featherstone(hanging_chain(static_cast<std::size_t>(bench.range(0))), {.integrator = Integrator::semi_implicit_euler});
  for (auto _ : bench) {
    benchmark::DoNotOptimize(step(state).status);
    benchmark::ClobberMemory();
  }
  bench.counters["links"] = static_cast<double>(bench.range(0));
}

void BM_ChainPass(benchmark::State& bench) {
  FeatherstoneState state = compile_featherstone(hanging_chain(static_cast<std::size_t>(bench.range(0))), {.integrator = Integrator::semi_implicit_euler});
  DynamicsWorkspace workspace;
  workspace.resize(state.tree);
  Eigen::VectorXd accelerations(state.tree.velocity_count());
  for (auto _ : bench) {
    forward_dynamics(state.tree, state.q, state.v, state.joint_forces, state.settings.gravity, workspace, accelerations);
    benchmark::DoNotOptimize(accelerations.data());
    benchmark::ClobberMemory();
  }
  bench.counters["links"] = static_cast<double>(bench.range(0));
}

// Whole steps of humanoid.xml lying on the floor after its fall: each iteration the same 200 steps
// (1 s of 0.005 s) from the state 2 s after the start, with its contacts, limits and drives,
// under semi-implicit Euler (MuJoCo's integrator); seconds_per_step is the time a step. For profiles of the
// step without the observers (perf record build/bench/featherstone_bench
// --benchmark_filter=HumanoidLyingSteps).
void BM_HumanoidLyingSteps(benchmark::State& bench) {
  const std::filesystem::path file = "/usr/share/mujoco/model/humanoid/humanoid.xml";
  if (!std::filesystem::exists(file)) return bench.SkipWithError("humanoid.xml not found (libmujoco-samples)");
  FeatherstoneState lying = compile_featherstone(load_scene_file(file).model, {.integrator = Integrator::semi_implicit_euler});
  for (int n = 0; n < 400; ++n) step(lying);
  constexpr int kSteps = 200;
  FeatherstoneState state = lying;
  for (auto _ : bench) {
    bench.PauseTiming();
    state = lying;
    bench.ResumeTiming();
    for (int n = 0; n < kSteps; ++n) benchmark::DoNotOptimize(step(state).status);
    benchmark::ClobberMemory();
  }
  bench.counters["seconds_per_step"] = benchmark::Counter(kSteps, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  bench.counters["contacts"] = static_cast<double>(state.contacts.size());
}

// The contact solve's run time against its error (kernel/featherstone/joint_space_contacts.hpp,
// "Impulses"): humanoid.xml under semi-implicit Euler, one step from each of 20 states with
// contacts of its fall (every 30 steps from 0.1 s: arg 1 = 0) or of its rest (from 4 s: 1) with
// arg 0 passes of projected Gauss-Seidel, warm-started as the run left it. error is the mean
// distance of the step's joint velocities from the converged answer's (2000 passes, cold), in
// the kinetic-energy norm, relative to the constraints' change (the converged answer less the
// unconstrained one); seconds_per_step the time of a step, contacts included.
//   build/bench/featherstone_bench --benchmark_filter=HumanoidContactSolve
void BM_HumanoidContactSolve(benchmark::State& bench) {
  const std::filesystem::path file = "/usr/share/mujoco/model/humanoid/humanoid.xml";
  if (!std::filesystem::exists(file)) return bench.SkipWithError("humanoid.xml not found (libmujoco-samples)");
  const Scene scene = load_scene_file(file);
  const double dt = scene.model.settings.time_step;
  FeatherstoneState run = compile_featherstone(scene.model, {.integrator = Integrator::semi_implicit_euler});
  run.settings.sleep.enabled = false;
  const int first = bench.range(1) == 0 ? 20 : 800;
  std::vector<FeatherstoneState> samples;
  for (int n = 0; samples.size() < 20; ++n) {
    if (n >= first && (n - first) % 30 == 0 && !run.contacts.empty()) samples.push_back(run);
    step(run, dt);
  }
  // Each sample's unconstrained and converged answers, and its H.
  const auto after_step = [&](const FeatherstoneState& start, int passes, bool cold) {
    FeatherstoneState state = start;
    state.contact_iterations = passes;
    if (cold) state.contact.memory.clear(), state.contact.remembered_rows.clear();
    step(state, dt);
    return Eigen::VectorXd(state.v);
  };
  std::vector<Eigen::VectorXd> free, converged;
  std::vector<Eigen::MatrixXd> inertia(samples.size());
  DynamicsWorkspace workspace;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    free.push_back(after_step(samples[k], 0, true)), converged.push_back(after_step(samples[k], 2000, true));
    mass_matrix(samples[k].tree, samples[k].q, workspace, inertia[k]);
  }
  const int passes = static_cast<int>(bench.range(0));
  double error = 0;
  FeatherstoneState state = samples[0];
  for (auto _ : bench) {
    error = 0;
    for (std::size_t k = 0; k < samples.size(); ++k) {
      bench.PauseTiming();
      state = samples[k];
      state.contact_iterations = passes;
      bench.ResumeTiming();
      benchmark::DoNotOptimize(step(state, dt).status);
      bench.PauseTiming();
      const auto norm = [&](const Eigen::VectorXd& x) { return std::sqrt(x.dot(inertia[k] * x)); };
      error += norm(state.v - converged[k]) / norm(converged[k] - free[k]) / static_cast<double>(samples.size());
      bench.ResumeTiming();
    }
  }
  bench.counters["error"] = error;
  bench.counters["seconds_per_step"] = benchmark::Counter(static_cast<double>(samples.size()), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

BENCHMARK(BM_ChainStep)->Arg(100)->Arg(1000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HumanoidContactSolve)->ArgsProduct({{1, 2, 4, 8, 16, 32}, {0, 1}})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ChainPass)->Arg(100)->Arg(1000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HumanoidArticulatedBodyPass)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HumanoidBiasForcesAndFactorSolve)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HumanoidMassMatrix)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HumanoidFactorAndDelassus)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HumanoidLyingSteps)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ArticulatedBodyRevoluteChain)->RangeMultiplier(10)->Range(10, 100000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ArticulatedBodySphericalChain)->RangeMultiplier(10)->Range(10, 100000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
