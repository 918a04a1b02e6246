#include "limber/kernel/world/world_bodies.hpp"

#include <stdexcept>

#include "limber/kernel/featherstone/step.hpp"

namespace limber::world_bodies {

Pose rigid_pose(const RigidScene& scene, std::size_t body) {
  const RigidBodyState& y = scene.bodies.state;
  // The Model body frame: a Model point p is at x + q·principal⁻¹·(p − centre_offset).
  const Eigen::Quaterniond orientation = (y.orientation[body] * scene.shapes.principal_frame[body].conjugate()).normalized();
  return {y.position[body] - orientation * scene.shapes.centre_offset[body], orientation};
}

Motion motion(const RigidScene& scene, std::size_t body) {
  const RigidBodyState& y = scene.bodies.state;
  const Eigen::Vector3d omega = scene.bodies.angular_velocity(y, body);
  const Eigen::Vector3d origin = rigid_pose(scene, body).position;
  return {scene.bodies.linear_velocity(y, body) + omega.cross(origin - y.position[body]), omega};
}

Eigen::Vector3d centre_of_mass(const RigidScene& scene, std::size_t body) { return scene.bodies.state.position[body]; }

void apply_load(RigidScene& scene, std::size_t body, const Eigen::Vector3d& force, const Eigen::Vector3d& torque) {
  scene.applied_force[body] += force;
  scene.applied_torque[body] += torque;
}

Eigen::Vector3d world_point(const RigidScene& scene, const Model&, std::size_t body, const Eigen::Quaterniond&,
                            const Eigen::Vector3d& local_point) {
  return limber::world_point(scene, body, local_point);
}

Eigen::Vector3d world_anchor(const SpringState& state, const Model&, std::size_t joint) { return state.springs.inboard_anchor[joint]; }
Eigen::Vector3d world_anchor(const LagrangeState& state, const Model&, std::size_t joint) { return state.joints.inboard_anchor[joint]; }
Eigen::Vector3d world_anchor(const FeatherstoneState& state, const Model&, std::size_t joint) { return state.joints.inboard_anchor[joint]; }

void move_world_anchor(SpringState& state, const Model&, std::size_t joint, const Eigen::Vector3d& target) {
  state.springs.inboard_anchor[joint] = target;
}
void move_world_anchor(LagrangeState& state, const Model&, std::size_t joint, const Eigen::Vector3d& target) {
  state.joints.inboard_anchor[joint] = target;
}
void move_world_anchor(FeatherstoneState&, const Model&, std::size_t, const Eigen::Vector3d&) {
  throw std::logic_error("move_world_anchor: Featherstone worlds hold no pins (World::pin refuses them)");
}

void wake(RigidScene& scene, std::size_t body) {
  scene.islands[scene.island_of_body[body]].wake();
}

void sleep(RigidScene& scene, std::size_t body) { rest_island(scene, scene.island_of_body[body]); }

void sleep(FeatherstoneState& state, std::size_t body) {
  rest_island(state, state.island_of_body[body]);
  zero_sleeping_velocities(state);
}

bool sleeping(const RigidScene& scene, std::size_t body) { return scene.islands[scene.island_of_body[body]].sleeping; }

void teleport(RigidScene& scene, std::size_t body, const Eigen::Vector3d& position, const Eigen::Quaterniond& orientation,
              const Motion& motion) {
  RigidBodyState& y = scene.bodies.state;
  y.orientation[body] = (orientation * scene.shapes.principal_frame[body]).normalized();
  y.position[body] = position + orientation * scene.shapes.centre_offset[body];
  y.linear_momentum[body] = scene.bodies.mass[body] * (motion.linear + motion.angular.cross(y.position[body] - position));
  y.angular_momentum[body] = scene.bodies.world_inertia(y, body) * motion.angular;
}

bool teleport_floating_root(FeatherstoneState& state, std::size_t body, const Eigen::Vector3d& position,
                            const Eigen::Quaterniond& orientation, const Motion& motion) {
  const std::int32_t i = state.tree_body[body];
  if (state.tree.body(i).joint != ArticulatedJoint::floating) return false;
  // A floating root's frame: the Model body frame's axes at the centre of mass; q = (p, w, x, y, z).
  const Eigen::Vector3d centre = position + orientation * state.shapes.centre_offset[body];
  const int p = state.tree.position_offset(i), v = state.tree.velocity_offset(i);
  state.q.segment<3>(p) = centre;
  state.q.segment<4>(p + 3) << orientation.w(), orientation.x(), orientation.y(), orientation.z();
  const Eigen::Matrix3d to_child = orientation.toRotationMatrix().transpose();
  state.v.segment<3>(v) = to_child * motion.angular;
  state.v.segment<3>(v + 3) = to_child * (motion.linear + motion.angular.cross(centre - position));
  refresh_rigid_bodies(state);
  return true;
}

namespace {

// The old index of new body b (−1: new): a limb's by survivors.bodies, a ball's by survivors.balls.
std::int64_t old_body(const RigidScene& old, const RigidScene& fresh, const Survivors& survivors, std::size_t b) {
  if (b >= fresh.ball_begin) {
    const std::size_t k = b - fresh.ball_begin;
    const std::int64_t old_ball = k < survivors.balls.size() ? survivors.balls[k] : -1;
    return old_ball < 0 ? -1 : static_cast<std::int64_t>(old.ball_begin) + old_ball;
  }
  return b < survivors.bodies.size() ? survivors.bodies[b] : -1;
}

// An island of surviving bodies sleeps if they all slept, else wakes; one of new bodies keeps
// what compile decided.
void carry_sleep(const RigidScene& old, RigidScene& fresh, const Survivors& survivors) {
  for (RigidIsland& island : fresh.islands) {
    bool any_old = false, all_asleep = true;
    for (const std::uint32_t b : island.bodies) {
      const std::int64_t o = old_body(old, fresh, survivors, b);
      if (o < 0) continue;
      any_old = true;
      all_asleep = all_asleep && old.islands[old.island_of_body[static_cast<std::size_t>(o)]].sleeping;
    }
    if (any_old) island.sleeping = all_asleep, island.still_time = 0;
  }
}

}  // namespace

void carry_state(const RigidScene& old, const Model&, RigidScene& fresh, const Model&, const Survivors& survivors) {
  const RigidBodyState& from = old.bodies.state;
  RigidBodyState& to = fresh.bodies.state;
  for (std::size_t b = 0; b < to.size(); ++b) {
    const std::int64_t o = old_body(old, fresh, survivors, b);
    if (o < 0) continue;
    const auto k = static_cast<std::size_t>(o);
    to.position[b] = from.position[k], to.orientation[b] = from.orientation[k];
    to.linear_momentum[b] = from.linear_momentum[k], to.angular_momentum[b] = from.angular_momentum[k];
  }
  fresh.time = old.time;
  carry_sleep(old, fresh, survivors);
}

bool carry_state(const FeatherstoneState& old, const Model& old_model, FeatherstoneState& fresh, const Model& new_model,
                 const Survivors& survivors, std::string& problem) {
  // The joint a tree body hangs from, by name (empty: floating), and its parent's old index.
  const auto hangs = [](const FeatherstoneState& state, const Model& model, std::int32_t i) {
    const std::int32_t joint = state.model_joint[static_cast<std::size_t>(i)];
    return joint < 0 ? std::string() : model.joints[static_cast<std::size_t>(joint)].name;
  };
  for (std::int32_t i = 0; i < fresh.tree.body_count(); ++i) {
    const std::int32_t b = fresh.scene_body[static_cast<std::size_t>(i)];
    const std::int64_t o = old_body(old, fresh, survivors, static_cast<std::size_t>(b));
    if (o < 0) continue;
    const std::int32_t oi = old.tree_body[static_cast<std::size_t>(o)];
    const std::int32_t parent = fresh.tree.body(i).parent, old_parent = old.tree.body(oi).parent;
    const std::int64_t parent_then =
        parent < 0 ? -1 : old_body(old, fresh, survivors, static_cast<std::size_t>(fresh.scene_body[static_cast<std::size_t>(parent)]));
    const std::int64_t old_parent_body = old_parent < 0 ? -1 : old.scene_body[static_cast<std::size_t>(old_parent)];
    if (hangs(fresh, new_model, i) != hangs(old, old_model, oi) || parent_then != old_parent_body ||
        fresh.tree.body(i).joint != old.tree.body(oi).joint) {
      const std::string name = static_cast<std::size_t>(b) < new_model.bodies.size() ? new_model.bodies[static_cast<std::size_t>(b)].name
                                                                                    : ball_name(new_model, static_cast<std::size_t>(b) - new_model.bodies.size());
      problem = "keeps a moving body's state only while it hangs from the same joint on the same parent; the edit changes how '" + name +
                "' hangs (reduced coordinates would re-root it)";
      return false;
    }
    const ArticulatedJoint type = fresh.tree.body(i).joint;
    fresh.q.segment(fresh.tree.position_offset(i), joint_position_count(type)) =
        old.q.segment(old.tree.position_offset(oi), joint_position_count(type));
    fresh.v.segment(fresh.tree.velocity_offset(i), joint_velocity_count(type)) =
        old.v.segment(old.tree.velocity_offset(oi), joint_velocity_count(type));
  }
  fresh.time = old.time;
  carry_sleep(old, fresh, survivors);
  refresh_rigid_bodies(fresh);
  return true;
}

}  // namespace limber::world_bodies
