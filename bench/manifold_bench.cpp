// limber's closed-form contact manifolds (kernel/geometry/manifolds.hpp): ns a pair and points a
// manifold, on the shapes and poses of bench/convex_pairs.cpp (bench/collision.md, "Convex pairs"):
// box 20×12×6 cm against a plank 30×8×4 cm, a capsule of radius 4 cm and core 24 cm against the
// box, a sphere of radius 6 cm against the box, and the box against the ground plane. 256 fixed
// poses a pair: random orientations, the second shape's centre along a random direction from the
// first's at their touching distance (bisection on the manifold with no margin) less 0.2–10 mm
// (half the poses) or plus 0.2–20 mm (the other half); a margin of 25 mm, so the separated poses
// give speculative points too.
//
//   build/bench/manifold_bench --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
//
// convex_pairs cannot link limber (Debian's FCL is built for baseline x86-64; limber for this
// CPU), so the two programs race in separate runs: compare their ns, not within one run. MuJoCo
// (libmujoco-dev) races here, in the same run, where it is found: its box–box function
// (mjCOLLISIONFUNC[box][box], `mjc_BoxBox`, called on the same 256 poses, the boxes' frames set
// straight into mjData) against limber's.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "limber/kernel/geometry/manifolds.hpp"

#ifdef LIMBER_HAS_MUJOCO
#include <mujoco/mujoco.h>
#endif

