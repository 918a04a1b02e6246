#include "limber/kernel/metrics/observers.hpp"

#include <algorithm>
#include <cmath>

#include "limber/kernel/featherstone/integration.hpp"
#include "limber/kernel/springs/spring_forces.hpp"

namespace limber {

template <typename Scalar>
Observation observe(const VerletState<Scalar>& state, ObservationScope scope) {
  Observation out;
  out.time = state.time;
  const auto& particles = state.particles;
  auto position = [&](std::uint32_t p) { return particles.position(p).template cast<double>().eval(); };

  double gap_squares = 0;
  std::size_t gaps = 0;
  const auto add_gap = [&](double gap, std::int64_t joint) {
    if (gap > out.max_joint_gap) out.max_joint_gap = gap, out.widest_joint = static_cast<int>(joint);
    gap_squares += gap * gap, ++gaps;
  };
  for (std::size_t k = 0; k < state.joint_constraints.size(); ++k) {
    const auto& [c, reference] = state.joint_constraints[k];
    add_gap((position(state.constraints.particle_i[c]) - position(state.constraints.particle_j[c])).norm() / reference,
            state.joint_constraint_joint[k]);
  }
  for (const JointRow& row : state.joint_rows.rows) {  // joints held by point rows: anchors off the ends
    if (row.kind != JointRowKind::point || row.joint < 0) continue;
    Eigen::Vector3d separation = Eigen::Vector3d::Zero();
    for (std::size_t k = 0; k < kJointRowParticles; ++k) {
      if (row.direction[k] != 0) separation += row.direction[k] * position(row.particle[k]);
    }
    add_gap(separation.norm() / row.reference, row.joint);
  }
  if (gaps > 0) out.rms_joint_gap = std::sqrt(gap_squares / gaps);

  for (std::size_t limb = 0; limb < state.limbs.size(); ++limb) {
    const std::uint32_t c = state.limbs.link_constraint[limb];
    const double rest = state.constraints.rest_length[c];
    const double length = (position(state.constraints.particle_i[c]) - position(state.constraints.particle_j[c])).norm();
    out.max_link_stretch = std::max(out.max_link_stretch, std::abs(length - rest) / rest);
  }

  const Eigen::Vector3d gravity = state.gravity.template cast<double>();
  double body_mass = 0;
  for (std::uint32_t p = 0; p < particles.size(); ++p) {
    const double mass = state.particle_mass[p];
    const Eigen::Vector3d x = position(p);
    const Eigen::Vector3d velocity = particle_velocity(state, p);
    out.linear_momentum += mass * velocity;
    out.kinetic_energy += 0.5 * mass * velocity.squaredNorm();
    out.potential_energy -= mass * gravity.dot(x);
    if (state.particle_origins[p].kind != ParticleOrigin::Kind::ball) {
      out.body_centre_of_mass += mass * x;
      body_mass += mass;
    }
  }
  if (body_mass > 0) out.body_centre_of_mass /= body_mass;
  if (scope == ObservationScope::divergence) return out;

  // A limb without a frame has no roll: its Model frame's convention, the shortest turn from z
  // onto its axis (Body::orientation), which only its axis — all a swing reads — depends on.
  out.joints = measure_joints(state.joint_controls, [&](std::size_t b) -> FramePose {
    const std::uint32_t limb = state.body_limb[b];
    const Eigen::Vector3d head = position(state.limbs.head[limb]), tail = position(state.limbs.tail[limb]);
    const auto framed = framed_orientation(state, b);
    const Eigen::Quaterniond orientation =
        framed ? *framed : Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), head - tail);
    return {orientation, 0.5 * (head + tail)};
  });
  out.islands = static_cast<int>(state.islands.size());
  out.body_sleeping = true;
  for (std::size_t k = 0; k < state.islands.size(); ++k) {
    out.islands_sleeping += state.islands[k].sleeping;
    const bool is_ball = state.particle_origins[state.islands[k].particle_begin].kind == ParticleOrigin::Kind::ball;
    if (!is_ball) out.body_sleeping = out.body_sleeping && state.islands[k].sleeping;
  }
  return out;
}

