// Handles with generations for members, rooms and props (as Box2D's ids): a 32-bit value whose
// low 16 bits name a slot and high 16 bits the slot's generation, bumped on every
// release, so a stale handle (a member that left, a packet from a previous session)
// never aliases a newer occupant. Value 0 is never issued.
#pragma once

#include <cstdint>
#include <vector>

namespace vistel::server {

struct MemberId {
  std::uint32_t value = 0;
  bool operator==(const MemberId&) const = default;
};

struct RoomId {
  std::uint32_t value = 0;
  bool operator==(const RoomId&) const = default;
};

// A prop of a room (from its own pool: prop and member ids may share values, so the wire
// always says which kind an id is).
struct PropId {
  std::uint32_t value = 0;
  bool operator==(const PropId&) const = default;
};

using ConnId = std::uint64_t;  // a TCP connection, numbered by the shell (never reused)

// Slot allocator issuing generation-tagged handles (capacity <= 65535).
class HandlePool {
 public:
  explicit HandlePool(int capacity) : capacity_(capacity) {}

  // A fresh handle, or 0 when all slots are taken.
  std::uint32_t allocate() {
    std::uint32_t slot = 0;
    if (!free_.empty()) {
      slot = free_.back();
      free_.pop_back();
    } else if (static_cast<int>(generations_.size()) < capacity_) {
      slot = static_cast<std::uint32_t>(generations_.size());
      generations_.push_back(1);
      live_.push_back(false);
    } else {
      return 0;
    }
    live_[slot] = true;
    return (static_cast<std::uint32_t>(generations_[slot]) << 16) | slot;
  }

  // Frees a live handle's slot (no-op for a stale or invalid one).
  void release(std::uint32_t handle) {
    if (!live(handle)) return;
    const std::uint32_t slot = handle & 0xFFFFu;
    live_[slot] = false;
    generations_[slot] = static_cast<std::uint16_t>(generations_[slot] + 1);
    if (generations_[slot] == 0) generations_[slot] = 1;
    free_.push_back(slot);
  }

  // True when the handle is the current occupant of its slot.
  bool live(std::uint32_t handle) const {
    const std::uint32_t slot = handle & 0xFFFFu;
    return handle != 0 && slot < generations_.size() && live_[slot] &&
           generations_[slot] == (handle >> 16);
  }

  static std::uint32_t slotOf(std::uint32_t handle) { return handle & 0xFFFFu; }

 private:
  int capacity_;
  std::vector<std::uint16_t> generations_;  // per slot
  std::vector<bool> live_;                  // per slot
  std::vector<std::uint32_t> free_;         // free slots
};

}  // namespace vistel::server
