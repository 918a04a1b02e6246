// The World's handles, one table type for bodies, joints, colliders, balls and pins: a handle
// (world.hpp's Handle) is a slot of the table and the slot's generation (Box2D v3's b2BodyId:
// index and revision). A slot holds the thing's position (its index in the Model's array); a
// removed thing's slot is reused with the next generation, so its old handle is refused. A
// lookup is two array reads; internal to kernel/world.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "limber/config.hpp"  // the instruction set limber was built for; stops a mismatched build

namespace limber {

template <typename Id>
class HandleTable {
 public:
  static constexpr std::uint32_t kNoSlot = ~0u;

  std::size_t size() const { return slot_of_position_.size(); }

  /// A handle for a thing appended at position size().
  Id add(std::uint32_t world) {
    std::uint32_t slot = kNoSlot;
    if (!free_.empty()) {
      slot = free_.back(), free_.pop_back();
      ++slots_[slot].generation;
    } else {
      slot = static_cast<std::uint32_t>(slots_.size());
      slots_.push_back({});
    }
    slots_[slot].position = static_cast<std::uint32_t>(size());
    slot_of_position_.push_back(slot);
    return Id{slot, slots_[slot].generation, world};
  }

  /// The position of `handle`'s thing, or nullopt when it was removed or never issued here
  /// (the World checks the serial).
  std::optional<std::size_t> find(const Id& handle) const {
    if (handle.slot >= slots_.size()) return std::nullopt;
    const Slot& slot = slots_[handle.slot];
    if (slot.generation != handle.generation || slot.position == kNoSlot) return std::nullopt;
    return slot.position;
  }

  /// The handle of the thing at `position`.
  Id at(std::size_t position, std::uint32_t world) const {
    const std::uint32_t slot = slot_of_position_[position];
    return Id{slot, slots_[slot].generation, world};
  }
  /// The slot of the thing at `position`: a key for what the World keeps per thing.
  std::uint32_t slot(std::size_t position) const { return slot_of_position_[position]; }
  /// Every slot, in position order.
  const std::vector<std::uint32_t>& slots() const { return slot_of_position_; }

  /// Removes the thing at `position`; those after it move down one.
  void erase(std::size_t position) {
    std::vector<char> kept(size(), 1);
    kept[position] = 0;
    keep(kept);
  }
  /// Keeps the things whose kept[position] is non-zero, in order, and removes the others.
  void keep(const std::vector<char>& kept) {
    std::size_t next = 0;
    for (std::size_t p = 0; p < slot_of_position_.size(); ++p) {
      const std::uint32_t slot = slot_of_position_[p];
      if (!kept[p]) {
        slots_[slot].position = kNoSlot;
        free_.push_back(slot);
        continue;
      }
      slots_[slot].position = static_cast<std::uint32_t>(next);
      slot_of_position_[next++] = slot;
    }
    slot_of_position_.resize(next);
  }

 private:
  struct Slot {
    std::uint32_t position = kNoSlot;
    std::uint32_t generation = 0;
  };
  std::vector<Slot> slots_;
  std::vector<std::uint32_t> slot_of_position_;
  std::vector<std::uint32_t> free_;  // slots of removed things, reused last-freed first
};

}  // namespace limber
