#include "limber/kernel/collision/rigid_contacts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "limber/kernel/geometry/bounding_volumes.hpp"
#include "limber/kernel/geometry/geometry.hpp"
#include "limber/kernel/geometry/shape_pairs.hpp"
#include "limber/kernel/geometry/time_of_impact.hpp"
#include "limber/kernel/collision/impulses.hpp"
#include "limber/kernel/rigid/rigid_integration.hpp"
#include "limber/kernel/threading/block_runner.hpp"

namespace limber {
namespace {

bool awake(const RigidScene& state, std::int32_t body) {
  return body >= 0 && !state.islands[state.island_of_body[body]].sleeping;
}

// The limb's axis end points (head: +length/2 along its axis) in world: world_point of (0, 0, ±length/2)
// with the body's turn from its Model frame formed once.
std::pair<Eigen::Vector3d, Eigen::Vector3d> head_and_tail(const RigidScene& state, std::size_t b) {
  const Eigen::Matrix3d turn = (state.bodies.state.orientation[b] * state.shapes.principal_frame[b].conjugate()).toRotationMatrix();
  const Eigen::Vector3d centre = state.bodies.state.position[b] - turn * state.shapes.centre_offset[b];
  const Eigen::Vector3d half_axis = (0.5 * state.shapes.length[b]) * turn.col(2);
  return {centre + half_axis, centre - half_axis};
}

constexpr std::size_t kBodiesPerBlock = 64;  // the per-body loops' blocks on the runner's threads

bool has_half_extents(const RigidScene& state, std::size_t b) { return has_half_extents(model_shape(state, b)); }

// A box's or an ellipsoid's shape frame in world, as it is now.
Eigen::Quaterniond shape_frame(const RigidScene& state, std::size_t b) {
  return (state.bodies.state.orientation[b] * state.shapes.principal_frame[b].conjugate() * state.shapes.shape_rotation[b]).normalized();
}

// Every body's limb segment (its axis end points and radius; a ball's a point; a box's or an
// ellipsoid's centre, bounding radius and shape frame) as it is now.
void find_limb_segments(RigidScene& state, BlockRunner* runner) {
  run_blocks(runner, state.bodies.size(), kBodiesPerBlock, [&](std::size_t b) {
    LimbSegment& segment = state.limb_segments[b];
    if (state.shapes.is_ball[b]) {
      segment.head = segment.tail = state.bodies.state.position[b];
    } else {
      std::tie(segment.head, segment.tail) = head_and_tail(state, b);
    }
    segment.radius = state.shapes.radius[b];
    if (has_half_extents(state, b)) segment.orientation = shape_frame(state, b);
  });
}

// A box or an ellipsoid body as the shape-pair table sees it, as it is now.
PlacedShape placed_shape(const RigidScene& state, std::size_t b) {
  const Eigen::Vector3d centre = head_and_tail(state, b).first;  // head = tail: its length is 0
  const Shape shape = model_shape(state, b);
  LimbSegment segment{centre, centre, state.shapes.radius[b]};
  segment.orientation = shape_frame(state, b);
  return placed_shape(shape, segment);
}

// A ball (centre, radius) against limb b: its separation and normal (from the limb towards the
// ball). A box's or an ellipsoid's through the shape-pair table, within `margin` (m): farther, an
// infinite separation.
SphereLimbContact ball_limb_contact(const RigidScene& state, const Eigen::Vector3d& centre, double radius, std::size_t b, double margin) {
  if (!has_half_extents(state, b)) {
    const auto [head, tail] = head_and_tail(state, b);
    return sphere_limb_contact(centre, radius, head, tail, state.shapes.shape[b], state.shapes.radius[b]);
  }
  SphereLimbContact contact;
  contact.separation = std::numeric_limits<double>::infinity();
  const Manifold manifold = collide(Capsule{centre, centre, radius}, placed_shape(state, b), margin);
  if (manifold.count > 0) contact.normal = manifold.normal, contact.separation = manifold.points[0].separation;
  return contact;
}

// A box's or an ellipsoid's contacts with a plane: the manifold's points within the body's reach.
void add_shape_plane_contacts(RigidScene& state, std::size_t b, const Plane& plane) {
  const double reach = state.limb_segments[b].reach;
  const Manifold manifold = collide(placed_shape(state, b), plane, reach);
  for (int k = 0; k < manifold.count; ++k) {
    const ManifoldPoint& point = manifold.points[k];
    if (!(point.separation < reach)) continue;  // as a capsule's: a gap its reach does not close is no contact
    state.contacts.push_back({static_cast<std::int32_t>(b), -1, point.point, plane.normal, -point.separation,
                              std::max(plane.restitution, state.shapes.restitution[b]), plane.friction});
  }
}

void add_plane_contacts(RigidScene& state, std::size_t b, std::size_t plane_index) {
  const Plane& plane = state.planes[plane_index];
  if (has_half_extents(state, b)) return add_shape_plane_contacts(state, b, plane);
  const double radius = state.shapes.radius[b];
  const Eigen::Vector3d head = state.limb_segments[b].head, tail = state.limb_segments[b].tail;
  const bool disk = state.shapes.shape[b] == ShapeType::cylinder && !state.shapes.is_ball[b];
  const Eigen::Vector3d axis = head - tail;
  const double length = axis.norm();
  const int ends = length > 0 ? 2 : 1;
  for (int e = 0; e < ends; ++e) {
    const Eigen::Vector3d centre = e == 0 ? head : tail;
    const bool end_disk = disk && length > 0;
    const Eigen::Vector3d u = end_disk ? Eigen::Vector3d(axis / length) : Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d lowest = centre + end_support(plane.normal, u, radius, end_disk).offset;
    const double depth = plane.offset - plane.normal.dot(lowest);
    if (depth <= -state.limb_segments[b].reach) continue;
    const double restitution = std::max(plane.restitution, state.shapes.restitution[b]);
    state.contacts.push_back({static_cast<std::int32_t>(b), -1, lowest + 0.5 * depth * plane.normal, plane.normal, depth,
                              restitution, plane.friction});
  }
}

ImpulseBody impulse_body(const RigidScene& state, std::int32_t b) {
  ImpulseBody body;
  body.inverse_mass = 0;
  body.inverse_inertia.setZero();
  body.centre_of_mass.setZero();
  body.linear_velocity.setZero();
  body.angular_velocity.setZero();
  if (b < 0) return body;
  const RigidBodyState& y = state.bodies.state;
  body.inverse_mass = state.bodies.inverse_mass[b];
  body.inverse_inertia = state.bodies.world_inverse_inertia(y, b);
  body.centre_of_mass = y.position[b];
  body.linear_velocity = state.bodies.linear_velocity(y, b);
  body.angular_velocity = body.inverse_inertia * y.angular_momentum[b];
  return body;
}

void store_velocities(RigidScene& state, std::int32_t b, const ImpulseBody& body) {
  if (b < 0) return;
  RigidBodyState& y = state.bodies.state;
  y.linear_momentum[b] = state.bodies.mass[b] * body.linear_velocity;
  y.angular_momentum[b] = state.bodies.world_inertia(y, b) * body.angular_velocity;
}

// Each body's speculative reach (RigidScene::speculative_time) into its limb segment, m.
void find_speculative_reach(RigidScene& state, BlockRunner* runner) {
  const double t = state.speculative_time;
  const RigidBodyState& y = state.bodies.state;
  run_blocks(runner, state.bodies.size(), kBodiesPerBlock, [&](std::size_t b) {
    double reach = 0;
    if (t > 0) {
      const double arm = 0.5 * state.shapes.length[b] + state.shapes.radius[b] + state.shapes.centre_offset[b].norm();
      // |ω| = |I⁻¹·(q⁻¹ L)| in the body's principal frame, without forming the world inverse
      // inertia. (The bound |L|/I_min, tried, reached far past a spinning capsule's gaps: 4 % fewer
      // steps/s on 22_humanoids.xml.)
      const double spin = (state.bodies.body_inverse_inertia[b] * (y.orientation[b].conjugate() * y.angular_momentum[b])).norm();
      const double speed = state.bodies.linear_velocity(y, b).norm() + spin * arm;
      reach = std::min(t * (speed + state.settings.gravity.norm() * t), kMostSpeculativeReach);  // also when not finite
    }
    state.limb_segments[b].reach = reach;
  });
}

// The collision world's contacts (limb–limb, ball–ball, and limbs and balls against static colliders)
// among the bodies as they are now, touching or overlapping, or (speculative_time) closer than
// their reaches: a rigid method that moves before it collides answers a contact only once it
// overlaps. An awake limb that touches a sleeping one wakes its island.
void add_collision_world_contacts(RigidScene& state, BlockRunner* runner) {
  for (std::size_t b = 0; b < state.bodies.size(); ++b) state.limb_awake[b] = awake(state, static_cast<std::int32_t>(b)) ? 1 : 0;
  state.collisions.find(state.limb_segments, state.limb_awake, 0, state.limb_contacts, runner);
  for (const LimbContact& contact : state.limb_contacts) {
    const auto a = static_cast<std::int32_t>(contact.first);
    RigidContact rigid{a, -1, contact.point, contact.normal, -contact.separation, contact.restitution, contact.friction};
    if (contact.second != kStaticShape) {
      rigid.b = static_cast<std::int32_t>(contact.second);
      state.islands[state.island_of_body[contact.first]].wake();
      state.islands[state.island_of_body[contact.second]].wake();
    }
    state.contacts.push_back(rigid);
  }
}

// A ball against every limb among its candidates (asleep or not: it wakes what it touches).
void add_ball_contacts(RigidScene& state, std::size_t ball) {
  const RigidBodyState& y = state.bodies.state;
  const Eigen::Vector3d centre = y.position[ball];
  const double ball_radius = state.shapes.radius[ball];
  for (const std::uint32_t b : state.collisions.ball_candidates().of(ball - state.ball_begin)) {
    if (b >= state.ball_begin) break;  // the other balls, after the limbs: the collision world's
    // Bounding spheres first (thesis 2.4); the exact closest point only when they overlap.
    const Shape shape = model_shape(state, b);
    const Eigen::Quaterniond model_orientation = y.orientation[b] * state.shapes.principal_frame[b].conjugate();
    if (!overlaps(BoundingSphere{centre, ball_radius}, limb_sphere(shape, world_point(state, b, Eigen::Vector3d::Zero()), model_orientation))) continue;
    const double reach = state.limb_segments[ball].reach + state.limb_segments[b].reach;
    const SphereLimbContact contact = ball_limb_contact(state, centre, ball_radius, b, reach);
    if (contact.separation >= reach) continue;
    state.islands[state.island_of_body[b]].wake();
    const Eigen::Vector3d point = centre - (ball_radius + 0.5 * contact.separation) * contact.normal;
    // Touching: overlapping, or (speculative contacts) a contact this step's impulses answer: the
    // ball closes the gap within the step, or bounces from where it is (contact_target_speed:
    // e > 0 from the resting approach up, record_approach).
    const double t = state.speculative_time;
    const double approach = t > 0 && contact.separation >= 0
                                ? (velocity_at(impulse_body(state, b), point) - velocity_at(impulse_body(state, static_cast<std::int32_t>(ball)), point)).dot(contact.normal)
                                : 0.0;
    const bool bounces = state.shapes.restitution[ball] > 0 && approach >= resting_approach(state.settings, t);
    state.ball_touching = state.ball_touching || contact.separation < 0 || (t > 0 && (contact.separation < approach * t || bounces));
    state.contacts.push_back({static_cast<std::int32_t>(ball), static_cast<std::int32_t>(b), point, contact.normal, -contact.separation,
                              state.shapes.restitution[ball], 0.0});
  }
}

// Continuous collision for the ball (rigid_contacts.hpp; which touches: answer_at_touch,
// time_of_impact.hpp). How far inside the touch the ball is put back, m: enough that the overlap
// test sees it through round-off, too little to push anything.
constexpr double kTouchDepth = 1e-6;

// Sweeps ball body `ball` from state.step_start_position to its position now against the limbs
// (at their poses now) and the static colliders, and moves it back to its first touch that needs
// answering there (see rigid_contacts.hpp). Returns whether it moved it.
bool sweep_ball(RigidScene& state, std::size_t ball) {
  RigidBodyState& y = state.bodies.state;
  const Eigen::Vector3d from = state.step_start_position[ball], to = y.position[ball], path = to - from;
  const double radius = state.shapes.radius[ball];
  if (!(path.norm() > kSweptSlop * radius)) return false;  // at rest (or asleep), or sliding in place
  SweptTouch first;
  const BoundingSphere swept{from + 0.5 * path, 0.5 * path.norm() + radius};
  for (const std::uint32_t b : state.collisions.ball_candidates().of(ball - state.ball_begin)) {
    if (b == ball) continue;
    const auto [head, tail] = head_and_tail(state, b);
    const double limb_radius = state.shapes.radius[b];
    if (!overlaps(swept, BoundingSphere{0.5 * (head + tail), 0.5 * (head - tail).norm() + limb_radius})) continue;
    if (ball_limb_contact(state, from, radius, b, radius).separation < -kSweptSlop * radius) continue;
    const TimeOfImpact impact = has_half_extents(state, b) ? sphere_shape_time_of_impact(from, to, radius, placed_shape(state, b))
                                                           : sphere_limb_time_of_impact(from, to, radius, head, tail, state.shapes.shape[b], limb_radius);
    if (!impact.hit || !(impact.time < first.time)) continue;
    const SphereLimbContact touch = ball_limb_contact(state, from + impact.time * path, radius, b, radius);
    const SphereLimbContact end = ball_limb_contact(state, to, radius, b, radius);
    const Eigen::Vector3d end_normal = std::isfinite(end.separation) ? end.normal : touch.normal;  // ends beyond the margin
    if (answer_at_touch(path, impact.time, touch.normal, radius, end.separation, end_normal)) {
      first.keep_if_earlier(impact.time, touch.normal, touch.separation);
    }
  }
  if (state.collisions.active()) {
    const SweptTouch wall = state.collisions.first_static_touch(static_cast<std::uint32_t>(ball), from, to, radius);
    if (wall.time < first.time) first = wall;
  }
  if (!first.found()) return false;
  y.position[ball] = from + first.time * path - std::max(first.separation + kTouchDepth, 0.0) * first.normal;
  return true;
}

// Each ball's candidates, the bodies its tests below can accept, through the broadphase
// (BallCandidates): a limb's bounding sphere and a ball's sphere about its whole path this step,
// as boxes; a ball's grown by twice kTouchDepth, as sweep_ball may move it back that far off its
// path before the later balls' tests and its own contacts see it. (None to fill for a few
// balls: each then tests every body.)
void find_ball_candidates(RigidScene& state) {
  const RigidBodyState& y = state.bodies.state;
  BallCandidates& candidates = state.collisions.ball_candidates();
  const std::span<Aabb> boxes = candidates.boxes(state.ball_begin, state.bodies.size() - state.ball_begin);
  for (std::size_t b = 0; b < state.bodies.size() && !boxes.empty(); ++b) {
    Eigen::Vector3d centre;
    double reach;
    if (b < state.ball_begin) {
      centre = world_point(state, b, Eigen::Vector3d::Zero());
      reach = 0.5 * state.shapes.length[b] + state.shapes.radius[b];
    } else {
      const Eigen::Vector3d path = y.position[b] - state.step_start_position[b];
      centre = state.step_start_position[b] + 0.5 * path;
      reach = 0.5 * path.norm() + state.shapes.radius[b] + 2 * kTouchDepth;
    }
    boxes[b] = {centre.array() - reach, centre.array() + reach};
  }
  candidates.find(/*other_balls=*/true);
}

}  // namespace

Shape model_shape(const RigidScene& state, std::size_t b) {
  const ShapeType type = state.shapes.shape[b];
  if (type != ShapeType::box && type != ShapeType::ellipsoid) return Shape{type, state.shapes.length[b], state.shapes.radius[b]};
  Shape shape;
  shape.type = type, shape.half_extents = state.shapes.half_extents[b], shape.rotation = state.shapes.shape_rotation[b];
  return shape;
}

void remember_step_start(RigidScene& state) { state.step_start_position = state.bodies.state.position; }

bool detect_rigid_contacts(RigidScene& state, BlockRunner* runner) {
  state.contacts.clear();
  state.ball_touching = false;
  // Nothing any body could meet (a hanging chain, a rope in the air): no reaches nor segments.
  if (state.planes.empty() && !state.collisions.active() && state.ball_begin >= state.bodies.size()) return false;
  find_speculative_reach(state, runner);
  bool moved = false;
  if (state.ball_begin < state.bodies.size()) find_ball_candidates(state);
  for (std::size_t ball = state.ball_begin; ball < state.bodies.size(); ++ball) {
    moved = sweep_ball(state, ball) || moved;
    add_ball_contacts(state, ball);
  }
  find_limb_segments(state, runner);  // after the balls' sweeps moved them
  for (std::size_t b = 0; b < state.bodies.size(); ++b) {
    if (!awake(state, static_cast<std::int32_t>(b))) continue;
    for (std::size_t p = 0; p < state.planes.size(); ++p) add_plane_contacts(state, b, p);
  }
  if (state.collisions.active()) add_collision_world_contacts(state, runner);
  return moved;
}

void resolve_rigid_contacts(RigidScene& state, double dt) {
  if (state.contacts.empty()) return;
  // Approach speeds before any impulse: they decide bouncing and bound the position correction.
  for (RigidContact& contact : state.contacts) {
    const ImpulseBody a = impulse_body(state, contact.a), b = impulse_body(state, contact.b);
    record_approach(contact, -(velocity_at(a, contact.point) - velocity_at(b, contact.point)).dot(contact.normal), state.settings, dt);
  }
  for (int pass = 0; pass < state.contact_iterations; ++pass) {
    for (const RigidContact& contact : state.contacts) {
      ImpulseBody a = impulse_body(state, contact.a), b = impulse_body(state, contact.b);
      const CollisionImpulse response = sequential_collision_impulse(a, b, contact.point, contact.normal, contact.restitution, contact.friction);
      if (response.normal_impulse <= 0) continue;
      apply_impulse(a, contact.point, response.impulse);
      apply_impulse(b, contact.point, -response.impulse);
      store_velocities(state, contact.a, a);
      store_velocities(state, contact.b, b);
    }
  }
  // Push out what still overlaps, through the effective mass along the normal.
  RigidBodyState& y = state.bodies.state;
  for (const RigidContact& contact : state.contacts) {
    const double correction = push_out_distance(contact, state.settings, dt);
    if (correction <= 0) continue;
    const ImpulseBody a = impulse_body(state, contact.a), b = impulse_body(state, contact.b);
    const double effective_inverse_mass = contact.normal.dot(collision_matrix(a, b, contact.point) * contact.normal);
    if (!(effective_inverse_mass > 0)) continue;
    const Eigen::Vector3d push = correction / effective_inverse_mass * contact.normal;
    auto move = [&](std::int32_t body, const ImpulseBody& view, const Eigen::Vector3d& amount) {
      if (body < 0) return;
      y.position[body] += view.inverse_mass * amount;
      const Eigen::Vector3d turn = view.inverse_inertia * (contact.point - view.centre_of_mass).cross(amount);
      y.orientation[body] = (rotation_quaternion(turn) * y.orientation[body]).normalized();
    };
    move(contact.a, a, push);
    move(contact.b, b, -push);
  }
}

}  // namespace limber
