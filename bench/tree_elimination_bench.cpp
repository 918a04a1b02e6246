// The tree elimination (kernel/numerics/tree_elimination.hpp) one instance at a time against
// SIMD lanes across instances (a lane an instance: ragdolls of one skeleton, ropes of one
// length), in one run (bench/speed.md, "The tree elimination in SIMD lanes across instances").
//
//   build/bench/tree_elimination_bench
//
// Shapes: a ragdoll's tree (13 limbs as rigid bodies, 6 × 6 blocks; 12 joints of 5 rows — a
// point and two limit or axis rows — padded as lanes need, one row count per joint); the
// `Scene` rows: the ragdoll of tools/scenes/ragdoll.json (the pile's and the rain's) as the joint
// trees compile it, each joint with its fixed rows (points, axes, a row per limit), as many
// instances as a batch holds floats (8 with AVX2), whose blocks stay in cache, in double or
// float lanes — the floor of a tree step's elimination stage (bench/ragdolls.md, "Where a tree
// step goes, against its floor", "Float lanes"); and a rope (100 particles, 3 × 3 blocks; 100
// distance constraints of one row, the first to the world).
// Each iteration loads the inputs (a copy), factors and solves every instance: the time per
// instance and per joint (counters `instance`, `joint`). The label says scalar or the lane
// count (xsimd's widest batch for this build: 8 doubles on AVX-512, 4 on AVX2). The `Packed`
// rows feed the lanes from instances kept one at a time, as the joint trees keep their
// ragdolls, and unpack the results (with `Inverse`: the inverse diagonal too). `RopeConstraintSpace`
// solves the rope's system in constraint space (constraint_elimination.hpp): the factor from
// the directions, weights and compliances, and a solve, one instance at a time or one a lane,
// in double and float.
#include <array>
#include <cstdint>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include <benchmark/benchmark.h>
#include <xsimd/xsimd.hpp>

#include "limber/kernel/numerics/constraint_elimination.hpp"
#include "limber/kernel/numerics/lane_blocks.hpp"
#include "limber/kernel/numerics/tree_elimination.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "limber/kernel/verlet/compile.hpp"

