// What each method supports, as one table in code: each method's compile refuses what its row
// does not have (require_supported, model.hpp), the World refuses the calls it lacks, the
// README's status table says the same, and tests/world/capabilities_test.cpp checks all three.
#pragma once

#include <array>
#include <cstddef>

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/options.hpp"

namespace limber {

struct MethodCapabilities {
  Method method;
  /// Joint types it compiles, indexed by JointType (spherical, revolute, prismatic, universal,
  /// fixed, serial). Particles and Lagrange run a serial joint's axes as revolute (and, for
  /// Lagrange, prismatic) joints through virtual links (serial_links.hpp); Featherstone exactly.
  std::array<bool, 6> joints;
  bool single_precision;  ///< a float state (WorldOptions::single_precision)
  bool threads;           ///< steps on more than one thread (VerletOptions::threads, FeatherstoneOptions::threads)
  bool gears;             ///< Model::gears (velocity constraints between joints)
  bool holds;             ///< points held to the world and moved while stepping (World::pin, move_pin)
  bool spheres;           ///< bodies shaped as spheres (capsules of length 0: MuJoCo's sphere geoms)
  /// Actuators on the axes of a serial joint of two or more axes (MuJoCo's bodies of several
  /// hinges, such as a hip). The particles' virtual links move such a body wrongly under a joint
  /// force (MuJoCo's humanoid.xml: −41 to +230 times MuJoCo's response on some axes, or
  /// diverging), so they refuse a servo there at compile and a motor's non-zero control
  /// (require_actuator_supported).
  bool serial_actuators;
  /// Box and ellipsoid limbs collide as themselves (the shape-pair table,
  /// kernel/geometry/shape_pairs.hpp); without, as their capsule proxies (the particles' limbs
  /// are segments: kernel/scene/capsule_proxy.hpp).
  bool true_shapes;
};

/// One row a method, in Method's order.
inline constexpr std::array<MethodCapabilities, 4> kMethodCapabilities{{
    //                     spherical revolute prismatic universal fixed serial   float  threads gears  holds  spheres serial_actuators true_shapes
    {Method::particles,    {true, true, false, true, true, true},               true,  true,   false, true,  true,   false,           false},
    {Method::springs,      {true, true, false, false, false, false},            false, false,  false, true,  false,  false,           true},
    {Method::lagrange,     {true, true, true, true, true, true},                false, false,  true,  true,  true,   true,            true},
    {Method::featherstone, {true, true, true, false, true, true},               false, true,   false, false, true,   true,            true},
}};
static_assert(kMethodCapabilities[static_cast<std::size_t>(Method::particles)].method == Method::particles &&
                  kMethodCapabilities[static_cast<std::size_t>(Method::springs)].method == Method::springs &&
                  kMethodCapabilities[static_cast<std::size_t>(Method::lagrange)].method == Method::lagrange &&
                  kMethodCapabilities[static_cast<std::size_t>(Method::featherstone)].method == Method::featherstone,
              "kMethodCapabilities is in Method's order");

constexpr const MethodCapabilities& capabilities(Method method) { return kMethodCapabilities[static_cast<std::size_t>(method)]; }

constexpr bool supports(Method method, JointType type) { return capabilities(method).joints[static_cast<std::size_t>(type)]; }

/// Throws ModelError naming the first joint whose type `method`'s row lacks, the first gear
/// when it has no gears, or the first sphere when it has none: "joints[3] 'knee': the springs method does not support prismatic
/// joints (it supports spherical, revolute; lagrange does)". Each method's
/// compile calls it first.
void require_supported(const Model& model, Method method);

/// Throws ModelError when `method` lacks serial_actuators and actuator `index` of `model` acts on
/// an axis of a serial joint of two or more axes with `control` (a servo acts at any control, a
/// motor at a non-zero one): "actuators[0] 'abdomen_y': the particles method does not drive an
/// axis of serial joint 'abdomen_z+abdomen_y' (2 axes in one body: …); lagrange, featherstone do".
/// require_supported calls it with control 0; World::set_controls with each new control.
void require_actuator_supported(const Model& model, Method method, std::size_t index, double control);

}  // namespace limber
