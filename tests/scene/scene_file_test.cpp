// The scene loader: every bad input gives one line naming source, field and problem; the
// shipped scenes load with the thesis's numbers.
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "limber/kernel/scene/scene_file.hpp"

namespace limber {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr double kPound = 0.45359237;  // kg
const std::string kScenes = LIMBER_SOURCE_DIR "/tools/scenes/";

// A pendulum of two limbs pinned to the world, with ground and ball: valid as written.
// upper spans z 1.1..1.5, lower z 0.9..1.1.
constexpr std::string_view kPendulum = R"({
  "limber_scene": 1,
  "name": "pendulum",
  "settings": {"gravity": [0, 0, -9.81], "time_step": 0.01, "duration": 1},
  "ground": {"height": 0, "restitution": 0.1, "friction": 0.6},
  "ball": {"radius": 0.05, "mass": 2.5, "restitution": 0.8, "position": [1, 0, 0.5],
           "speed": 6, "direction": [-2, 0, 0]},
  "bodies": [
    {"name": "upper", "shape": {"type": "cylinder", "length": 0.4, "radius": 0.02},
     "mass": 2, "position": [0, 0, 1.3], "axis": [0, 0, 3]},
    {"name": "lower", "shape": {"type": "capsule", "length": 0.2, "radius": 0.01},
     "density": 1000, "position": [0, 0, 1.0], "axis": [0, 0, 1]}
  ],
  "joints": [
    {"name": "pin", "type": "spherical", "inboard": "world", "outboard": "upper",
     "inboard_anchor": [0, 0, 1.5], "outboard_anchor": "head"},
    {"name": "elbow", "type": "spherical", "inboard": "upper", "outboard": "lower",
     "inboard_anchor": "tail", "outboard_anchor": "head"}
  ]
})";

/// `text` with its one occurrence of `from` replaced by `to` (fails the test if absent).
std::string with(std::string_view text, std::string_view from, std::string_view to) {
  std::string result(text);
  const std::size_t at = result.find(from);
  EXPECT_NE(at, std::string::npos) << "test setup: \"" << from << "\" not in the scene";
  EXPECT_EQ(result.find(from, at + 1), std::string::npos) << "test setup: \"" << from << "\" twice";
  if (at != std::string::npos) result.replace(at, from.size(), to);
  return result;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

/// The loader's message for `text` (source "test.json"); fails the test if it loads.
std::string load_error(std::string_view text, const SceneOptions& options = {}) {
  try {
    load_scene_text(text, "test.json", options);
  } catch (const ModelError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
    EXPECT_THAT(message, StartsWith("test.json"));
    return message;
  }
  ADD_FAILURE() << "loaded without error";
  return "";
}

std::string pendulum_error(std::string_view from, std::string_view to) {
  return load_error(with(kPendulum, from, to));
}

// ---- Bad input: one line naming source, field and problem

TEST(SceneErrors, MalformedJsonReportsLineAndColumn) {
  const std::string message = load_error("{\n  \"name\": \"x\",\n  \"settings\": }\n");
  EXPECT_THAT(message, StartsWith("test.json:3:15: malformed JSON: "));
  EXPECT_THAT(message, HasSubstr("unexpected '}'"));
}

TEST(SceneErrors, TruncatedJsonReportsTheEnd) {
  EXPECT_THAT(load_error("{\"limber_scene\": 1,\n"), StartsWith("test.json:2:1: malformed JSON: "));
}

TEST(SceneErrors, MissingRequiredFieldIsNamed) {
  EXPECT_EQ(pendulum_error(R"("mass": 2, "position": [0, 0, 1.3], )", R"("mass": 2, )"),
            "test.json: bodies[0].position: missing required field");
  EXPECT_EQ(pendulum_error(R"("duration": 1)", R"("damping": 0)"),
            "test.json: settings.duration: missing required field");
}

TEST(SceneErrors, UnknownFieldIsNamed) {
  EXPECT_EQ(pendulum_error(R"("mass": 2,)", R"("masss": 2,)"),
            "test.json: bodies[0]: unknown field \"masss\"");
  EXPECT_EQ(pendulum_error(R"("duration": 1)", R"("duration": 1, "substeps": 4)"),
            "test.json: settings: unknown field \"substeps\"");
}

TEST(SceneErrors, WrongTypeIsNamed) {
  EXPECT_EQ(pendulum_error(R"("mass": 2,)", R"("mass": "2",)"),
            "test.json: bodies[0].mass: must be a number, got string");
  EXPECT_EQ(pendulum_error(R"("position": [0, 0, 1.3])", R"("position": [0, 1.3])"),
            "test.json: bodies[0].position: must be an array of 3 numbers, got an array of 2");
}

TEST(SceneErrors, IntegerFieldRejectsAFraction) {
  const std::string fraction = R"("duration": 1, "relaxation": {"iterations": 2.5})";
  EXPECT_EQ(pendulum_error(R"("duration": 1)", fraction),
            "test.json: settings.relaxation.iterations: must be an integer, got 2.5");
}

TEST(SceneErrors, NegativeMassIsRejected) {
  EXPECT_EQ(pendulum_error(R"("mass": 2,)", R"("mass": -1,)"),
            "test.json: bodies[0].mass: must be > 0, got -1");
}

TEST(SceneErrors, ZeroMassIsRejected) {
  EXPECT_EQ(pendulum_error(R"("mass": 2,)", R"("mass": 0,)"),
            "test.json: bodies[0].mass: must be > 0, got 0");
}

TEST(SceneErrors, NegativeRadiusIsRejected) {
  EXPECT_EQ(pendulum_error(R"("radius": 0.01})", R"("radius": -0.01})"),
            "test.json: bodies[1].shape.radius: must be >= 0, got -0.01");
}

TEST(SceneErrors, NonFiniteNumberIsRejected) {
  EXPECT_EQ(pendulum_error(R"([0, 0, 1.0])", R"([0, 1e999, 1.0])"),
            "test.json: bodies[1].position[1]: must be a finite number, got 1e999");
}

TEST(SceneErrors, JointNamingAMissingBodyIsRejected) {
  EXPECT_EQ(pendulum_error(R"("outboard": "lower")", R"("outboard": "lowr")"),
            "test.json: joints[1].outboard: no body named \"lowr\"");
}

TEST(SceneErrors, NonPositiveTimeStepIsRejected) {
  EXPECT_EQ(pendulum_error(R"("time_step": 0.01)", R"("time_step": 0)"),
            "test.json: settings.time_step: must be > 0, got 0");
}

TEST(SceneErrors, MassAndDensityTogetherAreRejected) {
  EXPECT_EQ(pendulum_error(R"("mass": 2,)", R"("mass": 2, "density": 1000,)"),
            "test.json: bodies[0]: give either \"mass\" or \"density\", not both");
}

TEST(SceneErrors, NeitherMassNorDensityNamesBoth) {
  EXPECT_EQ(pendulum_error(R"("mass": 2,)", ""),
            "test.json: bodies[0]: missing required field \"mass\" (or \"density\" or \"point_masses\")");
}

TEST(SceneErrors, UnknownShapeTypeIsRejected) {
  EXPECT_EQ(pendulum_error(R"("type": "capsule")", R"("type": "sphere")"),
            "test.json: bodies[1].shape.type: must be \"cylinder\", \"capsule\", \"box\" or \"ellipsoid\", got \"sphere\"");
}

TEST(SceneErrors, DuplicateBodyNameIsRejected) {
  EXPECT_EQ(pendulum_error(R"("name": "lower")", R"("name": "upper")"),
            "test.json: bodies[1].name: duplicate name \"upper\" (also bodies[0])");
}

TEST(SceneErrors, UnknownVariantListsTheAvailableOnes) {
  SceneOptions options;
  options.variant = "huge";
  const std::string message = load_error(embedded_humanoid_scene(), options);
  EXPECT_THAT(message, StartsWith("test.json: variant: no variant named \"huge\""));
  EXPECT_THAT(message, HasSubstr("available: thin, medium, wide"));
}

TEST(SceneErrors, VariantForASceneWithoutVariantsIsRejected) {
  SceneOptions options;
  options.variant = "thin";
  EXPECT_EQ(load_error(kPendulum, options),
            "test.json: variants: variant \"thin\" requested but the scene has no \"variants\"");
}

TEST(SceneErrors, VariantOverrideOfAMissingBodyIsRejected) {
  const std::string scene =
      with(embedded_humanoid_scene(), R"("thin": {)", R"("thin": {"nek": {"mass": 1},)");
  EXPECT_EQ(load_error(scene), "test.json: variants.thin.nek: no body named \"nek\"");
}

TEST(SceneErrors, LinksForASceneWithoutChainAreRejected) {
  SceneOptions options;
  options.links = 100;
  EXPECT_EQ(load_error(kPendulum, options),
            "test.json: chain: 100 links requested but the scene has no \"chain\" or \"tree\" generator");
}

TEST(SceneErrors, ZeroLinksAreRejected) {
  const std::string chain = read_text(kScenes + "chain.json");
  SceneOptions options;
  options.links = 0;
  EXPECT_THAT(load_error(chain, options), StartsWith("test.json: chain.links"));
  EXPECT_THAT(load_error(chain, options), HasSubstr("must be >= 1, got 0"));
  EXPECT_EQ(load_error(with(chain, R"("links": 5)", R"("links": 0)")),
            "test.json: chain.links: must be >= 1, got 0");
}

TEST(SceneErrors, ZeroBallDirectionIsRejected) {
  EXPECT_EQ(pendulum_error(R"("direction": [-2, 0, 0])", R"("direction": [0, 0, 0])"),
            "test.json: ball.direction: must be a non-zero vector, got [0, 0, 0]");
}

// "balls" is a list of "ball"s; a scene gives one form or the other, and a bad ball is named by
// its place in the list.
constexpr std::string_view kOneBall = R"("ball": {"radius": 0.05, "mass": 2.5, "restitution": 0.8, "position": [1, 0, 0.5],
           "speed": 6, "direction": [-2, 0, 0]},)";
