// The World: every call under every method that supports it, each asserting a physical fact,
// and a clear refusal where a method cannot.
#include <dirent.h>

#include <cmath>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include "limber/kernel/world/world.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

using ::testing::HasSubstr;
using testing::load_shipped_scene;
using testing::make_chain;

const Method kMethods[] = {Method::particles, Method::springs, Method::lagrange, Method::featherstone};

std::string name(Method method) { return std::string(method_name(method)); }

WorldOptions options_for(Method method) {
  WorldOptions options;
  options.method = method;
  options.lagrange.stabilization = Stabilization::projection;
  return options;
}

// One free capsule without gravity, turning about x and drifting.
Model free_limb() {
  Model model = make_chain({2.0}, 0.4, false);
  model.settings.gravity.setZero();
  model.bodies[0].linear_velocity = Vector3(0.1, 0.2, -0.3);
  return model;
}

double angle_between(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) { return a.angularDistance(b); }

TEST(World, StartsWhereTheModelPutsItsBodies) {
  const Model model = make_chain({1, 2, 1}, 0.3, true);
  for (const Method method : kMethods) {
    World world(model, options_for(method));
    for (std::size_t b = 0; b < model.bodies.size(); ++b) {
      const Pose pose = world.pose(world.body(model.bodies[b].name));
      EXPECT_LT((pose.position - model.bodies[b].position).norm(), 1e-12) << name(method) << " body " << b;
      EXPECT_LT(angle_between(pose.orientation, model.bodies[b].orientation()), 1e-9) << name(method) << " body " << b;
    }
  }
}

// The segments collision sees are the bodies' poses: each limb's axis through its centre, as long
// as its shape, and then each ball's centre.
TEST(World, SegmentsFollowTheBodiesPosesAndEndWithTheBalls) {
  Model model = make_chain({1, 2, 1}, 0.3, true);
  model.balls.push_back(Ball{.radius = 0.1, .mass = 1, .restitution = 0.5, .position = Vector3(3, 0, 1), .velocity = Vector3(-1, 0, 0)});
  for (const Method method : kMethods) {
    World world(model, options_for(method));
    for (int step = 0; step < 10; ++step) world.step();
    std::vector<LimbSegment> segments;
    world.segments(segments);
    ASSERT_EQ(segments.size(), model.bodies.size() + 1) << name(method);
    for (std::size_t b = 0; b < model.bodies.size(); ++b) {
      const Pose pose = world.pose(world.bodies()[b]);
      const Eigen::Vector3d half = 0.5 * model.bodies[b].shape.length * (pose.orientation * Eigen::Vector3d::UnitZ());
      EXPECT_LT((segments[b].head - (pose.position + half)).norm(), 1e-6) << name(method) << " body " << b;
      EXPECT_LT((segments[b].tail - (pose.position - half)).norm(), 1e-6) << name(method) << " body " << b;
      EXPECT_EQ(segments[b].radius, model.bodies[b].shape.radius);
    }
    EXPECT_EQ(segments.back().head, world.ball(world.balls().front()).position) << name(method);
    EXPECT_EQ(segments.back().tail, segments.back().head);
  }
}

TEST(World, AnImpulseChangesMomentumByExactlyTheImpulse) {
  // No gravity, a free body: the change of linear momentum over the step is the impulse.
  const Eigen::Vector3d impulse(0.7, -1.1, 0.4);
  for (const Method method : kMethods) {
    World world(free_limb(), options_for(method));
    const BodyId limb = world.body("link_0");
    const Eigen::Vector3d before = world.observe().linear_momentum;
    world.apply_impulse(limb, impulse, world.pose(limb).position);
    ASSERT_EQ(world.step(1.0 / 120), StepStatus::ok);
    EXPECT_LT((world.observe().linear_momentum - before - impulse).norm(), 1e-12) << name(method);
  }
}

