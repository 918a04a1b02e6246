// Serial joints under the maximal-coordinate methods: revolute joints through virtual links
// (kernel/scene/serial_links.hpp). The expansion keeps the Model's indices, mass and joint points;
// a motion under Lagrange and under the particles approaches Featherstone's exact one as the
// links' mass share shrinks (first order); limits hold on every axis; motors act on the axis
// they name; bodies a serial joint joins do not collide.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "limber/kernel/featherstone/compile.hpp"
#include "limber/kernel/featherstone/step.hpp"
#include "limber/kernel/geometry/limb_collisions.hpp"
#include "limber/kernel/lagrange/compile.hpp"
#include "limber/kernel/lagrange/step.hpp"
#include "limber/kernel/metrics/observers.hpp"
#include "limber/kernel/scene/serial_links.hpp"
#include "limber/kernel/world/world.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

// A 1 m rod hanging from two hinges in a row at its top: about y through the origin, then about
// z through a point 0.1 m down the rod (skew axes, as MuJoCo's humanoid's ankles), swinging.
Model rod_on_two_skew_hinges() {
  Model model = testing::rod_held_at_head(JointType::serial);
  Joint& joint = model.joints[0];
  SerialAxis about_y, about_z;
  about_y.name = "about_y", about_y.axis = Eigen::Vector3d::UnitY();
  about_z.name = "about_z", about_z.axis = Eigen::Vector3d::UnitZ(), about_z.point = Eigen::Vector3d(0.1, 0, 0);
  joint.serial_axes = {about_y, about_z};
  joint.outboard_anchor = Eigen::Vector3d(0, 0, 0.4);  // the last axis's point on the rod
  model.bodies[0].angular_velocity = Eigen::Vector3d(0, 1, 0);
  model.bodies[0].linear_velocity = Eigen::Vector3d(0, 1, 0).cross(model.bodies[0].position);
  model.settings.gravity = Eigen::Vector3d(0, 0, -9.81);
  return model;
}

// The rod's tip (its tail) after `steps` steps of 1 ms, by a method's World.
Eigen::Vector3d tip_after(const Model& model, Method method, int steps, std::vector<double> controls = {}) {
  WorldOptions options;
  options.method = method;
  options.lagrange.integrator = Integrator::rk4;
  options.featherstone.integrator = Integrator::rk4;
  options.particles.relaxation.substeps = 4;
  options.particles.verlet.joint_solve = JointSolve::tree;
  options.particles.verlet.limb_masses = LimbMasses::inertia;  // the rod's inertia exact, as the rigid methods' is
  options.particles.relaxation.projection = ProjectionRule::rattle;
  World world(model, options);
  if (!controls.empty()) world.set_controls(controls);
  for (int n = 0; n < steps; ++n) world.step(1e-3);
  const Pose pose = world.pose(world.body("rod"));
  return pose.position + pose.orientation * Eigen::Vector3d(0, 0, -0.5);
}

TEST(SerialLinks, TheExpansionKeepsIndicesMassAndJointPoints) {
  const Model model = rod_on_two_skew_hinges();
  const SerialExpansion expansion = expand_serial_joints(model);
  const Model& out = expansion.model;
  ASSERT_EQ(out.bodies.size(), 2u);
  ASSERT_EQ(out.joints.size(), 2u);
  EXPECT_EQ(out.bodies[0].name, "rod");
  EXPECT_EQ(out.joints[0].type, JointType::revolute);
  EXPECT_EQ(out.joints[1].name, "hinge/about_z");
  EXPECT_EQ(expansion.joint_of_axis(0, 0), 0u);
  EXPECT_EQ(expansion.joint_of_axis(0, 1), 1u);
  EXPECT_EQ(model_joint_of(model, 0), 0u);
  EXPECT_EQ(model_joint_of(model, 1), 0u);  // the second axis's joint is the serial joint's
  EXPECT_NEAR(out.body_mass(), model.body_mass(), 1e-15);
  EXPECT_FALSE(filters_collide(out.bodies[1].collision, CollisionFilter{}));
  // Each joint's two anchors are one world point, on its axis.
  for (const Joint& joint : out.joints) {
    const Body& b = out.bodies[static_cast<std::size_t>(joint.outboard)];
    const Eigen::Vector3d inboard = joint.inboard == kWorld ? joint.inboard_anchor : out.bodies[static_cast<std::size_t>(joint.inboard)].to_world(joint.inboard_anchor);
    EXPECT_LT((inboard - b.to_world(joint.outboard_anchor)).norm(), 1e-15) << joint.name;
  }
  EXPECT_LT((out.bodies[0].to_world(out.joints[1].outboard_anchor) - Eigen::Vector3d(0.1, 0, 0)).norm(), 1e-15);
  validate(out);
}