constexpr std::string_view kTwoBalls = R"("balls": [{"radius": 0.05, "mass": 2.5, "restitution": 0.8, "position": [1, 0, 0.5],
           "speed": 6, "direction": [-2, 0, 0]}, {"radius": 0.1, "mass": 1, "restitution": 0.5, "position": [-1, 0, 0.5],
           "speed": 3, "direction": [1, 0, 0]}],)";

TEST(SceneLoading, BallsAreReadInOrder) {
  const Model model = load_scene_text(with(kPendulum, kOneBall, kTwoBalls), "test.json").model;
  ASSERT_EQ(model.balls.size(), 2u);
  EXPECT_EQ(model.balls[0].velocity, Vector3(-6, 0, 0));
  EXPECT_EQ(model.balls[1].radius, 0.1);
  EXPECT_EQ(model.balls[1].velocity, Vector3(3, 0, 0));
}

TEST(SceneErrors, BallAndBallsTogetherAreRejected) {
  EXPECT_EQ(load_error(with(kPendulum, kOneBall, std::string(kOneBall) + std::string(kTwoBalls))),
            "test.json: balls: give \"ball\" (one) or \"balls\" (a list), not both");
}

TEST(SceneErrors, ABadBallIsNamedByItsPlaceInTheList) {
  EXPECT_EQ(load_error(with(with(kPendulum, kOneBall, kTwoBalls), R"("radius": 0.1)", R"("radius": -0.1)")),
            "test.json: balls[1].radius: must be > 0, got -0.1");
  EXPECT_EQ(load_error(with(kPendulum, kOneBall, R"("balls": {},)")), "test.json: balls: must be an array, got object");
}

TEST(SceneErrors, RestitutionOutOfRangeIsRejected) {
  EXPECT_EQ(pendulum_error(R"("restitution": 0.1)", R"("restitution": 1.5)"),
            "test.json: ground.restitution: must be in [0, 1], got 1.5");
}

TEST(SceneErrors, HeadAnchorOnAWorldJointIsRejected) {
  EXPECT_EQ(
      pendulum_error(R"("inboard_anchor": [0, 0, 1.5])", R"("inboard_anchor": "head")"),
      "test.json: joints[0].inboard_anchor: must be a world point [x, y, z] when inboard is "
      "\"world\", got \"head\"");
}

TEST(SceneErrors, UnreadableFileIsReported) {
  try {
    load_scene_file("/nonexistent/limber/scene.json");
    FAIL() << "loaded a file that does not exist";
  } catch (const ModelError& error) {
    EXPECT_STREQ(error.what(),
                 "/nonexistent/limber/scene.json: cannot read file: No such file or directory");
  }
  try {
    load_scene_file(kScenes);  // a directory
    FAIL() << "loaded a directory";
  } catch (const ModelError& error) {
    EXPECT_THAT(error.what(), HasSubstr("cannot read file: Is a directory"));
  }
}

TEST(SceneErrors, ErrorsFoundByValidateNameTheSource) {
  // A generated link name clashing with an explicit body is only visible in the Model.
  const std::string chain = with(read_text(kScenes + "chain.json"), R"("chain": {)",
                                 R"("bodies": [{"name": "link_2", "shape": {"type": "cylinder",
      "length": 1, "radius": 0}, "mass": 1, "position": [0, 0, 0], "axis": [0, 0, 1]}],
  "chain": {)");
  EXPECT_EQ(load_error(chain),
            "test.json: bodies[3].name: duplicate name \"link_2\" (also bodies[0])");
}

// ---- Shipped scenes and what the loader builds

