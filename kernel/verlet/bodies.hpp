// The particle method's side of the World's calls (kernel/methods/method_contract.hpp): a body's
// pose, motion and centre of mass read from its limb's particles, loads, held points, sleep,
// teleports, balls, and the state carried across a recompile. Templates on the scalar type.
#pragma once

#include <cstdint>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/survivors.hpp"
#include "limber/kernel/particles/verlet_state.hpp"
#include "limber/kernel/sleeping/sleeping.hpp"
#include "limber/kernel/verlet/step.hpp"

namespace limber {

namespace particle_bodies {

template <typename Scalar>
Eigen::Vector3d particle_position(const VerletState<Scalar>& state, std::uint32_t p) {
  return state.particles.position(p).template cast<double>();
}

/// The limb's axis end points, head and tail, m.
template <typename Scalar>
std::pair<Eigen::Vector3d, Eigen::Vector3d> limb_ends(const VerletState<Scalar>& state, std::size_t body) {
  const std::uint32_t limb = state.body_limb[body];
  return {particle_position(state, state.limbs.head[limb]), particle_position(state, state.limbs.tail[limb])};
}

/// `previous` turned by the smallest rotation that takes its z axis onto the limb's axis now
/// (parallel transport: the roll a particle limb cannot have stays continuous).
template <typename Scalar>
Eigen::Quaterniond transported_frame(const VerletState<Scalar>& state, std::size_t body, const Eigen::Quaterniond& previous) {
  if (const auto framed = framed_orientation(state, body)) return *framed;  // a limb with a frame has its own roll
  const auto [head, tail] = limb_ends(state, body);
  const Eigen::Vector3d axis = head - tail;
  if (!(axis.norm() > 0) || !axis.allFinite()) return previous;
  return (Eigen::Quaterniond::FromTwoVectors(previous * Eigen::Vector3d::UnitZ(), axis) * previous).normalized();
}

}  // namespace particle_bodies

/// Turns every body's frame (VerletState::body_frame) onto its limb's axis now: compile and
/// step call it once each.
template <typename Scalar>
void transport_body_frames(VerletState<Scalar>& state) {
  for (std::size_t b = 0; b < state.body_frame.size(); ++b) {
    state.body_frame[b] = particle_bodies::transported_frame(state, b, state.body_frame[b]);
  }
}

/// The body frame: origin at the limb's centre (the mean of its ends), its orientation carried
/// by body_frame.
template <typename Scalar>
Pose body_pose(const VerletState<Scalar>& state, std::size_t body) {
  const auto [head, tail] = particle_bodies::limb_ends(state, body);
  return {0.5 * (head + tail), state.body_frame[body]};
}

/// The limb's own mass at its particles, kg, and their positions.
template <typename Scalar>
Eigen::Vector3d body_centre_of_mass(const VerletState<Scalar>& state, std::size_t body) {
  using particle_bodies::particle_position;
  const std::uint32_t limb = state.body_limb[body];
  const LimbBuffer& limbs = state.limbs;
  Eigen::Vector3d sum = limbs.head_mass[limb] * particle_position(state, limbs.head[limb]) +
                        limbs.tail_mass[limb] * particle_position(state, limbs.tail[limb]);
  if (limbs.centre[limb] != kNoCentre) sum += limbs.centre_mass[limb] * particle_position(state, limbs.centre[limb]);
  double mass = limbs.head_mass[limb] + limbs.centre_mass[limb] + limbs.tail_mass[limb];
  const JointRowSet& rows = state.joint_rows;
  if (!rows.frame_plus.empty() && rows.frame_plus[body] != state.particles.null_particle()) {  // its frame particles
    for (const std::uint32_t p : {rows.frame_plus[body], rows.frame_minus[body]}) {
      sum += state.particle_mass[p] * particle_position(state, p), mass += state.particle_mass[p];
    }
  }
  return sum / mass;
}

/// The velocity of the limb's centre (the mean of its ends') and its angular velocity across
/// its axis (a particle limb does not spin about it).
template <typename Scalar>
Motion body_motion(const VerletState<Scalar>& state, std::size_t body) {
  const std::uint32_t limb = state.body_limb[body];
  const auto [head, tail] = particle_bodies::limb_ends(state, body);
  const Eigen::Vector3d v_head = particle_velocity(state, state.limbs.head[limb]), v_tail = particle_velocity(state, state.limbs.tail[limb]);
  const Eigen::Vector3d axis = head - tail;
  const double length2 = axis.squaredNorm();
  return {0.5 * (v_head + v_tail), length2 > 0 ? Eigen::Vector3d(axis.cross(v_head - v_tail) / length2) : Eigen::Vector3d::Zero()};
}

/// A force at the limb's centre of mass (shared by its particles in proportion to its mass at
/// each: apply_force) and a torque: its part across the axis as a couple on the limb's ends, its
/// part along the axis as a couple on the frame's F± (a stick without a frame cannot spin: that
/// part is lost).
template <typename Scalar>
void apply_body_load(VerletState<Scalar>& state, std::size_t body, const Eigen::Vector3d& force, const Eigen::Vector3d& torque) {
  if (!force.isZero(0)) apply_force(state, static_cast<int>(body), force);
  const auto [head, tail] = particle_bodies::limb_ends(state, body);
  const Eigen::Vector3d axis = head - tail;
  const double length = axis.norm();
  if (torque.isZero(0) || !(length > 0)) return;
  const Eigen::Vector3d u = axis / length, across = torque - torque.dot(u) * u;
  const Eigen::Vector3d at_head = across.cross(u) / length;  // (L·u) × at_head = across
  const std::uint32_t limb = state.body_limb[body];
  state.pending_forces.emplace_back(state.limbs.head[limb], at_head);
  state.pending_forces.emplace_back(state.limbs.tail[limb], -at_head);
  // A limb with a frame spins: the part along its axis, as a couple on F⁺ and F⁻ (d ⟂ u, so
  // d × ((τ × d)/|d|²) = τ).
  const JointRowSet& rows = state.joint_rows;
  if (rows.frame_plus.empty() || rows.frame_plus[body] == state.particles.null_particle()) return;
  const Eigen::Vector3d d = state.particles.position(rows.frame_plus[body]).template cast<double>() -
                            state.particles.position(rows.frame_minus[body]).template cast<double>();
  const Eigen::Vector3d along = torque.dot(u) * u, d_across = d - d.dot(u) * u;
  if (along.isZero(0) || !(d_across.squaredNorm() > 0)) return;
  const Eigen::Vector3d at_plus = along.cross(d_across) / d_across.squaredNorm();
  state.pending_forces.emplace_back(rows.frame_plus[body], at_plus);
  state.pending_forces.emplace_back(rows.frame_minus[body], -at_plus);
}

/// Adds `force` (N·m on a hinge, N on a slide) to joint `joint`'s coordinate `axis` for the next
/// step: the pair of loads it is on the joint's limbs (apply_coordinate_force).
template <typename Scalar>
void apply_joint_force(VerletState<Scalar>& state, std::size_t joint, int axis, double force) {
  apply_coordinate_force(state, state.coordinate_axes, joint, axis, force);
}

/// Joint `joint`'s coordinate `axis` now (coordinate_motion over the expansion's bodies).
template <typename Scalar>
CoordinateMotion coordinate_motion(const VerletState<Scalar>& state, std::size_t joint, int axis) {
  return coordinate_motion(state, state.coordinate_axes, joint, axis);
}

/// The world position of `local_point` (the Model body frame, m).
template <typename Scalar>
Eigen::Vector3d body_point(const VerletState<Scalar>& state, std::size_t body, const Eigen::Vector3d& local_point) {
  const Pose pose = body_pose(state, body);
  return pose.position + pose.orientation * local_point;
}

namespace particle_bodies {

/// The held particle of world joint `joint`: its own pin particle (zero-length joints), or the
/// limb end it pins (shared-particle joints).
template <typename Scalar>
std::uint32_t held_particle(const VerletState<Scalar>& state, const Model& model, std::size_t joint) {
  for (std::uint32_t p = 0; p < state.particle_origins.size(); ++p) {
    const ParticleOrigin& origin = state.particle_origins[p];
    if (origin.kind == ParticleOrigin::Kind::world_pin && origin.index == joint) return p;
  }
  const Joint& j = model.joints[joint];
  const std::uint32_t limb = state.body_limb[static_cast<std::size_t>(j.outboard)];
  return j.outboard_anchor.z() > 0 ? state.limbs.head[limb] : state.limbs.tail[limb];
}

template <typename Scalar>
std::uint32_t island_of_limb(const VerletState<Scalar>& state, std::size_t body) {
  const std::uint32_t limb = state.body_limb[body];
  for (std::uint32_t k = 0; k < state.islands.size(); ++k) {
    if (limb >= state.islands[k].limb_begin && limb < state.islands[k].limb_end) return k;
  }
  return 0;
}

}  // namespace particle_bodies

/// Where world joint `joint` holds its body: its held particle, m.
template <typename Scalar>
Eigen::Vector3d world_anchor(const VerletState<Scalar>& state, const Model& model, std::size_t joint) {
  return particle_bodies::particle_position(state, particle_bodies::held_particle(state, model, joint));
}

/// A kinematic target for the next step: the held particle moves to `target` on a straight
/// path at constant velocity (exact).
template <typename Scalar>
void move_world_anchor(VerletState<Scalar>& state, const Model& model, std::size_t joint, const Eigen::Vector3d& target) {
  state.kinematic_targets.push_back({particle_bodies::held_particle(state, model, joint), target, Eigen::Vector3d::Zero()});
}

template <typename Scalar>
void wake_body(VerletState<Scalar>& state, std::size_t body) {
  wake_island(state, particle_bodies::island_of_limb(state, body));
}

template <typename Scalar>
void sleep_body(VerletState<Scalar>& state, std::size_t body) {
  const std::uint32_t k = particle_bodies::island_of_limb(state, body);
  if (state.islands[k].sleeping) return;
  rest_island(state, k);
  rebuild_awake_islands(state);
}

template <typename Scalar>
bool body_sleeping(const VerletState<Scalar>& state, std::size_t body) {
  return state.islands[particle_bodies::island_of_limb(state, body)].sleeping;
}

/// Puts the limb's movable particles where the pose puts its head, centre and tail, moving as
/// the motion says (a pinned particle stays; a particle a joint shares moves for both limbs),
/// and its frame at the pose's orientation. Any body: always true.
template <typename Scalar>
bool teleport_body(VerletState<Scalar>& state, std::size_t body, const Pose& pose, const Motion& motion) {
  const Eigen::Vector3d& position = pose.position;
  const Eigen::Quaterniond& orientation = pose.orientation;
  const std::uint32_t limb = state.body_limb[body];
  const double half = 0.5 * double(state.constraints.rest_length[state.limbs.link_constraint[limb]]);
  const Eigen::Vector3d axis = orientation * Eigen::Vector3d::UnitZ();
  auto place = [&](std::uint32_t p, const Eigen::Vector3d& x) {
    if (state.particles.inverse_mass[p] == Scalar(0)) return;
    const Eigen::Vector3d v = motion.linear + motion.angular.cross(x - position);
    state.particles.set_position(p, x.cast<Scalar>());
    state.particles.set_previous(p, (x - v * state.previous_time_step).template cast<Scalar>());
    state.particles.set_velocity(p, v.cast<Scalar>());
  };
  place(state.limbs.head[limb], position + half * axis);
  place(state.limbs.tail[limb], position - half * axis);
  if (state.limbs.centre[limb] != kNoCentre) place(state.limbs.centre[limb], position);
  state.body_frame[body] = orientation;
  return true;
}

/// Ball `ball`'s centre and velocity: its particle's.
template <typename Scalar>
BallMotion ball_motion(const VerletState<Scalar>& state, std::size_t ball) {
  const std::uint32_t p = state.balls[ball].particle;
  return {particle_bodies::particle_position(state, p), particle_velocity(state, p)};
}

/// Whether a ball touched a limb in the last step (Settings::release_drives_on_impact).
template <typename Scalar>
bool ball_touching(const VerletState<Scalar>& state) {
  return state.ball_touched;
}

namespace particle_bodies {

/// Island index of every limb (islands are contiguous limb ranges).
template <typename Scalar>
std::vector<std::uint32_t> island_of_each_limb(const VerletState<Scalar>& state) {
  std::vector<std::uint32_t> island(state.limbs.size(), 0);
  for (std::uint32_t k = 0; k < state.islands.size(); ++k) {
    for (std::uint32_t limb = state.islands[k].limb_begin; limb < state.islands[k].limb_end; ++limb) island[limb] = k;
  }
  return island;
}

}  // namespace particle_bodies

/// Copies every particle that stands for the same thing in both states (a limb's head, centre
/// or tail by body, a pin by joint name): positions, previous positions, velocities, the body
/// frames and the clock. An island of surviving bodies sleeps if they all slept, else wakes;
/// one of new bodies is as compiled. Linear in the particles and bodies (plus pins × joints).
/// Never refuses: true.
template <typename Scalar>
bool carry_state(const VerletState<Scalar>& old, const Model& old_model, VerletState<Scalar>& fresh, const Model& new_model,
                 const Survivors& survivors, std::string& /*problem*/) {
  using particle_bodies::island_of_each_limb;
  // The old particle standing for each (kind, index), the first one as compiled.
  const auto key = [](ParticleOrigin::Kind kind, std::int64_t index) {
    return (static_cast<std::uint64_t>(kind) << 40) | static_cast<std::uint64_t>(index);
  };
  std::unordered_map<std::uint64_t, std::uint32_t> old_of_origin;
  for (std::uint32_t p = 0; p < old.particle_origins.size(); ++p) {
    old_of_origin.emplace(key(old.particle_origins[p].kind, old.particle_origins[p].index), p);
  }
  const auto old_particle = [&](const ParticleOrigin& origin) -> std::int64_t {
    std::int64_t index = -1;
    if (origin.kind == ParticleOrigin::Kind::ball) {
      const std::int64_t old_ball = origin.index < survivors.balls.size() ? survivors.balls[origin.index] : -1;
      const auto found = old_ball < 0 ? old_of_origin.end() : old_of_origin.find(key(origin.kind, old_ball));
      return found == old_of_origin.end() ? -1 : static_cast<std::int64_t>(found->second);
    }
    if (origin.kind == ParticleOrigin::Kind::world_pin) {
      for (std::size_t j = 0; j < old_model.joints.size(); ++j) {
        if (old_model.joints[j].name == new_model.joints[origin.index].name) index = static_cast<std::int64_t>(j);
      }
    } else {
      index = survivors.bodies[origin.index];
    }
    if (index < 0) return -1;
    if (const auto found = old_of_origin.find(key(origin.kind, index)); found != old_of_origin.end()) return found->second;
    if (origin.kind == ParticleOrigin::Kind::world_pin) return -1;
    // A limb end merged into another slot's particle (shared-particle joints): through its limb.
    const std::uint32_t limb = old.body_limb[static_cast<std::size_t>(index)];
    switch (origin.kind) {
      case ParticleOrigin::Kind::limb_head: return old.limbs.head[limb];
      case ParticleOrigin::Kind::limb_tail: return old.limbs.tail[limb];
      case ParticleOrigin::Kind::limb_centre: return old.limbs.centre[limb];
      default: return -1;
    }
  };
  std::vector<std::uint32_t> new_frame_particles;
  for (std::uint32_t p = 0; p < fresh.particle_origins.size(); ++p) {
    const std::int64_t q = old_particle(fresh.particle_origins[p]);
    const ParticleOrigin::Kind kind = fresh.particle_origins[p].kind;
    if (q < 0) {
      const bool frame = kind == ParticleOrigin::Kind::limb_frame_plus || kind == ParticleOrigin::Kind::limb_frame_minus;
      if (frame && survivors.bodies[fresh.particle_origins[p].index] >= 0) new_frame_particles.push_back(p);
      continue;
    }
    const auto from = static_cast<std::uint32_t>(q);
    fresh.particles.set_position(p, old.particles.position(from));
    fresh.particles.set_previous(p, old.particles.previous(from));
    fresh.particles.set_velocity(p, old.particles.velocity(from));
  }
  // A surviving limb that gains a frame in this edit: its frame particles where the compiled
  // offset from the centre lands after the shortest turn from the Model's axis to the limb's
  // axis now, moving with the limb's centre.
  for (const std::uint32_t p : new_frame_particles) {
    const std::size_t b = fresh.particle_origins[p].index;
    const std::uint32_t limb = fresh.body_limb[b];
    const std::uint32_t head = fresh.limbs.head[limb], tail = fresh.limbs.tail[limb];
    const auto at = [&](auto get, std::uint32_t q) -> Eigen::Vector3d { return get(q).template cast<double>(); };
    const auto position = [&](std::uint32_t q) { return fresh.particles.position(q); };
    const auto previous = [&](std::uint32_t q) { return fresh.particles.previous(q); };
    const auto velocity = [&](std::uint32_t q) { return fresh.particles.velocity(q); };
    const Eigen::Vector3d offset = Eigen::Quaterniond::FromTwoVectors(new_model.bodies[b].axis, at(position, head) - at(position, tail)) *
                                   (at(position, p) - new_model.bodies[b].position);
    fresh.particles.set_position(p, (0.5 * (at(position, head) + at(position, tail)) + offset).template cast<Scalar>());
    fresh.particles.set_previous(p, (0.5 * (at(previous, head) + at(previous, tail)) + offset).template cast<Scalar>());
    fresh.particles.set_velocity(p, (0.5 * (at(velocity, head) + at(velocity, tail))).template cast<Scalar>());
  }
  fresh.time = old.time;
  fresh.previous_time_step = old.previous_time_step;
  fresh.correction_time = old.correction_time;
  // An island of surviving bodies sleeps if they all slept; one of new bodies as compiled.
  const std::vector<std::uint32_t> old_island = island_of_each_limb(old), fresh_island = island_of_each_limb(fresh);
  std::vector<char> any_old(fresh.islands.size(), 0), all_asleep(fresh.islands.size(), 1);
  for (std::size_t b = 0; b < fresh.body_limb.size(); ++b) {
    if (survivors.bodies[b] < 0) continue;
    const std::uint32_t k = fresh_island[fresh.body_limb[b]];
    any_old[k] = 1;
    all_asleep[k] &= old.islands[old_island[old.body_limb[static_cast<std::size_t>(survivors.bodies[b])]]].sleeping ? 1 : 0;
  }
  for (std::size_t k = 0; k < fresh.islands.size(); ++k) {
    if (any_old[k]) fresh.islands[k].sleeping = all_asleep[k] != 0, fresh.islands[k].still_time = 0;
  }
  rebuild_awake_islands(fresh);
  // A surviving body keeps its frame, turned onto its axis now; a new one starts from the Model's.
  for (std::size_t b = 0; b < fresh.body_frame.size(); ++b) {
    const std::int64_t o = survivors.bodies[b];
    fresh.body_frame[b] = o >= 0 ? old.body_frame[static_cast<std::size_t>(o)] : new_model.bodies[b].orientation();
  }
  transport_body_frames(fresh);
  return true;
}

}  // namespace limber