// A box's length is 0: where its two hinges' axes meet, the link between them takes a quarter of
// its longest side (not 0 m, whose direction is undefined).
TEST(SerialLinks, AHingedBoxGetsALinkOfAQuarterOfItsLongestSide) {
  Model model = rod_on_two_skew_hinges();
  Body& box = model.bodies[0];
  box.shape = Shape{};
  box.shape.type = ShapeType::box, box.shape.half_extents = {0.05, 0.1, 0.5};
  model.joints[0].serial_axes[1].point = Eigen::Vector3d::Zero();  // the axes meet at the origin,
  model.joints[0].outboard_anchor = Eigen::Vector3d(0, 0, 0.5);     // the box's end
  validate(model);
  const Model out = expand_serial_joints(model).model;
  ASSERT_EQ(out.bodies.size(), 2u);
  EXPECT_NEAR(out.bodies[1].shape.length, 0.25, 1e-15) << "a quarter of 1 m";
  EXPECT_TRUE(out.bodies[1].axis.allFinite());
  validate(out);
}

// Against Featherstone's exact motion, 0.5 s of a swing about both axes under gravity: the gap
// shrinks with the links' mass share, at first order (ten times less mass, about ten times less
// gap), so it is the virtual links' mass and nothing else.
// A gap on a serial joint's axis is reported as that joint's, by the methods that run the axes
// as joints of their own: the rod pulled 0.1 m off its hinges opens the joint after the link,
// joint 1 of the expansion, which World::observe() names as the Model's joint 0.
TEST(SerialLinks, AnAxisOpenIsReportedAsItsSerialJoint) {
  const Model model = rod_on_two_skew_hinges();
  for (const Method method : {Method::particles, Method::lagrange}) {
    WorldOptions options;
    options.method = method;
    World world(model, options);
    const BodyId rod = world.body("rod");
    Pose pulled = world.pose(rod);
    pulled.position.x() += 0.1;
    world.teleport(rod, pulled, Motion{});
    const Observation now = world.observe();
    EXPECT_GT(now.max_joint_gap, 0.05) << method_name(method);
    EXPECT_EQ(now.widest_joint, 0) << method_name(method);
  }
}

TEST(SerialLinks, LagrangeApproachesFeatherstoneAsTheLinksLighten) {
  const Model model = rod_on_two_skew_hinges();
  const Eigen::Vector3d exact = tip_after(model, Method::featherstone, 500);
  double gaps[2];
  const double shares[2] = {1e-2, 1e-3};
  for (int k = 0; k < 2; ++k) {
    const Model expanded = expand_serial_joints(model, Armature::as_rotor, shares[k]).model;
    gaps[k] = (tip_after(expanded, Method::lagrange, 500) - exact).norm();
    std::printf("share %g: tip %.3g m from Featherstone's\n", shares[k], gaps[k]);
  }
  EXPECT_GT(gaps[0], 5 * gaps[1]);
  EXPECT_LT(gaps[1], 1e-3);
  // The default share through the World, serial joint and all, is the first of these.
  EXPECT_NEAR((tip_after(model, Method::lagrange, 500) - exact).norm(), gaps[0], 1e-12);
}

TEST(SerialLinks, ParticlesFollowFeatherstone) {
  const Model model = rod_on_two_skew_hinges();
  const Eigen::Vector3d exact = tip_after(model, Method::featherstone, 500);
  const double gap = (tip_after(model, Method::particles, 500) - exact).norm();
  std::printf("particles: tip %.3g m from Featherstone's (the rod's tip moved %.3g m)\n", gap,
              (exact - Eigen::Vector3d(1, 0, 0)).norm());
  EXPECT_LT(gap, 0.05 * (exact - Eigen::Vector3d(1, 0, 0)).norm());
}

