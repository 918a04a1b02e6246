// The particle method's compile, its first half: where each particle sits and what it carries,
// planned from the Model before any state exists (thesis 4.1: particles at the limbs' ends,
// shared or joined by zero-length constraints). Named passes, in the order compile runs them:
// plan_limb_masses, plan_slots, place_slots, plan_islands, number_particles. The second half,
// which fills VerletState from the plan, is compile.cpp. Internal to kernel/verlet.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "limber/kernel/model/model.hpp"
#include "limber/kernel/model/options.hpp"
#include "limber/kernel/verlet/frames.hpp"
#include "limber/layouts/graph/compressed_rows.hpp"

namespace limber::particle_plan {

/// A limb's own mass at each of its particles, kg.
struct LimbParticleMasses {
  double tail = 0, centre = 0, head = 0;
};

/// `value` as a 32-bit index; throws ModelError past what 32 bits hold.
std::uint32_t checked_index(std::size_t value);

/// What the passes plan. Slots: every place a particle may sit. Body b has its head at slot s·b,
/// its tail at s·b + 1 and, with centre particles (s = 3; else s = 2), its centre at s·b + 2;
/// framed limbs' F⁺ and F⁻ follow at s·b + (2 or 3) and the next; each joint to the world has a
/// pin slot after all bodies. Shared-particle joints merge slots into one particle.
struct Plan {
  bool shared = false, centres = false;  // ParticleJoints::shared_particle, LimbMasses::inertia

  // plan_limb_masses: each limb's mass at its particles, and its frame (frames.hpp).
  std::vector<LimbParticleMasses> limb_masses;  // per body
  frames::Plan frames;

  // plan_slots.
  std::uint32_t frame_slot_offset = 2, slots_per_body = 2;
  std::size_t pin_slot_base = 0, slot_count = 0;
  std::vector<std::uint32_t> joint_inboard_slot, joint_outboard_slot, pin_slot_of_joint;  // per joint
  std::uint32_t head_slot(std::size_t b) const { return checked_index(slots_per_body * b); }
  std::uint32_t tail_slot(std::size_t b) const { return checked_index(slots_per_body * b + 1); }
  std::uint32_t centre_slot(std::size_t b) const { return checked_index(slots_per_body * b + 2); }
  std::uint32_t frame_slot(std::size_t b, int side) const { return checked_index(slots_per_body * b + frame_slot_offset + side); }

  // place_slots: each slot's position, velocity, mass share, and whether a pin holds it.
  std::vector<Vector3> slot_position, slot_velocity;
  std::vector<double> slot_mass;
  std::vector<bool> slot_pinned;

  // plan_islands: the Model's islands; per body its (joint, other body) neighbours and its
  // joints to the world; each island's bodies breadth-first from its root
  // (body_order[island_begin[i] .. island_begin[i + 1])) and the tree joint reaching each (−1: root).
  using Neighbour = std::pair<std::uint32_t, std::uint32_t>;
  BodyIslands islands;
  CompressedRows<Neighbour> neighbours;
  CompressedRows<std::uint32_t> world_joints;
  std::vector<std::uint32_t> body_order, island_begin;
  std::vector<std::int64_t> tree_joint;
  std::size_t island_count() const { return island_begin.size() - 1; }
  std::span<const std::uint32_t> island_bodies(std::size_t island) const {
    return {body_order.data() + island_begin[island], body_order.data() + island_begin[island + 1]};
  }

  // number_particles: each slot's particle (kUnassigned: none), island by island, body by body
  // (pins first, then head, centre, tail, frame); each particle's first slot; where each
  // island's particles end.
  static constexpr std::uint32_t kUnassigned = ~0u;
  std::vector<std::uint32_t> particle_of_slot, first_slot_of_particle, island_particle_end;
  std::uint32_t particle_of(std::uint32_t slot) const { return particle_of_slot[slot]; }
  std::size_t body_particle_count() const { return first_slot_of_particle.size(); }
};

/// Each limb's mass at its particles (LimbMasses: half at each end, three masses that keep its
/// inertia, or its lumps by the lever rule), then frames::plan, which gives framed limbs' frame
/// particles their mass. Throws ModelError naming the body for what particles cannot carry.
void plan_limb_masses(const Model& model, const VerletOptions& options, Plan& plan);
/// The slots of every body and world joint, and each joint's two slots.
void plan_slots(const Model& model, Plan& plan);
/// Slot positions, velocities (the Model's body motion at each point), mass shares and pins.
void place_slots(const Model& model, Plan& plan);
/// Islands, their roots (the first body held by the world, else the first body) and each
/// island's breadth-first body order.
void plan_islands(const Model& model, Plan& plan);
/// Merges the slots shared-particle joints join, then numbers the particles island by island.
void number_particles(const Model& model, Plan& plan);

}  // namespace limber::particle_plan
