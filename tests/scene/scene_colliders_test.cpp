// The scene file's collision fields: bodies' and colliders' "collision" filters,
// settings.limb_friction, the "colliders" of each type (and the "stairs" generator), stacked
// "copies", and the scenes that use them (ragdoll_pile.json, rope_over_obstacle.json). Each
// field is read into the Model; each bad value is one line naming the file and the field.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "limber/kernel/scene/generators.hpp"
#include "limber/kernel/scene/scene_file.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;
using testing::shipped_scene;

// One free limb above the ground; "COLLIDERS" and "EXTRA" are replaced by each test.
constexpr std::string_view kScene = R"({
  "limber_scene": 1,
  "name": "limb",
  "settings": {"gravity": [0, 0, -9.81], "time_step": 0.01, "duration": 1 EXTRA},
  "ground": {"height": 0, "restitution": 0, "friction": 0.6},
  "bodies": [
    {"name": "limb", "shape": {"type": "capsule", "length": 0.4, "radius": 0.02},
     "mass": 2, "position": [0, 0, 1.3], "axis": [1, 0, 0] BODY}
  ],
  "colliders": [COLLIDERS]
})";

std::string replaced(std::string text, std::string_view marker, std::string_view by) {
  const std::size_t at = text.find(marker);
  if (at != std::string::npos) text.replace(at, marker.size(), by);
  return text;
}

/// The scene with its marks replaced: colliders, a body field, a settings field (each led by a comma).
std::string scene(std::string_view colliders, std::string_view body = "", std::string_view settings = "") {
  return replaced(replaced(replaced(std::string(kScene), "COLLIDERS", colliders), "BODY", body), "EXTRA", settings);
}

Model load(const std::string& text) { return load_scene_text(text, "test.json").model; }

/// The loader's message for `text`; fails the test if it loads or the message is not one line
/// led by the source.
std::string load_error(const std::string& text) {
  try {
    load_scene_text(text, "test.json");
  } catch (const ModelError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
    EXPECT_THAT(message, StartsWith("test.json: "));
    return message;
  }
  ADD_FAILURE() << "loaded without error";
  return "";
}

constexpr std::string_view kBox = R"({"name": "wall", "type": "box", "position": [1, 2, 0.5], "half_extents": [0.1, 1, 0.5]})";

// ---- collision filters and limb friction

TEST(SceneCollisionFilter, BodyGroupAndMaskAreReadAndDefaultToModelDefaults) {
  const Model plain = load(scene(""));
  EXPECT_EQ(plain.bodies[0].collision.group, 1u);
  EXPECT_EQ(plain.bodies[0].collision.mask, 0xFFFFFFFFu);
  const Model given = load(scene("", R"(, "collision": {"group": 4, "mask": 4294967291})"));
  EXPECT_EQ(given.bodies[0].collision.group, 4u);
  EXPECT_EQ(given.bodies[0].collision.mask, 0xFFFFFFFBu);
  const Model mask_only = load(scene("", R"(, "collision": {"mask": 0})"));
  EXPECT_EQ(mask_only.bodies[0].collision.group, 1u);
  EXPECT_EQ(mask_only.bodies[0].collision.mask, 0u);
}

