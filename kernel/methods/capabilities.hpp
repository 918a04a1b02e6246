// What each method supports, as one table in code: the README's status table says the same,
// and tests/world/capabilities_test.cpp checks both against what compile_method accepts. A
// method's own compile still refuses what it cannot do with a ModelError naming the part; the
// table states those refusals in one place.
#pragma once

#include <array>
#include <cstddef>

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/options.hpp"

namespace limber {

struct MethodCapabilities {
  Method method;
  /// Joint types it compiles, indexed by JointType (spherical, revolute, prismatic, universal,
  /// fixed).
  std::array<bool, 5> joints;
  bool single_precision;  ///< a float state (WorldOptions::single_precision)
  bool threads;           ///< steps on more than one thread (VerletOptions::threads)
};

/// One row a method, in Method's order.
inline constexpr std::array<MethodCapabilities, 4> kMethodCapabilities{{
    //                        spherical revolute prismatic universal fixed
    {Method::particles,    {true, true, false, true, true}, true, true},
    {Method::springs,      {true, true, false, false, false}, false, false},
    {Method::lagrange,     {true, true, true, true, true}, false, false},
    {Method::featherstone, {true, true, true, false, true}, false, false},
}};
static_assert(kMethodCapabilities[static_cast<std::size_t>(Method::particles)].method == Method::particles &&
                  kMethodCapabilities[static_cast<std::size_t>(Method::springs)].method == Method::springs &&
                  kMethodCapabilities[static_cast<std::size_t>(Method::lagrange)].method == Method::lagrange &&
                  kMethodCapabilities[static_cast<std::size_t>(Method::featherstone)].method == Method::featherstone,
              "kMethodCapabilities is in Method's order");

constexpr const MethodCapabilities& capabilities(Method method) { return kMethodCapabilities[static_cast<std::size_t>(method)]; }

constexpr bool supports(Method method, JointType type) { return capabilities(method).joints[static_cast<std::size_t>(type)]; }

}  // namespace limber