TEST(ShippedScenes, HumanoidHasNineLimbsEightJointsGroundAndBall) {
  const Model model = load_scene_file(kScenes + "humanoid.json").model;
  EXPECT_EQ(model.name, "humanoid");
  EXPECT_EQ(model.bodies.size(), 9u);
  EXPECT_EQ(model.joints.size(), 8u);
  ASSERT_TRUE(model.ground.has_value());
  ASSERT_EQ(model.balls.size(), 1u);
  EXPECT_FALSE(model.bounds.has_value());
  // Thesis 4.5: a 5 lb ball of radius 5 cm, 80 cm from the body, level with the spine's centre
  // (the thesis's code puts both at height 25 cm), thrown at the body.
  EXPECT_DOUBLE_EQ(model.balls.front().mass, 5 * kPound);
  EXPECT_DOUBLE_EQ(model.balls.front().radius, 0.05);
  const Body& spine = model.bodies[model.find_body("spine")];
  EXPECT_NEAR(model.balls.front().position.z(), spine.position.z(), 1e-9);
  EXPECT_NEAR((model.balls.front().position - spine.position).norm(), 0.8, 1e-9);
  EXPECT_GT(model.balls.front().velocity.dot(spine.position - model.balls.front().position), 0) << "thrown towards the body";
  EXPECT_TRUE(model.settings.sleep.start_asleep);
  // The default variant is medium: a 140 lb torso of radius 10 cm.
  const Body& torso = model.bodies[model.find_body("upper_torso")];
  EXPECT_DOUBLE_EQ(torso.mass, 140 * kPound);
  EXPECT_DOUBLE_EQ(torso.shape.radius, 0.10);
}

TEST(ShippedScenes, HumanoidVariantsGiveTheThesisMassesAndRadii) {
  SceneOptions thin;
  thin.variant = "thin";
  const Model thin_model = load_scene_text(embedded_humanoid_scene(), "humanoid", thin).model;
  const Body& thin_torso = thin_model.bodies[thin_model.find_body("upper_torso")];
  EXPECT_DOUBLE_EQ(thin_torso.mass, 84 * kPound);
  EXPECT_DOUBLE_EQ(thin_torso.shape.radius, 0.06);
  EXPECT_DOUBLE_EQ(thin_model.bodies[thin_model.find_body("tibia_left")].shape.radius, 0.02);

  SceneOptions wide;
  wide.variant = "wide";
  const Model wide_model = load_scene_text(embedded_humanoid_scene(), "humanoid", wide).model;
  const Body& wide_spine = wide_model.bodies[wide_model.find_body("spine")];
  EXPECT_DOUBLE_EQ(wide_spine.mass, 25 * kPound);
  EXPECT_DOUBLE_EQ(wide_spine.shape.radius, 0.02);
  EXPECT_DOUBLE_EQ(wide_model.bodies[wide_model.find_body("basin")].mass, 87.5 * kPound);
  EXPECT_DOUBLE_EQ(wide_model.body_mass(), (40 + 5 + 350 + 25 + 87.5 + 4 * 90) * kPound);
}

TEST(ShippedScenes, HumanoidStandsAssembledInEveryVariant) {
  for (const char* variant : {"thin", "medium", "wide"}) {
    SceneOptions options;
    options.variant = variant;
    const Model model = load_scene_text(embedded_humanoid_scene(), "humanoid", options).model;
    for (const Joint& joint : model.joints) {
      const Vector3 inboard = model.bodies[joint.inboard].to_world(joint.inboard_anchor);
      const Vector3 outboard = model.bodies[joint.outboard].to_world(joint.outboard_anchor);
      EXPECT_LT((inboard - outboard).norm(), 1e-9) << variant << " " << joint.name;
    }
    // Standing on the ground: the tibias' tails touch z = 0.
    EXPECT_NEAR(model.bodies[model.find_body("tibia_left")].tail().z(), 0, 1e-12);
  }
}

TEST(ShippedScenes, ChainHasFiveLinksWithADoubleEndLink) {
  const Model model = load_scene_file(kScenes + "chain.json").model;
  ASSERT_EQ(model.bodies.size(), 5u);
  EXPECT_EQ(model.joints.size(), 5u);
  EXPECT_FALSE(model.ground.has_value());
  EXPECT_TRUE(model.balls.empty());
  EXPECT_EQ(model.bodies[0].shape.type, ShapeType::capsule);
  EXPECT_DOUBLE_EQ(model.bodies[4].mass, 2 * model.bodies[3].mass);
  EXPECT_DOUBLE_EQ(model.bodies[0].mass, 5 * kPound);
}

TEST(ShippedScenes, StickInBoxHasOneStickInsideItsBounds) {
  const Model model = load_scene_file(kScenes + "stick_in_box.json").model;
  ASSERT_EQ(model.bodies.size(), 1u);
  EXPECT_TRUE(model.joints.empty());
  ASSERT_TRUE(model.bounds.has_value());
  EXPECT_EQ(model.bounds->max, Vector3(5, 5, 5));
  const Body& stick = model.bodies[0];
  EXPECT_NEAR(stick.axis.norm(), 1, 1e-15);
  EXPECT_EQ(stick.angular_velocity, Vector3(0, 4, 0));
  for (const Vector3& end : {stick.head(), stick.tail()}) {
    EXPECT_TRUE((end.array() > model.bounds->min.array()).all());
    EXPECT_TRUE((end.array() < model.bounds->max.array()).all());
  }
}

TEST(ShippedScenes, EmbeddedHumanoidIsTheFileAndLoads) {
  EXPECT_EQ(embedded_humanoid_scene(), read_text(kScenes + "humanoid.json"));
  EXPECT_EQ(load_scene_text(embedded_humanoid_scene(), "embedded").model.bodies.size(), 9u);
}

TEST(SceneLoading, LinksOptionBuildsALongChainLaidHeadToTail) {
  SceneOptions options;
  options.links = 100;
  const Model model = load_scene_file(kScenes + "chain.json", options).model;
  ASSERT_EQ(model.bodies.size(), 100u);
  ASSERT_EQ(model.joints.size(), 100u);
  EXPECT_EQ(model.bodies[99].name, "link_99");
  EXPECT_EQ(model.joints[99].name, "joint_99");
  EXPECT_DOUBLE_EQ(model.bodies[98].mass, 5 * kPound);
  EXPECT_DOUBLE_EQ(model.bodies[99].mass, 10 * kPound);
  // Pinned at the anchor; link k from anchor + k·L·dir (head) to anchor + (k+1)·L·dir (tail).
  EXPECT_EQ(model.joints[0].inboard, kWorld);
  EXPECT_EQ(model.joints[0].inboard_anchor, Vector3(0, 0, 1.5));
  EXPECT_LT((model.bodies[0].head() - Vector3(0, 0, 1.5)).norm(), 1e-12);
  EXPECT_LT((model.bodies[99].tail() - Vector3(20, 0, 1.5)).norm(), 1e-9);
  EXPECT_LT((model.bodies[7].axis - Vector3(-1, 0, 0)).norm(), 1e-15);
  for (const Joint& joint : model.joints) {
    const Vector3 inboard = joint.inboard == kWorld
                                ? joint.inboard_anchor
                                : model.bodies[joint.inboard].to_world(joint.inboard_anchor);
    const Vector3 outboard = model.bodies[joint.outboard].to_world(joint.outboard_anchor);
    EXPECT_LT((inboard - outboard).norm(), 1e-9) << joint.name;
  }
}