TEST(SceneCollisionFilter, BitsOutsideThirtyTwoAreNamed) {
  EXPECT_EQ(load_error(scene("", R"(, "collision": {"group": -1})")), "test.json: bodies[0].collision.group: must be >= 0, got -1");
  EXPECT_EQ(load_error(scene("", R"(, "collision": {"mask": 4294967296})")),
            "test.json: bodies[0].collision.mask: must be < 2^32 (4294967296), got 4294967296");
  EXPECT_EQ(load_error(scene("", R"(, "collision": {"group": 1.5})")), "test.json: bodies[0].collision.group: must be an integer, got 1.5");
  EXPECT_EQ(load_error(scene("", R"(, "collision": {"layer": 1})")), "test.json: bodies[0].collision: unknown field \"layer\"");
  EXPECT_EQ(load_error(scene(std::string(R"({"name": "wall", "type": "box", "position": [1, 2, 0.5], "half_extents": [0.1, 1, 0.5],
                                             "collision": {"group": "all"}})"))),
            "test.json: colliders[0].collision.group: must be an integer, got string");
}

TEST(SceneCollisionFilter, LimbFrictionIsReadAndChecked) {
  EXPECT_EQ(load(scene("")).settings.limb_friction, 0.5);
  EXPECT_EQ(load(scene("", "", R"(, "limb_friction": 0.8)")).settings.limb_friction, 0.8);
  EXPECT_EQ(load_error(scene("", "", R"(, "limb_friction": -0.1)")), "test.json: settings.limb_friction: must be >= 0, got -0.1");
}

// ---- colliders

TEST(SceneColliders, ABoxTakesPositionRotationVectorAndHalfExtents) {
  const Model model = load(scene(R"({"name": "wall", "type": "box", "position": [1, 2, 0.5], "rotation": [0, 0, 0.5],
                                     "half_extents": [0.1, 1, 0.5], "restitution": 0.2, "friction": 0.9,
                                     "collision": {"group": 2, "mask": 1}})"));
  ASSERT_EQ(model.colliders.size(), 1u);
  const StaticCollider& box = model.colliders[0];
  EXPECT_EQ(box.name, "wall");
  EXPECT_EQ(box.type, ColliderType::box);
  EXPECT_EQ(box.position, Vector3(1, 2, 0.5));
  EXPECT_LT(box.orientation.angularDistance(Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Vector3::UnitZ()))), 1e-12);
  EXPECT_EQ(box.half_extents, Vector3(0.1, 1, 0.5));
  EXPECT_EQ(box.restitution, 0.2);
  EXPECT_EQ(box.friction, 0.9);
  EXPECT_EQ(box.collision.group, 2u);
  EXPECT_EQ(box.collision.mask, 1u);
  // Omitted: no rotation, restitution 0, friction 0.5, the default filter (model.hpp's defaults).
  const StaticCollider plain = load(scene(kBox)).colliders[0];
  EXPECT_TRUE(plain.orientation.isApprox(Eigen::Quaterniond::Identity()));
  EXPECT_EQ(plain.restitution, 0);
  EXPECT_EQ(plain.friction, 0.5);
  EXPECT_EQ(plain.collision.mask, 0xFFFFFFFFu);
}

TEST(SceneColliders, ACapsuleTakesARotationOrAnAxis) {
  const Model model = load(scene(R"({"name": "bar", "type": "capsule", "position": [0, 0, 1], "axis": [0, 2, 0], "length": 1.2, "radius": 0.05},
                                    {"name": "tilted", "type": "capsule", "position": [0, 0, 1], "rotation": [0.3, 0, 0], "length": 0, "radius": 0.1})"));
  ASSERT_EQ(model.colliders.size(), 2u);
  const StaticCollider& bar = model.colliders[0];
  EXPECT_EQ(bar.type, ColliderType::capsule);
  EXPECT_LT((bar.orientation * Vector3::UnitZ() - Vector3::UnitY()).norm(), 1e-12);  // local z onto the axis
  EXPECT_EQ(bar.length, 1.2);
  EXPECT_EQ(bar.radius, 0.05);
  EXPECT_LT(model.colliders[1].orientation.angularDistance(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Vector3::UnitX()))), 1e-12);
  EXPECT_EQ(load_error(scene(R"({"name": "bar", "type": "capsule", "position": [0, 0, 1], "axis": [0, 1, 0], "rotation": [0, 0, 1],
                                 "length": 1, "radius": 0.05})")),
            "test.json: colliders[0]: give either \"rotation\" or \"axis\", not both");
}

TEST(SceneColliders, AMeshIsHeldInWorldCoordinates) {
  // A square facing up, given in a frame turned a quarter about x and moved up 0.5 m.
  const Model model = load(scene(R"({"name": "floor", "type": "mesh", "position": [0, 0, 0.5], "rotation": [1.5707963267948966, 0, 0],
                                     "vertices": [[0, 0, 0], [1, 0, 0], [1, 0, -1], [0, 0, -1]],
                                     "triangles": [[0, 1, 2], [0, 2, 3]], "thickness": 0.05})"));
  const StaticCollider& floor = model.colliders[0];
  EXPECT_EQ(floor.type, ColliderType::mesh);
  ASSERT_EQ(floor.mesh.vertices.size(), 4u);
  ASSERT_EQ(floor.mesh.triangles.size(), 2u);
  EXPECT_LT((floor.mesh.vertices[2] - Vector3(1, 1, 0.5)).norm(), 1e-12);
  for (const auto& triangle : floor.mesh.triangles) {
    const Vector3& a = floor.mesh.vertices[triangle[0]];
    const Vector3 normal = (floor.mesh.vertices[triangle[1]] - a).cross(floor.mesh.vertices[triangle[2]] - a).normalized();
    EXPECT_LT((normal - Vector3::UnitZ()).norm(), 1e-12);
  }
  EXPECT_EQ(floor.thickness, 0.05);
  EXPECT_EQ(floor.position, Vector3::Zero());  // unused: the vertices are world points
}