TEST(World, AnOffCentreImpulseTurnsTheBodyByRCrossJ) {
  // At the head, across the axis: the angular velocity gained is I⁻¹ (r × J), the same for every
  // method whose limb has the inertia of its particles (limb_masses "ends" is m·L²/4; the rigid
  // methods use the capsule's), so compare each with its own I: the spin about the centre,
  // ω·I = r × J, with I about a transverse axis.
  const Eigen::Vector3d impulse(0, 0.5, 0);
  for (const Method method : kMethods) {
    World world(free_limb(), options_for(method));
    const BodyId limb = world.body("link_0");
    const Pose pose = world.pose(limb);
    const Eigen::Vector3d head = pose.position + pose.orientation * Eigen::Vector3d(0, 0, 0.2);
    const Eigen::Vector3d spin_before = world.motion(limb).angular;
    world.apply_impulse(limb, impulse, head);
    world.step(1e-4);
    const Eigen::Vector3d spin = world.motion(limb).angular - spin_before;
    const Eigen::Vector3d expected_axis = (head - pose.position).cross(impulse).normalized();
    EXPECT_GT(spin.norm(), 1e-3) << name(method);
    EXPECT_LT((spin.normalized() - expected_axis).norm(), 1e-3) << name(method);
  }
}

TEST(World, AJointTorqueTurnsTheTwoBodiesApartAndKeepsAngularMomentum) {
  Model model = make_chain({1, 1}, 0.3, false);
  model.settings.gravity.setZero();
  for (const Method method : kMethods) {
    World world(model, options_for(method));
    world.apply_joint_torque(world.joint("joint_1"), Eigen::Vector3d(0, 0, 0.2));  // about z, across both axes
    for (int s = 0; s < 10; ++s) ASSERT_EQ(world.step(1.0 / 240), StepStatus::ok);
    const double inboard = world.motion(world.body("link_0")).angular.z(), outboard = world.motion(world.body("link_1")).angular.z();
    EXPECT_GT(outboard, 1e-3) << name(method);
    EXPECT_LT(inboard, -1e-3) << name(method);
    EXPECT_LT(world.observe().linear_momentum.norm(), 1e-9) << name(method);
  }
}

TEST(World, APinnedPointStaysPut) {
  // A chain's free end pinned where it is, then released: it swings about the pin, which does
  // not move (particles: the held particle itself; Lagrange: to its projection's tolerance).
  for (const Method method : {Method::particles, Method::lagrange}) {
    for (const ParticleJoints joints : {ParticleJoints::shared_particle, ParticleJoints::zero_length_constraint}) {
      if (method != Method::particles && joints == ParticleJoints::zero_length_constraint) continue;
      Model model = make_chain({1, 1, 1}, 0.2, false);
      model.settings.sleep.enabled = false;
      WorldOptions options = options_for(method);
      options.particles.verlet.joints = joints;
      World world(model, options);
      const BodyId end = world.body("link_2");
      const Eigen::Vector3d local(0, 0, -0.1);  // the tail
      const Pose start = world.pose(end);
      const Eigen::Vector3d held = start.position + start.orientation * local;
      world.pin(end, local);
      double largest = 0;
      for (int s = 0; s < 240; ++s) {
        ASSERT_EQ(world.step(1.0 / 240), StepStatus::ok);
        const Pose pose = world.pose(end);
        largest = std::max(largest, (pose.position + pose.orientation * local - held).norm());
      }
      const double tolerance = method == Method::particles && joints == ParticleJoints::shared_particle ? 1e-15 : 1e-4;
      EXPECT_LT(largest, tolerance) << name(method) << " joints " << int(joints);
      EXPECT_GT((world.pose(world.body("link_0")).position - model.bodies[0].position).norm(), 0.05) << "the chain must swing";
    }
  }
}

