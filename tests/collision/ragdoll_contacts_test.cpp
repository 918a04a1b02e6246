// Limb–limb contacts on whole ragdolls, through the World, for the methods that hold them: a
// ragdoll that lands on its own limbs, a ragdoll dropped onto another, and the thesis's ball
// fired at a thin limb, and at thin static geometry, at 100 m/s. Every measure is taken alike for every method, from the
// limbs' segments (observers.hpp's limb_segments) and the collision world's own geometry
// (limb_collisions.hpp), never from a method's own contact list.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <gtest/gtest.h>

#include "limber/kernel/geometry/limb_collisions.hpp"
#include "limber/kernel/world/world.hpp"
#include "tests/support/models.hpp"

namespace limber {
namespace {

using Eigen::Vector3d;

constexpr double kStep = 1.0 / 240;  // s, the shipped scenes' step
constexpr double kGravity = 9.81;    // m/s², the scenes' |g|

std::string param_name(const ::testing::TestParamInfo<Method>& info) { return std::string(method_name(info.param)); }

// A method as the ragdoll tests step it; Featherstone by its integrator, which decides when its
// contacts are solved: after the move under RK4 (the thesis's loop), before it under semi-implicit
// Euler (kernel/featherstone/joint_space_contacts.hpp).
struct Stepping {
  Method method = Method::particles;
  Integrator featherstone = Integrator::rk4;
};
std::string stepping_name(const ::testing::TestParamInfo<Stepping>& info) {
  std::string name(method_name(info.param.method));
  if (info.param.method == Method::featherstone && info.param.featherstone != Integrator::rk4) name += "_semi_implicit_euler";
  return name;
}
constexpr Stepping kFeatherstoneBeforeTheMove{Method::featherstone, Integrator::semi_implicit_euler};

// Turns `model` as one rigid piece by `turn` about the origin, then moves it by `offset`: every
// pose, velocity and world-frame joint datum (axes, cone axes, world anchors). A body's frame is
// the shortest arc from +z onto its axis (model.hpp), which after the turn may differ from the
// turned frame by a roll about the axis; the body-frame data (joint anchors, point masses, an
// inertial) are carried through that roll, so each stays on the same material point. The
// callers check the result with largest_joint_gap().
void turn_model(Model& model, const Eigen::Quaterniond& turn, const Vector3d& offset) {
  std::vector<Eigen::Quaterniond> roll;  // per body: new body frame <- old body frame
  for (Body& body : model.bodies) {
    const Eigen::Quaterniond before = body.orientation();
    body.position = turn * body.position + offset;
    body.axis = turn * body.axis;
    body.linear_velocity = turn * body.linear_velocity;
    body.angular_velocity = turn * body.angular_velocity;
    roll.push_back(body.orientation().inverse() * turn * before);
    for (PointMass& lump : body.point_masses) lump.position = roll.back() * lump.position;
    if (body.inertial) {
      const Eigen::Matrix3d r = roll.back().toRotationMatrix();
      body.inertial->centre_of_mass = r * body.inertial->centre_of_mass;
      body.inertial->inertia = r * body.inertial->inertia * r.transpose();
    }
  }
  for (Joint& joint : model.joints) {
    if (joint.inboard == kWorld) {
      joint.inboard_anchor = turn * joint.inboard_anchor + offset;
    } else {
      joint.inboard_anchor = roll[static_cast<std::size_t>(joint.inboard)] * joint.inboard_anchor;
    }
    joint.outboard_anchor = roll[static_cast<std::size_t>(joint.outboard)] * joint.outboard_anchor;
    joint.axis = turn * joint.axis;
    joint.second_axis = turn * joint.second_axis;
    if (joint.limits.swing_axis) joint.limits.swing_axis = turn * *joint.limits.swing_axis;
    if (joint.drive) joint.drive->target_rotation = turn * joint.drive->target_rotation;
  }
}

Eigen::Quaterniond quarter_turn(const Vector3d& axis) { return Eigen::Quaterniond(Eigen::AngleAxisd(0.5 * std::numbers::pi, axis)); }

// The largest gap between a joint's two anchors at the Model's poses, m (0 for the ragdoll as
// shipped): a turn that lost an anchor's material point would open one.
double largest_joint_gap(const Model& model) {
  double largest = 0;
  for (const Joint& joint : model.joints) {
    if (joint.inboard == kWorld) continue;
    const Vector3d a = model.bodies[static_cast<std::size_t>(joint.inboard)].to_world(joint.inboard_anchor);
    const Vector3d b = model.bodies[static_cast<std::size_t>(joint.outboard)].to_world(joint.outboard_anchor);
    largest = std::max(largest, (a - b).norm());
  }
  return largest;
}

// The shipped ragdoll (medium: 13 limbs, 197 kg), limp, no ball, awake and with sleep off, so
// nothing zeroes a motion the test means to see. Its limbs collide with each other (the default
// filter), but for the pairs the collision world excludes: joined, or overlapping at rest.
Model limp_ragdoll() {
  Model model = testing::load_shipped_scene("ragdoll.json");
  model.balls.clear();
  model.settings.sleep.enabled = false;
  model.settings.sleep.start_asleep = false;
  return model;
}

// A World for `model` with the ragdoll scene's method settings (for particles, its joint trees at 2
// substeps × 2 sweeps).
World ragdoll_world(const Model& model, Stepping stepping) {
  WorldOptions options = world_options(stepping.method, testing::shipped_scene("ragdoll.json").methods);
  options.featherstone.integrator = stepping.featherstone;
  return World(model, options);
}

// Limb–limb contacts now, found by a collision world of the Model (its filters and exclusions:
// joined pairs and pairs overlapping at rest never count), static and ball contacts dropped.
class LimbPairs {
 public:
  explicit LimbPairs(const Model& model) : collisions_(model), limb_count_(model.bodies.size()) {}