TEST(SceneColliders, StairsBecomeAClosedMesh) {
  const Model model = load(scene(R"({"name": "stairs", "type": "stairs", "steps": 4, "rise": 0.2, "run": 0.3, "width": 2,
                                     "position": [1, 0, 0], "direction": [0, -3, 0], "landing": 1, "friction": 0.7})"));
  const StaticCollider& stairs = model.colliders[0];
  EXPECT_EQ(stairs.type, ColliderType::mesh);
  EXPECT_EQ(stairs.mesh.triangles.size(), 8u * 4 + 4);
  EXPECT_EQ(stairs.friction, 0.7);
  EXPECT_EQ(stairs.thickness, 0.1);
  double top = 0, far = 0;
  for (const Vector3& vertex : stairs.mesh.vertices) top = std::max(top, vertex.z()), far = std::min(far, vertex.y());
  EXPECT_NEAR(top, 4 * 0.2, 1e-12);
  EXPECT_NEAR(far, -(3 * 0.3 + 1), 1e-12);  // uphill is −y: three treads and the landing
  // Without "landing", the top is one run deep.
  const Model short_top = load(scene(R"({"name": "stairs", "type": "stairs", "steps": 2, "rise": 0.2, "run": 0.3, "width": 2,
                                         "position": [0, 0, 0], "direction": [1, 0, 0]})"));
  double length = 0;
  for (const Vector3& vertex : short_top.colliders[0].mesh.vertices) length = std::max(length, vertex.x());
  EXPECT_NEAR(length, 0.6, 1e-12);
}

// A few bytes of "stairs" could ask for gigabytes (10⁶ steps took 7 GB and minutes): the
// colliders' triangles are counted against SceneOptions::max_triangles before any is made.
TEST(SceneColliders, TrianglesPastTheLimitAreRefusedBeforeTheMeshIsMade) {
  EXPECT_EQ(load_error(scene(R"({"name": "stairs", "type": "stairs", "steps": 1000000, "rise": 0.2, "run": 0.3, "width": 2,
                                 "position": [1, 0, 0], "direction": [1, 0, 0]})")),
            "test.json: colliders[0].steps: asks for 8000004 triangles, more than the 1000000 left of the 1000000 the colliders may have");
  // The limit is on all the colliders together: two stairs of 36 triangles pass 40, one does not.
  const std::string stairs = R"({"name": "NAME", "type": "stairs", "steps": 4, "rise": 0.2, "run": 0.3, "width": 2,
                                 "position": [1, 0, 0], "direction": [1, 0, 0]})";
  const std::string two = replaced(stairs, "NAME", "a") + ", " + replaced(stairs, "NAME", "b");
  SceneOptions options;
  options.max_triangles = 40;
  EXPECT_EQ(load_scene_text(scene(replaced(stairs, "NAME", "a")), "test.json", options).model.colliders.size(), 1u);
  try {
    load_scene_text(scene(two), "test.json", options);
    ADD_FAILURE() << "two stairs of 36 triangles loaded under a limit of 40";
  } catch (const ModelError& error) {
    EXPECT_STREQ(error.what(), "test.json: colliders[1].steps: asks for 36 triangles, more than the 4 left of the 40 the colliders may have");
  }
  // A mesh counts its triangles as given.
  options.max_triangles = 1;
  try {
    load_scene_text(scene(R"({"name": "floor", "type": "mesh", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]],
                              "triangles": [[0, 1, 2], [1, 3, 2]]})"),
                    "test.json", options);
    ADD_FAILURE() << "a mesh of 2 triangles loaded under a limit of 1";
  } catch (const ModelError& error) {
    EXPECT_STREQ(error.what(), "test.json: colliders[0].triangles: asks for 2 triangles, more than the 1 left of the 1 the colliders may have");
  }
}