TEST(World, FeatherstoneRefusesPinsAndTeleportsOnlyItsFloatingRoots) {
  const Model model = make_chain({1, 1}, 0.2, true);
  World world(model, options_for(Method::featherstone));
  try {
    world.pin(world.body("link_1"), Eigen::Vector3d(0, 0, -0.1));
    FAIL() << "pinned";
  } catch (const WorldError& error) {
    EXPECT_THAT(error.what(), HasSubstr("pin: the featherstone method"));
  }
  try {
    world.teleport(world.body("link_1"), {}, {});
    FAIL() << "teleported";
  } catch (const WorldError& error) {
    EXPECT_THAT(error.what(), HasSubstr("'link_1' hangs from a joint"));
  }
  World free_world(free_limb(), options_for(Method::featherstone));
  const Pose target{Eigen::Vector3d(1, 2, 3), Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()))};
  free_world.teleport(free_world.body("link_0"), target, {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d::Zero()});
  EXPECT_LT((free_world.pose(free_world.body("link_0")).position - target.position).norm(), 1e-12);
  EXPECT_LT(angle_between(free_world.pose(free_world.body("link_0")).orientation, target.orientation), 1e-9);
}

TEST(World, TeleportSetsPoseAndMotion) {
  for (const Method method : kMethods) {
    World world(free_limb(), options_for(method));
    const BodyId limb = world.body("link_0");
    const Pose target{Eigen::Vector3d(0.5, -1, 2), Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d(1, 1, 0).normalized()))};
    const Motion moving{Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 0, 0)};
    world.teleport(limb, target, moving);
    EXPECT_LT((world.pose(limb).position - target.position).norm(), 1e-12) << name(method);
    EXPECT_LT(angle_between(world.pose(limb).orientation, target.orientation), 1e-9) << name(method);
    world.step(0.01);
    EXPECT_LT((world.pose(limb).position - target.position - Eigen::Vector3d(0.01, 0, 0)).norm(), 1e-9) << name(method);
  }
}

TEST(World, AKinematicTargetIsFollowedWithItsVelocity) {
  // A rope held by a hand moving at 0.5 m/s along +y: the held particle is where the hand is,
  // moving as it moves (particles exactly; Lagrange's body follows the moving anchor closely).
  for (const Method method : {Method::particles, Method::lagrange}) {
    for (const ProjectionRule projection : {ProjectionRule::pbd, ProjectionRule::rattle}) {
      if (method != Method::particles && projection == ProjectionRule::rattle) continue;
      Model model = make_chain({0.2, 0.2, 0.2, 0.2}, 0.1, false);
      model.settings.sleep.enabled = false;
      WorldOptions options = options_for(method);
      options.particles.verlet.joints = ParticleJoints::shared_particle;
      options.particles.relaxation.projection = projection;
      options.particles.relaxation.substeps = projection == ProjectionRule::rattle ? 4 : 1;
      World world(model, options);
      const BodyId first = world.body("link_0");
      const PinId hand = world.pin(first, Eigen::Vector3d(0, 0, 0.05));  // link_0's head
      const Eigen::Vector3d start = world.pin_position(hand);
      const double dt = 1.0 / 120, speed = 0.5;
      double largest = 0;
      for (int s = 1; s <= 120; ++s) {
        const Eigen::Vector3d target = start + Eigen::Vector3d(0, speed * s * dt, 0);
        world.move_pin(hand, target);
        ASSERT_EQ(world.step(dt), StepStatus::ok);
        const Pose pose = world.pose(first);
        largest = std::max(largest, (pose.position + pose.orientation * Eigen::Vector3d(0, 0, 0.05) - target).norm());
      }
      EXPECT_LT(largest, method == Method::particles ? 1e-12 : 2e-3) << name(method) << " projection " << int(projection);
      // The chain was dragged along: its far end moved with the hand, on average.
      EXPECT_GT(world.pose(world.body("link_3")).position.y() - model.bodies[3].position.y(), 0.2) << name(method);
    }
  }
}

