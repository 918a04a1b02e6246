// Bullet's rigid bodies and point-to-point constraints on the heavy-end chain: see peer_chain.hpp.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <vector>

#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btDefaultCollisionConfiguration.h>
#include <BulletCollision/CollisionShapes/btCapsuleShape.h>
#include <BulletDynamics/ConstraintSolver/btPoint2PointConstraint.h>
#include <BulletDynamics/ConstraintSolver/btSequentialImpulseConstraintSolver.h>
#include <BulletDynamics/Dynamics/btDiscreteDynamicsWorld.h>
#include <BulletDynamics/Dynamics/btRigidBody.h>

#include "bench/peers/peer_chain.hpp"

namespace limber::peers {
namespace {

constexpr double link_length = 0.1;     // m
constexpr double link_radius = 0.01;    // m
constexpr double link_mass = 1.0;       // kg
constexpr double last_link_mass = 2.0;  // kg, the heavy end
constexpr double gravity = 9.81;        // m/s², along −z
// btTransformUtil::integrateTransform (LinearMath/btTransformUtil.h, ANGULAR_MOTION_THRESHOLD):
// the largest angle a body's orientation turns in one step, rad.
constexpr double largest_turn_per_step = std::numbers::pi / 4;

// Principal moments about the link's centre, link frame (x along the link), kg m²: a solid
// cylinder, as every peer uses (peer_chain.hpp).
btVector3 cylinder_inertia(double mass) {
  const double axial = mass * link_radius * link_radius / 2;
  const double transverse = mass * (3 * link_radius * link_radius + link_length * link_length) / 12;
  return btVector3(btScalar(axial), btScalar(transverse), btScalar(transverse));
}

// From a link's centre to its outboard end, link frame; its inboard end is at minus this.
btVector3 half_link() { return btVector3(btScalar(link_length / 2), 0, 0); }

using WorldPoint = std::array<double, 3>;  // m

// In double, so that measuring a joint gap adds no rounding of its own to Bullet's.
WorldPoint to_world(const btTransform& frame, const btVector3& local) {
  WorldPoint point;
  for (int row = 0; row < 3; ++row) {
    point[row] = frame.getOrigin()[row];
    for (int column = 0; column < 3; ++column) point[row] += double(frame.getBasis()[row][column]) * local[column];
  }
  return point;
}

double distance(const WorldPoint& a, const WorldPoint& b) {
  return std::hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
}

// The chain in its own Bullet world: links 0..N−1 along +x, link 0's inboard end held at the
// origin by a one-body point-to-point constraint (its other side is Bullet's fixed body), link i's
// inboard end joined to link i − 1's outboard end. The world keeps raw pointers to every other
// member, so it is declared after them and destroyed first, once the destructor has taken the
// constraints and bodies out of it.
class RigidChain {
 public:
  RigidChain(int links, int solver_iterations);
  RigidChain(const RigidChain&) = delete;
  RigidChain& operator=(const RigidChain&) = delete;
  ~RigidChain();

  // maxSubSteps = 0: exactly one step of time_step, no fixed-step accumulator or interpolation.
  void step(double time_step) { world_.stepSimulation(btScalar(time_step), 0); }

  double largest_joint_gap() const;
  double kinetic_plus_potential() const;
  bool state_is_finite() const;
  double fastest_turn() const;  // largest |ω| over the links, rad/s