/// Each joint's two anchors at one point in the model's pose.
void expect_joints_hold(const Model& model) {
  for (const Joint& joint : model.joints) {
    const Vector3 inboard = joint.inboard == kWorld ? joint.inboard_anchor : model.bodies[joint.inboard].to_world(joint.inboard_anchor);
    const Vector3 outboard = model.bodies[joint.outboard].to_world(joint.outboard_anchor);
    EXPECT_LT((inboard - outboard).norm(), 1e-9) << joint.name;
  }
}

constexpr std::string_view kTree = R"({"limber_scene": 1, "name": "tree",
  "settings": {"gravity": [0, 0, -9.81], "time_step": 0.01, "duration": 1},
  "tree": {"branching": 2, "depth": 3, "link_length": 0.1, "link_mass": 1, "anchor": [1, 2, 3], "pinned": true}})";

TEST(SceneGenerators, TreeByDepthOrLinksHangsFromItsAnchor) {
  const Model tree = load_scene_text(kTree, "test.json").model;
  ASSERT_EQ(tree.bodies.size(), 15u);  // 1 + 2 + 4 + 8
  EXPECT_LT((tree.bodies[0].head() - Vector3(1, 2, 3)).norm(), 1e-12);
  expect_joints_hold(tree);
  SceneOptions options;
  options.links = 40;
  EXPECT_EQ(load_scene_text(kTree, "test.json", options).model.bodies.size(), 40u);
  EXPECT_EQ(load_scene_text(with(kTree, R"("depth": 3)", R"("links": 6)"), "test.json").model.bodies.size(), 6u);
}

TEST(SceneGenerators, GridIsASheetOfLinksFromItsAnchor) {
  const Model grid = load_scene_text(with(kTree, R"("tree": {"branching": 2, "depth": 3, "link_length": 0.1, "link_mass": 1, "anchor": [1, 2, 3], "pinned": true})",
                                          R"("grid": {"columns": 4, "rows": 3, "spacing": 0.1, "link_mass": 0.01, "anchor": [0, 0, 2], "pin_top_corners": true})"),
                                     "test.json").model;
  EXPECT_EQ(grid.bodies.size(), 3u * 3u + 4u * 2u);  // rows·(columns−1) + columns·(rows−1)
  EXPECT_LT((grid.bodies[0].head() - Vector3(0, 0, 2)).norm(), 1e-12);
  expect_joints_hold(grid);
}

TEST(SceneGenerators, CopiesRepeatBodiesJointsAndGearsSideBySide) {
  const Model one = load_scene_text(kPendulum, "test.json").model;
  const Model four = load_scene_text(with(kPendulum, R"("name": "pendulum",)", R"("name": "pendulum", "copies": {"count": 4, "spacing": 2},)"), "test.json").model;
  ASSERT_EQ(four.bodies.size(), 4 * one.bodies.size());
  ASSERT_EQ(four.joints.size(), 4 * one.joints.size());
  EXPECT_EQ(four.balls.size(), 1u);  // one ball, one ground, one set of settings
  // Copy 3 of 4 (two per row) sits at spacing · (1, 1, 0), its names led by "c3.".
  EXPECT_EQ(four.bodies[7].name, "c3.lower");
  EXPECT_LT((four.bodies[7].position - one.bodies[1].position - Vector3(2, 2, 0)).norm(), 1e-12);
  EXPECT_EQ(four.joints[7].inboard, 6);
  expect_joints_hold(four);
  // --copies on a scene without "copies": side by side beyond the bodies' footprint.
  SceneOptions options;
  options.copies = 3;
  const Model three = load_scene_text(kPendulum, "test.json", options).model;
  ASSERT_EQ(three.bodies.size(), 3 * one.bodies.size());
  EXPECT_GE((three.bodies[2].position - three.bodies[0].position).norm(), 1.0);
  expect_joints_hold(three);
}

TEST(SceneLoading, InertialGivesCentreOfMassAndInertiaTensorInMuJoCosOrder) {
  const std::string scene = with(kPendulum, R"("mass": 2, "position": [0, 0, 1.3])",
                                 R"("mass": 2, "inertial": {"centre_of_mass": [0, 0.01, -0.05], "inertia": [0.03, 0.025, 0.012, 0.001, 0.002, 0.003]},
                                    "position": [0, 0, 1.3])");
  const Model model = load_scene_text(scene, "test.json").model;
  ASSERT_TRUE(model.bodies[0].inertial.has_value());
  const Inertial& inertial = *model.bodies[0].inertial;
  EXPECT_EQ(inertial.centre_of_mass, Vector3(0, 0.01, -0.05));
  Eigen::Matrix3d expected;
  expected << 0.03, 0.001, 0.002, 0.001, 0.025, 0.003, 0.002, 0.003, 0.012;  // [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]
  EXPECT_EQ(inertial.inertia, expected);
  EXPECT_EQ(model.bodies[0].mass, 2);
  const auto scene_with = [&](std::string_view inertial_text) {
    return with(kPendulum, R"("mass": 2, "position": [0, 0, 1.3])", std::string(inertial_text) + R"(, "position": [0, 0, 1.3])");
  };
  EXPECT_EQ(load_error(scene_with(R"("mass": 2, "inertial": {"centre_of_mass": [0, 0, 0], "inertia": [1, 1, 1]})")),
            "test.json: bodies[0].inertial.inertia: must be an array of 6 numbers [Ixx, Iyy, Izz, Ixy, Ixz, Iyz], got an array of 3");
  EXPECT_EQ(load_error(scene_with(R"("density": 2, "inertial": {"centre_of_mass": [0, 0, 0], "inertia": [1, 1, 1, 0, 0, 0]})")),
            "test.json: bodies[0]: give \"mass\" with \"inertial\", not \"density\"");
  EXPECT_EQ(load_error(scene_with(R"("mass": 2, "inertial": {"centre_of_mass": [0, 0, 0], "inertia": [1, 1, 3, 0, 0, 0]})")),
            "test.json: bodies[0].inertial.inertia: principal moments [1, 1, 3] break the triangle inequality I1 + I2 >= I3 (no body has them)");
}

TEST(SceneErrors, BadGeneratorsAndCopiesAreNamed) {
  EXPECT_EQ(load_error(with(kTree, R"("depth": 3)", R"("depth": 3, "links": 4)")),
            "test.json: tree: give exactly one of \"links\" and \"depth\"");
  EXPECT_EQ(load_error(with(kTree, R"("branching": 2)", R"("branching": 0)")), "test.json: tree.branching: must be >= 1, got 0");
  EXPECT_THAT(load_error(with(kTree, R"("depth": 3)", R"("depth": 40)")), StartsWith("test.json: tree.depth: asks for "));
  EXPECT_THAT(load_error(with(kPendulum, R"("name": "pendulum",)", R"("name": "pendulum", "copies": {"count": 2, "spacing": 0.01},)")),
              StartsWith("test.json: copies.spacing: must be >= "));
  EXPECT_EQ(load_error(with(kPendulum, R"("name": "pendulum",)", R"("name": "pendulum", "copies": {"count": 0, "spacing": 1},)")),
            "test.json: copies.count: must be >= 1, got 0");
  SceneOptions options;
  options.copies = 6'000'000;  // 12 million bodies
  EXPECT_THAT(load_error(kPendulum, options), StartsWith("test.json: copies.count: asks for "));
  options.copies = 0;
  EXPECT_THAT(load_error(kPendulum, options), StartsWith("test.json: copies.count (SceneOptions::copies): must be >= 1"));
}