// A held point moved by move_pin stays where it was moved across a recompile (an added
// collider), and the Model keeps the anchor it was given: the World, not the Model, holds it.
TEST(World, AMovedPinSurvivesARecompileAndTheModelKeepsItsAnchor) {
  for (const Method method : {Method::particles, Method::lagrange}) {
    Model model = make_chain({0.2, 0.2, 0.2, 0.2}, 0.1, false);
    model.settings.sleep.enabled = false;
    WorldOptions options = options_for(method);
    options.particles.verlet.joints = ParticleJoints::shared_particle;
    World world(model, options);
    const PinId hand = world.pin(world.body("link_0"), Eigen::Vector3d(0, 0, 0.05));
    const Eigen::Vector3d start = world.pin_position(hand), given = world.model().joints.back().inboard_anchor;
    const Eigen::Vector3d moved = start + Eigen::Vector3d(0, 0.1, 0);
    for (int s = 1; s <= 10; ++s) {
      world.move_pin(hand, start + Eigen::Vector3d(0, 0.01 * s, 0));
      ASSERT_EQ(world.step(1.0 / 120), StepStatus::ok) << name(method);
    }
    const Joint& pin_joint = world.model().joints.back();
    EXPECT_EQ(pin_joint.inboard_anchor, given) << name(method) << ": stepping wrote the Model";
    StaticCollider wall;
    wall.name = "wall", wall.position = Eigen::Vector3d(5, 0, 0), wall.half_extents = Eigen::Vector3d(0.1, 1, 1);
    world.add_collider(wall);
    EXPECT_LT((world.pin_position(hand) - moved).norm(), 1e-12) << name(method) << ": the recompile forgot the moved anchor";
    ASSERT_EQ(world.step(1.0 / 120), StepStatus::ok) << name(method);
    EXPECT_LT((world.pin_position(hand) - moved).norm(), 1e-9) << name(method) << ": the held point went back";
  }
}

TEST(World, TransformsAreContinuousInTime) {
  // A chain swinging down: no body's orientation jumps between steps (particle limbs carry their
  // roll by parallel transport; the rigid methods integrate it).
  const Model model = make_chain({1, 1, 1, 2}, 0.2, true);
  for (const Method method : kMethods) {
    World world(model, options_for(method));
    std::vector<Pose> last;
    for (const BodyId body : world.bodies()) last.push_back(world.pose(body));
    double largest_turn = 0;
    for (int s = 0; s < 480; ++s) {
      ASSERT_EQ(world.step(1.0 / 480), StepStatus::ok);
      for (std::size_t k = 0; k < last.size(); ++k) {
        const Pose pose = world.pose(world.bodies()[k]);
        largest_turn = std::max(largest_turn, angle_between(pose.orientation, last[k].orientation));
        last[k] = pose;
      }
    }
    EXPECT_LT(largest_turn, 0.2) << name(method);  // rad per 1/480 s: a bounded angular speed
    EXPECT_GT(largest_turn, 1e-3) << name(method) << ": it must have swung";
  }
}

// The bulk read-outs give, in Model order, the bits of the one-body calls, for every method,
// and refuse a span of the wrong size without writing into it.
TEST(World, BulkPosesAndMotionsAreTheOneBodyCallsBits) {
  const Model model = make_chain({1, 1, 1, 2}, 0.2, true);
  for (const Method method : kMethods) {
    World world(model, options_for(method));
    world.apply_impulse(world.bodies().back(), Vector3(0.3, 0.1, 0), world.pose(world.bodies().back()).position);
    for (int s = 0; s < 30; ++s) ASSERT_EQ(world.step(1.0 / 480), StepStatus::ok) << name(method) << " step " << s;
    std::vector<Pose> poses(model.bodies.size());
    std::vector<Motion> motions(model.bodies.size());
    world.poses(poses), world.motions(motions);
    for (std::size_t k = 0; k < poses.size(); ++k) {
      const BodyId body = world.bodies()[k];
      const Pose one = world.pose(body);
      const Motion moving = world.motion(body);
      EXPECT_EQ(poses[k].position, one.position) << name(method) << " body " << k;
      EXPECT_EQ(poses[k].orientation.coeffs(), one.orientation.coeffs()) << name(method) << " body " << k;
      EXPECT_EQ(motions[k].linear, moving.linear) << name(method) << " body " << k;
      EXPECT_EQ(motions[k].angular, moving.angular) << name(method) << " body " << k;
    }
    std::vector<Pose> short_by_one(model.bodies.size() - 1, Pose{Vector3(7, 7, 7), Eigen::Quaterniond::Identity()});
    EXPECT_THROW(world.poses(short_by_one), WorldError) << name(method);
    EXPECT_EQ(short_by_one.front().position, Vector3(7, 7, 7)) << name(method) << ": nothing written";
    std::vector<Motion> too_many(model.bodies.size() + 1);
    EXPECT_THROW(world.motions(too_many), WorldError) << name(method);
  }
}