 private:
  btDefaultCollisionConfiguration collision_configuration_;
  btCollisionDispatcher dispatcher_{&collision_configuration_};
  btDbvtBroadphase broadphase_;
  btSequentialImpulseConstraintSolver solver_;
  // Only the broadphase's bounding boxes use it: the bodies are added with an empty collision
  // mask, so no pair is ever made. Its cylinder part spans the link between the joint pivots.
  btCapsuleShapeX shape_{btScalar(link_radius), btScalar(link_length)};
  std::vector<std::unique_ptr<btRigidBody>> bodies_;
  std::vector<std::unique_ptr<btPoint2PointConstraint>> joints_;
  btDiscreteDynamicsWorld world_{&dispatcher_, &broadphase_, &solver_, &collision_configuration_};
};

RigidChain::RigidChain(int links, int solver_iterations) {
  world_.setGravity(btVector3(0, 0, btScalar(-gravity)));
  world_.getSolverInfo().m_numIterations = solver_iterations;
  for (int link = 0; link < links; ++link) {
    const double mass = link + 1 == links ? last_link_mass : link_mass;
    btRigidBody::btRigidBodyConstructionInfo info(btScalar(mass), /*motionState=*/nullptr, &shape_, cylinder_inertia(mass));
    info.m_startWorldTransform.setIdentity();
    info.m_startWorldTransform.setOrigin(btVector3(btScalar((link + 0.5) * link_length), 0, 0));
    info.m_linearDamping = 0;
    info.m_angularDamping = 0;
    bodies_.push_back(std::make_unique<btRigidBody>(info));
    btRigidBody& body = *bodies_.back();
    body.setActivationState(DISABLE_DEACTIVATION);
    world_.addRigidBody(&body, /*group=*/1, /*mask=*/0);
    if (link == 0) {
      joints_.push_back(std::make_unique<btPoint2PointConstraint>(body, -half_link()));
    } else {
      joints_.push_back(std::make_unique<btPoint2PointConstraint>(*bodies_[link - 1], body, half_link(), -half_link()));
    }
    world_.addConstraint(joints_.back().get(), /*disableCollisionsBetweenLinkedBodies=*/true);
  }
}

RigidChain::~RigidChain() {
  for (auto& joint : joints_) world_.removeConstraint(joint.get());
  for (auto& body : bodies_) world_.removeRigidBody(body.get());
}

double RigidChain::largest_joint_gap() const {
  double largest = 0;
  for (const auto& joint : joints_) {
    const WorldPoint on_a = to_world(joint->getRigidBodyA().getCenterOfMassTransform(), joint->getPivotInA());
    const WorldPoint on_b = to_world(joint->getRigidBodyB().getCenterOfMassTransform(), joint->getPivotInB());
    largest = std::max(largest, distance(on_a, on_b));
  }
  return largest;
}

double RigidChain::kinetic_plus_potential() const {
  double kinetic = 0, potential = 0;  // J
  for (const auto& body : bodies_) {
    const double mass = 1 / double(body->getInvMass());
    const btVector3& angular = body->getAngularVelocity();
    const btMatrix3x3& rotation = body->getCenterOfMassTransform().getBasis();
    // ½ ω·(R I Rᵀ ω) = ½ Σ I_k (Rᵀω)_k²
    const btVector3 local_angular = rotation.transpose() * angular;
    const btVector3 inertia = body->getLocalInertia();
    kinetic += 0.5 * (mass * double(body->getLinearVelocity().length2()) + double(inertia.x() * local_angular.x() * local_angular.x()) +
                      double(inertia.y() * local_angular.y() * local_angular.y()) +
                      double(inertia.z() * local_angular.z() * local_angular.z()));
    potential += mass * gravity * double(body->getCenterOfMassPosition().z());
  }
  return kinetic + potential;
}

bool RigidChain::state_is_finite() const {
  for (const auto& body : bodies_) {
    const btVector3& centre = body->getCenterOfMassPosition();
    const btVector3& linear = body->getLinearVelocity();
    const btVector3& angular = body->getAngularVelocity();
    for (int axis = 0; axis < 3; ++axis)
      if (!std::isfinite(centre[axis]) || !std::isfinite(linear[axis]) || !std::isfinite(angular[axis])) return false;
  }
  return true;
}

double RigidChain::fastest_turn() const {
  double fastest = 0;
  for (const auto& body : bodies_) fastest = std::max(fastest, double(body->getAngularVelocity().length()));
  return fastest;
}

}  // namespace

PeerChainResult run_bullet_rigid_chain(int links, double time_step, int steps, int solver_iterations) {
  // Bullet silently skips steps it rounds to zero (up to SIMD_EPSILON), so those are refused too.
  if (links < 1 || steps < 0 || solver_iterations < 1 || !(time_step > SIMD_EPSILON) || !std::isfinite(time_step))
    throw std::invalid_argument(
        "run_bullet_rigid_chain: needs links >= 1, steps >= 0, solver_iterations >= 1, finite time_step > SIMD_EPSILON");
  RigidChain chain(links, solver_iterations);
  PeerChainResult result;
  result.initial_kinetic_plus_potential = chain.kinetic_plus_potential();

  std::chrono::steady_clock::duration stepping{};
  while (result.steps_taken < steps && result.finite) {
    const auto start = std::chrono::steady_clock::now();
    chain.step(time_step);
    stepping += std::chrono::steady_clock::now() - start;
    ++result.steps_taken;
    result.finite = chain.state_is_finite();
    result.max_joint_gap = std::max(result.max_joint_gap, chain.largest_joint_gap());
    // The step just taken turned each orientation by ω·Δt with the ω read here (the solver's), capped.
    if (chain.fastest_turn() * time_step > largest_turn_per_step) ++result.steps_with_clamped_rotation;
  }

  result.final_kinetic_plus_potential = chain.kinetic_plus_potential();
  if (result.steps_taken > 0) result.seconds_per_step = std::chrono::duration<double>(stepping).count() / result.steps_taken;
  return result;
}

}  // namespace limber::peers