TEST(SceneColliders, BadCollidersAreNamedByTheirField) {
  EXPECT_EQ(load_error(scene(R"({"name": "wall", "type": "cone", "position": [0, 0, 0]})")),
            "test.json: colliders[0].type: must be \"box\", \"capsule\", \"mesh\" or \"stairs\", got \"cone\"");
  EXPECT_EQ(load_error(scene(R"({"name": "wall", "type": "box", "position": [0, 0, 0], "half_extents": [1, 1, 1], "radius": 1})")),
            "test.json: colliders[0].radius: is not used by a box collider");
  EXPECT_EQ(load_error(scene(R"({"name": "wall", "type": "box", "position": [0, 0, 0], "half_extents": [1, 1, 1], "colour": 1})")),
            "test.json: colliders[0]: unknown field \"colour\"");
  EXPECT_EQ(load_error(scene(R"({"name": "wall", "type": "box", "position": [0, 0, 0]})")),
            "test.json: colliders[0].half_extents: missing required field");
  EXPECT_EQ(load_error(scene(R"({"name": "wall", "type": "box", "position": [0, 0, 0], "half_extents": [1, 0, 1]})")),
            "test.json: colliders[0].half_extents[1]: must be > 0, got 0");
  EXPECT_EQ(load_error(scene(R"({"name": "bar", "type": "capsule", "position": [0, 0, 0], "length": -1, "radius": 0.1})")),
            "test.json: colliders[0].length: must be >= 0, got -1");
  EXPECT_EQ(load_error(scene(R"({"name": "bar", "type": "capsule", "position": [0, 0, 0], "length": 1, "radius": 0})")),
            "test.json: colliders[0].radius: must be > 0, got 0");
  EXPECT_EQ(load_error(scene(std::string(kBox) + ", " + R"({"name": "wall", "type": "box", "position": [0, 0, 0], "half_extents": [1, 1, 1], "friction": -1})")),
            "test.json: colliders[1].friction: must be >= 0, got -1");
  EXPECT_EQ(load_error(scene(std::string(kBox) + ", " + std::string(kBox))),
            "test.json: colliders[1].name: duplicate name \"wall\" (also colliders[0])");
  EXPECT_EQ(load_error(scene(R"({"name": "limb", "type": "box", "position": [3, 0, 0], "half_extents": [1, 1, 1]})")),
            "test.json: colliders[0].name: \"limb\" is also a body's name");
  EXPECT_EQ(load_error(scene(R"({"name": "wall", "type": "box", "position": [0, 0, 0], "half_extents": [1, 1, 1], "restitution": 2})")),
            "test.json: colliders[0].restitution: must be in [0, 1], got 2");
  EXPECT_EQ(load_error(replaced(scene(""), R"("colliders": [])", R"("colliders": {})")), "test.json: colliders: must be an array, got object");
}