namespace {

// What every rigid-body method reports alike: momentum, kinetic energy ½ m v² + ½ ω·L, gravity's
// potential energy, the limbs' centre of mass, sleeping. Joint gaps are the method's to add.
Observation observe_rigid_scene(const RigidScene& scene, const JointControls& scene_controls, ObservationScope scope) {
  Observation out;
  out.time = scene.time;
  const RigidBodyBuffer& bodies = scene.bodies;
  const RigidBodyState& y = bodies.state;
  double body_mass = 0;
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const double mass = bodies.mass[b];
    out.linear_momentum += y.linear_momentum[b];
    out.kinetic_energy += 0.5 * y.linear_momentum[b].squaredNorm() / mass +
                          0.5 * bodies.angular_velocity(y, b).dot(y.angular_momentum[b]);
    out.potential_energy -= mass * scene.settings.gravity.dot(y.position[b]);
    if (!scene.shapes.is_ball[b]) {
      out.body_centre_of_mass += mass * y.position[b];
      body_mass += mass;
    }
  }
  if (body_mass > 0) out.body_centre_of_mass /= body_mass;
  if (scope == ObservationScope::divergence) return out;
  // The Model body frame: a Model point p is at x + q·principal⁻¹·(p − centre_offset).
  out.joints = measure_joints(scene_controls, [&](std::size_t b) -> FramePose {
    const Eigen::Quaterniond orientation = (y.orientation[b] * scene.shapes.principal_frame[b].conjugate()).normalized();
    return {orientation, y.position[b] - orientation * scene.shapes.centre_offset[b]};
  });
  out.islands = static_cast<int>(scene.islands.size());
  out.body_sleeping = true;
  for (const RigidIsland& island : scene.islands) {
    out.islands_sleeping += island.sleeping;
    const bool is_ball = island.bodies.size() == 1 && scene.shapes.is_ball[island.bodies[0]];
    if (!is_ball) out.body_sleeping = out.body_sleeping && island.sleeping;
  }
  return out;
}

// Max and RMS of gap_j / reference_j over the joints, gap_j given by `gap`.
template <typename Gap>
void add_joint_gaps(Observation& out, const JointAnchors& joints, Gap&& gap) {
  double squares = 0;
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const double relative = gap(j) / joints.reference_length[j];
    if (relative > out.max_joint_gap) out.max_joint_gap = relative, out.widest_joint = static_cast<int>(j);
    squares += relative * relative;
  }
  if (joints.size() > 0) out.rms_joint_gap = std::sqrt(squares / joints.size());
}

}  // namespace

Observation observe(const SpringState& state, ObservationScope scope) {
  Observation out = observe_rigid_scene(state, state.joint_controls, scope);
  add_joint_gaps(out, state.springs, [&](std::size_t j) { return joint_separation(state.springs, state.bodies.state, j).norm(); });
  out.potential_energy += spring_energy(state);
  return out;
}

Observation observe(const LagrangeState& state, ObservationScope scope) {
  Observation out = observe_rigid_scene(state, state.joint_controls, scope);
  // The gap is what a joint's position rows leave open (a prismatic joint slides along its axis).
  add_joint_gaps(out, state.joints, [&](std::size_t j) {
    return position_error(state.constraints.rows[j], constraint_error(state.constraints, state.joints, state.bodies.state, j));
  });
  return out;
}

namespace {

// A serial joint's axes: each coordinate is its tree body's q, measured against its range and its
// spring's rest (measure_joints sees the joint's own limits and drive, which a serial joint leaves empty).
void measure_serial_axes(const FeatherstoneState& state, JointMeasures& measures) {
  std::int32_t last_limited = -1, last_driven = -1;
  for (const TreeSerialAxis& node : state.serial_axes) {
    const SerialAxis& axis = state.joint_controls.joints[static_cast<std::size_t>(node.joint)].serial_axes[static_cast<std::size_t>(node.axis)];
    const double x = state.q[state.tree.position_offset(node.body)];
    if (axis.range) {
      measures.limit_violation = std::max({measures.limit_violation, axis.range->min - x, x - axis.range->max});
      if (node.joint != last_limited) ++measures.limited_joints, last_limited = node.joint;
    }
    if (axis.drive) {
      const double error = axis.drive->target - x;
      measures.drive_error = std::max(measures.drive_error, std::abs(axis.slide ? error : shorter_way_round(error)));
      if (node.joint != last_driven) ++measures.driven_joints, last_driven = node.joint;
    }
  }
}

}  // namespace

Observation observe(const FeatherstoneState& state, ObservationScope scope) {
  Observation out = observe_rigid_scene(state, state.joint_controls, scope);
  out.kinetic_energy += armature_energy(state.tree, state.v);  // the rotors, which the rigid bodies do not hold
  if (scope == ObservationScope::full) measure_serial_axes(state, out.joints);
  const RigidBodyState& y = state.bodies.state;
  add_joint_gaps(out, state.joints, [&](std::size_t j) {
    // A serial joint is its chain of tree bodies: the child's frame is where the chain puts it.
    if (state.joint_controls.joints[j].type == JointType::serial) return 0.0;
    Eigen::Vector3d separation = joint_separation(state.joints, y, j);
    if (!state.slide_axis[j].isZero(0)) {
      const Eigen::Vector3d axis = y.orientation[state.joints.outboard[j]] * state.slide_axis[j];
      separation -= separation.dot(axis) * axis;
    }
    return separation.norm();
  });
  return out;
}

