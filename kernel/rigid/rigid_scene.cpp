#include "limber/kernel/rigid/rigid_scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "limber/kernel/mass/mass_properties.hpp"
#include "limber/kernel/model/checks.hpp"

namespace limber {
namespace {

// The rigid body's frame: the limb's principal axes (so its inertia is diagonal, which the
// free-rotation flow needs), with moments below 10⁻⁶ of the largest raised to it: a limb of zero
// radius has none about its axis, and M must be invertible. Its value is not what keeps such a
// limb stable (rigid_scene.hpp).
struct PrincipalFrame {
  Eigen::Quaterniond rotation;  // principal frame → Model body frame
  Eigen::Vector3d moments;
};
PrincipalFrame principal_frame(const Eigen::Matrix3d& inertia) {
  const PrincipalAxes principal = principal_axes(inertia);
  return {Eigen::Quaterniond(principal.axes).normalized(), principal.moments.cwiseMax(1e-6 * principal.moments.maxCoeff())};
}

// Limb `b`'s mass properties as a rigid body: body_mass_properties, with what it cannot compute
// (a capsule whose volume under- or overflows: radius 1e-200 or 1e200 m) or what leaves the body
// no rotational inertia to invert (its mass at one point: one lump of radius 0, or a length and
// radius too small) refused as a ModelError naming the body and the field that gives them.
MassProperties limb_mass_properties(const Body& body, std::size_t b) {
  const std::string field = "bodies[" + std::to_string(b) + "] ('" + body.name + "')." +
                            (body.inertial ? "inertial" : body.point_masses.empty() ? "shape" : "point_masses");
  MassProperties mass;
  try {
    mass = body_mass_properties(body);
  } catch (const std::invalid_argument& error) {
    throw ModelError(field + ": the rigid-body methods cannot spread the mass over it (" + error.what() + ")");
  }
  const double largest = mass.inertia.diagonal().maxCoeff();
  if (!std::isfinite(1 / (1e-6 * largest)) || !mass.inertia.allFinite()) {
    throw ModelError(field + ": gives the rigid-body methods no rotational inertia to invert (largest moment " +
                     checks::format_number(largest) + " kg·m²: the mass at one point, or a mass or sizes too small)");
  }
  return mass;
}

}  // namespace

RigidScene compile_rigid_scene(const Model& model) {
  validate(model);
  RigidScene scene;
  scene.settings = model.settings;
  const std::size_t limb_count = model.bodies.size();
  const std::size_t body_count = limb_count + model.balls.size();
  RigidBodyBuffer& bodies = scene.bodies;
  bodies.resize(body_count);
  RigidShapes& shapes = scene.shapes;
  shapes.shape.resize(body_count), shapes.length.resize(body_count), shapes.radius.resize(body_count);
  shapes.half_extents.assign(body_count, Eigen::Vector3d::Zero()), shapes.shape_rotation.assign(body_count, Eigen::Quaterniond::Identity());
  shapes.centre_offset.resize(body_count), shapes.principal_frame.resize(body_count), shapes.is_ball.assign(body_count, false);
  shapes.restitution.assign(body_count, 0.0);

  auto set_body = [&](std::size_t b, const MassProperties& mass, const Eigen::Quaterniond& orientation,
                      const Eigen::Vector3d& centre, const Eigen::Vector3d& velocity, const Eigen::Vector3d& angular_velocity) {
    const PrincipalFrame frame = principal_frame(mass.inertia);
    shapes.principal_frame[b] = frame.rotation;
    bodies.mass[b] = mass.mass;
    bodies.inverse_mass[b] = 1.0 / mass.mass;
    bodies.body_inertia[b] = frame.moments.asDiagonal();
    bodies.body_inverse_inertia[b] = frame.moments.cwiseInverse().asDiagonal();
    bodies.state.position[b] = centre;
    bodies.state.orientation[b] = (orientation * frame.rotation).normalized();
    bodies.state.linear_momentum[b] = mass.mass * velocity;
    bodies.state.angular_momentum[b] = bodies.world_inertia(bodies.state, b) * angular_velocity;
  };
  for (std::size_t b = 0; b < limb_count; ++b) {
    const Body& body = model.bodies[b];
    const MassProperties mass = limb_mass_properties(body, b);
    set_body(b, mass, body.orientation(), body.to_world(mass.centre_of_mass), body.velocity_at(mass.centre_of_mass),
             body.angular_velocity);
    shapes.shape[b] = body.shape.type, shapes.length[b] = body.shape.length, shapes.radius[b] = body.shape.radius;
    if (has_half_extents(body.shape)) {
      shapes.radius[b] = bounding_radius(body.shape);
      shapes.half_extents[b] = body.shape.half_extents, shapes.shape_rotation[b] = body.shape.rotation;
    }
    shapes.centre_offset[b] = mass.centre_of_mass;
  }
  scene.ball_begin = static_cast<std::uint32_t>(limb_count);
  for (std::size_t b = limb_count; b < body_count; ++b) {
    const Ball& ball = model.balls[b - limb_count];
    shapes.restitution[b] = ball.restitution;
    set_body(b, solid_sphere(ball.mass, ball.radius), Eigen::Quaterniond::Identity(), ball.position, ball.velocity,
             Eigen::Vector3d::Zero());
    shapes.shape[b] = ShapeType::capsule, shapes.length[b] = 0, shapes.radius[b] = ball.radius;
    shapes.centre_offset[b].setZero();
    shapes.is_ball[b] = true;
  }

  // The Model's islands (body_islands), and each ball as its own, last.
  const BodyIslands islands = body_islands(model);
  scene.island_of_body = islands.island_of_body;
  scene.islands.resize(islands.count);
  for (std::size_t b = limb_count; b < body_count; ++b) {
    scene.island_of_body.push_back(static_cast<std::uint32_t>(scene.islands.size()));
    scene.islands.emplace_back();
  }
  for (std::uint32_t b = 0; b < body_count; ++b) scene.islands[scene.island_of_body[b]].bodies.push_back(b);
  for (RigidIsland& island : scene.islands) {
    bool at_rest = true;
    for (std::uint32_t b : island.bodies) {
      at_rest = at_rest && bodies.state.linear_momentum[b].isZero(0) && bodies.state.angular_momentum[b].isZero(0);
    }
    island.sleeping = model.settings.sleep.enabled && model.settings.sleep.start_asleep && at_rest;
  }

  scene.planes = scene_planes(model);
  scene.collisions = LimbCollisions(model);
  // Every limb end against every plane, plus each ball against every limb; with the collision
  // world, room for a limb pair and two static contacts per body (more grows it once).
  std::size_t contacts = 2 * body_count * scene.planes.size() + model.balls.size() * limb_count;
  scene.limb_segments.resize(body_count);  // their speculative reaches too (detect_rigid_contacts)
  if (scene.collisions.active()) {
    contacts += 3 * body_count;
    scene.limb_awake.resize(body_count);
    scene.limb_contacts.reserve(3 * body_count);
  }
  scene.contacts.reserve(contacts);
  scene.step_start_position = bodies.state.position;
  scene.velocity.assign(body_count, Eigen::Vector3d::Zero());
  scene.angular_velocity.assign(body_count, Eigen::Vector3d::Zero());
  scene.applied_force.assign(body_count, Eigen::Vector3d::Zero());
  scene.applied_torque.assign(body_count, Eigen::Vector3d::Zero());
  return scene;
}

JointAnchors joint_anchors(const RigidScene& scene, const Model& model) {
  JointAnchors joints;
  for (const Joint& joint : model.joints) {
    joints.inboard.push_back(joint.inboard);
    joints.outboard.push_back(joint.outboard);
    joints.outboard_anchor.push_back(body_anchor(scene, joint.outboard, joint.outboard_anchor));
    // A sphere (length 0) counts by its diameter.
    const auto size = [&](int body) {
      const Shape& shape = model.bodies[static_cast<std::size_t>(body)].shape;
      return shape.length > 0 ? shape.length : 2 * shape.radius;
    };
    double reference = size(joint.outboard);
    if (joint.inboard == kWorld) {
      joints.inboard_anchor.push_back(joint.inboard_anchor);
    } else {
      joints.inboard_anchor.push_back(body_anchor(scene, joint.inboard, joint.inboard_anchor));
      reference = 0.5 * (reference + size(joint.inboard));
    }
    joints.reference_length.push_back(reference);
  }
  return joints;
}

Eigen::Vector3d joint_separation(const JointAnchors& joints, const RigidBodyState& y, std::size_t j) {
  const std::int32_t inboard = joints.inboard[j], outboard = joints.outboard[j];
  const Eigen::Vector3d outboard_point = y.position[outboard] + y.orientation[outboard] * joints.outboard_anchor[j];
  const Eigen::Vector3d inboard_point =
      inboard >= 0 ? Eigen::Vector3d(y.position[inboard] + y.orientation[inboard] * joints.inboard_anchor[j]) : joints.inboard_anchor[j];
  return inboard_point - outboard_point;
}

Eigen::Vector3d body_anchor(const RigidScene& scene, std::size_t body, const Eigen::Vector3d& local_point) {
  return scene.shapes.principal_frame[body].conjugate() * (local_point - scene.shapes.centre_offset[body]);
}

Eigen::Vector3d world_point(const RigidScene& scene, std::size_t body, const Eigen::Vector3d& local_point) {
  return scene.bodies.state.position[body] + scene.bodies.state.orientation[body] * body_anchor(scene, body, local_point);
}

void body_velocities(RigidScene& scene, const RigidBodyState& y) {
  for (std::size_t b = 0; b < y.size(); ++b) {
    scene.velocity[b] = scene.bodies.linear_velocity(y, b);
    scene.angular_velocity[b] = scene.bodies.angular_velocity(y, b);
  }
}

void accumulate_applied_forces(RigidScene& scene, const RigidBodyState& y, RigidForces& forces) {
  body_velocities(scene, y);
  const Settings& settings = scene.settings;
  const RigidBodyBuffer& bodies = scene.bodies;
  const bool drag = !settings.drag.linear.isZero(0) || !settings.drag.angular.isZero(0);
  for (const RigidIsland& island : scene.islands) {
    if (island.sleeping) continue;
    for (std::uint32_t b : island.bodies) {
      forces.force[b] += bodies.mass[b] * settings.gravity + scene.applied_force[b];
      forces.torque[b] += scene.applied_torque[b];
      if (settings.damping > 0) {
        forces.force[b] -= settings.damping * bodies.mass[b] * scene.velocity[b];
        forces.torque[b] -= settings.damping * y.angular_momentum[b];
      }
      if (drag) {
        // The Model's body frame (z: the limb's axis), not the principal frame.
        const Eigen::Matrix3d rotation = (y.orientation[b] * scene.shapes.principal_frame[b].conjugate()).toRotationMatrix();
        forces.force[b] -= rotation * settings.drag.linear.cwiseProduct(rotation.transpose() * scene.velocity[b]);
        forces.torque[b] -= rotation * settings.drag.angular.cwiseProduct(rotation.transpose() * scene.angular_velocity[b]);
      }
    }
  }
}

void clear_applied_loads(RigidScene& scene) {
  for (Eigen::Vector3d& force : scene.applied_force) force.setZero();
  for (Eigen::Vector3d& torque : scene.applied_torque) torque.setZero();
}

StepStatus update_sleep(RigidScene& scene, double dt) {
  body_velocities(scene, scene.bodies.state);
  return update_sleep_from_velocities(scene, dt);
}

StepStatus update_sleep_from_velocities(RigidScene& scene, double dt) {
  const Settings& settings = scene.settings;
  StepStatus status = StepStatus::ok;
  for (RigidIsland& island : scene.islands) {
    if (island.sleeping) continue;
    double fastest = 0;  // NaN once a body's speed or position is not finite
    for (std::uint32_t b : island.bodies) {
      // The fastest surface point: spin about the limb's axis moves it at most ω·r, the rest at
      // most |ω⊥|·(L/2 + r).
      const Eigen::Vector3d axis = scene.bodies.state.orientation[b] * (scene.shapes.principal_frame[b].conjugate() * Eigen::Vector3d::UnitZ());
      const Eigen::Vector3d& omega = scene.angular_velocity[b];
      const double axial = omega.dot(axis);
      double speed = scene.velocity[b].norm() + std::abs(axial) * scene.shapes.radius[b] +
                     (omega - axial * axis).norm() * (0.5 * scene.shapes.length[b] + scene.shapes.radius[b]);
      if (!scene.bodies.state.position[b].allFinite()) speed = std::numeric_limits<double>::quiet_NaN();
      fastest = speed > fastest || std::isnan(speed) ? speed : fastest;
    }
    if (island.settle(fastest, dt, settings, status)) rest_island(scene, static_cast<std::size_t>(&island - scene.islands.data()));
  }
  return status;
}

void rest_island(RigidScene& scene, std::size_t k) {
  RigidIsland& island = scene.islands[k];
  island.sleeping = true;
  for (std::uint32_t b : island.bodies) {
    scene.bodies.state.linear_momentum[b].setZero();
    scene.bodies.state.angular_momentum[b].setZero();
  }
}

}  // namespace limber