TEST(SceneErrors, MaxBodiesRefusesAGeneratorBeforeItAllocates) {
  // 10¹² links would need ~10¹⁴ bytes: the refusal must come before the generator runs.
  SceneOptions options;
  options.links = 1'000'000'000'000;
  EXPECT_EQ(load_error(read_text(kScenes + "chain.json"), options),
            "test.json: chain.links (SceneOptions::links): asks for 1e+12 bodies, more than the 1e+07 a scene may generate");
  // An engine loading untrusted files lowers the limit; the same scene then loads under a higher one.
  options.links = 50;
  options.max_bodies = 49;
  EXPECT_THAT(load_error(read_text(kScenes + "chain.json"), options),
              StartsWith("test.json: chain.links (SceneOptions::links): asks for 50 bodies, more than the 49 "));
  options.max_bodies = 50;
  EXPECT_EQ(load_scene_text(read_text(kScenes + "chain.json"), "test.json", options).model.bodies.size(), 50u);
  options = {};
  options.max_bodies = 100;
  EXPECT_THAT(load_error(with(kTree, R"("depth": 3)", R"("depth": 7)"), options), StartsWith("test.json: tree.depth: asks for "))
      << "a binary tree of depth 7 has 255 links";
}

TEST(SceneErrors, BeforeGeneratingHearsTheBodiesAndItsRefusalStopsTheLoad) {
  // The caller's own check (the command line's memory estimate) hears each generator's count
  // and path before the generator runs, and what it throws ends the load: 10⁷ links, under
  // kMaxSceneBodies, are refused here before a byte of them is allocated.
  std::vector<std::pair<double, std::string>> heard;
  SceneOptions options;
  options.links = 10'000'000;
  options.before_generating = [&](double bodies, const std::string& path) {
    heard.emplace_back(bodies, path);
    if (bodies > 1000) throw ModelError(path + ": too many for this test");
  };
  EXPECT_EQ(load_error(read_text(kScenes + "chain.json"), options), "test.json: chain.links (SceneOptions::links): too many for this test");
  ASSERT_EQ(heard.size(), 1u);
  EXPECT_EQ(heard[0].first, 1e7);
  // Copies: the copies' bodies together, after the generator's own.
  heard.clear();
  options.links = 10;
  options.copies = 200;
  EXPECT_EQ(load_error(read_text(kScenes + "chain.json"), options), "test.json: copies.count: too many for this test");
  ASSERT_EQ(heard.size(), 2u);
  EXPECT_EQ(heard[0], std::make_pair(10.0, std::string("chain.links (SceneOptions::links)")));
  EXPECT_EQ(heard[1].first, 2000.0);
}

// ---- Boxes and ellipsoids: half_extents and a rotation in place of a length and a radius

// A box turned 60° about the body's z (the quaternion's w = cos 30°, z = sin 30°) and an
// ellipsoid in the body frame (no rotation: the identity), both hanging from the world.
constexpr std::string_view kBoxAndEllipsoid = R"({
  "limber_scene": 1,
  "name": "box_and_ellipsoid",
  "settings": {"gravity": [0, 0, -9.81], "time_step": 0.01, "duration": 1},
  "bodies": [
    {"name": "crate", "shape": {"type": "box", "half_extents": [0.1, 0.2, 0.3], "rotation": [0.8660254037844387, 0, 0, 0.5]},
     "density": 500, "position": [0, 0, 1], "axis": [0, 0, 1]},
    {"name": "egg", "shape": {"type": "ellipsoid", "half_extents": [0.05, 0.04, 0.08]},
     "mass": 1.5, "position": [1, 0, 1], "axis": [1, 0, 0]},
    {"name": "rod", "shape": {"type": "capsule", "length": 0.2, "radius": 0.01},
     "mass": 1, "position": [2, 0, 1], "axis": [0, 0, 1]}
  ],
  "joints": [
    {"name": "hook", "type": "spherical", "inboard": "world", "outboard": "crate",
     "inboard_anchor": [0, 0, 1.3], "outboard_anchor": [0, 0, 0.3]}
  ]
})";

std::string box_error(std::string_view from, std::string_view to) { return load_error(with(kBoxAndEllipsoid, from, to)); }

TEST(SceneLoading, BoxesAndEllipsoidsKeepTheirTypeHalfExtentsAndRotation) {
  const Model model = load_scene_text(kBoxAndEllipsoid, "test.json").model;
  const Shape& crate = model.bodies[0].shape;
  EXPECT_EQ(crate.type, ShapeType::box);
  EXPECT_EQ(crate.half_extents, Vector3(0.1, 0.2, 0.3));
  EXPECT_EQ(crate.rotation.coeffs(), Eigen::Quaterniond(0.8660254037844387, 0, 0, 0.5).coeffs()) << "kept as given";
  EXPECT_EQ(crate.length, 0);
  EXPECT_EQ(crate.radius, 0);
  EXPECT_DOUBLE_EQ(model.bodies[0].mass, 500 * 0.2 * 0.4 * 0.6) << "density × the box's volume";
  const Shape& egg = model.bodies[1].shape;
  EXPECT_EQ(egg.type, ShapeType::ellipsoid);
  EXPECT_EQ(egg.half_extents, Vector3(0.05, 0.04, 0.08));
  EXPECT_EQ(egg.rotation.coeffs(), Eigen::Quaterniond::Identity().coeffs()) << "rotation left out: the identity";
  const Shape& rod = model.bodies[2].shape;
  EXPECT_EQ(rod.half_extents, Vector3::Zero());
  EXPECT_EQ(rod.rotation.coeffs(), Eigen::Quaterniond::Identity().coeffs());
}

