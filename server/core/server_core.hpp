// The whole session server as one pure, single-threaded object: the lobby, the rooms it
// creates, and the routing between them (DESIGN.md §6; STYLE.md "a pure protocol core").
// Fed (bytes, endpoint, now), it accumulates what to send in effects(); tests drive it
// over a simulated network with a fake clock. The Asio shell uses the same pieces (the
// lobby, Room, RoomRouter and routeDatagram) but runs each room on its own strand.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <unordered_map>

#include "common/wire/endpoint.hpp"
#include "server/core/drop_log.hpp"
#include "server/core/effects.hpp"
#include "server/core/lobby.hpp"
#include "server/core/room.hpp"
#include "server/core/server_config.hpp"

namespace vistel::server {

// Which room each live member is in, mirrored from RoomCommands (for routing UDP).
class RoomRouter {
 public:
  void apply(const RoomCommand& command);
  std::optional<RoomId> roomOf(std::uint32_t member_id) const;

 private:
  std::unordered_map<std::uint32_t, RoomId> room_of_member_;
};

// Where an incoming datagram goes: hellos to the lobby; postures and pings to their
// member's room; anything else (unknown version/type, too short, unknown member) is
// dropped with `reason`.
struct DatagramRoute {
  enum class Target { kLobby, kRoom, kDrop };
  Target target = Target::kDrop;
  RoomId room;
  std::string_view reason;
};
DatagramRoute routeDatagram(std::span<const std::uint8_t> datagram, const RoomRouter& router);

class ServerCore {
 public:
  ServerCore(const ServerConfig& config, std::uint64_t seed = 0);

  void onConnect(ConnId conn, double now);
  void onStreamBytes(ConnId conn, std::span<const std::uint8_t> bytes, double now);
  void onDisconnect(ConnId conn, double now);
  void onDatagram(std::span<const std::uint8_t> datagram, const wire::Endpoint& from, double now);
  // Room ticks and timeouts due by `now`; call at least at the tick rate.
  void update(double now);
  void shutdown(double now);

  // Datagrams, frames and closes produced so far (room commands and timeouts are
  // settled internally); the caller carries them out and clears them.
  Effects& effects() { return fx_; }

  // Earliest time update() has work (next room tick or timeout check).
  double nextWakeTime(double now) const;

  const Lobby& lobby() const { return lobby_; }
  const Room* findRoom(std::string_view name) const;
  const DropLog& drops() const { return drops_; }

 private:
  // Delivers room commands and timeout reports between the lobby and rooms until none
  // are pending.
  void settle(double now);

  ServerConfig config_;
  Lobby lobby_;
  RoomRouter router_;
  std::unordered_map<std::uint32_t, std::unique_ptr<Room>> rooms_;
  Effects fx_;
  DropLog drops_{"server"};
};

}  // namespace vistel::server
