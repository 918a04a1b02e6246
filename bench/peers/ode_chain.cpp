// ODE's rigid bodies and ball joints on the heavy-end chain: see peer_chain.hpp.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include <ode/ode.h>

#include "bench/peers/peer_chain.hpp"

namespace limber::peers {
namespace {

using namespace heavy_end_chain;

// dInitODE2 once per process, before the first world; ODE is never closed (its data is static).
void initialize_ode_once() {
  static const bool initialized = dInitODE2(0) != 0;
  if (!initialized) throw std::runtime_error("run_ode_chain: dInitODE2 failed");
}

// The chain in its own ODE world (no collision space: nothing collides): links 0..N−1 along +x,
// ball joint 0 from link 0's inboard end to the static environment (body 0) at the origin, ball
// joint i from link i − 1's outboard end to link i's inboard end.
class OdeChain {
 public:
  OdeChain(int links, OdeStepper stepper, int quick_step_iterations);
  OdeChain(const OdeChain&) = delete;
  OdeChain& operator=(const OdeChain&) = delete;
  ~OdeChain() { dWorldDestroy(world_); }  // destroys its bodies and joints too

  void step(double time_step) {
    if (stepper_ == OdeStepper::world_step) dWorldStep(world_, dReal(time_step));
    else dWorldQuickStep(world_, dReal(time_step));
  }

  double largest_joint_gap() const;
  double kinetic_plus_potential() const;
  bool state_is_finite() const;

 private:
  dWorldID world_;
  OdeStepper stepper_;
  std::vector<dBodyID> bodies_;
  std::vector<dJointID> joints_;
};

OdeChain::OdeChain(int links, OdeStepper stepper, int quick_step_iterations) : world_(dWorldCreate()), stepper_(stepper) {
  dWorldSetGravity(world_, 0, 0, dReal(-gravity));
  dWorldSetQuickStepNumIterations(world_, quick_step_iterations);
  dWorldSetAutoDisableFlag(world_, 0);
  for (int link = 0; link < links; ++link) {
    const dBodyID body = dBodyCreate(world_);
    dMass mass;
    // direction 1: the cylinder's axis along the body's x, the link's direction.
    dMassSetCylinderTotal(&mass, dReal(link + 1 == links ? last_link_mass : link_mass), 1, dReal(link_radius), dReal(link_length));
    dBodySetMass(body, &mass);
    dBodySetPosition(body, dReal((link + 0.5) * link_length), 0, 0);
    dBodySetLinearDamping(body, 0);
    dBodySetAngularDamping(body, 0);
    const dJointID joint = dJointCreateBall(world_, nullptr);
    dJointAttach(joint, body, link == 0 ? nullptr : bodies_.back());  // body 1: this link; body 2: its parent or the world
    dJointSetBallAnchor(joint, dReal(link * link_length), 0, 0);
    bodies_.push_back(body);
    joints_.push_back(joint);
  }
}

double OdeChain::largest_joint_gap() const {
  double largest = 0;
  for (const dJointID joint : joints_) {
    // Anchor 1: where this link's frame puts the pivot; anchor 2: where its parent's (or the world) does.
    dVector3 on_link, on_parent;
    dJointGetBallAnchor(joint, on_link);
    dJointGetBallAnchor2(joint, on_parent);
    largest = std::max(largest, std::hypot(double(on_link[0] - on_parent[0]), double(on_link[1] - on_parent[1]),
                                           double(on_link[2] - on_parent[2])));
  }
  return largest;
}

double OdeChain::kinetic_plus_potential() const {
  double kinetic = 0, potential = 0;  // J
  for (const dBodyID body : bodies_) {
    dMass mass;
    dBodyGetMass(body, &mass);
    const dReal* linear = dBodyGetLinearVel(body);
    const dReal* angular = dBodyGetAngularVel(body);  // world frame
    const dReal* rotation = dBodyGetRotation(body);   // body to world, 3×4 row major
    // ω in the body frame (Rᵀω), where mass.I (3×4 row major, about the centre) applies.
    double local[3];
    for (int k = 0; k < 3; ++k) local[k] = double(rotation[k] * angular[0] + rotation[4 + k] * angular[1] + rotation[8 + k] * angular[2]);
    double rotational = 0;
    for (int row = 0; row < 3; ++row)
      for (int column = 0; column < 3; ++column) rotational += local[row] * double(mass.I[4 * row + column]) * local[column];
    kinetic += 0.5 * (double(mass.mass) * double(linear[0] * linear[0] + linear[1] * linear[1] + linear[2] * linear[2]) + rotational);
    potential += double(mass.mass) * gravity * double(dBodyGetPosition(body)[2]);
  }
  return kinetic + potential;
}

bool OdeChain::state_is_finite() const {
  for (const dBodyID body : bodies_) {
    const dReal* position = dBodyGetPosition(body);
    const dReal* linear = dBodyGetLinearVel(body);
    const dReal* angular = dBodyGetAngularVel(body);
    for (int axis = 0; axis < 3; ++axis)
      if (!std::isfinite(position[axis]) || !std::isfinite(linear[axis]) || !std::isfinite(angular[axis])) return false;
  }
  return true;
}

}  // namespace

PeerChainResult run_ode_chain(int links, double time_step, int steps, OdeStepper stepper, int quick_step_iterations) {
  if (links < 1 || steps < 0 || quick_step_iterations < 1 || !(time_step > 0) || !std::isfinite(time_step))
    throw std::invalid_argument("run_ode_chain: needs links >= 1, steps >= 0, quick_step_iterations >= 1, finite time_step > 0");
  initialize_ode_once();
  // QuickStep shuffles its constraint order with ODE's global random generator: reseed it so every
  // run (and every repetition of one) sees the same order and gives the same numbers.
  dRandSetSeed(0);
  OdeChain chain(links, stepper, quick_step_iterations);
  return measure_chain(chain, time_step, steps, [](PeerChainResult&) {});
}

bool ode_uses_double_precision() { return std::is_same_v<dReal, double>; }

}  // namespace limber::peers
