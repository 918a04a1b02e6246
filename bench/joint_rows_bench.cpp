// The particle method's joint rows in the coloured sweep, and its exact joint trees' Newton
// step: time per row of each kind (per tree joint) against a plain distance constraint, in one
// run (bench/speed.md, "Joint rows in the coloured sweep, and the exact joint tree").
//
//   build/bench/joint_rows_bench                                  all, 10⁵ joints each
//   build/bench/joint_rows_bench --benchmark_filter=Rows/.*/2     two threads
//
// Each model is `joints` copies of a two-limb body (a torso-like limb held at its head to the
// world, a limb hanging from it) joined by one kind of joint: the 10⁵ joints of some 7,000
// fourteen-joint ragdolls. One sweep over the rows is timed: for "distance", the distance
// constraints (links and zero-length joints: the plain constraint); otherwise the joint rows —
// the joint's own (hinge: axis and range; cone-twist: swing and twist; drive, friction: one
// orientation row) and the two limbs' frame rows — counted from the batches (padding included).
// "cone_twist_tree" times the cone-twist bodies' exact joint trees instead (joint_trees.hpp):
// one Newton step, fresh factor included, per tree joint (the world hold and the cone-twist).
#include <string>

#include <benchmark/benchmark.h>

#include "limber/kernel/relaxation/joint_relaxation.hpp"
#include "limber/kernel/relaxation/joint_trees.hpp"
#include "limber/kernel/relaxation/relaxation.hpp"
#include "limber/kernel/verlet/compile.hpp"
#include "limber/kernel/verlet/step.hpp"

namespace limber {
namespace {

enum Variant : int { distance, hinge_range, cone_twist, drive, friction, cone_twist_tree };

const char* variant_name(int variant) {
  constexpr const char* names[] = {"distance", "hinge_range", "cone_twist", "drive", "friction", "cone_twist_tree"};
  return names[variant];
}

Model jointed_bodies(long count, int variant) {
  Model model;
  model.settings.sleep.enabled = false;
  model.settings.time_step = 1.0 / 60;
  for (long c = 0; c < count; ++c) {
    const Vector3 at(static_cast<double>(c % 300), static_cast<double>(c / 300), 1.0);
    const int first = static_cast<int>(model.bodies.size());
    // Appended, not "t" + std::string&&: GCC 12's -Wrestrict false positive (bug 105329).
    const auto label = [c](const char* kind) { return std::string(kind).append(std::to_string(c)); };
    Body torso;
    torso.name = label("t"), torso.shape = {ShapeType::capsule, 0.4, 0.1}, torso.mass = 30, torso.position = at;
    Body limb;
    limb.name = label("l"), limb.shape = {ShapeType::capsule, 0.4, 0.04}, limb.mass = 5;
    limb.axis = Vector3(0, 0.3, 1).normalized();
    limb.position = torso.tail() - 0.2 * limb.axis;
    limb.angular_velocity = Vector3(1, 2, 3);
    model.bodies.push_back(torso), model.bodies.push_back(limb);
    Joint hold;
    hold.name = label("h"), hold.type = JointType::spherical;
    hold.inboard = kWorld, hold.outboard = first, hold.inboard_anchor = torso.head(), hold.outboard_anchor = Vector3(0, 0, 0.2);
    Joint joint = spherical_joint(label("j"), first, first + 1, Vector3(0, 0, -0.2), Vector3(0, 0, 0.2));
    if (variant == hinge_range) joint.type = JointType::revolute, joint.axis = Vector3::UnitX(), joint.limits.range = Range{-0.5, 0.5};
    if (variant == cone_twist || variant == cone_twist_tree) joint.limits.swing = 0.5, joint.limits.twist = Range{-0.3, 0.3};
    if (variant == drive) joint.drive = JointDrive{.stiffness = 200, .damping = 20, .target_rotation = Vector3(0.2, 0, 0)};
    if (variant == friction) joint.friction = 2;
    model.joints.push_back(hold), model.joints.push_back(joint);
  }
  return model;
}

// One sweep of the distance constraints (the plain row: a zero-length joint) or of the joint
// rows, per constraint or row; or, for the tree, one Newton step of every island's joint tree
// (a fresh factor and a solve: begin_joint_trees drops the factor, and the joints, closed by
// the steps before, take no second step), per tree joint (a joint's rows are one node).
template <typename Scalar>
void BM_Rows(benchmark::State& run) {
  const int variant = static_cast<int>(run.range(0));
  const long joints = run.range(1);
  VerletOptions options;
  options.threads = static_cast<int>(run.range(2));
  options.relaxation.iterations = 1;
  const bool tree = variant == cone_twist_tree;
  if (tree) options.verlet.joint_solve = JointSolve::tree;
  auto state = compile<Scalar>(jointed_bodies(joints, variant), options);
  if (tree && !state.plan.joint_trees.active()) {
    run.SkipWithError("the joints formed no tree");
    return;
  }
  for (int s = 0; s < 3; ++s) step(state);
  begin_relaxation(state, state.settings.time_step);
  const bool rows = variant != distance && !tree;
  double moved = 0;  // the tree's largest move: under 1e-5 m, one Newton step a call
  for (auto _ : run) {
    if (tree) {
      begin_joint_trees(state, state.settings.time_step);
      benchmark::DoNotOptimize(moved = project_joint_trees(state));
    } else {
      benchmark::DoNotOptimize(rows ? joint_position_sweep(state) : relaxation_sweep(state, 1.0));
    }
  }
  end_relaxation(state);
  const double slots = tree ? static_cast<double>(state.plan.joint_trees.joints.size())
                       : rows ? static_cast<double>(state.plan.joint_batches.slot_count())
                              : static_cast<double>(state.constraints.size());
  run.SetLabel(variant_name(variant));
  if (tree) run.counters["move (m)"] = moved;
  run.counters["rows"] = slots;
  run.counters["ns/row"] = benchmark::Counter(slots, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  run.counters["ns/joint"] = benchmark::Counter(static_cast<double>(joints), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
void variants(benchmark::internal::Benchmark* b) {
  for (int threads : {1, 2}) {
    for (int variant : {distance, hinge_range, cone_twist, drive, friction, cone_twist_tree}) b->Args({variant, 100000, threads});
  }
  b->Unit(benchmark::kMillisecond)->UseRealTime();
}
BENCHMARK_TEMPLATE(BM_Rows, float)->Apply(variants);
BENCHMARK_TEMPLATE(BM_Rows, double)->Apply(variants);

}  // namespace
}  // namespace limber

BENCHMARK_MAIN();