namespace limber {
namespace {

constexpr std::size_t kInstances = 64;  // a multiple of every lane width

struct Shape {
  int bodies = 0;
  std::vector<std::int32_t> inboard, outboard;  // per joint: its bodies (inboard −1: the world)
  std::vector<std::uint8_t> rows;               // per joint
  std::size_t instances = kInstances;           // a multiple of every lane width
};

// The ragdoll: limb 0 the pelvis; spine, torso, head; two arms of two limbs off the torso; two
// legs of two off the pelvis; a hand on the right forearm.
Shape ragdoll() {
  Shape shape;
  shape.bodies = 13;
  const std::int32_t parent[13] = {-1, 0, 1, 2, 2, 4, 2, 6, 0, 8, 0, 10, 7};
  for (std::int32_t limb = 1; limb < 13; ++limb) shape.inboard.push_back(parent[limb]), shape.outboard.push_back(limb), shape.rows.push_back(5);
  return shape;
}

Shape scene_ragdoll() {
  const Scene scene = load_scene_file(std::string(LIMBER_SOURCE_DIR) + "/tools/scenes/ragdoll.json");
  VerletOptions options;
  options.verlet.joint_solve = JointSolve::tree;
  const VerletState<double> state = compile<double>(scene.model, options);
  const JointTrees& trees = state.plan.joint_trees;
  Shape shape;
  shape.bodies = trees.elimination.body_count();
  for (const JointTrees::Joint& joint : trees.joints) {
    shape.inboard.push_back(joint.limb_a), shape.outboard.push_back(joint.limb_b);
    shape.rows.push_back(static_cast<std::uint8_t>(joint.fixed_rows()));
  }
  shape.instances = xsimd::batch<float>::size;  // one batch of floats, a multiple of every lane width; in cache
  return shape;
}

Shape rope() {
  Shape shape;
  shape.bodies = 100;
  for (std::int32_t particle = 0; particle < 100; ++particle) shape.inboard.push_back(particle - 1), shape.outboard.push_back(particle), shape.rows.push_back(1);
  return shape;
}

// `instances` systems of one shape, `width` to an elimination: the inputs kept to reload them.
template <typename Value, int B>
struct Batch {
  TreeElimination<Value, B> elimination;
  std::vector<Block<Value, B, B>> diagonal;
  std::vector<Block<Value, B, 1>> right;
  std::vector<std::array<Block<Value, B, B>, 2>> edge;  // per constraint: on inboard, outboard
};

template <typename Value>
constexpr std::size_t lane_count() {
  if constexpr (std::is_arithmetic_v<Value>) {
    return 1;
  } else {
    return Value::size;
  }
}

template <typename Value, int B>
std::vector<Batch<Value, B>> batches(const Shape& shape) {
  constexpr std::size_t width = lane_count<Value>();
  std::mt19937 random(5);
  std::uniform_real_distribution<double> entry(-1, 1);
  std::vector<Batch<Value, B>> out(shape.instances / width);
  for (Batch<Value, B>& batch : out) {
    batch.elimination.assign(order_tree(static_cast<std::size_t>(shape.bodies), shape.inboard, shape.outboard),
                             static_cast<std::size_t>(shape.bodies), shape.rows);
    const std::size_t nodes = batch.elimination.node_count();
    batch.diagonal.assign(nodes, Block<Value, B, B>::Zero());
    batch.right.assign(nodes, Block<Value, B, 1>::Zero());
    batch.edge.assign(shape.inboard.size(), {Block<Value, B, B>::Zero(), Block<Value, B, B>::Zero()});
    for (std::size_t lane = 0; lane < width; ++lane) {
      for (std::size_t body = 0; body < static_cast<std::size_t>(shape.bodies); ++body) {
        const double mass = 1 + 60 * (entry(random) + 1) / 2;  // 1 to 61 kg
        for (int i = 0; i < B; ++i) {
          for (int j = 0; j < B; ++j) set_lane(batch.diagonal[body](i, j), lane, i == j ? (i < 3 ? mass : 0.05 * mass) : (i >= 3 && j >= 3 ? 0.01 * mass * entry(random) : 0.0));
          set_lane(batch.right[body](i, 0), lane, entry(random));
        }
        // Symmetric inertia.
        for (int i = 3; i < B; ++i) {
          for (int j = 3; j < i; ++j) batch.diagonal[body](j, i) = batch.diagonal[body](i, j);
        }
      }
      for (std::size_t c = 0; c < shape.inboard.size(); ++c) {
        for (int i = 0; i < B; ++i) {
          // A joint's rows: a point (E on its outboard, −E and a lever on its inboard), axis rows.
          for (int j = 0; j < B; ++j) {
            set_lane(batch.edge[c][1](i, j), lane, (i == j ? 1.0 : 0.0) + 0.2 * entry(random));
            set_lane(batch.edge[c][0](i, j), lane, (i == j ? -1.0 : 0.0) + 0.2 * entry(random));
          }
          set_lane(batch.right[static_cast<std::size_t>(shape.bodies) + c](i, 0), lane, entry(random));
        }
      }
    }
  }
  return out;
}

template <typename Value, int B>
void BM_Eliminate(benchmark::State& run, const Shape& shape, bool inverse = false) {
  std::vector<Batch<Value, B>> all = batches<Value, B>(shape);
  for (auto _ : run) {
    for (Batch<Value, B>& batch : all) {
      TreeElimination<Value, B>& elimination = batch.elimination;
      for (std::size_t node = 0; node < elimination.node_count(); ++node) {
        elimination.diagonal(node) = batch.diagonal[node], elimination.work(node) = batch.right[node];
      }
      const TreeOrdering::Component& component = elimination.ordering().components[0];
      const bool definite = elimination.eliminate(component.begin, component.end, [&](std::size_t c, std::int32_t body) -> const Block<Value, B, B>& {
        return batch.edge[c][shape.outboard[c] == body ? 1 : 0];
      });
      benchmark::DoNotOptimize(definite);
      benchmark::DoNotOptimize(elimination.work(0));
      if (!inverse) continue;
      elimination.inverse_diagonal(component.begin, component.end);
      benchmark::DoNotOptimize(elimination.mobility(0));
    }
  }
  // Time per instance and per joint (printed in seconds with an SI prefix).
  run.counters["instance"] = benchmark::Counter(static_cast<double>(shape.instances), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  run.counters["joint"] = benchmark::Counter(static_cast<double>(shape.instances * shape.inboard.size()),
                                             benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  run.SetLabel((std::is_arithmetic_v<Value> ? std::string("scalar") : std::to_string(lane_count<Value>()) + " lanes") +
               (sizeof(decltype(get_lane(Value(0), 0))) == 4 ? " of float" : "") + std::string(inverse ? ", with the inverse diagonal" : ""));
}

// A solve alone with a kept factor (the trees' contact iterations, each a back-substitution):
// every instance factored once, then each iteration reloads the right-hand sides and solves.
template <typename Value, int B>
void BM_Solve(benchmark::State& run, const Shape& shape) {
  std::vector<Batch<Value, B>> all = batches<Value, B>(shape);
  for (Batch<Value, B>& batch : all) {
    TreeElimination<Value, B>& elimination = batch.elimination;
    for (std::size_t node = 0; node < elimination.node_count(); ++node) elimination.diagonal(node) = batch.diagonal[node];
    const TreeOrdering::Component& component = elimination.ordering().components[0];
    elimination.factor(component.begin, component.end, [&](std::size_t c, std::int32_t body) -> const Block<Value, B, B>& {
      return batch.edge[c][shape.outboard[c] == body ? 1 : 0];
    });
  }
  for (auto _ : run) {
    for (Batch<Value, B>& batch : all) {
      TreeElimination<Value, B>& elimination = batch.elimination;
      for (std::size_t node = 0; node < elimination.node_count(); ++node) elimination.work(node) = batch.right[node];
      const TreeOrdering::Component& component = elimination.ordering().components[0];
      elimination.solve(component.begin, component.end);
      benchmark::DoNotOptimize(elimination.work(0));
    }
  }
  run.counters["instance"] = benchmark::Counter(static_cast<double>(shape.instances), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  run.SetLabel((std::is_arithmetic_v<Value> ? "scalar" : std::to_string(xsimd::batch<double>::size) + " lanes") + std::string(", a solve with a kept factor"));
}

// Lanes fed from instances kept one at a time (as the joint trees keep each ragdoll's blocks):
// each iteration packs `width` instances' inputs into the lanes (a lane-major gather per
// entry), eliminates, and unpacks every node's solution and, with `inverse`, every body's block
// of the inverse (what the trees' contacts read) back to the instances: what laning costs
// beside the elimination itself.
template <int B>
void BM_EliminatePacked(benchmark::State& run, const Shape& shape, bool inverse) {
  using Value = xsimd::batch<double>;
  constexpr std::size_t width = Value::size;
  std::vector<Batch<double, B>> instances = batches<double, B>(shape);
  std::vector<Batch<Value, B>> lanes = batches<Value, B>(shape);
  std::vector<std::vector<Block<double, B, 1>>> solution(shape.instances, std::vector<Block<double, B, 1>>(instances[0].elimination.node_count()));
  std::vector<std::vector<Block<double, B, B>>> mobility(shape.instances, std::vector<Block<double, B, B>>(static_cast<std::size_t>(shape.bodies)));
  std::vector<const Block<double, B, B>*> in_matrix(width);
  std::vector<const Block<double, B, 1>*> in_vector(width);
  std::vector<Block<double, B, 1>*> out_vector(width);
  std::vector<Block<double, B, B>*> out_matrix(width);
  for (auto _ : run) {
    for (std::size_t k = 0; k < lanes.size(); ++k) {
      Batch<Value, B>& batch = lanes[k];
      TreeElimination<Value, B>& elimination = batch.elimination;
      for (std::size_t node = 0; node < elimination.node_count(); ++node) {
        for (std::size_t lane = 0; lane < width; ++lane) {
          in_matrix[lane] = &instances[k * width + lane].diagonal[node], in_vector[lane] = &instances[k * width + lane].right[node];
        }
        pack_lanes(elimination.diagonal(node), in_matrix), pack_lanes(elimination.work(node), in_vector);
      }
      for (std::size_t c = 0; c < shape.inboard.size(); ++c) {
        for (std::size_t side = 0; side < 2; ++side) {
          for (std::size_t lane = 0; lane < width; ++lane) in_matrix[lane] = &instances[k * width + lane].edge[c][side];
          pack_lanes(batch.edge[c][side], in_matrix);
        }
      }
      const TreeOrdering::Component& component = elimination.ordering().components[0];
      const bool definite = elimination.eliminate(component.begin, component.end, [&](std::size_t c, std::int32_t body) -> const Block<Value, B, B>& {
        return batch.edge[c][shape.outboard[c] == body ? 1 : 0];
      });
      benchmark::DoNotOptimize(definite);
      if (inverse) elimination.inverse_diagonal(component.begin, component.end);
      for (std::size_t node = 0; node < elimination.node_count(); ++node) {
        for (std::size_t lane = 0; lane < width; ++lane) out_vector[lane] = &solution[k * width + lane][node];
        unpack_lanes(elimination.work(node), out_vector);
        if (!inverse || node >= static_cast<std::size_t>(shape.bodies)) continue;
        for (std::size_t lane = 0; lane < width; ++lane) out_matrix[lane] = &mobility[k * width + lane][node];
        unpack_lanes(elimination.mobility(node), out_matrix);
      }
    }
    benchmark::DoNotOptimize(solution.front().front());
  }
  run.counters["instance"] = benchmark::Counter(static_cast<double>(shape.instances), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  run.SetLabel(std::to_string(width) + " lanes, packed from instances" + (inverse ? ", with the inverse diagonal" : ""));
}

// Value: double or float, one rope an elimination, or xsimd's widest batch of them, one rope a
// lane (each lane's bits its own: tests/numerics/constraint_elimination_test.cpp).
template <typename Value>
void BM_RopeConstraintSpace(benchmark::State& run) {
  using Number = decltype(get_lane(Value(0), 0));
  std::size_t width = 1;
  if constexpr (!std::is_arithmetic_v<Value>) width = Value::size;
  const Shape shape = rope();
  std::mt19937 random(5);
  std::uniform_real_distribution<double> entry(-1, 1);
  const std::size_t constraints = shape.inboard.size();
  struct Instance {
    ConstraintElimination<Value> elimination;
    std::vector<Block<Value, 3, 1>> direction;
    std::vector<Value> weight, right;
  };
  std::vector<Instance> instances(kInstances / width);
  const TreeOrdering ordering = order_tree(static_cast<std::size_t>(shape.bodies), shape.inboard, shape.outboard);
  for (Instance& instance : instances) {
    instance.elimination.assign(ordering, static_cast<std::size_t>(shape.bodies), shape.outboard, shape.inboard,
                                std::vector<std::uint8_t>(constraints, 1));
    instance.direction.resize(constraints), instance.right.resize(constraints, Value(0));
    instance.weight.resize(static_cast<std::size_t>(shape.bodies), Value(0));
    for (std::size_t lane = 0; lane < width; ++lane) {
      for (std::size_t c = 0; c < constraints; ++c) {
        const Eigen::Vector3d n = Eigen::Vector3d(entry(random), entry(random), entry(random)).normalized();
        for (int a = 0; a < 3; ++a) set_lane(instance.direction[c](a, 0), lane, static_cast<Number>(n[a]));
        set_lane(instance.right[c], lane, static_cast<Number>(entry(random)));
      }
      for (Value& w : instance.weight) set_lane(w, lane, static_cast<Number>(1 / (1 + 60 * (entry(random) + 1) / 2)));  // 1 to 61 kg
    }
  }
  for (auto _ : run) {
    for (Instance& instance : instances) {
      const bool definite = instance.elimination.factor(
          0, [&](std::size_t body) { return instance.weight[body]; },
          [&](std::size_t c) -> const Block<Value, 3, 1>& { return instance.direction[c]; }, [](std::size_t) { return Value(0); });
      for (std::size_t c = 0; c < constraints; ++c) instance.elimination.multiplier(c) = instance.right[c];
      instance.elimination.solve(0);
      benchmark::DoNotOptimize(definite);
      benchmark::DoNotOptimize(instance.elimination.multiplier(0));
    }
  }
  run.counters["instance"] = benchmark::Counter(kInstances, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  run.counters["joint"] = benchmark::Counter(static_cast<double>(kInstances * constraints),
                                             benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  run.SetLabel(std::string(sizeof(Number) == 4 ? "float" : "double") + ", " + (width == 1 ? std::string("scalar") : std::to_string(width) + " lanes") +
               ", constraint space");
}

void BM_RagdollScalar(benchmark::State& run) { BM_Eliminate<double, 6>(run, ragdoll()); }
void BM_RagdollScalarInverse(benchmark::State& run) { BM_Eliminate<double, 6>(run, ragdoll(), true); }
void BM_RagdollLanesPacked(benchmark::State& run) { BM_EliminatePacked<6>(run, ragdoll(), false); }
void BM_RagdollLanesPackedInverse(benchmark::State& run) { BM_EliminatePacked<6>(run, ragdoll(), true); }
void BM_RagdollLanes(benchmark::State& run) { BM_Eliminate<xsimd::batch<double>, 6>(run, ragdoll()); }
void BM_SceneRagdollScalar(benchmark::State& run) { BM_Eliminate<double, 6>(run, scene_ragdoll()); }
void BM_SceneRagdollLanes(benchmark::State& run) { BM_Eliminate<xsimd::batch<double>, 6>(run, scene_ragdoll()); }
void BM_SceneRagdollLanesInverse(benchmark::State& run) { BM_Eliminate<xsimd::batch<double>, 6>(run, scene_ragdoll(), true); }
void BM_SceneRagdollFloatLanes(benchmark::State& run) { BM_Eliminate<xsimd::batch<float>, 6>(run, scene_ragdoll()); }
void BM_SceneRagdollFloatLanesInverse(benchmark::State& run) { BM_Eliminate<xsimd::batch<float>, 6>(run, scene_ragdoll(), true); }
void BM_SceneRagdollLanesSolve(benchmark::State& run) { BM_Solve<xsimd::batch<double>, 6>(run, scene_ragdoll()); }
void BM_SceneRagdollLanesPacked(benchmark::State& run) { BM_EliminatePacked<6>(run, scene_ragdoll(), false); }
void BM_SceneRagdollLanesPackedInverse(benchmark::State& run) { BM_EliminatePacked<6>(run, scene_ragdoll(), true); }
void BM_RopeScalar(benchmark::State& run) { BM_Eliminate<double, 3>(run, rope()); }
void BM_RopeLanes(benchmark::State& run) { BM_Eliminate<xsimd::batch<double>, 3>(run, rope()); }

BENCHMARK(BM_RagdollScalar)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RagdollLanes)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RagdollLanesPacked)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RagdollScalarInverse)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RagdollLanesPackedInverse)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SceneRagdollScalar)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SceneRagdollLanes)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SceneRagdollLanesInverse)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SceneRagdollFloatLanes)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SceneRagdollFloatLanesInverse)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SceneRagdollLanesSolve)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SceneRagdollLanesPacked)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_SceneRagdollLanesPackedInverse)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RopeScalar)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RopeLanes)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RopeConstraintSpace<double>)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RopeConstraintSpace<xsimd::batch<double>>)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RopeConstraintSpace<float>)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_RopeConstraintSpace<xsimd::batch<float>>)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace limber

BENCHMARK_MAIN();
