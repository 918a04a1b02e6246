// A servo (a position or velocity actuator, model.hpp's Actuator) as the pull of a drive on its
// coordinate, for the methods that take servos implicitly (Featherstone, Lagrange: their
// apply_actuator): force − stiffness·q − damping·q̇, found at the state the step ends with.
#pragma once

#include "limber/kernel/model/model.hpp"

namespace limber {

struct ServoPull {
  double force = 0;      ///< at q = 0, q̇ = 0, its control clamped: gear·kp·(u − gear·ref) or gear·kv·u, N·m or N
  double stiffness = 0;  ///< gear²·kp (a position actuator), N·m/rad or N/m
  double damping = 0;    ///< gear²·kv (a velocity actuator), N·m·s/rad or N·s/m
};

/// `actuator`'s pull at `control`; a motor's is its force alone.
inline ServoPull servo_pull(const Actuator& actuator, double control) {
  const double squared = actuator.gear * actuator.gear * actuator.gain;
  return {actuator_force(actuator, control), actuator.kind == ActuatorKind::position ? squared : 0.0,
          actuator.kind == ActuatorKind::velocity ? squared : 0.0};
}

}  // namespace limber
