// Time per call of the articulated-body algorithm (Featherstone 2008, Table 7.1) against the
// number of links: a chain of revolute joints (axes turning from link to link) or of spherical
// joints, 0.1 m slender links, at a fixed pseudo-random state. ns_per_link staying flat from 10 to
// 10⁵ links shows the algorithm is O(n); the workspace is sized before timing, so the loop
// allocates nothing.
//   build/bench/featherstone_bench --benchmark_min_time=0.2
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "limber/kernel/featherstone/dynamics.hpp"

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

BENCHMARK(BM_ArticulatedBodyRevoluteChain)->RangeMultiplier(10)->Range(10, 100000)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ArticulatedBodySphericalChain)->RangeMultiplier(10)->Range(10, 100000)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
