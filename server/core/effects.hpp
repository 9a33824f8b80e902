// What the protocol cores ask their shell to do: the only way they act on the world.
// A call into a core appends to an Effects; the shell (Asio, or a test's simulated
// network) carries them out in order and clears it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/scene/seat_layout.hpp"
#include "common/wire/datagram_crypto.hpp"
#include "common/wire/endpoint.hpp"
#include "server/core/collision_model.hpp"
#include "server/core/handles.hpp"
#include "server/core/props.hpp"

namespace vistel::server {

struct OutDatagram {
  wire::Endpoint to;
  std::vector<std::uint8_t> bytes;
};

// Outgoing datagrams whose slots (and their byte buffers) survive clear(), so that a
// room's tick, once warmed up, allocates nothing to send its snapshots.
class DatagramQueue {
 public:
  // A slot at the end: its bytes empty, with the capacity they had.
  OutDatagram& emplace_back() {
    if (size_ == slots_.size()) slots_.emplace_back();
    OutDatagram& d = slots_[size_++];
    d.bytes.clear();
    return d;
  }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  OutDatagram& operator[](std::size_t i) { return slots_[i]; }
  const OutDatagram& operator[](std::size_t i) const { return slots_[i]; }
  OutDatagram& back() { return slots_[size_ - 1]; }
  OutDatagram* begin() { return slots_.data(); }
  OutDatagram* end() { return slots_.data() + size_; }
  const OutDatagram* begin() const { return slots_.data(); }
  const OutDatagram* end() const { return slots_.data() + size_; }
  // Forgets the datagrams, keeping the slots.
  void clear() { size_ = 0; }

 private:
  std::vector<OutDatagram> slots_;
  std::size_t size_ = 0;
};

struct OutFrame {
  ConnId conn = 0;
  std::vector<std::uint8_t> bytes;  // complete frames (length-prefixed), in order
};

// Lobby -> room instructions (the lobby owns membership; a room only mirrors what it
// needs for UDP traffic and ticking).
struct RoomCommand {
  enum class Kind {
    kCreate,     // room, name
    kClose,      // room (it is empty)
    kAddMember,  // room, member, uplink/downlink keys, seat, joint_count and collision (0 and null
                 // until the avatar is ready)
    kRemoveMember,  // room, member
    kBindEndpoint,  // room, member, endpoint (UDP hello accepted)
    kSetAvatar,     // room, member, joint_count, collision
    kSpawnProp,     // room, prop, prop_spec, then position/velocity, or (member != 0) above
                    // that member's head
    kRemoveProp,    // room, prop
  };
  Kind kind = Kind::kCreate;
  RoomId room;
  MemberId member;
  wire::AeadKey uplink_key{};    // kAddMember: the member's client -> server datagram key
  wire::AeadKey downlink_key{};  // kAddMember: the server -> client key of the room's datagrams
  wire::Endpoint endpoint;
  int joint_count = 0;
  std::shared_ptr<const CollisionModel> collision;
  SeatPlacement seat;
  PropId prop;
  PropSpec prop_spec;
  glm::vec3 position{0.0f};  // room space, metres
  glm::vec3 velocity{0.0f};  // m/s
  std::string name;
};

struct Effects {
  DatagramQueue datagrams;
  std::vector<OutFrame> frames;
  std::vector<ConnId> closes;              // close after the frames queued before it are written
  std::vector<RoomCommand> room_commands;  // lobby -> rooms
  std::vector<MemberId> timed_out;         // rooms -> lobby

  bool empty() const {
    return datagrams.empty() && frames.empty() && closes.empty() && room_commands.empty() &&
           timed_out.empty();
  }
  void clear() {
    datagrams.clear();
    frames.clear();
    closes.clear();
    room_commands.clear();
    timed_out.clear();
  }
};

}  // namespace vistel::server