TEST(SceneErrors, BadBoxAndEllipsoidFieldsAreNamed) {
  EXPECT_EQ(box_error(R"("type": "box", )", R"("type": "box", "length": 0.2, )"),
            "test.json: bodies[0].shape.length: a box has half_extents, not this field; leave it out");
  EXPECT_EQ(box_error(R"("type": "ellipsoid", )", R"("type": "ellipsoid", "radius": 0.2, )"),
            "test.json: bodies[1].shape.radius: an ellipsoid has half_extents, not this field; leave it out");
  EXPECT_EQ(box_error(R"("half_extents": [0.1, 0.2, 0.3], )", ""), "test.json: bodies[0].shape.half_extents: missing required field");
  EXPECT_EQ(box_error("[0.1, 0.2, 0.3]", "[0.1, 0, 0.3]"), "test.json: bodies[0].shape.half_extents[1]: must be > 0, got 0");
  EXPECT_EQ(box_error("[0.05, 0.04, 0.08]", "[0.05, 0.04, -0.08]"), "test.json: bodies[1].shape.half_extents[2]: must be > 0, got -0.08");
  EXPECT_EQ(box_error("[0.1, 0.2, 0.3]", "[0.1, 0.2]"),
            "test.json: bodies[0].shape.half_extents: must be an array of 3 numbers, got an array of 2");
  EXPECT_EQ(box_error("[0.8660254037844387, 0, 0, 0.5]", "[1, 0, 0, 0.1]"),
            "test.json: bodies[0].shape.rotation: must be a unit quaternion [w, x, y, z], got one of norm 1.004987562112089 (1 within 1e-9)");
  EXPECT_EQ(box_error("[0.8660254037844387, 0, 0, 0.5]", "[0.866, 0, 0, 0.5]"),
            "test.json: bodies[0].shape.rotation: must be a unit quaternion [w, x, y, z], got one of norm 0.9999779997579946 (1 within 1e-9)");
  EXPECT_EQ(box_error("[0.8660254037844387, 0, 0, 0.5]", "[0, 0, 0, 0]"),
            "test.json: bodies[0].shape.rotation: must be a unit quaternion [w, x, y, z], got one of norm 0 (1 within 1e-9)");
  EXPECT_EQ(box_error("[0.8660254037844387, 0, 0, 0.5]", "[0, 0, 1]"),
            "test.json: bodies[0].shape.rotation: must be a unit quaternion [w, x, y, z], got an array of 3");
  EXPECT_EQ(box_error("[0.8660254037844387, 0, 0, 0.5]", "[1e999, 0, 0, 0]"),
            "test.json: bodies[0].shape.rotation[0]: must be a finite number, got 1e999");
  EXPECT_EQ(box_error("[0.8660254037844387, 0, 0, 0.5]", R"([1, 0, 0, "0"])"),
            "test.json: bodies[0].shape.rotation[3]: must be a number, got string");
  // A capsule's or cylinder's shape takes neither field of a box's.
  EXPECT_EQ(box_error(R"("radius": 0.01})", R"("radius": 0.01, "half_extents": [0.1, 0.1, 0.1]})"),
            "test.json: bodies[2].shape.half_extents: a capsule has a length and a radius, not this field; leave it out");
  EXPECT_EQ(box_error(R"("radius": 0.01})", R"("radius": 0.01, "rotation": [1, 0, 0, 0]})"),
            "test.json: bodies[2].shape.rotation: a capsule has a length and a radius, not this field; leave it out");
}