TEST(World, StructuralEditsCarryUntouchedBodiesBitForBit) {
  // Two chains in one world; after some steps, remove a body of the second and add one: the
  // first chain's poses and motions are the same bits before and after each edit.
  for (const Method method : kMethods) {
    Model model = make_chain({1, 1, 1}, 0.2, true);
    model.settings.sleep.enabled = false;
    WorldOptions options = options_for(method);
    // Semi-implicit springs open these light 0.2 m links by a whole link at 1/240 s (reported as
    // diverged_joint_gap); the edits, not the springs, are under test here.
    options.springs.integrator = Integrator::backward_euler;
    World world(model, options);
    world.add_model(make_chain({1, 2}, 0.2, true, Vector3(0, 1, 1)), "b.");
    for (int s = 0; s < 60; ++s) ASSERT_EQ(world.step(1.0 / 240), StepStatus::ok);
    const auto snapshot = [&] {
      std::vector<double> bits;
      for (const char* body : {"link_0", "link_1", "link_2"}) {
        const Pose pose = world.pose(world.body(body));
        const Motion motion = world.motion(world.body(body));
        bits.insert(bits.end(), {pose.position.x(), pose.position.y(), pose.position.z(), pose.orientation.w(), pose.orientation.x(),
                                 motion.linear.x(), motion.linear.z(), motion.angular.y()});
      }
      return bits;
    };
    const std::vector<double> before = snapshot();
    world.remove_body(world.body("b.link_1"));
    EXPECT_EQ(snapshot(), before) << name(method) << " after remove";
    Body extra = model.bodies[0];
    extra.name = "extra";
    extra.position += Vector3(0, -1, 0);
    world.add_body(extra);
    EXPECT_EQ(snapshot(), before) << name(method) << " after add";
    EXPECT_EQ(world.model().bodies.size(), 5u);
    for (int s = 0; s < 10; ++s) ASSERT_EQ(world.step(1.0 / 240), StepStatus::ok);
  }
}

TEST(World, SeveralRagdollsShareAWorld) {
  const Model humanoid = load_shipped_scene("humanoid.json");
  for (const Method method : kMethods) {
    World world(humanoid, options_for(method));
    const std::vector<BodyId> second = world.add_model(humanoid, "second.", Eigen::Vector3d(0, 1.5, 0));  // beside, out of the ball's way
    EXPECT_EQ(second.size(), humanoid.bodies.size());
    EXPECT_EQ(world.model().bodies.size(), 2 * humanoid.bodies.size());
    for (int s = 0; s < 120; ++s) ASSERT_EQ(world.step(), StepStatus::ok) << name(method);
    // The ball knocks the first over; the second, asleep and untouched, stays where it was put.
    const BodyId first_head = world.body("head"), second_head = world.body("second.head");
    EXPECT_LT(world.pose(first_head).position.z(), humanoid.bodies[0].position.z() - 0.05) << name(method);
    EXPECT_LT((world.pose(second_head).position - humanoid.bodies[0].position - Eigen::Vector3d(0, 1.5, 0)).norm(), 1e-12) << name(method);
  }
}