TEST(SceneColliders, BadMeshesAndStairsAreNamedByTheirField) {
  const auto mesh = [](std::string_view vertices, std::string_view triangles) {
    return scene(R"({"name": "floor", "type": "mesh", "vertices": )" + std::string(vertices) + R"(, "triangles": )" + std::string(triangles) + "}");
  };
  const std::string square = "[[0, 0, 0], [1, 0, 0], [1, 1, 0]]";
  EXPECT_EQ(load_error(mesh(square, "[[0, 1, 2], [0, 2, 7]]")),
            "test.json: colliders[0].triangles[1]: vertex index 7 names no vertex (there are 3)");
  const std::string none = "test.json: colliders[0].triangles: mesh \"floor\" has no useful triangle: of ";
  const std::string counts = " degenerate (no area: repeated or collinear vertices) and ";
  EXPECT_EQ(load_error(mesh("[[0, 0, 0], [1, 0, 0], [2, 0, 0]]", "[[0, 1, 2]]")),
            none + "1, 1" + counts + "0 duplicate (the same corners as an earlier triangle)");
  EXPECT_EQ(load_error(mesh(square, "[[0, 1, 1], [0, 1, 1]]")), none + "2, 2" + counts + "0 duplicate (the same corners as an earlier triangle)");
  EXPECT_EQ(load_error(mesh(square, "[[0, 1]]")), "test.json: colliders[0].triangles[0]: must be an array of 3 vertex indices, got an array of 2");
  EXPECT_EQ(load_error(mesh(square, "[[0, -1, 2]]")), "test.json: colliders[0].triangles[0][1]: must be >= 0, got -1");
  EXPECT_EQ(load_error(mesh(square, "[]")), "test.json: colliders[0].triangles: must list at least one triangle");
  EXPECT_EQ(load_error(mesh("[[0, 0, 0], [1, 0], [1, 1, 0]]", "[[0, 1, 2]]")),
            "test.json: colliders[0].vertices[1]: must be an array of 3 numbers, got an array of 2");
  EXPECT_EQ(load_error(scene(R"({"name": "floor", "type": "mesh", "vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0]], "triangles": [[0, 1, 2]],
                                 "thickness": 0})")),
            "test.json: colliders[0].thickness: must be > 0, got 0");
  const auto stairs = [](std::string_view field) {
    return scene(R"({"name": "stairs", "type": "stairs", "steps": 3, "rise": 0.2, "run": 0.3, "width": 2, "position": [0, 0, 0], )" +
                 std::string(field) + "}");
  };
  EXPECT_EQ(load_error(stairs(R"("direction": [1, 0, 0.1])")), "test.json: colliders[0].direction: must be horizontal (z = 0), got [1, 0, 0.1]");
  EXPECT_EQ(load_error(stairs(R"("direction": [0, 0, 0])")), "test.json: colliders[0].direction: must be a non-zero vector, got [0, 0, 0]");
  EXPECT_EQ(load_error(stairs(R"("direction": [1, 0, 0], "landing": 0)")), "test.json: colliders[0].landing: must be > 0, got 0");
  EXPECT_EQ(load_error(stairs(R"("direction": [1, 0, 0], "half_extents": [1, 1, 1])")),
            "test.json: colliders[0].half_extents: is not used by a stairs collider");
  EXPECT_EQ(load_error(replaced(stairs(R"("direction": [1, 0, 0])"), R"("steps": 3)", R"("steps": 0)")),
            "test.json: colliders[0].steps: must be >= 1, got 0");
}

// ---- copies in layers

constexpr std::string_view kCopies = R"({
  "limber_scene": 1,
  "name": "limbs",
  "settings": {"gravity": [0, 0, -9.81], "time_step": 0.01, "duration": 1},
  "colliders": [{"name": "floor", "type": "box", "position": [0, 0, -0.5], "half_extents": [5, 5, 0.5]}],
  "bodies": [
    {"name": "limb", "shape": {"type": "capsule", "length": 0.4, "radius": 0.02},
     "mass": 2, "position": [0, 0, 1.3], "axis": [0, 0, 1]}
  ],
  "copies": COPIES
})";

std::string copies(std::string_view value) { return replaced(std::string(kCopies), "COPIES", value); }

// A mesh collider "floor" of `vertices` and `triangles` (JSON arrays) as a scene.
std::string floor_mesh(std::string_view vertices, std::string_view triangles) {
  return scene(R"({"name": "floor", "type": "mesh", "vertices": )" + std::string(vertices) + R"(, "triangles": )" + std::string(triangles) + "}");
}

TEST(SceneColliders, DuplicateTrianglesAreDroppedWithANote) {
  // A square of two triangles, the first listed 10⁴ times more, from another corner and through
  // vertex 4 at vertex 0's point; the first turned over faces down, so it stays.
  const std::string vertices = "[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 0]]";
  std::string triangles = "[[0, 1, 2], [0, 2, 3]";
  for (int k = 0; k < 10'000; ++k) triangles += ", [0, 1, 2]";
  triangles += ", [1, 2, 0], [4, 1, 2], [0, 2, 1]]";
  const Scene loaded = load_scene_text(floor_mesh(vertices, triangles), "test.json");
  using Triangle = std::array<std::uint32_t, 3>;
  EXPECT_EQ(loaded.model.colliders[0].mesh.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}, {0, 2, 1}}));
  EXPECT_EQ(loaded.notes, std::vector<std::string>{"test.json: colliders[0].triangles: dropped 10002 of 10005 triangles of mesh \"floor\", "
                                                   "0 degenerate (no area: repeated or collinear vertices) and 10002 duplicate (the same corners "
                                                   "as an earlier triangle): they add no surface, only cost"});
}