namespace limber {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr int kPoses = 256;
constexpr double kMargin = 0.025;  // m

Matrix3d random_rotation(std::mt19937& random) {
  std::normal_distribution<double> normal;
  return Eigen::Quaterniond(normal(random), normal(random), normal(random), normal(random)).normalized().toRotationMatrix();
}

Vector3d random_direction(std::mt19937& random) {
  std::normal_distribution<double> normal;
  return Vector3d(normal(random), normal(random), normal(random)).normalized();
}

// A pair's manifold as a function of the second shape's centre offset from the first's.
using PairAt = std::function<Manifold(const Vector3d& offset, double margin)>;

// The offsets of kPoses poses: along a random direction, at the touching distance found by
// bisection, less 0.2–10 mm or plus 0.2–20 mm.
std::vector<Vector3d> poses(const std::function<PairAt(std::mt19937&)>& make, std::vector<PairAt>& pairs, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> into(0.0002, 0.010), apart(0.0002, 0.020);
  std::vector<Vector3d> offsets;
  for (int k = 0; k < kPoses; ++k) {
    PairAt pair = make(random);
    const Vector3d direction = random_direction(random);
    double touching = 0, far = 2;  // m: overlapping at 0, apart at 2
    for (int i = 0; i < 60; ++i) {
      const double middle = 0.5 * (touching + far);
      (pair(middle * direction, 0).count > 0 ? touching : far) = middle;
    }
    offsets.push_back((touching + (k % 2 == 0 ? -into(random) : apart(random))) * direction);
    pairs.push_back(std::move(pair));
  }
  return offsets;
}

void run(benchmark::State& state, const std::function<PairAt(std::mt19937&)>& make, unsigned seed) {
  std::vector<PairAt> pairs;
  const std::vector<Vector3d> offsets = poses(make, pairs, seed);
  std::int64_t points = 0, manifolds = 0;
  for (auto _ : state) {
    for (int k = 0; k < kPoses; ++k) {
      const Manifold m = pairs[static_cast<std::size_t>(k)](offsets[static_cast<std::size_t>(k)], kMargin);
      benchmark::DoNotOptimize(m);
      points += m.count, manifolds += m.count > 0;
    }
  }
  state.SetItemsProcessed(state.iterations() * kPoses);
  state.counters["ns_a_pair"] = benchmark::Counter(static_cast<double>(state.iterations() * kPoses), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["points_a_manifold"] = manifolds > 0 ? static_cast<double>(points) / static_cast<double>(manifolds) : 0.0;
}

const Vector3d kBox(0.10, 0.06, 0.03), kPlank(0.15, 0.04, 0.02);  // half-extents, m

void BM_BoxBox(benchmark::State& state) {
  run(state, [](std::mt19937& random) -> PairAt {
    const Matrix3d a = random_rotation(random), b = random_rotation(random);
    return [a, b](const Vector3d& offset, double margin) { return box_box_manifold({offset, kPlank, b}, {Vector3d::Zero(), kBox, a}, margin); };
  }, 1);
}

void BM_CapsuleBox(benchmark::State& state) {
  run(state, [](std::mt19937& random) -> PairAt {
    const Matrix3d a = random_rotation(random);
    const Vector3d axis = random_direction(random) * 0.12;
    return [a, axis](const Vector3d& offset, double margin) {
      return capsule_box_manifold({offset - axis, offset + axis, 0.04}, {Vector3d::Zero(), kBox, a}, margin);
    };
  }, 2);
}

void BM_SphereBox(benchmark::State& state) {
  run(state, [](std::mt19937& random) -> PairAt {
    const Matrix3d a = random_rotation(random);
    return [a](const Vector3d& offset, double margin) { return capsule_box_manifold({offset, offset, 0.06}, {Vector3d::Zero(), kBox, a}, margin); };
  }, 3);
}

void BM_BoxPlane(benchmark::State& state) {
  run(state, [](std::mt19937& random) -> PairAt {
    const Matrix3d a = random_rotation(random);
    return [a](const Vector3d& offset, double margin) {
      // The ground at the offset's distance below the box, its normal the offset's direction.
      const Vector3d n = offset.normalized();
      return box_plane_manifold({Vector3d::Zero(), kBox, a}, Plane{n, -offset.norm(), 0, 0}, margin);
    };
  }, 4);
}

BENCHMARK(BM_BoxBox);

#ifdef LIMBER_HAS_MUJOCO
// MuJoCo's box–box on the poses of BM_BoxBox (the same seed and the same draws): two box geoms of
// free bodies, their frames written into mjData's geom_xpos and geom_xmat (row-major), the pair
// function called directly with the same margin. Its contacts a pair are `points_a_manifold`.
void BM_MujocoBoxBox(benchmark::State& state) {
  static const char* kXml = R"(<mujoco><worldbody>
    <body><freejoint/><geom type="box" size="0.15 0.04 0.02"/></body>
    <body><freejoint/><geom type="box" size="0.10 0.06 0.03"/></body>
  </worldbody></mujoco>)";
  char error[1000] = "";
  const auto vfs = std::make_unique<mjVFS>();  // megabytes: not on the stack
  mj_defaultVFS(vfs.get());
  mj_makeEmptyFileVFS(vfs.get(), "boxes.xml", static_cast<int>(std::strlen(kXml)));
  std::memcpy(vfs->filedata[vfs->nfile - 1], kXml, std::strlen(kXml));
  mjModel* model = mj_loadXML("boxes.xml", vfs.get(), error, sizeof error);
  mj_deleteVFS(vfs.get());
  if (!model) {
    state.SkipWithError(error);
    return;
  }
  mjData* data = mj_makeData(model);
  mjContact contacts[mjMAXCONPAIR];
  const auto place = [data](int geom, const Vector3d& centre, const Matrix3d& rotation) {
    for (int k = 0; k < 3; ++k) data->geom_xpos[3 * geom + k] = centre[k];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) data->geom_xmat[9 * geom + 3 * r + c] = rotation(r, c);
    }
  };
  run(state, [&](std::mt19937& random) -> PairAt {
    const Matrix3d a = random_rotation(random), b = random_rotation(random);
    return [=, &contacts](const Vector3d& offset, double margin) {
      place(0, offset, b), place(1, Vector3d::Zero(), a);
      Manifold manifold;  // only its count: MuJoCo's contacts
      manifold.count = mjCOLLISIONFUNC[mjGEOM_BOX][mjGEOM_BOX](model, data, contacts, 0, 1, margin);
      return manifold;
    };
  }, 1);
  mj_deleteData(data);
  mj_deleteModel(model);
}
BENCHMARK(BM_MujocoBoxBox);
#endif
BENCHMARK(BM_CapsuleBox);
BENCHMARK(BM_SphereBox);
BENCHMARK(BM_BoxPlane);

}  // namespace
}  // namespace limber

BENCHMARK_MAIN();