namespace {

// The first `bodies` limbs' segments, then the balls'.
template <typename Scalar>
void particle_limb_segments(const VerletState<Scalar>& state, std::size_t bodies, std::vector<LimbSegment>& segments) {
  segments.resize(bodies);
  for (std::size_t body = 0; body < segments.size(); ++body) {
    const std::uint32_t limb = state.body_limb[body];
    segments[body] = {state.particles.position(state.limbs.head[limb]).template cast<double>(),
                      state.particles.position(state.limbs.tail[limb]).template cast<double>(), state.limbs.radius[limb]};
    if (state.limbs.sphere[limb]) segments[body].head = segments[body].tail = 0.5 * (segments[body].head + segments[body].tail);
  }
  for (const BallParticle& ball : state.balls) {
    const Eigen::Vector3d centre = state.particles.position(ball.particle).template cast<double>();
    segments.push_back({centre, centre, ball.radius});
  }
}

}  // namespace

template <typename Scalar>
void limb_segments(const VerletState<Scalar>& state, const Model& model, std::vector<LimbSegment>& segments) {
  particle_limb_segments(state, model.bodies.size(), segments);
}

template <typename Scalar>
void limb_segments(const VerletState<Scalar>& state, std::vector<LimbSegment>& segments) {
  particle_limb_segments(state, state.body_limb.size(), segments);
}

void limb_segments(const RigidScene& scene, const Model& model, std::vector<LimbSegment>& segments) {
  segments.resize(model.bodies.size());
  for (std::size_t body = 0; body < segments.size(); ++body) {
    const Shape& shape = model.bodies[body].shape;
    segments[body] = {world_point(scene, body, {0, 0, 0.5 * shape.length}), world_point(scene, body, {0, 0, -0.5 * shape.length}),
                      shape.radius};
    if (has_half_extents(shape)) {
      segments[body].radius = bounding_radius(shape);
      segments[body].orientation = scene.bodies.state.orientation[body] * scene.shapes.principal_frame[body].conjugate() * shape.rotation;
    }
  }
  for (std::size_t ball = scene.ball_begin; ball < scene.bodies.size(); ++ball) {
    segments.push_back({scene.bodies.state.position[ball], scene.bodies.state.position[ball], scene.shapes.radius[ball]});
  }
}

Penetration deepest_penetration(const Model& model, LimbCollisions& collisions, std::span<const LimbSegment> segments) {
  Penetration deepest;
  if (collisions.active()) {
    const LimbContact contact = collisions.deepest_overlap(segments);
    if (contact.separation < 0) {
      deepest.depth = -contact.separation, deepest.first = static_cast<int>(contact.first);
      if (contact.second == kStaticShape) {
        deepest.collider = static_cast<int>(contact.collider);
      } else {
        deepest.second = static_cast<int>(contact.second);
      }
    }
  }
  if (!model.ground) return deepest;
  for (std::size_t body = 0; body < segments.size() && body < model.bodies.size(); ++body) {
    const LimbSegment& segment = segments[body];
    if (has_half_extents(collisions.shape(body))) {  // a box's or an ellipsoid's lowest point
      const PlacedShape shape = placed_shape(collisions.shape(body), segment);
      const double lowest = std::visit([](const auto& s) { return support(s, -Eigen::Vector3d::UnitZ()).z(); }, shape);
      if (model.ground->height - lowest > deepest.depth) deepest = {model.ground->height - lowest, static_cast<int>(body), -1, -1};
      continue;
    }
    const Eigen::Vector3d axis = segment.tail - segment.head;
    const double length = axis.norm();
    const bool disk = model.bodies[body].shape.type == ShapeType::cylinder && length > 0;
    const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
    // An end's reach below its centre (end_support, geometry.hpp): the radius for a sphere, the
    // rim's r·√(1 − (n·u)²) for a disk.
    const double reach = disk ? end_support(up, axis / length, segment.radius, true).reach : segment.radius;
    const double depth = model.ground->height - (std::min(segment.head.z(), segment.tail.z()) - reach);
    if (depth > deepest.depth) deepest = {depth, static_cast<int>(body), -1, -1};
  }
  return deepest;
}

template void limb_segments<float>(const VerletState<float>&, std::vector<LimbSegment>&);
template void limb_segments<double>(const VerletState<double>&, std::vector<LimbSegment>&);
template void limb_segments<float>(const VerletState<float>&, const Model&, std::vector<LimbSegment>&);
template void limb_segments<double>(const VerletState<double>&, const Model&, std::vector<LimbSegment>&);
template Observation observe<float>(const VerletState<float>&, ObservationScope);
template Observation observe<double>(const VerletState<double>&, ObservationScope);

}  // namespace limber
