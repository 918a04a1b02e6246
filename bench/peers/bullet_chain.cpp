// Bullet's btMultiBody on the heavy-end chain: see peer_chain.hpp.
#include "bench/peers/peer_chain.hpp"
#include "bench/peers/bullet_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <BulletCollision/BroadphaseCollision/btDbvtBroadphase.h>
#include <BulletCollision/CollisionDispatch/btCollisionDispatcher.h>
#include <BulletCollision/CollisionDispatch/btDefaultCollisionConfiguration.h>
#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyConstraintSolver.h>
#include <BulletDynamics/Featherstone/btMultiBodyDynamicsWorld.h>

namespace limber::peers {
namespace {

using namespace heavy_end_chain;
constexpr double raised_velocity_clamp = 1e4;  // rad/s; an accurate solution peaks near 200 rad/s

// The chain in its own Bullet world: a fixed base at the origin (the world pin) and links 0..N−1,
// link i hanging from link i − 1 (link 0 from the base) by a spherical joint. The world keeps raw
// pointers to all the other members, so it is declared after them and destroyed first.
class MultiBodyChain {
 public:
  MultiBodyChain(int links, bool raise_velocity_clamp);
  MultiBodyChain(const MultiBodyChain&) = delete;
  MultiBodyChain& operator=(const MultiBodyChain&) = delete;

  // maxSubSteps = 0 makes stepSimulation take exactly one step of time_step, with no fixed-step
  // accumulator or interpolation.
  void step(double time_step) { world_.stepSimulation(btScalar(time_step), 0); }

  // Bullet refreshes the links' world transforms at the start of a step, from the positions
  // before it; this brings them up to the positions after it. The next step recomputes them from
  // the same positions, so the simulation is unchanged.
  void update_link_transforms() { body_.forwardKinematics(world_to_link_scratch_, link_origin_scratch_); }

  double largest_joint_gap() const;
  double kinetic_plus_potential() const;
  bool state_is_finite() const;

 private:
  btDefaultCollisionConfiguration collision_configuration_;
  btCollisionDispatcher dispatcher_{&collision_configuration_};
  btDbvtBroadphase broadphase_;
  btMultiBodyConstraintSolver solver_;
  btMultiBody body_;
  btMultiBodyDynamicsWorld world_{&dispatcher_, &broadphase_, &solver_, &collision_configuration_};
  btAlignedObjectArray<btQuaternion> world_to_link_scratch_;
  btAlignedObjectArray<btVector3> link_origin_scratch_;
};

MultiBodyChain::MultiBodyChain(int links, bool raise_velocity_clamp)
    : body_(links, /*mass=*/0, /*inertia=*/btVector3(0, 0, 0), /*fixedBase=*/true, /*canSleep=*/false) {
  // With identity joint rotations every link frame is the world frame, so the chain lies along +x.
  for (int link = 0; link < links; ++link) {
    const double mass = link + 1 == links ? last_link_mass : link_mass;
    const btVector3 parent_centre_to_pivot = link == 0 ? btVector3(0, 0, 0) : half_link();
    body_.setupSpherical(link, btScalar(mass), cylinder_inertia(mass), link - 1, btQuaternion::getIdentity(),
                         parent_centre_to_pivot, /*thisPivotToThisComOffset=*/half_link());
  }
  body_.finalizeMultiDof();
  // Bullet's defaults damp the links (0.04) and clamp each joint-velocity coordinate (100 rad/s).
  body_.setLinearDamping(0);
  body_.setAngularDamping(0);
  if (raise_velocity_clamp) body_.setMaxCoordinateVelocity(btScalar(raised_velocity_clamp));

  world_.setGravity(btVector3(0, 0, btScalar(-gravity)));
  world_.addMultiBody(&body_);
  update_link_transforms();
}

double MultiBodyChain::largest_joint_gap() const {
  double largest = 0;
  WorldPoint parent_pivot = {0, 0, 0};  // the world pin
  for (int link = 0; link < body_.getNumLinks(); ++link) {
    const btTransform& frame = body_.getLink(link).m_cachedWorldTransform;
    largest = std::max(largest, distance(parent_pivot, to_world(frame, -half_link())));
    parent_pivot = to_world(frame, half_link());
  }
  return largest;
}

double MultiBodyChain::kinetic_plus_potential() const {
  // btMultiBody::getKineticEnergy leaves out ball-joint rates (its compTreeLinkVelocities handles
  // only revolute and prismatic joints), so the link velocities are propagated here as Bullet's
  // articulated-body pass does: in each link's frame, about its centre, from its parent (the
  // previous link, or the fixed base at rest).
  btVector3 parent_angular(0, 0, 0), parent_linear(0, 0, 0);  // rad/s, m/s
  double kinetic = 0, potential = 0;                           // J
  for (int link = 0; link < body_.getNumLinks(); ++link) {
    const btMatrix3x3 parent_to_link(body_.getParentToLocalRot(link));
    const btVector3 carried_angular = parent_to_link * parent_angular;
    const btScalar* rate = body_.getJointVelMultiDof(link);  // relative angular velocity, link frame
    const btVector3 joint_rate(rate[0], rate[1], rate[2]);
    const btVector3 angular = carried_angular + joint_rate;
    // getRVector: from the parent's centre to this link's centre; the joint turns about the pivot.
    const btVector3 linear = parent_to_link * parent_linear - body_.getRVector(link).cross(carried_angular) +
                             joint_rate.cross(half_link());
    const double mass = body_.getLinkMass(link);
    kinetic += 0.5 * (mass * double(linear.length2()) + double((body_.getLinkInertia(link) * angular).dot(angular)));
    potential += mass * gravity * double(body_.getLink(link).m_cachedWorldTransform.getOrigin().z());
    parent_angular = angular;
    parent_linear = linear;
  }
  return kinetic + potential;
}

bool MultiBodyChain::state_is_finite() const {
  for (int link = 0; link < body_.getNumLinks(); ++link) {
    const btVector3& centre = body_.getLink(link).m_cachedWorldTransform.getOrigin();
    const btScalar* rate = body_.getJointVelMultiDof(link);
    for (int axis = 0; axis < 3; ++axis)
      if (!std::isfinite(centre[axis]) || !std::isfinite(rate[axis])) return false;
  }
  return true;
}

}  // namespace

PeerChainResult run_bullet_multibody_chain(int links, double time_step, int steps, bool raise_velocity_clamp) {
  // Bullet silently skips steps it rounds to zero (up to SIMD_EPSILON), so those are refused too.
  if (links < 1 || steps < 0 || !(time_step > SIMD_EPSILON))
    throw std::invalid_argument("run_bullet_multibody_chain: needs links >= 1, steps >= 0, time_step > SIMD_EPSILON");
  MultiBodyChain chain(links, raise_velocity_clamp);
  return measure_chain(chain, time_step, steps, [&](PeerChainResult&) { chain.update_link_transforms(); });
}

bool bullet_uses_double_precision() { return sizeof(btScalar) == sizeof(double); }

}  // namespace limber::peers