TEST(SceneColliders, DegenerateTrianglesAreDroppedWithANote) {
  // The square, a triangle with a repeated vertex and one whose corners are in a line.
  const std::string vertices = "[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0]]";
  const Scene loaded = load_scene_text(floor_mesh(vertices, "[[0, 1, 1], [0, 1, 2], [0, 1, 4], [0, 2, 3]]"), "test.json");
  using Triangle = std::array<std::uint32_t, 3>;
  EXPECT_EQ(loaded.model.colliders[0].mesh.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}}));
  ASSERT_EQ(loaded.notes.size(), 1u);
  EXPECT_THAT(loaded.notes[0], StartsWith("test.json: colliders[0].triangles: dropped 2 of 4 triangles of mesh \"floor\", 2 degenerate"));
  // A clean mesh adds no note.
  EXPECT_TRUE(load_scene_text(floor_mesh(vertices, "[[0, 1, 2], [0, 2, 3]]"), "test.json").notes.empty());
}

TEST(SceneCopies, LayersStackTheLatticesAndKeepOneSetOfColliders) {
  const Model model = load(copies(R"({"count": 7, "spacing": 1, "layers": 2, "layer_height": 0.5})"));
  ASSERT_EQ(model.bodies.size(), 7u);
  EXPECT_EQ(model.colliders.size(), 1u);  // like the ground: once, not per copy
  // 4 per layer, 2 by 2; the upper layer 0.5 m up and half a spacing across.
  EXPECT_EQ(model.bodies[3].position, Vector3(1, 1, 1.3));
  EXPECT_EQ(model.bodies[4].name, "c4.limb");
  EXPECT_EQ(model.bodies[4].position, Vector3(0.5, 0.5, 1.8));
  EXPECT_EQ(model.bodies[6].position, Vector3(0.5, 1.5, 1.8));
  // Without layers: one lattice, as before.
  const Model flat = load(copies(R"({"count": 7, "spacing": 1})"));
  EXPECT_EQ(flat.bodies[6].position, Vector3(0, 2, 1.3));
}

TEST(SceneCopies, PerLayerFillsFullLatticesFromTheBottomWhateverTheCount) {
  // 3 to a layer (2 by 2 lattices): copy 3 opens the second layer, copy 6 the third.
  const Model model = load(copies(R"({"count": 7, "spacing": 1, "per_layer": 3, "layer_height": 0.5})"));
  ASSERT_EQ(model.bodies.size(), 7u);
  EXPECT_EQ(model.bodies[2].position, Vector3(0, 1, 1.3));
  EXPECT_EQ(model.bodies[3].position, Vector3(0.5, 0.5, 1.8));
  EXPECT_EQ(model.bodies[6].position, Vector3(0, 0, 2.3));
  // A count from --copies keeps the layers' size: 2 copies are one layer's first two.
  SceneOptions two;
  two.copies = 2;
  const Model fewer = load_scene_text(copies(R"({"count": 7, "spacing": 1, "per_layer": 3, "layer_height": 0.5})"), "test.json", two).model;
  ASSERT_EQ(fewer.bodies.size(), 2u);
  EXPECT_EQ(fewer.bodies[1].position, Vector3(1, 0, 1.3));
  // So does one copy, where "layers" would refuse a count below it.
  two.copies = 1;
  EXPECT_EQ(load_scene_text(copies(R"({"count": 7, "spacing": 1, "per_layer": 3, "layer_height": 0.5})"), "test.json", two).model.bodies.size(), 1u);
}

TEST(SceneCopies, BadLayersAreNamed) {
  EXPECT_EQ(load_error(copies(R"({"count": 4, "spacing": 1, "layers": 0, "layer_height": 1})")), "test.json: copies.layers: must be >= 1, got 0");
  EXPECT_EQ(load_error(copies(R"({"count": 4, "spacing": 1, "layers": 5, "layer_height": 1})")), "test.json: copies.layers: must be <= count (4), got 5");
  EXPECT_EQ(load_error(copies(R"({"count": 4, "spacing": 1, "layers": 2})")), "test.json: copies.layer_height: missing required field");
  EXPECT_EQ(load_error(copies(R"({"count": 4, "spacing": 1, "layer_height": 1})")),
            "test.json: copies.layer_height: is used only with \"layers\" or \"per_layer\"");
  EXPECT_EQ(load_error(copies(R"({"count": 4, "spacing": 1, "layers": 2, "per_layer": 2, "layer_height": 1})")),
            "test.json: copies.per_layer: is used only without \"layers\" (give one of them)");
  EXPECT_EQ(load_error(copies(R"({"count": 4, "spacing": 1, "per_layer": 0, "layer_height": 1})")), "test.json: copies.per_layer: must be >= 1, got 0");
  EXPECT_EQ(load_error(copies(R"({"count": 4, "spacing": 1, "per_layer": 2})")), "test.json: copies.layer_height: missing required field");
  EXPECT_THAT(load_error(copies(R"({"count": 4, "spacing": 1, "per_layer": 2, "layer_height": 0.2})")),
              StartsWith("test.json: copies.layer_height: must be >= 0.4"));
  EXPECT_THAT(load_error(copies(R"({"count": 4, "spacing": 1, "layers": 2, "layer_height": 0.2})")),
              StartsWith("test.json: copies.layer_height: must be >= 0.4"));  // 0.44 m, the limb's height
  EXPECT_THAT(load_error(copies(R"({"count": 4, "spacing": 1, "layers": 2, "layer_height": 0.2})")),
              HasSubstr(" (the bodies' height, m) so layers do not overlap, got 0.2"));
}

