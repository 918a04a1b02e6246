// The stairs mesh (make_stairs_mesh) and copies in layers (copies_of): every triangle of the
// stairs faces out of the solid (treads up, risers towards the foot), none is degenerate, and
// the surface is closed (it encloses the stairs' volume); stacked copies never start inside one
// another, and the model's colliders stay one set.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

using ::testing::StartsWith;

struct Triangle {
  Vector3 a, b, c;
  Vector3 normal() const { return (b - a).cross(c - a).normalized(); }
  double area() const { return 0.5 * (b - a).cross(c - a).norm(); }
  Vector3 centre() const { return (a + b + c) / 3; }
};

std::vector<Triangle> triangles(const TriangleMesh& mesh) {
  std::vector<Triangle> out;
  for (const auto& t : mesh.triangles) out.push_back({mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]});
  return out;
}

/// The stairs' coordinates of a world point: s uphill from the foot, t to the left, h up.
struct StairsFrame {
  StairsSpec spec;
  Vector3 d = spec.direction.normalized(), w = Vector3::UnitZ().cross(d);
  Vector3 local(const Vector3& p) const {
    const Vector3 r = p - spec.position;
    return {r.dot(d), r.dot(w), r.z()};
  }
  double length() const { return double(spec.steps - 1) * spec.run + spec.landing; }
  /// Whether `p` is inside the solid: under the tread (or landing) above its place.
  bool inside(const Vector3& p) const {
    const Vector3 q = local(p);
    if (!(q.x() > 0 && q.x() < length() && std::abs(q.y()) < 0.5 * spec.width && q.z() > 0)) return false;
    const double step = std::min(std::floor(q.x() / spec.run), double(spec.steps - 1));
    return q.z() < (step + 1) * spec.rise;
  }
};

const StairsSpec kSpecs[] = {
    {},  // the defaults: 6 steps along +x
    {.steps = 1, .rise = 0.2, .run = 0.5, .width = 1, .landing = 0.7, .position = {1, 2, 3}, .direction = {0, 1, 0}},
    {.steps = 4, .rise = 0.17, .run = 0.28, .width = 1.5, .landing = 1.2, .position = {-1, 0.5, 0.25}, .direction = {-3, 4, 0}},
};

TEST(StairsMesh, EveryTriangleFacesOutOfTheSolidAndNoneIsDegenerate) {
  for (const StairsSpec& spec : kSpecs) {
    const TriangleMesh mesh = make_stairs_mesh(spec);
    const StairsFrame frame{spec};
    EXPECT_EQ(mesh.triangles.size(), 8 * spec.steps + 4);
    for (const Triangle& triangle : triangles(mesh)) {
      ASSERT_GT(triangle.area(), 1e-3);
      // Just in front of its centre is outside the solid, just behind it inside.
      const Vector3 n = triangle.normal(), c = triangle.centre();
      EXPECT_FALSE(frame.inside(c + 1e-6 * n)) << "steps " << spec.steps << ": a triangle at " << c.transpose() << " faces in";
      EXPECT_TRUE(frame.inside(c - 1e-6 * n)) << "steps " << spec.steps << ": a triangle at " << c.transpose() << " has nothing behind it";
    }
  }
}

TEST(StairsMesh, TreadsFaceUpAndRisersFaceTheFoot) {
  for (const StairsSpec& spec : kSpecs) {
    const StairsFrame frame{spec};
    std::vector<int> treads(spec.steps, 0), risers(spec.steps, 0);
    for (const Triangle& triangle : triangles(make_stairs_mesh(spec))) {
      const Vector3 n = triangle.normal(), q = frame.local(triangle.centre());
      if ((n - Vector3::UnitZ()).norm() < 1e-12) {  // a tread: at the height of the riser below it
        const double k = std::round(q.z() / spec.rise) - 1;
        EXPECT_NEAR(q.z(), (k + 1) * spec.rise, 1e-12);
        ++treads.at(static_cast<std::size_t>(k));
      } else if ((n + frame.d).norm() < 1e-12) {  // a riser: facing down the stairs, where its step begins
        const double k = std::round(q.x() / spec.run);
        EXPECT_NEAR(q.x(), k * spec.run, 1e-12);
        ++risers.at(static_cast<std::size_t>(k));
      }
    }
    EXPECT_EQ(treads, std::vector<int>(spec.steps, 2));  // each a quad; the last is the landing
    EXPECT_EQ(risers, std::vector<int>(spec.steps, 2));
  }
}

TEST(StairsMesh, TheSurfaceIsClosedAndEnclosesTheStairsVolume) {
  for (const StairsSpec& spec : kSpecs) {
    Vector3 area_vector = Vector3::Zero();
    double volume = 0;  // divergence theorem: Σ a · (b × c) / 6 over outward triangles
    for (const Triangle& t : triangles(make_stairs_mesh(spec))) {
      area_vector += (t.b - t.a).cross(t.c - t.a) / 2;
      volume += t.a.dot(t.b.cross(t.c)) / 6;
    }
    EXPECT_LT(area_vector.norm(), 1e-12);
    double expected = spec.landing * double(spec.steps) * spec.rise;
    for (std::size_t k = 0; k + 1 < spec.steps; ++k) expected += spec.run * double(k + 1) * spec.rise;
    EXPECT_NEAR(volume, expected * spec.width, 1e-9);
  }
}

