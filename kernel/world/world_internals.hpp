// What a World keeps behind its public face (world.hpp): the method's compiled state, the bounds
// its divergence check measures against, the last step's report, the handle tables, the pins and
// the drives set since the Model. For limber's own tools (the command line, the viewer, the
// studies, tests) that read a state's observers and counters; it includes the whole kernel,
// which world.hpp does not.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <optional>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "limber/kernel/methods/method.hpp"
#include "limber/kernel/metrics/divergence.hpp"
#include "limber/kernel/world/handle_table.hpp"
#include "limber/kernel/world/world.hpp"

namespace limber {

struct WorldInternals {
  MethodState state;
  DivergenceBounds divergence;  ///< from the start, the last structural edit or teleport
  StepReport report;            ///< the last step's: the method's, with the World's status

  /// Handles ↔ positions in the Model's arrays (and in `pins`).
  HandleTable<BodyId> bodies;
  HandleTable<JointId> joints;
  HandleTable<ColliderId> colliders;
  HandleTable<BallId> balls;
  HandleTable<PinId> pin_handles;

  /// A held point (World::pin): its joint to the world, move_pin's target for the next step, and
  /// where the last target put the held point (world, m), which a recompile gives the joint.
  struct Pin {
    JointId joint;
    std::optional<Eigen::Vector3d> target;
    std::optional<Eigen::Vector3d> anchor;
  };
  std::vector<Pin> pins;  ///< by pin_handles' position
  std::uint32_t pins_made = 0;  ///< names each pin's joint ("pin 7") uniquely

  /// Drives set since the Model (set_joint_drive) or released on impact, by joint handle slot.
  std::unordered_map<std::uint32_t, std::optional<JointDrive>> drives;

  /// The actuators' controls (Model::actuators order), as set_controls left them: 0 at first.
  std::vector<double> controls;

  /// World::observe()'s penetration measure: a LimbCollisions of the Model of its own (so that
  /// observing never changes the method's kept pairs or counters) and its segments, built at the
  /// first observe() after a compile.
  struct PenetrationGauge {
    LimbCollisions collisions;
    std::vector<LimbSegment> segments;
  };
  std::optional<PenetrationGauge> penetration_gauge;
};


// Shared by the World's source files (world.cpp, world_joints.cpp).

// old_body_of_new for an edit that keeps the first `kept` of `count` bodies where they were and
// adds the rest (−1: new).
inline std::vector<std::int64_t> first_bodies_kept(std::size_t count, std::size_t kept) {
  std::vector<std::int64_t> old_body_of_new(count, -1);
  for (std::size_t b = 0; b < kept; ++b) old_body_of_new[b] = static_cast<std::int64_t>(b);
  return old_body_of_new;
}

// The position of `id`'s thing, or a WorldError naming the handle ("body handle 3: no such body
// (removed?)"); `call` prefixes it when given.
template <typename Id>
std::size_t position_of(const HandleTable<Id>& table, Id id, std::string_view kind, std::string_view call = {}) {
  if (const std::optional<std::size_t> position = table.find(id)) return *position;
  throw WorldError((call.empty() ? std::string() : std::string(call) + ": ") + std::string(kind) + " handle " + std::to_string(id.slot) +
                   ": no such " + std::string(kind) + " (removed?)");
}

}  // namespace limber
