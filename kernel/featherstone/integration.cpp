#include "limber/kernel/featherstone/integration.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

namespace limber {
namespace {

// exp(δ/2) as a unit quaternion: the rotation by the rotation vector δ.
Eigen::Quaterniond rotation_exponential(const Eigen::Vector3d& rotation) {
  const double angle = rotation.norm();
  // sin(|δ|/2)/|δ|, by its series below 1e-4 rad (error < 1e-18).
  const double scale = angle < 1e-4 ? 0.5 - angle * angle / 48 : std::sin(0.5 * angle) / angle;
  return {std::cos(0.5 * angle), scale * rotation.x(), scale * rotation.y(), scale * rotation.z()};
}

// J_r⁻¹(θ) ω = ω + ½ θ × ω + β θ × (θ × ω), β = 1/|θ|² − (1 + cos|θ|) / (2|θ| sin|θ|): the rate
// of θ in R = R₀ exp(θ) when the body-frame angular velocity is ω (the inverse of SO(3)'s right
// Jacobian; Solà, Deray & Atchuthan 2018, "A micro Lie theory for state estimation in robotics").
Eigen::Vector3d inverse_right_jacobian_times(const Eigen::Vector3d& theta, const Eigen::Vector3d& omega) {
  const double angle = theta.norm();
  const double beta = angle < 1e-3 ? 1.0 / 12 + angle * angle / 720
                                   : 1 / (angle * angle) - (1 + std::cos(angle)) / (2 * angle * std::sin(angle));
  const Eigen::Vector3d theta_cross_omega = theta.cross(omega);
  return omega + 0.5 * theta_cross_omega + beta * theta.cross(theta_cross_omega);
}

// Θ̇ at the stage q₀ ⊕ Θ with velocity v (see integration.hpp), into `rate`, for the bodies of
// `range`.
void displacement_rate(const ArticulatedTree& tree, const Eigen::VectorXd& displacement, const Eigen::VectorXd& v,
                       Eigen::VectorXd& rate, BodyRange range) {
  for (int i = range.first; i < range.last; ++i) {
    const int offset = tree.velocity_offset(i);
    switch (tree.body(i).joint) {
      case ArticulatedJoint::revolute:
      case ArticulatedJoint::prismatic: rate[offset] = v[offset]; break;
      case ArticulatedJoint::spherical:
        rate.segment<3>(offset) = inverse_right_jacobian_times(displacement.segment<3>(offset), v.segment<3>(offset));
        break;
      case ArticulatedJoint::floating: {
        const Eigen::Vector3d theta = displacement.segment<3>(offset);
        rate.segment<3>(offset) = inverse_right_jacobian_times(theta, v.segment<3>(offset));
        rate.segment<3>(offset + 3) = rotation_exponential(theta) * v.segment<3>(offset + 3);
        break;
      }
      case ArticulatedJoint::fixed: break;
    }
  }
}

}  // namespace

void FeatherstoneIntegratorWorkspace::resize(const ArticulatedTree& tree) {
  dynamics.resize(tree);
  const int nq = tree.position_count(), nv = tree.velocity_count();
  start_positions.setZero(nq), stage_positions.setZero(nq);
  start_velocities.setZero(nv), stage_velocities.setZero(nv), stage_rate.setZero(nv);
  stage_displacement.setZero(nv), accelerations.setZero(nv);
  acceleration_sum.setZero(nv), displacement_rate_sum.setZero(nv);
}

bool FeatherstoneIntegratorWorkspace::fits(const ArticulatedTree& tree) const {
  return dynamics.fits(tree) && start_positions.size() == tree.position_count() && stage_rate.size() == tree.velocity_count();
}

void displace_positions(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                        const Eigen::Ref<const Eigen::VectorXd>& displacement, Eigen::Ref<Eigen::VectorXd> out) {
  displace_positions(tree, q, displacement, out, tree.all_bodies());
}

void displace_positions(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                        const Eigen::Ref<const Eigen::VectorXd>& displacement, Eigen::Ref<Eigen::VectorXd> out, BodyRange range) {
  if (q.size() != tree.position_count() || out.size() != tree.position_count() || displacement.size() != tree.velocity_count()) {
    throw std::invalid_argument("displace_positions: expected q and out of size " + std::to_string(tree.position_count()) +
                                " and a displacement of size " + std::to_string(tree.velocity_count()));
  }
  for (int i = range.first; i < range.last; ++i) {
    const int p = tree.position_offset(i), d = tree.velocity_offset(i);
    switch (tree.body(i).joint) {
      case ArticulatedJoint::revolute:
      case ArticulatedJoint::prismatic: out[p] = q[p] + displacement[d]; break;
      case ArticulatedJoint::spherical: {
        const Eigen::Quaterniond start(q[p], q[p + 1], q[p + 2], q[p + 3]);
        const Eigen::Quaterniond end = (start * rotation_exponential(displacement.segment<3>(d))).normalized();
        out[p] = end.w(), out[p + 1] = end.x(), out[p + 2] = end.y(), out[p + 3] = end.z();
        break;
      }
      case ArticulatedJoint::floating: {
        const Eigen::Quaterniond start = Eigen::Quaterniond(q[p + 3], q[p + 4], q[p + 5], q[p + 6]).normalized();
        const Eigen::Vector3d position = q.segment<3>(p) + start * displacement.segment<3>(d + 3);
        const Eigen::Quaterniond end = (start * rotation_exponential(displacement.segment<3>(d))).normalized();
        out.segment<3>(p) = position;
        out[p + 3] = end.w(), out[p + 4] = end.x(), out[p + 5] = end.y(), out[p + 6] = end.z();
        break;
      }
      case ArticulatedJoint::fixed: break;
    }
  }
}

void integrate(const ArticulatedTree& tree, Eigen::VectorXd& q, Eigen::VectorXd& v,
               const Eigen::Ref<const Eigen::VectorXd>& joint_forces, const Eigen::Vector3d& gravity, double h,
               Integrator integrator, FeatherstoneIntegratorWorkspace& workspace, const DynamicsWorkspace* kinematics) {
  if (!workspace.fits(tree)) workspace.resize(tree);
  integrate(tree, q, v, joint_forces, gravity, h, integrator, workspace, kinematics, tree.all_bodies());
}

namespace {

// v̇(q, v) into workspace.accelerations on `range`, from `kinematics` when given (forward_kinematics of q and v).
void find_accelerations(const ArticulatedTree& tree, const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                        const Eigen::Ref<const Eigen::VectorXd>& joint_forces, const Eigen::Vector3d& gravity,
                        FeatherstoneIntegratorWorkspace& workspace, const DynamicsWorkspace* kinematics, BodyRange range) {
  if (kinematics) {
    forward_dynamics(tree, *kinematics, joint_forces, nullptr, gravity, workspace.dynamics, workspace.accelerations, range);
  } else {
    forward_dynamics(tree, q, v, joint_forces, gravity, workspace.dynamics, workspace.accelerations, range);
  }
}

}  // namespace

void accelerate(const ArticulatedTree& tree, const Eigen::VectorXd& q, Eigen::VectorXd& v,
                const Eigen::Ref<const Eigen::VectorXd>& joint_forces, const Eigen::Vector3d& gravity, double h,
                FeatherstoneIntegratorWorkspace& workspace, const DynamicsWorkspace* kinematics, BodyRange range) {
  if (!workspace.fits(tree)) throw std::invalid_argument("accelerate: the workspace is not sized for this tree");
  find_accelerations(tree, q, v, joint_forces, gravity, workspace, kinematics, range);
  semi_implicit_velocity(tree, v, workspace.accelerations, h, range);
}

void semi_implicit_velocity(const ArticulatedTree& tree, Eigen::VectorXd& v, const Eigen::VectorXd& accelerations, double h,
                            BodyRange range) {
  const auto [first, last] = tree.velocity_span(range);
  for (int i = range.first; i < range.last; ++i) {
    if (tree.body(i).joint != ArticulatedJoint::floating) continue;
    const int offset = tree.velocity_offset(i);
    const Eigen::Vector3d omega = v.segment<3>(offset), linear = v.segment<3>(offset + 3);
    v.segment<3>(offset + 3) += h * omega.cross(linear);  // v̇ + ω × v, with h·v̇ added below
  }
  v.segment(first, last - first) += h * accelerations.segment(first, last - first);
}

void semi_implicit_move(const ArticulatedTree& tree, Eigen::VectorXd& q, Eigen::VectorXd& v, double h, Eigen::VectorXd& displacement,
                        BodyRange range) {
  const auto [first, last] = tree.velocity_span(range);
  displacement.segment(first, last - first) = h * v.segment(first, last - first);
  displace_positions(tree, q, displacement, q, range);
  for (int i = range.first; i < range.last; ++i) {
    if (tree.body(i).joint != ArticulatedJoint::floating) continue;
    const int offset = tree.velocity_offset(i);
    const Eigen::Quaterniond back = rotation_exponential(displacement.segment<3>(offset)).conjugate();
    v.segment<3>(offset) = back * Eigen::Vector3d(v.segment<3>(offset));
    v.segment<3>(offset + 3) = back * Eigen::Vector3d(v.segment<3>(offset + 3));
  }
}

void integrate(const ArticulatedTree& tree, Eigen::VectorXd& q, Eigen::VectorXd& v,
               const Eigen::Ref<const Eigen::VectorXd>& joint_forces, const Eigen::Vector3d& gravity, double h,
               Integrator integrator, FeatherstoneIntegratorWorkspace& workspace, const DynamicsWorkspace* kinematics, BodyRange range) {
  if (!workspace.fits(tree)) throw std::invalid_argument("integrate: the workspace is not sized for this tree");
  FeatherstoneIntegratorWorkspace& w = workspace;
  // The range's coordinates: element by element, the same bits as over the whole vectors.
  const auto [first_velocity, last_velocity] = tree.velocity_span(range);
  const auto [first_position, last_position] = tree.position_span(range);
  const auto velocities = [&, first = first_velocity, count = last_velocity - first_velocity](Eigen::VectorXd& x) { return x.segment(first, count); };
  const auto positions = [&, first = first_position, count = last_position - first_position](Eigen::VectorXd& x) { return x.segment(first, count); };
  switch (integrator) {
    case Integrator::semi_implicit_euler:
      accelerate(tree, q, v, joint_forces, gravity, h, workspace, kinematics, range);
      semi_implicit_move(tree, q, v, h, w.stage_displacement, range);
      return;
    case Integrator::rk4: {
      // Stage s at (q₀ ⊕ Θ_s, v₀ + c_s h a_{s−1}); weights b = (1, 2, 2, 1)/6, nodes c = (0, ½, ½, 1).
      constexpr double kWeights[4] = {1.0 / 6, 2.0 / 6, 2.0 / 6, 1.0 / 6};
      constexpr double kNextNodes[3] = {0.5, 0.5, 1.0};
      positions(w.start_positions) = positions(q), velocities(w.start_velocities) = velocities(v);
      positions(w.stage_positions) = positions(q), velocities(w.stage_velocities) = velocities(v);
      velocities(w.stage_displacement).setZero();
      velocities(w.acceleration_sum).setZero(), velocities(w.displacement_rate_sum).setZero();
      for (int s = 0; s < 4; ++s) {
        find_accelerations(tree, w.stage_positions, w.stage_velocities, joint_forces, gravity, w, s == 0 ? kinematics : nullptr, range);
        displacement_rate(tree, w.stage_displacement, w.stage_velocities, w.stage_rate, range);
        velocities(w.acceleration_sum) += kWeights[s] * velocities(w.accelerations);
        velocities(w.displacement_rate_sum) += kWeights[s] * velocities(w.stage_rate);
        if (s == 3) break;
        velocities(w.stage_displacement) = (kNextNodes[s] * h) * velocities(w.stage_rate);
        velocities(w.stage_velocities) = velocities(w.start_velocities) + (kNextNodes[s] * h) * velocities(w.accelerations);
        displace_positions(tree, w.start_positions, w.stage_displacement, w.stage_positions, range);
      }
      velocities(v) = velocities(w.start_velocities) + h * velocities(w.acceleration_sum);
      velocities(w.stage_displacement) = h * velocities(w.displacement_rate_sum);
      displace_positions(tree, w.start_positions, w.stage_displacement, q, range);
      return;
    }
    case Integrator::euler:
    case Integrator::rk2:
    case Integrator::backward_euler: break;
  }
  require_integrator(integrator, {Integrator::semi_implicit_euler, Integrator::rk4}, "featherstone");  // throws
}

double kinetic_energy(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                      const Eigen::Ref<const Eigen::VectorXd>& v, DynamicsWorkspace& workspace) {
  forward_kinematics(tree, q, v, workspace);
  double energy = armature_energy(tree, v);
  for (int i = 0; i < tree.body_count(); ++i) {
    const SpatialVector& velocity = workspace.velocity[static_cast<std::size_t>(i)];
    energy += 0.5 * velocity.dot(tree.body(i).inertia * velocity);
  }
  return energy;
}

double armature_energy(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& v) {
  double energy = 0;
  for (int i = 0; i < tree.body_count(); ++i) {
    const double armature = tree.body(i).armature;  // 0 unless a revolute or prismatic joint
    if (armature != 0) energy += 0.5 * armature * v[tree.velocity_offset(i)] * v[tree.velocity_offset(i)];
  }
  return energy;
}

double potential_energy(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q, const Eigen::Vector3d& gravity,
                        DynamicsWorkspace& workspace) {
  body_poses(tree, q, workspace);
  double energy = 0;
  for (int i = 0; i < tree.body_count(); ++i) {
    const PluckerTransform& body_from_world = workspace.world_to_body[static_cast<std::size_t>(i)];
    const SpatialInertia& inertia = tree.body(i).inertia;
    const Eigen::Vector3d centre = body_from_world.translation + body_from_world.rotation.transpose() * inertia.centre_of_mass();
    energy -= inertia.mass * gravity.dot(centre);
  }
  return energy;
}

SpatialVector spatial_momentum(const ArticulatedTree& tree, const Eigen::Ref<const Eigen::VectorXd>& q,
                               const Eigen::Ref<const Eigen::VectorXd>& v, DynamicsWorkspace& workspace) {
  forward_kinematics(tree, q, v, workspace);
  SpatialVector momentum = SpatialVector::Zero();
  for (int i = 0; i < tree.body_count(); ++i) {
    const auto index = static_cast<std::size_t>(i);
    momentum += workspace.world_to_body[index].transpose_apply_force(tree.body(i).inertia * workspace.velocity[index]);
  }
  return momentum;
}

}  // namespace limber