TEST(World, WakeAndSleep) {
  Model model = load_shipped_scene("humanoid.json");
  model.balls.clear();
  for (const Method method : kMethods) {
    World world(model, options_for(method));
    const BodyId head = world.body("head");
    EXPECT_TRUE(world.sleeping(head)) << name(method) << ": the humanoid starts asleep";
    world.apply_force(head, Eigen::Vector3d(30, 0, 0), world.pose(head).position);
    EXPECT_FALSE(world.sleeping(head)) << name(method);
    for (int s = 0; s < 20; ++s) ASSERT_EQ(world.step(), StepStatus::ok) << name(method);
    ASSERT_GT(world.motion(head).linear.norm(), 1e-3) << name(method) << ": the push must have moved it";
    // Put to sleep by the engine: at rest at once, and held there however long it is stepped.
    world.sleep(head);
    EXPECT_TRUE(world.sleeping(head)) << name(method);
    EXPECT_EQ(world.motion(head).linear.norm(), 0.0) << name(method);
    const Pose held = world.pose(head);
    for (int s = 0; s < 20; ++s) ASSERT_EQ(world.step(), StepStatus::ok) << name(method);
    EXPECT_TRUE(world.sleeping(head)) << name(method);
    EXPECT_LT((world.pose(head).position - held.position).norm(), 1e-12) << name(method);
    world.wake(head);
    for (int s = 0; s < 20; ++s) ASSERT_EQ(world.step(), StepStatus::ok) << name(method);
    EXPECT_GT((world.pose(head).position - held.position).norm(), 1e-4) << name(method) << ": awake, the body falls on";
  }
}

TEST(World, ASceneBringsItsMethodSettings) {
  // chain.json asks the particle method for the rattle rule in 16 substeps of 2 sweeps: a world
  // made from the Scene steps so; one made from its Model alone takes the defaults.
  const Scene chain = testing::shipped_scene("chain.json");
  World from_scene(chain, Method::particles);
  World from_model(chain.model);
  ASSERT_EQ(from_scene.step(), StepStatus::ok);
  ASSERT_EQ(from_model.step(), StepStatus::ok);
  EXPECT_EQ(from_scene.last_report().substeps, 16);
  EXPECT_EQ(from_scene.last_report().iterations, 16 * 2);
  EXPECT_EQ(from_model.last_report().substeps, 1);
  EXPECT_EQ(from_model.last_report().iterations, RelaxationSettings{}.iterations);
  // Bad method settings are refused by name, from a scene or from options.
  WorldOptions bad;
  bad.particles.relaxation.substeps = 0;
  try {
    World world(chain.model, bad);
    ADD_FAILURE() << "compiled";
  } catch (const ModelError& error) {
    EXPECT_THAT(error.what(), HasSubstr("settings.relaxation.substeps: must be >= 1"));
  }
}

TEST(World, TheLastStepsReportIsTheMethodsReport) {
  // The ball reaches the humanoid: every method's report counts the contacts of that step;
  // the particle method's also its sweeps; a refused Δt is reported too.
  const Model humanoid = load_shipped_scene("humanoid.json");
  for (const Method method : kMethods) {
    World world(humanoid, options_for(method));
    int most_contacts = 0;
    for (int s = 0; s < 120; ++s) {
      ASSERT_EQ(world.step(), StepStatus::ok) << name(method);
      EXPECT_EQ(world.last_report().status, StepStatus::ok);
      most_contacts = std::max(most_contacts, world.last_report().contacts);
    }
    EXPECT_GT(most_contacts, 0) << name(method) << ": the ball hits";
    if (method == Method::particles) {
      EXPECT_EQ(world.last_report().iterations, RelaxationSettings{}.iterations);
    }
    EXPECT_EQ(world.step(-1.0), StepStatus::invalid_time_step);
    EXPECT_EQ(world.last_report().status, StepStatus::invalid_time_step) << name(method);
  }
}

