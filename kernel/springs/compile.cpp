// GCC 12 false positive inside Eigen's AVX-512 code (bug 105593); must precede Eigen's headers.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include "kernel/springs/compile.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "kernel/mass/mass_properties.hpp"
#include "kernel/springs/implicit_step.hpp"
#include "layouts/graph/disjoint_sets.hpp"

namespace limber {
namespace {

// The rigid body's frame: the limb's principal axes (so its inertia is diagonal, which the
// free-rotation flow needs), with moments below 10⁻⁶ of the largest raised to it.
struct PrincipalFrame {
  Eigen::Quaterniond rotation;  // principal frame → Model body frame
  Eigen::Vector3d moments;
};
PrincipalFrame principal_frame(const Eigen::Matrix3d& inertia) {
  const PrincipalAxes principal = principal_axes(inertia);
  return {Eigen::Quaterniond(principal.axes).normalized(), principal.moments.cwiseMax(1e-6 * principal.moments.maxCoeff())};
}

}  // namespace

SpringState compile_springs(const Model& model, const SpringOptions& options) {
  validate(model);
  if (options.stiffness && !(*options.stiffness > 0 && std::isfinite(*options.stiffness))) {
    throw ModelError("stiffness: must be a finite number > 0");
  }
  if (options.damping && !(*options.damping >= 0 && std::isfinite(*options.damping))) {
    throw ModelError("damping: must be a finite number >= 0");
  }
  SpringState state;
  state.options = options;
  state.settings = model.settings;
  const std::size_t limb_count = model.bodies.size();
  const std::size_t body_count = limb_count + (model.ball ? 1 : 0);
  RigidBodyBuffer& bodies = state.bodies;
  bodies.resize(body_count);
  RigidShapes& shapes = state.shapes;
  shapes.shape.resize(body_count), shapes.length.resize(body_count), shapes.radius.resize(body_count);
  shapes.centre_offset.resize(body_count), shapes.is_ball.assign(body_count, false);

  shapes.principal_frame.resize(body_count);
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
    const MassProperties mass = body_mass_properties(body);
    const Eigen::Quaterniond orientation = body.orientation();
    set_body(b, mass, orientation, body.to_world(mass.centre_of_mass), body.velocity_at(mass.centre_of_mass),
             body.angular_velocity);
    shapes.shape[b] = body.shape.type, shapes.length[b] = body.shape.length, shapes.radius[b] = body.shape.radius;
    shapes.centre_offset[b] = mass.centre_of_mass;
  }
  if (model.ball) {
    const Ball& ball = *model.ball;
    const auto b = static_cast<std::int32_t>(limb_count);
    state.ball = b;
    state.ball_restitution = ball.restitution;
    set_body(b, solid_sphere(ball.mass, ball.radius), Eigen::Quaterniond::Identity(), ball.position, ball.velocity,
             Eigen::Vector3d::Zero());
    shapes.shape[b] = ShapeType::capsule, shapes.length[b] = 0, shapes.radius[b] = ball.radius;
    shapes.centre_offset[b].setZero();
    shapes.is_ball[b] = true;
  }

  // Springs, one per joint, anchors relative to the centres of mass.
  SpringBuffer& springs = state.springs;
  DisjointSets connected(static_cast<std::uint32_t>(body_count));
  for (const Joint& joint : model.joints) {
    const Body& outboard = model.bodies[joint.outboard];
    springs.inboard.push_back(joint.inboard);
    springs.outboard.push_back(joint.outboard);
    auto body_anchor = [&](int b, const Vector3& anchor) {
      return Eigen::Vector3d(shapes.principal_frame[b].conjugate() * (anchor - shapes.centre_offset[b]));
    };
    springs.outboard_anchor.push_back(body_anchor(joint.outboard, joint.outboard_anchor));
    double reference = outboard.shape.length;
    if (joint.inboard == kWorld) {
      springs.inboard_anchor.push_back(joint.inboard_anchor);
    } else {
      springs.inboard_anchor.push_back(body_anchor(joint.inboard, joint.inboard_anchor));
      reference = 0.5 * (reference + model.bodies[joint.inboard].shape.length);
      connected.unite(static_cast<std::uint32_t>(joint.inboard), static_cast<std::uint32_t>(joint.outboard));
    }
    springs.reference_length.push_back(reference);
    springs.stiffness.push_back(options.stiffness.value_or(joint.stiffness.value_or(model.settings.springs.stiffness)));
    springs.damping.push_back(options.damping.value_or(joint.damping.value_or(model.settings.springs.damping)));
  }

  // Islands in order of their lowest body; the ball is its own.
  state.island_of_body.assign(body_count, 0);
  std::vector<std::int64_t> island_of_root(body_count, -1);
  for (std::uint32_t b = 0; b < body_count; ++b) {
    const std::uint32_t root = connected.find(b);
    if (island_of_root[root] < 0) {
      island_of_root[root] = static_cast<std::int64_t>(state.islands.size());
      state.islands.emplace_back();
    }
    state.island_of_body[b] = static_cast<std::uint32_t>(island_of_root[root]);
    state.islands[island_of_root[root]].bodies.push_back(b);
  }
  for (RigidIsland& island : state.islands) {
    bool at_rest = true;
    for (std::uint32_t b : island.bodies) {
      at_rest = at_rest && bodies.state.linear_momentum[b].isZero(0) && bodies.state.angular_momentum[b].isZero(0);
    }
    island.sleeping = model.settings.sleep.enabled && model.settings.sleep.start_asleep && at_rest;
  }

  state.planes = scene_planes(model);
  // Every limb end against every plane, plus the ball against the planes and every limb.
  state.contacts.reserve(2 * body_count * state.planes.size() + limb_count);
  state.scratch.resize(body_count);
  state.velocity.assign(body_count, Eigen::Vector3d::Zero());
  state.angular_velocity.assign(body_count, Eigen::Vector3d::Zero());
  state.scratch_world_inertia.assign(body_count, Eigen::Matrix3d::Zero());
  if (options.integrator == SpringIntegrator::backward_euler) prepare_implicit_system(state);
  return state;
}

Eigen::Vector3d world_point(const SpringState& state, std::size_t body, const Eigen::Vector3d& local_point) {
  return state.bodies.state.position[body] + state.bodies.state.orientation[body] *
                                                 (state.shapes.principal_frame[body].conjugate() * (local_point - state.shapes.centre_offset[body]));
}

}  // namespace limber