// A motor on the second axis turns the rod about z: the same way, and about as far, as under
// Featherstone (no gravity, so only the motor moves it). The particles refuse the control
// (MethodCapabilities::serial_actuators): on this rod they came within 5 % of Featherstone, on
// MuJoCo's humanoid they moved its bodies of several hinges wrongly (bench/models.md).
TEST(SerialLinks, AMotorActsOnTheAxisItNames) {
  Model model = rod_on_two_skew_hinges();
  model.settings.gravity.setZero();
  model.bodies[0].angular_velocity.setZero(), model.bodies[0].linear_velocity.setZero();
  model.actuators.push_back({.name = "turn", .joint = 0, .axis = 1, .gear = 0.5, .control_range = {}});
  const Eigen::Vector3d exact = tip_after(model, Method::featherstone, 300, {1.0});
  ASSERT_GT(exact.y(), 0.01);  // turned about +z: the tip, at +x, moves to +y
  EXPECT_LT((tip_after(model, Method::lagrange, 300, {1.0}) - exact).norm(), 0.05 * exact.y());
  EXPECT_THROW(tip_after(model, Method::particles, 300, {1.0}), WorldError);
}

// Each axis's range holds under every method: a rod jointed by the two hinges to a heavier free
// body, swung hard about both axes without gravity, stays within both ranges (the angles of its
// direction relative to the other body). The particles solve the joints as trees (a light link
// between heavy bodies is what the trees solve exactly; relaxation sweeps converge slowly there).
TEST(SerialLinks, EveryAxisHoldsItsRange) {
  Model model = rod_on_two_skew_hinges();
  model.joints[0].serial_axes[0].range = Range{-0.3, 0.3};
  model.joints[0].serial_axes[1].range = Range{-0.2, 0.2};
  Body upper = model.bodies[0];
  upper.name = "upper", upper.position = Eigen::Vector3d(-0.5, 0, 0), upper.mass = 2;
  upper.angular_velocity.setZero(), upper.linear_velocity.setZero();
  model.bodies.insert(model.bodies.begin(), upper);  // the root first (Featherstone's tree)
  Joint& joint = model.joints[0];
  joint.inboard = 0, joint.outboard = 1, joint.inboard_anchor = Eigen::Vector3d(0, 0, -0.5);
  model.bodies[1].angular_velocity = Eigen::Vector3d(0, 4, 3);
  model.bodies[1].linear_velocity = model.bodies[1].angular_velocity.cross(model.bodies[1].position);
  model.settings.gravity.setZero();
  const Eigen::Quaterniond upper_rest = model.bodies[0].orientation(), rod_rest = model.bodies[1].orientation();
  for (Method method : {Method::featherstone, Method::lagrange, Method::particles}) {
    WorldOptions options;
    options.method = method;
    options.particles.verlet.joint_solve = JointSolve::tree;
    options.particles.relaxation.iterations = 4;
    World world(model, options);
    double pitch = 0, yaw = 0;
    for (int n = 0; n < 1000; ++n) {
      world.step(1e-3);
      const Eigen::Quaterniond turned = (world.pose(world.body("upper")).orientation * upper_rest.conjugate()).conjugate() *
                                        (world.pose(world.body("rod")).orientation * rod_rest.conjugate());
      const Eigen::Vector3d d = turned * Eigen::Vector3d::UnitX();  // to the rod's tip, +x at rest
      pitch = std::max(pitch, std::abs(std::atan2(-d.z(), d.x())));  // the angle about y: +x turns to −z
      yaw = std::max(yaw, std::abs(std::atan2(d.y(), std::hypot(d.x(), d.z()))));  // then about the carried z
    }
    EXPECT_LT(pitch, 0.3 + 1e-3) << method_name(method);
    EXPECT_GT(pitch, 0.3 - 1e-3) << method_name(method) << ": the swing reached the pitch range";
    EXPECT_LT(yaw, 0.2 + 1e-3) << method_name(method);
    EXPECT_GT(yaw, 0.2 - 1e-3) << method_name(method) << ": the swing reached the yaw range";
  }
}

