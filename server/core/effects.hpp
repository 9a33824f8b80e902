// What the protocol cores ask their shell to do: the only way they act on the world.
// A call into a core appends to an Effects; the shell (Asio, or a test's simulated
// network) carries them out in order and clears it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "common/wire/endpoint.hpp"
#include "server/core/handles.hpp"

namespace vistel::server {

struct OutDatagram {
  wire::Endpoint to;
  std::vector<std::uint8_t> bytes;
};

struct OutFrame {
  ConnId conn = 0;
  std::vector<std::uint8_t> bytes;  // complete frames (length-prefixed), in order
};

// Lobby -> room instructions (the lobby owns membership; a room only mirrors what it
// needs for UDP traffic and ticking).
struct RoomCommand {
  enum class Kind {
    kCreate,        // room, name
    kClose,         // room (it is empty)
    kAddMember,     // room, member, key, joint_count (0 until the avatar is ready)
    kRemoveMember,  // room, member
    kBindEndpoint,  // room, member, endpoint (UDP hello accepted)
    kSetAvatar,     // room, member, joint_count
  };
  Kind kind = Kind::kCreate;
  RoomId room;
  MemberId member;
  std::uint64_t key = 0;
  wire::Endpoint endpoint;
  int joint_count = 0;
  std::string name;
};

struct Effects {
  std::vector<OutDatagram> datagrams;
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