// ---- the scenes

/// Each copy's bounding box (limb ends ± radius), copies named "c<k>.".
std::vector<Eigen::AlignedBox3d> copy_boxes(const Model& model) {
  std::vector<Eigen::AlignedBox3d> boxes;
  for (const Body& body : model.bodies) {
    const std::size_t copy = std::stoul(body.name.substr(1, body.name.find('.') - 1));
    if (copy >= boxes.size()) boxes.resize(copy + 1);
    const Vector3 reach = Vector3::Constant(body.shape.radius);
    for (const Vector3& end : {body.head(), body.tail()}) boxes[copy].extend(end - reach).extend(end + reach);
  }
  return boxes;
}

TEST(PileScene, ThirtyTwoRagdollsStartApartAboveTheStairsInEveryVariant) {
  const Model ragdoll = shipped_scene("ragdoll.json").model;
  for (const char* variant : {"thin", "medium", "wide"}) {
    SceneOptions options;
    options.variant = variant;
    const Scene scene = shipped_scene("ragdoll_pile.json", options);
    const Model& model = scene.model;
    EXPECT_THAT(model.name, HasSubstr("pile"));
    ASSERT_EQ(model.bodies.size(), 32 * ragdoll.bodies.size()) << variant;
    EXPECT_EQ(model.joints.size(), 32 * ragdoll.joints.size());
    EXPECT_TRUE(model.balls.empty());
    EXPECT_TRUE(model.settings.sleep.enabled);
    EXPECT_FALSE(model.settings.sleep.start_asleep);
    EXPECT_EQ(model.settings.duration, 3);
    ASSERT_EQ(model.colliders.size(), 1u);
    const StaticCollider& stairs = model.colliders[0];
    EXPECT_EQ(stairs.type, ColliderType::mesh);
    double top = -1;
    for (const Vector3& vertex : stairs.mesh.vertices) top = std::max(top, vertex.z());
    // Copy 0 is ragdoll.json's body (the medium variant's) raised by 1 m.
    if (std::string(variant) == "medium") {
      for (std::size_t b = 0; b < ragdoll.bodies.size(); ++b) {
        EXPECT_EQ(model.bodies[b].name, "c0." + ragdoll.bodies[b].name);
        EXPECT_LT((model.bodies[b].position - ragdoll.bodies[b].position - Vector3(0, 0, 1)).norm(), 1e-9);
        EXPECT_EQ(model.bodies[b].mass, ragdoll.bodies[b].mass);
      }
    }
    // No two copies overlap, every one starts above the stairs' top and over the stairs.
    const std::vector<Eigen::AlignedBox3d> boxes = copy_boxes(model);
    ASSERT_EQ(boxes.size(), 32u);
    Eigen::AlignedBox3d stairs_box;
    for (const Vector3& vertex : stairs.mesh.vertices) stairs_box.extend(vertex);
    for (std::size_t a = 0; a < boxes.size(); ++a) {
      EXPECT_GT(boxes[a].min().z(), top) << variant << " copy " << a;
      EXPECT_TRUE((boxes[a].min().head<2>().array() >= stairs_box.min().head<2>().array()).all() &&
                  (boxes[a].max().head<2>().array() <= stairs_box.max().head<2>().array()).all())
          << variant << " copy " << a << " is not over the stairs";
      for (std::size_t b = a + 1; b < boxes.size(); ++b) {
        EXPECT_TRUE(boxes[a].intersection(boxes[b]).isEmpty()) << variant << " copies " << a << " and " << b << " overlap";
      }
    }
  }
}

