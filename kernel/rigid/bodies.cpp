#include "limber/kernel/rigid/bodies.hpp"

namespace limber {

Pose body_pose(const RigidScene& scene, std::size_t body) {
  const RigidBodyState& y = scene.bodies.state;
  const Eigen::Quaterniond orientation = (y.orientation[body] * scene.shapes.principal_frame[body].conjugate()).normalized();
  return {y.position[body] - orientation * scene.shapes.centre_offset[body], orientation};
}

Motion body_motion(const RigidScene& scene, std::size_t body) {
  const RigidBodyState& y = scene.bodies.state;
  const Eigen::Vector3d omega = scene.bodies.angular_velocity(y, body);
  const Eigen::Vector3d origin = body_pose(scene, body).position;
  return {scene.bodies.linear_velocity(y, body) + omega.cross(origin - y.position[body]), omega};
}

Eigen::Vector3d body_centre_of_mass(const RigidScene& scene, std::size_t body) { return scene.bodies.state.position[body]; }

void apply_body_load(RigidScene& scene, std::size_t body, const Eigen::Vector3d& force, const Eigen::Vector3d& torque) {
  scene.applied_force[body] += force;
  scene.applied_torque[body] += torque;
}

Eigen::Vector3d body_point(const RigidScene& scene, std::size_t body, const Eigen::Vector3d& local_point) {
  return world_point(scene, body, local_point);
}

void wake_body(RigidScene& scene, std::size_t body) { scene.islands[scene.island_of_body[body]].wake(); }

void sleep_body(RigidScene& scene, std::size_t body) { rest_island(scene, scene.island_of_body[body]); }

bool body_sleeping(const RigidScene& scene, std::size_t body) { return scene.islands[scene.island_of_body[body]].sleeping; }

bool teleport_body(RigidScene& scene, std::size_t body, const Pose& pose, const Motion& motion) {
  RigidBodyState& y = scene.bodies.state;
  y.orientation[body] = (pose.orientation * scene.shapes.principal_frame[body]).normalized();
  y.position[body] = pose.position + pose.orientation * scene.shapes.centre_offset[body];
  y.linear_momentum[body] = scene.bodies.mass[body] * (motion.linear + motion.angular.cross(y.position[body] - pose.position));
  y.angular_momentum[body] = scene.bodies.world_inertia(y, body) * motion.angular;
  return true;
}

BallMotion ball_motion(const RigidScene& scene, std::size_t ball) {
  const std::size_t b = scene.ball_begin + ball;
  return {scene.bodies.state.position[b], scene.bodies.linear_velocity(scene.bodies.state, b)};
}

namespace rigid_bodies {

std::int64_t old_body(const RigidScene& old, const RigidScene& fresh, const Survivors& survivors, std::size_t b) {
  if (b >= fresh.ball_begin) {
    const std::size_t k = b - fresh.ball_begin;
    const std::int64_t old_ball = k < survivors.balls.size() ? survivors.balls[k] : -1;
    return old_ball < 0 ? -1 : static_cast<std::int64_t>(old.ball_begin) + old_ball;
  }
  return b < survivors.bodies.size() ? survivors.bodies[b] : -1;
}

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

}  // namespace rigid_bodies

bool carry_state(const RigidScene& old, const Model&, RigidScene& fresh, const Model&, const Survivors& survivors, std::string&) {
  const RigidBodyState& from = old.bodies.state;
  RigidBodyState& to = fresh.bodies.state;
  for (std::size_t b = 0; b < to.size(); ++b) {
    const std::int64_t o = rigid_bodies::old_body(old, fresh, survivors, b);
    if (o < 0) continue;
    const auto k = static_cast<std::size_t>(o);
    to.position[b] = from.position[k], to.orientation[b] = from.orientation[k];
    to.linear_momentum[b] = from.linear_momentum[k], to.angular_momentum[b] = from.angular_momentum[k];
  }
  fresh.time = old.time;
  rigid_bodies::carry_sleep(old, fresh, survivors);
  return true;
}

}  // namespace limber