TEST(World, BadHandlesAndVectorsAreRefusedByName) {
  World world(free_limb());
  EXPECT_THROW(world.body("nobody"), WorldError);
  const BodyId limb = world.body("link_0");
  try {
    world.apply_force(limb, Eigen::Vector3d(NAN, 0, 0), Eigen::Vector3d::Zero());
    FAIL();
  } catch (const WorldError& error) {
    EXPECT_THAT(error.what(), HasSubstr("apply_force: must be finite"));
  }
  world.remove_body(limb);
  EXPECT_THROW(world.pose(limb), WorldError);
}

// A limb hung by its head, its mass given directly: centre of mass 5 cm beyond its centre
// towards the tail, a transverse inertia unlike its shape's. It swings with the compound
// pendulum's period T = 2π √(I_pivot / (m g d)), I_pivot = I_c + m d², d the pivot to the centre
// of mass — with the given tensor, not the shape's.
Model pendulum_with_given_inertia() {
  Model model;
  model.name = "compound_pendulum";
  Body body;
  body.name = "limb";
  body.shape = {ShapeType::capsule, 0.4, 0.02};
  body.mass = 2;
  body.inertial = Inertial{Vector3(0, 0, -0.05), Eigen::Vector3d(0.02, 0.02, 0.004).asDiagonal()};
  const double release = 0.05;  // rad from hanging straight down
  body.axis = Vector3(std::sin(release), 0, std::cos(release));
  const Vector3 pivot(0, 0, 1);
  body.position = pivot - 0.5 * body.shape.length * body.axis;
  model.bodies.push_back(body);
  model.joints.push_back(spherical_joint("pin", kWorld, 0, pivot, Vector3(0, 0, 0.2)));
  model.settings.sleep.enabled = false;
  return model;
}

TEST(World, AGivenInertiaTensorAndCentreOfMassSetTheSwingPeriod) {
  const double m = 2, g = 9.81, d = 0.2 + 0.05, pivot_inertia = 0.02 + m * d * d;
  const double expected = 2 * std::numbers::pi * std::sqrt(pivot_inertia / (m * g * d)) * (1 + 0.05 * 0.05 / 16);
  for (const Method method : kMethods) {
    WorldOptions options = options_for(method);
    options.particles.verlet.limb_masses = LimbMasses::inertia;  // particles: mass placed to match the tensor
    World world(pendulum_with_given_inertia(), options);
    const BodyId limb = world.body("limb");
    // Upward zero crossings of the limb's x, interpolated within the step.
    const double dt = 1e-3;
    std::vector<double> crossings;
    double previous = world.pose(limb).position.x();
    for (int s = 1; s <= 2600 && crossings.size() < 3; ++s) {
      ASSERT_EQ(world.step(dt), StepStatus::ok) << name(method);
      const double x = world.pose(limb).position.x();
      if (previous < 0 && x >= 0) crossings.push_back(dt * (s - x / (x - previous)));
      previous = x;
    }
    ASSERT_EQ(crossings.size(), 3u) << name(method);
    const double period = 0.5 * (crossings[2] - crossings[0]);
    // Springs flex at the pin (a stiff spring, not a constraint): 1%; the others 0.2%.
    EXPECT_NEAR(period / expected, 1.0, method == Method::springs ? 1e-2 : 2e-3) << name(method) << " period " << period;
  }
}