TEST(RainScene, ThreeHundredRagdollsStartApartAboveTheStairsTopTumblingAThirdOfThemOverTheStairs) {
  const Model ragdoll = shipped_scene("ragdoll.json").model;
  for (const char* variant : {"thin", "wide"}) {
    SceneOptions options;
    options.variant = variant;
    const Model model = shipped_scene("rain.json", options).model;
    ASSERT_EQ(model.bodies.size(), 300 * ragdoll.bodies.size()) << variant;
    EXPECT_EQ(model.joints.size(), 300 * ragdoll.joints.size());
    ASSERT_EQ(model.colliders.size(), 1u);
    double top = -1;
    Eigen::AlignedBox3d stairs_box;
    for (const Vector3& vertex : model.colliders[0].mesh.vertices) stairs_box.extend(vertex), top = std::max(top, vertex.z());
    const std::vector<Eigen::AlignedBox3d> boxes = copy_boxes(model);
    ASSERT_EQ(boxes.size(), 300u);
    std::size_t over_stairs = 0;
    for (std::size_t a = 0; a < boxes.size(); ++a) {
      EXPECT_GT(boxes[a].min().z(), top) << variant << " copy " << a;
      const Eigen::Vector2d centre = boxes[a].center().head<2>();
      over_stairs += (centre.array() >= stairs_box.min().head<2>().array()).all() && (centre.array() <= stairs_box.max().head<2>().array()).all();
      for (std::size_t b = a + 1; b < boxes.size(); ++b) {
        EXPECT_TRUE(boxes[a].intersection(boxes[b]).isEmpty()) << variant << " copies " << a << " and " << b << " overlap";
      }
    }
    EXPECT_EQ(over_stairs, 95u) << variant;  // as its description says (centres over the stairs)
    // Each copy tumbles as one rigid body: both sides of every joint start at one velocity.
    for (const Joint& joint : model.joints) {
      const Body& inboard = model.bodies[std::size_t(joint.inboard)];
      const Body& outboard = model.bodies[std::size_t(joint.outboard)];
      EXPECT_LT((inboard.velocity_at(joint.inboard_anchor) - outboard.velocity_at(joint.outboard_anchor)).norm(), 1e-9) << joint.name;
      EXPECT_GT(inboard.angular_velocity.norm(), 1.0) << joint.name;
    }
  }
  // --copies N fills the lowest layers first: 150 are a full layer and half of the next.
  SceneOptions crowd;
  crowd.copies = 150;
  const std::vector<Eigen::AlignedBox3d> boxes = copy_boxes(shipped_scene("rain.json", crowd).model);
  ASSERT_EQ(boxes.size(), 150u);
  EXPECT_NEAR(boxes[100].min().z() - boxes[99].min().z(), 1.4, 1e-9);
  EXPECT_NEAR(boxes[149].min().z(), boxes[100].min().z(), 1e-9);
}

TEST(RopeScene, AnUnpinnedRopeStartsAboveABarAndASlab) {
  const Model model = shipped_scene("rope_over_obstacle.json").model;
  ASSERT_EQ(model.bodies.size(), 24u);
  EXPECT_EQ(model.joints.size(), 23u);  // unpinned: link to link only
  ASSERT_EQ(model.colliders.size(), 2u);
  const StaticCollider& bar = model.colliders[0];
  EXPECT_EQ(bar.type, ColliderType::capsule);
  EXPECT_EQ(model.colliders[1].type, ColliderType::box);
  ASSERT_TRUE(model.ground.has_value());
  EXPECT_TRUE(model.balls.empty());
  // The bar's core spans y; the rope lies across it, above it.
  const Vector3 core = bar.orientation * Vector3::UnitZ();
  EXPECT_NEAR(std::abs(core.dot(Vector3::UnitY())), 1, 1e-12);
  bool crosses = false;
  for (const Body& link : model.bodies) {
    EXPECT_GT(link.position.z() - link.shape.radius, bar.position.z() + bar.radius + 0.1);
    crosses = crosses || (std::min(link.head().x(), link.tail().x()) <= bar.position.x() &&
                          bar.position.x() <= std::max(link.head().x(), link.tail().x()));
  }
  EXPECT_TRUE(crosses);
}

}  // namespace
}  // namespace limber
