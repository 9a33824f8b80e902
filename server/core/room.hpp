// A room's share of the session protocol: the UDP side of its members (latest posture,
// clock pings), its collision world (RoomWorld: members' primitives, props, Step 1) and
// the fixed-rate tick that steps the world and sends every member a snapshot of the
// others' newest postures, the prop states and the interaction list (DESIGN.md §6,
// proto/SESSION.md §3, proto/WIRE.md §3.6). Pure: fed (bytes, endpoint, now), it appends
// to Effects; no sockets, no clocks, no threads (the shell runs each room on its own
// strand). Membership and props come from the lobby as RoomCommands.
//
// Cost per tick: the world step (O(primitives) posing, stepBall per prop, Step 1) plus
// the snapshots; no heap allocation once the room's buffers and the Effects' datagram
// slots have grown to its size (reuse one Effects across ticks).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/wire/endpoint.hpp"
#include "common/wire/packets.hpp"
#include "server/core/drop_log.hpp"
#include "server/core/effects.hpp"
#include "server/core/room_world.hpp"
#include "server/core/server_config.hpp"

namespace vistel::server {

struct RoomSettings {
  double tick_rate_hz = 60.0;
  double member_timeout_s = 10.0;  // silence on UDP (from join, until the first packet)
  WorldSettings world;
};

// The room settings a server configuration asks for.
RoomSettings roomSettings(const ServerConfig& config);

class Room {
 public:
  Room(RoomId id, std::string name, const RoomSettings& settings, double now);

  RoomId id() const { return id_; }
  const std::string& name() const { return name_; }
  int memberCount() const { return static_cast<int>(members_.size()); }
  std::uint32_t tickCount() const { return tick_; }
  const DropLog& drops() const { return drops_; }
  // Postures accepted into the room so far (all members).
  std::uint64_t posturesAccepted() const { return postures_accepted_; }

  // Mirrors a lobby decision (add/remove/bind/set avatar); commands for other rooms or
  // unknown members are ignored.
  void apply(const RoomCommand& command, double now);

  // A posture or ping datagram addressed (by member id) to this room. Accepted only from
  // a member's bound endpoint with its key; postures must carry the member's joint count
  // and a newer sequence number than the last accepted one. Everything else is dropped
  // with a counted, logged reason. A ping is answered with a pong (smaller than the ping).
  void onDatagram(std::span<const std::uint8_t> datagram, const wire::Endpoint& from, double now,
                  Effects& fx);

  // If a tick is due, sends each bound member the others' newest postures (as many
  // datagrams of at most kMaxDatagramBytes as needed) and reports members silent for
  // longer than the timeout (once each, in fx.timed_out). Missed ticks are skipped, not
  // replayed. Call at least at the tick rate.
  void update(double now, Effects& fx);

  // Server time of the next due tick, and of the last one (-1 before the first).
  double nextTickTime() const { return next_tick_; }
  double lastTickTime() const { return last_tick_time_; }

  // The collision world as of the last tick.
  const RoomWorld& world() const { return world_; }

 private:
  struct Member {
    MemberId id;
    std::uint64_t key = 0;
    bool bound = false;
    wire::Endpoint endpoint;
    int joint_count = 0;  // 0 = avatar not ready: postures are refused
    bool has_posture = false;
    std::uint16_t sequence = 0;              // of the stored posture
    std::vector<std::uint8_t> record_bytes;  // serialized newest posture record
    double last_heard = 0.0;
    bool timeout_reported = false;
  };

  Member* find(std::uint32_t member_id);
  void onPosture(std::span<const std::uint8_t> datagram, const wire::Endpoint& from, double now,
                 Effects& fx);
  void onPing(std::span<const std::uint8_t> datagram, const wire::Endpoint& from, double now,
              Effects& fx);
  // Common checks of a client datagram's sender; logs and returns nullptr on failure.
  Member* authenticate(std::uint32_t member_id, std::uint64_t key, const wire::Endpoint& from,
                       double now, std::string_view what);
  void sendSnapshots(double now, Effects& fx);

  RoomId id_;
  std::string name_;
  RoomSettings settings_;
  double tick_interval_;
  double next_tick_;
  double last_tick_time_ = -1.0;  // server time of the last tick (-1: none yet)
  RoomWorld world_;
  std::uint32_t tick_ = 0;
  std::vector<Member> members_;
  DropLog drops_;
  std::uint64_t postures_accepted_ = 0;
  // Reused per datagram, so steady state allocates only the outgoing datagrams.
  wire::PosturePacket scratch_posture_;
};

}  // namespace vistel::server