TEST(SceneErrors, ABoxHasNoHeadOrTailAnchorAndNoRadiusToVary) {
  EXPECT_EQ(box_error(R"("outboard_anchor": [0, 0, 0.3])", R"("outboard_anchor": "head")"),
            "test.json: joints[0].outboard_anchor: must be a body-frame point [x, y, z] on a box, which has no head, got \"head\"");
  const std::string variants = with(kBoxAndEllipsoid, R"(  "joints": [)", R"(  "variants": {"big": {"crate": {"radius": 0.5}}},
  "variant": "big",
  "joints": [)");
  EXPECT_EQ(load_error(variants), "test.json: variants.big.crate.radius: body \"crate\" is a box, which has half_extents and no radius");
}

TEST(SceneErrors, AChainsLinksAreCylindersOrCapsules) {
  const std::string chain = read_text(kScenes + "chain.json");
  EXPECT_EQ(load_error(with(chain, R"("shape": "capsule")", R"("shape": "box")")),
            "test.json: chain.shape: must be \"cylinder\" or \"capsule\" (a chain's links are link_length long with link_radius), got \"box\"");
  EXPECT_EQ(load_error(with(chain, R"("shape": "capsule")", R"("shape": "ellipsoid")")),
            "test.json: chain.shape: must be \"cylinder\" or \"capsule\" (a chain's links are link_length long with link_radius), got \"ellipsoid\"");
}

TEST(SceneLoading, DensityGivesMassDensityTimesVolume) {
  const Model model = load_scene_text(kPendulum, "test.json").model;
  const double r = 0.01;
  const double capsule_volume =
      std::numbers::pi * r * r * 0.2 + 4.0 / 3 * std::numbers::pi * r * r * r;
  EXPECT_DOUBLE_EQ(model.bodies[1].mass, 1000 * capsule_volume);
}

TEST(SceneLoading, VariantRadiusAppliesBeforeDensityBecomesMass) {
  const std::string scene = with(kPendulum, R"(  "joints": [)", R"(  "variants": {
    "fat": {"lower": {"radius": 0.02}}, "heavy": {"lower": {"mass": 7}}},
  "variant": "fat",
  "joints": [)");
  const Model fat = load_scene_text(scene, "test.json").model;
  EXPECT_DOUBLE_EQ(fat.bodies[1].shape.radius, 0.02);
  EXPECT_DOUBLE_EQ(fat.bodies[1].mass, 1000 * volume(fat.bodies[1].shape));
  SceneOptions heavy;
  heavy.variant = "heavy";
  EXPECT_DOUBLE_EQ(load_scene_text(scene, "test.json", heavy).model.bodies[1].mass, 7);
}

TEST(SceneLoading, HeadAndTailAnchorsAreTheAxisEnds) {
  const Model model = load_scene_text(kPendulum, "test.json").model;
  EXPECT_EQ(model.joints[0].outboard_anchor, Vector3(0, 0, 0.2));   // upper's head, length 0.4
  EXPECT_EQ(model.joints[1].inboard_anchor, Vector3(0, 0, -0.2));   // upper's tail
  EXPECT_EQ(model.joints[1].outboard_anchor, Vector3(0, 0, 0.1));   // lower's head, length 0.2
  EXPECT_EQ(model.joints[0].inboard, kWorld);
  EXPECT_EQ(model.joints[1].inboard, 0);
  EXPECT_EQ(model.joints[1].outboard, 1);
}

TEST(SceneLoading, AxisAndBallDirectionAreNormalized) {
  const Model model = load_scene_text(kPendulum, "test.json").model;
  EXPECT_EQ(model.bodies[0].axis, Vector3(0, 0, 1));  // given as [0, 0, 3]
  EXPECT_EQ(model.balls.front().velocity, Vector3(-6, 0, 0));  // speed 6 along [-2, 0, 0]
}

TEST(SceneLoading, OmittedOptionalFieldsKeepTheModelDefaults) {
  const Scene scene = load_scene_text(kPendulum, "test.json");
  const Model& model = scene.model;
  const Settings defaults;
  EXPECT_EQ(model.settings.damping, defaults.damping);
  EXPECT_EQ(model.settings.divergence_speed, defaults.divergence_speed);
  EXPECT_EQ(scene.methods.relaxation.iterations, RelaxationSettings{}.iterations);
  EXPECT_EQ(model.settings.sleep.time_to_sleep, defaults.sleep.time_to_sleep);
  EXPECT_FALSE(scene.methods.verlet.drag_factor.has_value());
  EXPECT_EQ(model.bodies[0].linear_velocity, Vector3::Zero());
}

// "upper" of kPendulum with its 2 kg given as two lumps instead.
constexpr std::string_view kLumps =
    R"("point_masses": [{"position": [0, 0, 0.1], "mass": 1.5, "radius": 0.02}, {"position": [0, 0, -0.15], "mass": 0.5}],)";

TEST(SceneLoading, PointMassesAreReadAndTheirSumIsTheMass) {
  const Model model = load_scene_text(with(kPendulum, R"("mass": 2,)", kLumps), "test.json").model;
  const Body& upper = model.bodies[0];
  ASSERT_EQ(upper.point_masses.size(), 2u);
  EXPECT_EQ(upper.point_masses[0].position, Vector3(0, 0, 0.1));
  EXPECT_EQ(upper.point_masses[0].mass, 1.5);
  EXPECT_EQ(upper.point_masses[0].radius, 0.02);
  EXPECT_EQ(upper.point_masses[1].radius, 0.0);  // optional, a point
  EXPECT_EQ(upper.mass, 2.0);
  EXPECT_TRUE(model.bodies[1].point_masses.empty());  // "density": uniform
}

TEST(SceneErrors, BadPointMassesAreNamedByTheirPath) {
  const std::string lumps(kLumps);
  const auto lumps_error = [&](std::string_view from, std::string_view to) {
    return load_error(with(kPendulum, R"("mass": 2,)", with(lumps, from, to)));
  };
  EXPECT_EQ(lumps_error(R"("mass": 0.5)", R"("mass": -1)"), "test.json: bodies[0].point_masses[1].mass: must be > 0, got -1");
  EXPECT_EQ(lumps_error(R"("radius": 0.02)", R"("radius": -0.02)"),
            "test.json: bodies[0].point_masses[0].radius: must be >= 0, got -0.02");
  EXPECT_EQ(lumps_error(R"("position": [0, 0, -0.15], )", ""),
            "test.json: bodies[0].point_masses[1].position: missing required field");
  EXPECT_EQ(lumps_error(R"("mass": 0.5})", R"("mass": 0.5, "inertia": 1})"),
            "test.json: bodies[0].point_masses[1]: unknown field \"inertia\"");
  EXPECT_EQ(lumps_error(R"([0, 0, -0.15])", R"([0, -0.15])"),
            "test.json: bodies[0].point_masses[1].position: must be an array of 3 numbers, got an array of 2");
  EXPECT_EQ(pendulum_error(R"("mass": 2,)", R"("point_masses": [],)"),
            "test.json: bodies[0].point_masses: must list at least one point mass");
  EXPECT_EQ(pendulum_error(R"("mass": 2,)", R"("point_masses": {"mass": 2},)"),
            "test.json: bodies[0].point_masses: must be an array, got object");
  EXPECT_EQ(pendulum_error(R"("mass": 2,)", std::string(kLumps) + R"( "mass": 2,)"),
            "test.json: bodies[0]: give either \"point_masses\" or \"mass\", not both");
  EXPECT_EQ(pendulum_error(R"("density": 1000,)", std::string(kLumps) + R"( "density": 1000,)"),
            "test.json: bodies[1]: give either \"point_masses\" or \"density\", not both");
}

TEST(SceneErrors, VariantsCannotChangeTheMassOfABodyWithPointMasses) {
  // Its mass is the sum of its lumps; a variant may still change its radius.
  const std::string scene = with(with(kPendulum, R"("mass": 2,)", kLumps), R"(  "joints": [)", R"(  "variants": {
    "fat": {"upper": {"radius": 0.05}}, "heavy": {"upper": {"mass": 7}}},
  "variant": "fat",
  "joints": [)");
  EXPECT_EQ(load_error(scene),
            "test.json: variants.heavy.upper.mass: body \"upper\" gives \"point_masses\", whose sum is its mass; a "
            "variant may change only its \"radius\"");
  const std::string fat_only = with(scene, R"(, "heavy": {"upper": {"mass": 7}})", "");
  const Model fat = load_scene_text(fat_only, "test.json").model;
  EXPECT_EQ(fat.bodies[0].shape.radius, 0.05);
  EXPECT_EQ(fat.bodies[0].mass, 2.0);
}

TEST(SceneLoading, LimbMassesSettingIsReadAndCheckedByName) {
  EXPECT_EQ(load_scene_text(kPendulum, "test.json").methods.verlet.limb_masses, LimbMasses::ends);
  const auto with_limb_masses = [](std::string_view value) {
    return with(kPendulum, R"("duration": 1)", R"("duration": 1, "verlet": {"limb_masses": )" + std::string(value) + "}");
  };
  EXPECT_EQ(load_scene_text(with_limb_masses(R"("inertia")"), "test.json").methods.verlet.limb_masses,
            LimbMasses::inertia);
  EXPECT_EQ(load_scene_text(with_limb_masses(R"("ends")"), "test.json").methods.verlet.limb_masses, LimbMasses::ends);
  EXPECT_EQ(load_scene_text(with_limb_masses(R"("lumps")"), "test.json").methods.verlet.limb_masses, LimbMasses::lumps);
  EXPECT_EQ(load_error(with_limb_masses(R"("centre")")),
            "test.json: settings.verlet.limb_masses: must be \"ends\", \"inertia\" or \"lumps\", got \"centre\"");
  EXPECT_EQ(load_error(with_limb_masses("3")), "test.json: settings.verlet.limb_masses: must be a string, got number");
  const auto with_joint_solve = [](std::string_view value) {
    return with(kPendulum, R"("duration": 1)", R"("duration": 1, "verlet": {"joint_solve": )" + std::string(value) + "}");
  };
  EXPECT_EQ(load_scene_text(kPendulum, "test.json").methods.verlet.joint_solve, JointSolve::rows);
  EXPECT_EQ(load_scene_text(with_joint_solve(R"("tree")"), "test.json").methods.verlet.joint_solve, JointSolve::tree);
  EXPECT_EQ(load_scene_text(with_joint_solve(R"("rows")"), "test.json").methods.verlet.joint_solve, JointSolve::rows);
  EXPECT_EQ(load_error(with_joint_solve(R"("trees")")), "test.json: settings.verlet.joint_solve: must be \"rows\" or \"tree\", got \"trees\"");
}

TEST(SceneLoading, ProjectionRuleAndSubstepsAreReadAndCheckedByName) {
  const MethodSettings defaults = load_scene_text(kPendulum, "test.json").methods;
  EXPECT_EQ(defaults.relaxation.projection, ProjectionRule::pbd);
  EXPECT_EQ(defaults.relaxation.substeps, 1);
  const auto with_relaxation = [](std::string_view fields) {
    return with(kPendulum, R"("duration": 1)", R"("duration": 1, "relaxation": {)" + std::string(fields) + "}");
  };
  const MethodSettings rattle =
      load_scene_text(with_relaxation(R"("projection": "rattle", "substeps": 64, "iterations": 4)"), "test.json").methods;
  EXPECT_EQ(rattle.relaxation.projection, ProjectionRule::rattle);
  EXPECT_EQ(rattle.relaxation.substeps, 64);
  EXPECT_EQ(rattle.relaxation.iterations, 4);
  EXPECT_EQ(load_error(with_relaxation(R"("projection": "shake")")),
            "test.json: settings.relaxation.projection: must be \"pbd\" or \"rattle\", got \"shake\"");
  EXPECT_EQ(load_error(with_relaxation(R"("substeps": 0)")), "test.json: settings.relaxation.substeps: must be >= 1, got 0");
  EXPECT_EQ(load_error(with_relaxation(R"("substeps": 20000)")),
            "test.json: settings.relaxation.substeps: must be <= 10000, got 20000");
  EXPECT_EQ(load_error(with_relaxation(R"("substeps": 1.5)")), "test.json: settings.relaxation.substeps: must be an integer, got 1.5");
}

TEST(SceneLoading, TolerancesAreReadAndCheckedByName) {
  const Tolerances defaults = load_scene_text(kPendulum, "test.json").model.settings.tolerances;
  EXPECT_FALSE(defaults.penetration.has_value());  // derived from the Model by the verdict
  EXPECT_FALSE(defaults.energy_gain.has_value());
  const auto with_tolerances = [](std::string_view fields) {
    return with(kPendulum, R"("duration": 1)", R"("duration": 1, "tolerances": {)" + std::string(fields) + "}");
  };
  const Tolerances read =
      load_scene_text(with_tolerances(R"("joint_gap": 0.05, "penetration": 0.002, "limit": 0.2, "energy_gain": 3)"), "test.json")
          .model.settings.tolerances;
  EXPECT_EQ(read.joint_gap, 0.05);
  EXPECT_EQ(read.penetration, 0.002);
  EXPECT_EQ(read.limit, 0.2);
  EXPECT_EQ(read.energy_gain, 3);
  EXPECT_EQ(load_error(with_tolerances(R"("penetration": -1)")), "test.json: settings.tolerances.penetration: must be >= 0, got -1");
  EXPECT_EQ(load_error(with_tolerances(R"("gap": 1)")), "test.json: settings.tolerances: unknown field \"gap\"");
}

// ---- The spring method's settings

TEST(SceneSprings, StiffnessAndDampingAreReadPerSceneAndPerJoint) {
  const Scene scene = load_scene_text(
      with(with(kPendulum, R"("duration": 1})", R"("duration": 1, "springs": {"stiffness": 5e4, "damping": 7},
                                                   "drag": {"linear": [1, 2, 3], "angular": [0, 0, 0.5]}})"),
           R"("inboard_anchor": "tail", "outboard_anchor": "head"})",
           R"("inboard_anchor": "tail", "outboard_anchor": "head", "stiffness": 9e5, "damping": 0})"),
      "test.json");
  const Model& model = scene.model;
  EXPECT_EQ(scene.methods.springs.stiffness, 5e4);
  EXPECT_EQ(scene.methods.springs.damping, 7);
  EXPECT_EQ(model.settings.drag.linear, Vector3(1, 2, 3));
  EXPECT_EQ(model.settings.drag.angular, Vector3(0, 0, 0.5));
  EXPECT_FALSE(model.joints[0].stiffness.has_value());
  EXPECT_EQ(model.joints[1].stiffness, 9e5);
  EXPECT_EQ(model.joints[1].damping, 0.0);
}