  const std::vector<LimbContact>& within(const World& world, double margin) {
    world.segments(segments_);
    awake_.assign(segments_.size(), 1);
    collisions_.find(segments_, awake_, margin, contacts_);
    std::erase_if(contacts_, [&](const LimbContact& c) { return c.second == kStaticShape || c.second >= limb_count_; });
    return contacts_;
  }

 private:
  LimbCollisions collisions_;
  std::size_t limb_count_;
  std::vector<LimbSegment> segments_;
  std::vector<std::uint8_t> awake_;
  std::vector<LimbContact> contacts_;
};

// Two limbs touch when their surfaces are within 1 mm: far under any limb's radius (2 cm and
// more), so a touch is a contact, not a near miss.
constexpr double kTouch = 1e-3;  // m

// The deepest limb–limb overlap allowed at any step, m. A limb that lands on the ground stops
// within a step, while one above it still comes on at the landing speed v: a contact found
// from the motion so far cannot foresee that stop, so up to v·Δt may show for a step — 11.7 mm
// for the 0.4 m drop below (v = 2.8 m/s), 10.1 mm for the 0.3 m one. 1 cm is less than
// either: the contacts must catch most of that step, and hold resting limbs, which carry the
// trunk's weight, to well under it.
constexpr double kDeepestOverlap = 0.01;  // m

// ---------------------------------------------------------------------------------------------
// 1. A ragdoll dropped on its side lands on its own limbs: the trunk onto the arm under it, the
//    upper leg onto the lower one.

struct SelfFall {
  double deepest = 0;      // m, the deepest limb–limb overlap at any step
  int touching_steps = 0;  // steps with some pair of its limbs touching
};

// The ragdoll on its right side, its lowest point `drop` m up, falls and settles for `seconds`.
SelfFall fall_on_side(Stepping method, double drop, double seconds) {
  Model model = limp_ragdoll();
  // A quarter turn about x takes its up (+z) to −y and its left (+y) up, so the right arm lies
  // under the trunk and the left leg over the right one. The arms reach 0.16 m across the
  // midline, the lowest point.
  turn_model(model, quarter_turn(Vector3d::UnitX()), Vector3d(0, 0.6, drop + 0.16));
  EXPECT_LT(largest_joint_gap(model), 1e-9) << "the turn kept every joint closed";
  World world = ragdoll_world(model, method);
  LimbPairs pairs(world.model());
  SelfFall result;
  const int steps = static_cast<int>(std::lround(seconds / kStep));
  for (int step = 0; step < steps; ++step) {
    EXPECT_EQ(world.step(kStep), StepStatus::ok) << "step " << step;
    const auto& touching = pairs.within(world, kTouch);
    for (const LimbContact& contact : touching) result.deepest = std::max(result.deepest, -contact.separation);
    result.touching_steps += !touching.empty();
  }
  return result;
}

// A 0.4 m drop (landing at v = 2.8 m/s, 11.7 mm a step), raised by a fraction of a step's
// travel so that it lands at four phases of a step: the overlap a landing leaves depends on
// where in its step the contact begins, and one drop height would test one phase only.
constexpr double kSideDrop = 0.4;  // m
std::vector<double> landing_drops(double drop) {
  const double step_travel = std::sqrt(2 * kGravity * drop) * kStep;
  std::vector<double> out;
  for (const double phase : {0.1, 0.35, 0.6, 0.85}) out.push_back(drop + phase * step_travel);
  return out;
}

class RagdollSelfContact : public ::testing::TestWithParam<Stepping> {};

TEST_P(RagdollSelfContact, RagdollLandingOnItsSideDoesNotSinkIntoItself) {
  for (const double drop : landing_drops(kSideDrop)) {
    SCOPED_TRACE("dropped from " + std::to_string(drop) + " m");
    const SelfFall fall = fall_on_side(GetParam(), drop, 2.0);
    // Not vacuous: its limbs lay on each other for at least 0.5 s (120 steps) of the 1.7 s
    // after it lands (at 0.29 s), not for a step or two.
    EXPECT_GT(fall.touching_steps, 120) << "steps with two of its limbs touching";
    EXPECT_LT(fall.deepest, kDeepestOverlap) << "deepest limb-limb overlap over the fall and settling, m";
    RecordProperty("drop_" + std::to_string(drop), "deepest overlap " + std::to_string(fall.deepest) + " m, touching steps " + std::to_string(fall.touching_steps));
  }
}

// ---------------------------------------------------------------------------------------------
// 2. A ragdoll dropped across another lying on its back comes to rest draped over it.

// The lower ragdoll lies on its back along x; the upper, on its back along y, falls 0.3 m onto
// the lower's waist. `across`: the two bodies collide with each other (else each collides only
// with itself: the control). Both are whole 13-limb ragdolls, each self-colliding.
struct Stack {
  double deepest_between = 0;  // m, the deepest overlap of a limb of one with a limb of the other
  double deepest_within = 0;   // m, the same within either body
  int touching_steps = 0;      // steps with a limb of one touching a limb of the other
  double lower_height = 0, upper_height = 0;  // m, the centres of mass at the end
  double settled_energy = 0;   // J, the largest kinetic energy over the last 0.5 s
  double settled_speed = 0;    // m/s, the fastest limb centre over the last 0.5 s
  double drop_energy = 0;      // J, m_upper·g·(the upper's start height over the lower's top)
};

constexpr double kSettleWindow = 0.5;  // s: "at rest" holds over this, SleepSettings' time_to_sleep

Stack drop_onto_another(Stepping method, bool across, double drop, double seconds) {
  Model lower = limp_ragdoll(), upper = limp_ragdoll();
  // The lower on its back, head to −x: a quarter turn about −y takes +z to −x and the front
  // (+x) up; the trunk (radius 0.1 m) lies 5 mm over the ground, its top at 0.205 m.
  constexpr double kLowerTop = 0.205;  // m
  turn_model(lower, quarter_turn(-Vector3d::UnitY()), Vector3d(0.6, 0, 0.105));
  // The upper the same, then a quarter turn about z (head to −y): it crosses the lower at its
  // own hips, over the lower's basin (x ≈ 0), its back `drop` m over the lower's top.
  turn_model(upper, quarter_turn(Vector3d::UnitZ()) * quarter_turn(-Vector3d::UnitY()), Vector3d(-0.03, 0.65, kLowerTop + drop + 0.1));
  EXPECT_LT(largest_joint_gap(lower), 1e-9);
  EXPECT_LT(largest_joint_gap(upper), 1e-9);
  if (!across) {
    for (Body& body : lower.bodies) body.collision = {1, 1};
    for (Body& body : upper.bodies) body.collision = {2, 2};
  }
  Model model = lower;
  append_model(model, upper, "upper.", Vector3d::Zero());
  const std::size_t first_upper = lower.bodies.size();

  World world = ragdoll_world(model, method);
  const std::vector<BodyId> bodies = world.bodies();
  const auto centre_of_mass = [&](std::size_t begin, std::size_t end) {
    Vector3d weighted = Vector3d::Zero();
    double mass = 0;
    for (std::size_t b = begin; b < end; ++b) {
      weighted += world.body_description(bodies[b]).mass * world.pose(bodies[b]).position;
      mass += world.body_description(bodies[b]).mass;
    }
    return std::pair{Vector3d(weighted / mass), mass};
  };
  Stack result;
  const auto [upper_start, upper_mass] = centre_of_mass(first_upper, bodies.size());
  result.drop_energy = upper_mass * kGravity * (upper_start.z() - kLowerTop);
  LimbPairs pairs(world.model());
  const int steps = static_cast<int>(std::lround(seconds / kStep));
  const int settled_from = steps - static_cast<int>(std::lround(kSettleWindow / kStep));
  for (int step = 0; step < steps; ++step) {
    EXPECT_EQ(world.step(kStep), StepStatus::ok) << "step " << step;
    bool touching = false;
    for (const LimbContact& contact : pairs.within(world, kTouch)) {
      const bool between = (contact.first < first_upper) != (contact.second < first_upper);
      double& deepest = between ? result.deepest_between : result.deepest_within;
      deepest = std::max(deepest, -contact.separation);
      touching = touching || between;
    }
    result.touching_steps += touching;
    if (step < settled_from) continue;
    result.settled_energy = std::max(result.settled_energy, world.observe().kinetic_energy);
    for (const BodyId body : bodies) result.settled_speed = std::max(result.settled_speed, world.motion(body).linear.norm());
  }
  result.lower_height = centre_of_mass(0, first_upper).first.z();
  result.upper_height = centre_of_mass(first_upper, bodies.size()).first.z();
  return result;
}

// A 0.3 m drop (landing at 2.4 m/s, 10.1 mm a step), at four phases of a step as test 1's.
constexpr double kStackDrop = 0.3;  // m

class RagdollStack : public ::testing::TestWithParam<Stepping> {};

TEST_P(RagdollStack, RagdollDroppedOnAnotherComesToRestOnTopOfIt) {
  for (const double drop : landing_drops(kStackDrop)) {
    SCOPED_TRACE("dropped from " + std::to_string(drop) + " m");
    const Stack stack = drop_onto_another(GetParam(), true, drop, 3.0);
    // The two bodies lay on each other for at least 1 s (240 steps) of the 2.7 s after the
    // upper lands (at 0.25 s), not a glance.
    EXPECT_GT(stack.touching_steps, 240) << "steps with a limb of one touching a limb of the other";
    // At rest over the last 0.5 s: every limb slower than the kernel's own rest speed
    // (SleepSettings' 0.05 m/s), and the kinetic energy under 0.1% of what the drop released
    // (770 J: a body still sliding or rocking carries joules).
    EXPECT_LT(stack.settled_speed, 0.05) << "fastest limb centre over the last 0.5 s, m/s";
    EXPECT_LT(stack.settled_energy, 1e-3 * stack.drop_energy) << "largest kinetic energy over the last 0.5 s, J";
    // Stacked: the upper body's centre of mass rests at least a leg's thickness (6 cm) above
    // the lower's. Interleaved, both would lie on their backs on the ground, their centres of
    // mass at one height, as in the control below.
    EXPECT_GT(stack.upper_height - stack.lower_height, 0.06) << "upper minus lower centre of mass height, m";
    EXPECT_LT(stack.deepest_between, kDeepestOverlap) << "deepest overlap of a limb of one body with one of the other, m";
    EXPECT_LT(stack.deepest_within, kDeepestOverlap) << "deepest overlap within either body, m";
    RecordProperty("drop_" + std::to_string(drop), "settled speed " + std::to_string(stack.settled_speed) + " m/s, energy " +
                                                       std::to_string(stack.settled_energy) + " J, stacked " +
                                                       std::to_string(stack.upper_height - stack.lower_height) + " m, overlap " +
                                                       std::to_string(std::max(stack.deepest_between, stack.deepest_within)) + " m");
  }
  // The control: the same drop with the two bodies filtered apart ends interleaved, level.
  const Stack through = drop_onto_another(GetParam(), false, kStackDrop, 3.0);
  EXPECT_LT(through.upper_height - through.lower_height, 0.06) << "upper minus lower centre of mass height, m";
}

// ---------------------------------------------------------------------------------------------
// 3. The thesis's ball at 100 m/s against a thin limb (4 cm thick), in free space.

constexpr double kBallSpeed = 100;                      // m/s
constexpr double kBallRadius = 0.05, kBallMass = 2.26796185, kBallRestitution = 0.8;  // the thesis's ball
constexpr double kLimbRadius = 0.02, kLimbLength = 0.4, kLimbMass = 5;  // about a forearm's mass

struct Shot {
  Vector3d limb_velocity = Vector3d::Zero();  // m/s, after
  Vector3d ball_velocity = Vector3d::Zero();  // m/s, after
};

// The limb stands along z at the origin, at rest, with no gravity and no ground: the ball's
// contact is the only thing that can move it. The ball flies along −x, `aside` m off the limb's
// axis in y, from `start` m out in x; the run lasts until it would be 1 m past the limb, and two
// steps more, so the last step is free flight after any hit.
// The shots' model: one capsule limb along z at `position`, at rest, no gravity, no ground, no sleep.
Model lone_limb(const char* name, double dt, const Vector3d& position) {
  Model model;
  model.name = name;
  model.settings.gravity = Vector3d::Zero();
  model.settings.time_step = dt;
  model.settings.sleep.enabled = false;
  Body limb;
  limb.name = "limb";
  limb.shape = {ShapeType::capsule, kLimbLength, kLimbRadius};
  limb.mass = kLimbMass;
  limb.position = position;
  model.bodies.push_back(limb);
  return model;
}

Shot fire_ball(Method method, double dt, double aside, double start) {
  Model model = lone_limb("ball_at_limb", dt, Vector3d::Zero());
  model.balls = {Ball{kBallRadius, kBallMass, kBallRestitution, Vector3d(start, aside, 0), Vector3d(-kBallSpeed, 0, 0)}};
  World world(model, WorldOptions{.method = method});
  std::vector<LimbSegment> segments;
  const int steps = static_cast<int>(std::ceil((start + 1) / (kBallSpeed * dt))) + 2;
  Vector3d before = Vector3d::Zero();
  for (int step = 0; step < steps; ++step) {
    world.segments(segments);
    before = segments.back().head;  // the ball's centre
    EXPECT_EQ(world.step(dt), StepStatus::ok) << "step " << step;
  }
  world.segments(segments);
  return {world.motion(world.body("limb")).linear, (segments.back().head - before) / dt};
}

// The ball starts 3 steps and a fraction out, at four fractions of a step, so that the test does
// not rest on one alignment of the ball's positions, a step apart, with the 14 cm in which it
// overlaps the limb (at 100 m/s a step is 42 cm at 240 Hz, 1.7 m at 60 Hz).
std::vector<double> starts(double dt) {
  std::vector<double> out;
  for (const double phase : {0.1, 0.35, 0.6, 0.85}) out.push_back(kBallRadius + kLimbRadius + (3 + phase) * kBallSpeed * dt);
  return out;
}

void expect_hit(Method method, double dt) {
  // A head-on hit at the limb's middle (it does not turn): the common velocity after a
  // perfectly inelastic hit, twice it after an elastic one; the ball's e = 0.8 lies between.
  const double common = kBallMass * kBallSpeed / (kBallMass + kLimbMass);
  const Vector3d along = -Vector3d::UnitX();
  for (const double start : starts(dt)) {
    SCOPED_TRACE("dt " + std::to_string(dt) + " s, ball from x = " + std::to_string(start) + " m");
    const Shot shot = fire_ball(method, dt, 0, start);
    // The limb was hit: it moves along the ball's flight, between the inelastic and elastic
    // speeds (5% for the methods' contact resolution), and not sideways.
    EXPECT_GT(shot.limb_velocity.dot(along), 0.95 * common) << "limb velocity along the flight, m/s";
    EXPECT_LT(shot.limb_velocity.dot(along), 1.05 * 2 * common) << "limb velocity along the flight, m/s";
    EXPECT_LT((shot.limb_velocity - shot.limb_velocity.dot(along) * along).norm(), 0.05 * common);
    // The ball did not pass through: after the hit it is no faster along its flight than the
    // limb it pushed (with e = 0.8 > m_ball/m_limb it comes back).
    EXPECT_LE(shot.ball_velocity.dot(along), shot.limb_velocity.dot(along)) << "ball velocity along the flight, m/s";
    // Momentum kept (no other body, no gravity) to 1%, and no energy made (0.1%).
    EXPECT_NEAR(kLimbMass * shot.limb_velocity.dot(along) + kBallMass * shot.ball_velocity.dot(along), kBallMass * kBallSpeed,
                0.01 * kBallMass * kBallSpeed);
    EXPECT_LE(kLimbMass * shot.limb_velocity.squaredNorm() + kBallMass * shot.ball_velocity.squaredNorm(),
              1.001 * kBallMass * kBallSpeed * kBallSpeed);
  }
  // A graze: aimed 5 mm inside the touch, the ball's path meets the limb for 5.2 cm, an eighth of
  // a step at 240 Hz — it still pushes the limb aside (away from its side, −y) and along.
  for (const double start : starts(dt)) {
    SCOPED_TRACE("graze, dt " + std::to_string(dt) + " s, ball from x = " + std::to_string(start) + " m");
    const Shot graze = fire_ball(method, dt, kLimbRadius + kBallRadius - 0.005, start);
    EXPECT_LT(graze.limb_velocity.y(), -0.1) << "m/s";
    EXPECT_GT(graze.limb_velocity.dot(along), 0.1) << "m/s";
  }
  // The control: aimed to pass 10 cm clear of the limb's surface, the ball leaves the limb
  // untouched and flies on at its speed.
  const Shot miss = fire_ball(method, dt, kLimbRadius + kBallRadius + 0.10, starts(dt).front());
  EXPECT_LT(miss.limb_velocity.norm(), 1e-9);
  EXPECT_NEAR(miss.ball_velocity.x(), -kBallSpeed, 1e-6);
}

class BallOnLimb : public ::testing::TestWithParam<Method> {};

TEST_P(BallOnLimb, BallAt100MetresPerSecondHitsAThinLimbAt240Hz) { expect_hit(GetParam(), 1.0 / 240); }

TEST_P(BallOnLimb, BallAt100MetresPerSecondHitsAThinLimbAt60Hz) { expect_hit(GetParam(), 1.0 / 60); }

// ---------------------------------------------------------------------------------------------
// 4. The ball at 100 m/s against thin static geometry, in free space: a plate 2 cm thick (a box)
// and a one-sided square of two mesh triangles facing the ball.

enum class Wall { plate, mesh };
constexpr double kPlateHalfThickness = 0.01;  // m

// The wall stands across x at the origin, 1 m square (the plate's front face at x = +1 cm, the
// mesh's face at x = 0, facing +x); the ball flies along −x at its middle from `start` m out, with
// no gravity, until it would be 1 m past and two steps more. A limb stands 3 m aside, untouched.
// The ball's velocity is read over the last step, as in fire_ball.
struct Rebound {
  Vector3d position = Vector3d::Zero();  // m, the ball's centre at the end
  Vector3d velocity = Vector3d::Zero();  // m/s, over the last step
};

Rebound fire_at_wall(Method method, double dt, Wall wall, double start) {
  Model model = lone_limb("ball_at_wall", dt, Vector3d(0, 3, 0));
  StaticCollider collider;
  collider.name = "wall";
  if (wall == Wall::plate) {
    collider.type = ColliderType::box;
    collider.half_extents = Vector3d(kPlateHalfThickness, 0.5, 0.5);
  } else {
    collider.type = ColliderType::mesh;
    collider.mesh.vertices = {Vector3d(0, -0.5, -0.5), Vector3d(0, 0.5, -0.5), Vector3d(0, 0.5, 0.5), Vector3d(0, -0.5, 0.5)};
    collider.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};  // counter-clockwise from +x: facing the ball
  }
  model.colliders.push_back(collider);
  model.balls = {Ball{kBallRadius, kBallMass, kBallRestitution, Vector3d(start, 0, 0), Vector3d(-kBallSpeed, 0, 0)}};
  World world(model, WorldOptions{.method = method});
  std::vector<LimbSegment> segments;
  const int steps = static_cast<int>(std::ceil((start + 1) / (kBallSpeed * dt))) + 2;
  Vector3d before = Vector3d::Zero();
  for (int step = 0; step < steps; ++step) {
    world.segments(segments);
    before = segments.back().head;
    EXPECT_EQ(world.step(dt), StepStatus::ok) << "step " << step;
  }
  world.segments(segments);
  return {segments.back().head, (segments.back().head - before) / dt};
}

void expect_rebound(Method method, double dt) {
  for (const Wall wall : {Wall::plate, Wall::mesh}) {
    const double face = wall == Wall::plate ? kPlateHalfThickness : 0.0;
    for (const double phase : {0.1, 0.35, 0.6, 0.85}) {
      const double start = face + kBallRadius + (3 + phase) * kBallSpeed * dt;
      SCOPED_TRACE(std::string(wall == Wall::plate ? "plate" : "mesh") + ", dt " + std::to_string(dt) + " s, ball from x = " +
                   std::to_string(start) + " m");
      const Rebound rebound = fire_at_wall(method, dt, wall, start);
      // It stayed on its side and flies back (restitution 0.8: at 80 m/s), gaining no energy.
      EXPECT_GT(rebound.position.x(), face) << "the ball's centre at the end, m";
      EXPECT_GT(rebound.velocity.x(), 0.5 * kBallSpeed) << "m/s";
      EXPECT_LE(rebound.velocity.norm(), 1.001 * kBallSpeed) << "m/s";
    }
  }
}

class BallOnWall : public ::testing::TestWithParam<Method> {};

TEST_P(BallOnWall, BallAt100MetresPerSecondBouncesOffAThinPlateAndAMeshAt240Hz) { expect_rebound(GetParam(), 1.0 / 240); }

TEST_P(BallOnWall, BallAt100MetresPerSecondBouncesOffAThinPlateAndAMeshAt60Hz) { expect_rebound(GetParam(), 1.0 / 60); }

INSTANTIATE_TEST_SUITE_P(Methods, RagdollStack, ::testing::Values(Stepping{Method::particles}, Stepping{Method::lagrange}, kFeatherstoneBeforeTheMove),
                         stepping_name);
INSTANTIATE_TEST_SUITE_P(Methods, RagdollSelfContact,
                         ::testing::Values(Stepping{Method::particles}, Stepping{Method::lagrange}, Stepping{Method::featherstone}, kFeatherstoneBeforeTheMove),
                         stepping_name);
INSTANTIATE_TEST_SUITE_P(Methods, BallOnLimb, ::testing::Values(Method::particles, Method::springs, Method::lagrange, Method::featherstone),
                         param_name);
INSTANTIATE_TEST_SUITE_P(Methods, BallOnWall, ::testing::Values(Method::particles, Method::springs, Method::lagrange, Method::featherstone),
                         param_name);

// Known failures, kept to reproduce them (--gtest_also_run_disabled_tests); measured at 240 Hz:
// - the side landing: the springs, which move before they collide, let a pair of limbs overlap
//   past 1 cm at some of the four landing phases, 16-23 mm (the upper tibia sinking into the
//   lower one after the landing). The particles' rows let it reach 19 mm; ragdoll.json's joint
//   trees, which push the contacts through the whole body, hold it, and so do Featherstone and
//   Lagrange under semi-implicit Euler, whose speculative contacts are solved before the move
//   (enabled above; Lagrange moving first reached 12.2-13.7 mm, now 0.9-1.3), and Featherstone
//   under RK4, which moves first but now finds speculative contacts for the next move (enabled
//   above: 0.6-4.2 mm; 9.8-12.3 mm without them, the right forearm caught between the basin and
//   the ground);
// - the stack: springs and Featherstone under RK4 do not come to rest in 3 s (limbs still at
//   0.04-0.83 m/s over the last 0.5 s), and the upper body slides down (its centre of mass ends
//   2-3 cm above the lower's under springs, 4.8-5.8 cm under Featherstone with RK4 at three of
//   the four phases; before its speculative contacts one phase also overlapped 18 mm). Enabled above: Featherstone under semi-implicit Euler, whose contacts
//   and limits are solved before the move by warm-started projected Gauss-Seidel, rests at every
//   phase (limbs under 2.5 mm/s, stacked 8.7-8.9 cm, overlaps under 4.3 mm; with sequential
//   impulses it rested 5.8 cm up at one phase, and without the limit rows' warm start it still
//   moved at 0.14 m/s at another); Lagrange, whose contacts take the same contact step before
//   the move, rests at every phase (limbs under 0.028 m/s, stacked 6.4-8.8 cm; moving first,
//   0.042-0.045 m/s; with each tangent on its own and the pair clamped, 0.58 m/s and 5.7 cm at
//   one phase).
INSTANTIATE_TEST_SUITE_P(DISABLED_KnownFailures, RagdollSelfContact, ::testing::Values(Stepping{Method::springs}), stepping_name);
INSTANTIATE_TEST_SUITE_P(DISABLED_KnownFailures, RagdollStack, ::testing::Values(Stepping{Method::springs}, Stepping{Method::featherstone}),
                         stepping_name);

}  // namespace
}  // namespace limber
