// Time integrators: one enum for every method. Each method implements some of them and refuses
// the rest when it compiles (require_integrator), so no step ever meets an integrator it lacks.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <string_view>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

enum class Integrator : std::uint8_t {
  euler,                ///< explicit forward Euler, Y' = Y + h·Ẏ(Y) (the thesis's; order 1)
  semi_implicit_euler,  ///< symplectic Euler: velocities first, then positions with the new ones (order 1)
  rk2,                  ///< explicit midpoint Runge-Kutta (order 2)
  rk4,                  ///< explicit classical Runge-Kutta (order 4)
  backward_euler,       ///< implicit: one linearized backward-Euler solve (Baraff & Witkin 1998; springs only)
};

inline const char* integrator_name(Integrator integrator) {
  switch (integrator) {
    case Integrator::euler: return "forward Euler";
    case Integrator::semi_implicit_euler: return "semi-implicit Euler";
    case Integrator::rk2: return "RK2 (midpoint)";
    case Integrator::rk4: return "RK4";
    case Integrator::backward_euler: return "linearized backward Euler";
  }
  return "?";
}

/// Throws std::invalid_argument "<method>: integrator <name> is not one it implements (<list>)"
/// unless `integrator` is in `implemented`.
inline void require_integrator(Integrator integrator, std::initializer_list<Integrator> implemented, std::string_view method) {
  std::string list;
  for (const Integrator candidate : implemented) {
    if (candidate == integrator) return;
    list += (list.empty() ? "" : ", ") + std::string(integrator_name(candidate));
  }
  throw std::invalid_argument(std::string(method) + ": integrator " + integrator_name(integrator) + " is not one it implements (" + list + ")");
}

}  // namespace limber