TEST(SceneSprings, BadSpringValuesAreNamed) {
  EXPECT_EQ(pendulum_error(R"("duration": 1})", R"("duration": 1, "springs": {"stiffness": -3}})"),
            "test.json: settings.springs.stiffness: must be > 0, got -3");
  EXPECT_EQ(pendulum_error(R"("outboard_anchor": "head"},)", R"("outboard_anchor": "head", "damping": -1},)"),
            "test.json: joints[0].damping: must be >= 0, got -1");
  EXPECT_EQ(pendulum_error(R"("duration": 1})", R"("duration": 1, "drag": {"angular": [0, -2, 0]}})"),
            "test.json: settings.drag.angular[1]: must be >= 0, got -2");
}

TEST(SceneJoints, JointTypesAndAxesAreRead) {
  const Model model = load_scene_text(
      with(with(kPendulum, R"("name": "elbow", "type": "spherical")", R"("name": "elbow", "type": "universal")"),
           R"("inboard_anchor": "tail", "outboard_anchor": "head"})",
           R"("inboard_anchor": "tail", "outboard_anchor": "head", "axis": [2, 0, 0], "second_axis": [0, 1, 0]})"),
      "test.json").model;
  EXPECT_EQ(model.joints[0].type, JointType::spherical);
  EXPECT_EQ(model.joints[1].type, JointType::universal);
  EXPECT_EQ(model.joints[1].axis, Vector3::UnitX());  // normalized
  EXPECT_EQ(model.joints[1].second_axis, Vector3::UnitY());
}

TEST(SceneJoints, BadJointTypesAndAxesAreNamed) {
  EXPECT_EQ(pendulum_error(R"("name": "pin", "type": "spherical")", R"("name": "pin", "type": "hinge")"),
            "test.json: joints[0].type: must be \"spherical\", \"revolute\", \"prismatic\", \"universal\", \"fixed\" or \"serial\", got \"hinge\"");
  EXPECT_EQ(pendulum_error(R"("name": "pin", "type": "spherical")", R"("name": "pin", "type": "revolute")"),
            "test.json: joints[0].axis: missing required field");
  EXPECT_EQ(pendulum_error(R"("outboard_anchor": "head"},)", R"("outboard_anchor": "head", "axis": [1, 0, 0]},)"),
            "test.json: joints[0].axis: is not used by a spherical joint");
  EXPECT_THAT(pendulum_error(R"("name": "pin", "type": "spherical")", R"("name": "pin", "type": "prismatic", "axis": [0, 0, 0])"),
              HasSubstr("joints[0].axis:"));
  EXPECT_THAT(
      pendulum_error(R"("name": "pin", "type": "spherical")",
                     R"("name": "pin", "type": "universal", "axis": [1, 0, 0], "second_axis": [1, 1, 0])"),
      HasSubstr("test.json: joints[0].second_axis: must be perpendicular to axis"));
}

TEST(SceneJoints, GearsAreReadAndCheckedByName) {
  const Model model = load_scene_file(kScenes + "gears.json").model;
  ASSERT_EQ(model.gears.size(), 1u);
  EXPECT_EQ(model.gears[0].first, model.find_body("large"));
  EXPECT_EQ(model.gears[0].second, model.find_body("small"));
  EXPECT_EQ(model.gears[0].ratio, -2);
  const std::string gear = R"(], "gears": [{"name": "mesh", "first": "upper", "second": "lower", "first_axis": [0, 1, 0],
                                           "second_axis": [0, 1, 0], "ratio": 3}]})";
  const auto gear_error = [&](std::string_view from, std::string_view to) {
    return load_error(with(with(kPendulum, "]\n}", gear), from, to));
  };
  EXPECT_EQ(gear_error(R"("second": "lower")", R"("second": "upper")"), "test.json: gears[0].second: must differ from first, both are \"upper\"");
  EXPECT_EQ(gear_error(R"("ratio": 3)", R"("ratio": 0)"), "test.json: gears[0].ratio: must not be 0 (the second gear would be held still)");
  EXPECT_EQ(gear_error(R"("first": "upper")", R"("first": "world")"), "test.json: gears[0].first: must name a body, not \"world\"");
  EXPECT_EQ(gear_error(R"("ratio": 3)", R"("ratio": 3, "radius": 1)"), "test.json: gears[0]: unknown field \"radius\"");
}

}  // namespace
}  // namespace limber
