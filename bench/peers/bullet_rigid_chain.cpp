// Bullet's rigid bodies and point-to-point constraints on the heavy-end chain: see peer_chain.hpp.
#include <algorithm>
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
#include "bench/peers/bullet_geometry.hpp"

namespace limber::peers {
namespace {

using namespace heavy_end_chain;
// btTransformUtil::integrateTransform (LinearMath/btTransformUtil.h, ANGULAR_MOTION_THRESHOLD):
// the largest angle a body's orientation turns in one step, rad.
constexpr double largest_turn_per_step = std::numbers::pi / 4;

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
  return measure_chain(chain, time_step, steps, [&](PeerChainResult& result) {
    // The step just taken turned each orientation by ω·Δt with the ω read here (the solver's), capped.
    if (chain.fastest_turn() * time_step > largest_turn_per_step) ++result.steps_with_clamped_rotation;
  });
}

}  // namespace limber::peers