TEST(StairsMesh, ANonsenseSpecIsOneLine) {
  const auto error = [](const StairsSpec& spec) {
    try {
      make_stairs_mesh(spec);
    } catch (const ModelError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_EQ(error({.steps = 0}), "stairs.steps: must be >= 1, got 0");
  EXPECT_EQ(error({.rise = -1}), "stairs.rise: must be > 0, got -1");
  EXPECT_EQ(error({.direction = {1, 0, 1}}), "stairs.direction: must be horizontal (z = 0), got [1, 0, 1]");
}

// ---- copies in layers

TEST(CopiesInLayers, StackedCopiesStartApartAndKeepOneSetOfColliders) {
  Model humanoid = load_scene_text(embedded_humanoid_scene(), "humanoid").model;
  humanoid.balls.clear(), humanoid.bounds.reset();
  StaticCollider ramp;
  ramp.name = "ramp", ramp.type = ColliderType::box, ramp.half_extents = {2, 2, 0.1}, ramp.position = {0, 0, -0.2};
  humanoid.colliders.push_back(ramp);
  const double spacing = footprint(humanoid), layer_height = vertical_extent(humanoid);  // as tight as allowed
  const Model pile = copies_of(humanoid, 32, spacing, "h", "pile", 4, layer_height);
  validate(pile);
  ASSERT_EQ(pile.bodies.size(), 32 * humanoid.bodies.size());
  EXPECT_EQ(pile.colliders.size(), 1u);
  // Copy k's bounding box; no two overlap (touching faces, at this tightest spacing, allowed).
  const std::size_t n = humanoid.bodies.size();
  std::vector<Eigen::AlignedBox3d> boxes(32);
  for (std::size_t b = 0; b < pile.bodies.size(); ++b) {
    const Body& body = pile.bodies[b];
    const Vector3 reach = Vector3::Constant(body.shape.radius);
    for (const Vector3& end : {body.head(), body.tail()}) boxes[b / n].extend(end - reach).extend(end + reach);
  }
  for (std::size_t a = 0; a < boxes.size(); ++a) {
    for (std::size_t b = a + 1; b < boxes.size(); ++b) {
      const Eigen::AlignedBox3d common = boxes[a].intersection(boxes[b]);
      EXPECT_TRUE(common.isEmpty() || common.sizes().minCoeff() < 1e-9) << "copies " << a << " and " << b << " overlap";
    }
  }
  // 8 copies a layer; layer l is l · layer_height up, odd layers half a spacing across.
  for (std::size_t k : {0u, 8u, 17u, 31u}) {
    const std::size_t layer = k / 8, place = k % 8;
    const double stagger = layer % 2 == 1 ? 0.5 : 0;
    const Vector3 offset(spacing * (double(place % 3) + stagger), spacing * (double(place / 3) + stagger), layer_height * double(layer));
    EXPECT_LT((pile.bodies[k * n].position - humanoid.bodies[0].position - offset).norm(), 1e-12) << "copy " << k;
  }
  // Layers = 1 is the flat lattice, bit for bit.
  const Model flat = copies_of(humanoid, 5, 1.0, "h", "pile");
  const Model one_layer = copies_of(humanoid, 5, 1.0, "h", "pile", 1, 0);
  for (std::size_t b = 0; b < flat.bodies.size(); ++b) EXPECT_EQ(flat.bodies[b].position, one_layer.bodies[b].position);
}

TEST(CopiesInLayers, TooLowALayerOrTooManyLayersIsRefused) {
  const Model humanoid = load_scene_text(embedded_humanoid_scene(), "humanoid").model;
  const auto error = [&](std::size_t count, std::size_t layers, double layer_height) {
    try {
      copies_of(humanoid, count, 1.0, "h", "pile", layers, layer_height);
    } catch (const ModelError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_THAT(error(8, 2, 0.5), StartsWith("pile.layer_height: must be >= "));
  EXPECT_EQ(error(8, 9, 2), "pile.layers: must be <= count (8), got 9");
  EXPECT_EQ(error(8, 0, 2), "pile.layers: must be >= 1, got 0");
}

TEST(AppendModel, KeepsTheTargetsCollidersOnly) {
  Model target = testing::make_chain({1, 1}, 0.2, false);
  Model other = target;
  StaticCollider wall;
  wall.name = "wall", wall.half_extents = {1, 1, 1};
  other.colliders.push_back(wall);
  append_model(target, other, "b.", Vector3(0, 1, 0));
  EXPECT_EQ(target.bodies.size(), 4u);
  EXPECT_TRUE(target.colliders.empty());  // like ground, bounds and ball: the target's
}

}  // namespace
}  // namespace limber