TEST(World, AGivenInertiaIsCheckedAndParticlesRefuseAnOffAxisCentre) {
  Model model = pendulum_with_given_inertia();
  const auto error_of = [](const Model& candidate, Method method) -> std::string {
    WorldOptions options = options_for(method);
    options.particles.verlet.limb_masses = LimbMasses::inertia;  // particles: mass placed to match the tensor
    try {
      World world(candidate, options);
    } catch (const ModelError& error) {
      return error.what();
    }
    return "";
  };
  model.bodies[0].inertial->inertia(0, 1) = 0.001;  // not symmetric
  EXPECT_EQ(error_of(model, Method::featherstone), "bodies[0].inertial.inertia: must be symmetric");
  model.bodies[0].inertial->inertia = Eigen::Vector3d(0.01, 0.01, 0.03).asDiagonal();  // I1 + I2 < I3
  EXPECT_THAT(error_of(model, Method::featherstone), HasSubstr("bodies[0].inertial.inertia: principal moments [0.01, 0.01, 0.03] break the triangle inequality"));
  model.bodies[0].inertial->inertia = Eigen::Vector3d(0.01, 0.01, -0.001).asDiagonal();
  EXPECT_THAT(error_of(model, Method::lagrange), HasSubstr("must be positive definite"));
  model = pendulum_with_given_inertia();
  model.bodies[0].inertial->centre_of_mass = Vector3(0.01, 0, 0);
  EXPECT_EQ(error_of(model, Method::featherstone), "");  // the rigid methods take any centre of mass
  EXPECT_THAT(error_of(model, Method::particles), HasSubstr("the centre of mass on the limb's axis"));
}

// The threads of this process (Linux: /proc/self/task).
int thread_count() {
  int count = 0;
  if (DIR* tasks = opendir("/proc/self/task")) {
    while (const dirent* entry = readdir(tasks)) count += entry->d_name[0] != '.';
    closedir(tasks);
  }
  return count;
}

TEST(World, ADefaultWorldStartsNoThread) {
  const int before = thread_count();
  World world(load_shipped_scene("humanoid.json"));
  for (int s = 0; s < 60; ++s) world.step();
  World chain(make_chain(std::vector<double>(50, 1.0), 0.1, true));
  for (int s = 0; s < 60; ++s) chain.step(1.0 / 240);
  EXPECT_EQ(thread_count(), before);
}

TEST(World, OnAnEnginesTaskSystemStepsTheSerialBits) {
  // Threading::tasks: the particles' colour sweeps, and Featherstone's islands and contact groups
  // (the ragdoll and the ball), run on the engine's scheduler (here two threads of the test's
  // own, and a oneTBB arena) and every body ends each step where the serial World puts it, bit
  // for bit. (tools/sanitize.sh thread runs this.)
  const Scene ragdoll = testing::shipped_scene("ragdoll.json");
  const auto poses_after = [&](const WorldOptions& options) {
    World world(ragdoll.model, options);
    std::vector<double> coordinates;
    for (int s = 0; s < 90; ++s) {
      EXPECT_EQ(world.step(), StepStatus::ok);
      for (const BodyId body : world.bodies()) {
        const Pose pose = world.pose(body);
        coordinates.insert(coordinates.end(), pose.position.data(), pose.position.data() + 3);
        coordinates.insert(coordinates.end(), pose.orientation.coeffs().data(), pose.orientation.coeffs().data() + 4);
      }
    }
    return coordinates;
  };
  TaskSystem two_threads;
  two_threads.enqueue = [](TaskSystem::Work work, std::size_t count, void* work_context, void*) -> void* {
    std::thread second(work, count / 2, count, work_context);
    work(0, count / 2, work_context);
    second.join();
    return nullptr;
  };
  two_threads.finish = [](void*, void*) {};
  tbb::task_arena arena(2);
  for (const Method method : {Method::particles, Method::featherstone}) {
    const WorldOptions serial = world_options(method, ragdoll.methods);
    const std::vector<double> expected = poses_after(serial);
    for (const TaskSystem& tasks : {two_threads, tbb_task_system(arena)}) {
      WorldOptions options = serial;
      options.particles.threading = Threading::tasks, options.particles.tasks = tasks, options.particles.threads = 2;
      options.particles.parallel_minimum_slots = 1;
      options.featherstone.threading = Threading::tasks, options.featherstone.tasks = tasks, options.featherstone.threads = 2;
      EXPECT_EQ(poses_after(options), expected) << method_name(method);
    }
  }
}

}  // namespace
}  // namespace limber