// Bodies a serial joint joins overlap at the joint by design (a hip's pelvis and thigh): they do
// not collide, through the virtual links between them, while a body jointed to neither does.
TEST(SerialLinks, TheBodiesItJoinsDoNotCollide) {
  Model model = rod_on_two_skew_hinges();
  Body upper = model.bodies[0];
  upper.name = "upper", upper.position = Eigen::Vector3d(0.5, 5, 0);  // apart at rest: no rest overlap
  model.bodies.push_back(upper);
  Body other = upper;
  other.name = "other", other.position = Eigen::Vector3d(0.5, -5, 0);
  model.bodies.push_back(other);
  model.joints[0].inboard = 1, model.joints[0].inboard_anchor = Eigen::Vector3d(0, 0, 0.5);
  const Model expanded = expand_serial_joints(model).model;
  LimbCollisions collisions(expanded);
  std::vector<LimbSegment> segments;
  for (const Body& body : expanded.bodies) segments.push_back({body.head(), body.tail(), body.shape.radius});
  // "upper" and "other" now cross the rod, upright through (0.5, 0, 0) and (0.7, 0, 0).
  segments[1].head = Eigen::Vector3d(0.5, 0, 0.5), segments[1].tail = Eigen::Vector3d(0.5, 0, -0.5);
  segments[2].head = Eigen::Vector3d(0.7, 0, 0.5), segments[2].tail = Eigen::Vector3d(0.7, 0, -0.5);
  std::vector<std::uint8_t> awake(segments.size(), 1);
  std::vector<LimbContact> contacts;
  collisions.find(segments, awake, 0.01, contacts);
  bool rod_other = false;
  for (const LimbContact& c : contacts) {
    EXPECT_FALSE(c.first == 0 && c.second == 1) << "the rod touched the body it hangs from";
    rod_other |= (c.first == 0 && c.second == 2);
  }
  EXPECT_TRUE(rod_other);
}

}  // namespace
}  // namespace limber

namespace limber {
namespace {

// Lagrange applies a hinge's armature as a compliant row on the hinge's rate (M + a·JᵀJ,
// kernel/lagrange/README.md), MuJoCo's term exactly. On one hinge to the world the rod swings as
// Featherstone's with armature; on two skew hinges it is off by no more than the virtual link's
// own error (the same pair without armature). As a rotor disc on the body after each hinge it
// was 0.069 m off after 0.5 s, its a/2 across the axis adding to the other hinge's inertia.
TEST(SerialLinks, LagrangesArmatureIsFeatherstones) {
  Model model = testing::rod_held_at_head(JointType::revolute);
  model.settings.gravity = Eigen::Vector3d(0, 0, -9.81);
  model.joints[0].armature = 0.2;  // beside the rod's 1/3 kg·m² about the hinge
  const Eigen::Vector3d exact = tip_after(model, Method::featherstone, 500);
  const double with_armature = (tip_after(model, Method::lagrange, 500) - exact).norm();
  Model without = model;
  without.joints[0].armature = 0;
  const double without_armature = (tip_after(without, Method::lagrange, 500) - exact).norm();
  std::printf("one hinge: tip from Featherstone's with armature: %.3g m, %.3g m without armature\n", with_armature, without_armature);
  EXPECT_LT(with_armature, 1e-6);
  EXPECT_GT(without_armature, 0.1) << "the armature matters here";
  Model pair = rod_on_two_skew_hinges();
  for (SerialAxis& axis : pair.joints[0].serial_axes) axis.armature = 0.05;
  const double pair_error = (tip_after(pair, Method::lagrange, 500) - tip_after(pair, Method::featherstone, 500)).norm();
  for (SerialAxis& axis : pair.joints[0].serial_axes) axis.armature = 0;
  const double links_error = (tip_after(pair, Method::lagrange, 500) - tip_after(pair, Method::featherstone, 500)).norm();
  std::printf("two skew hinges: %.3g m with armature, %.3g m without (the virtual link's error)\n", pair_error, links_error);
  EXPECT_LT(pair_error, 2 * links_error);
}

}  // namespace
}  // namespace limber
