#include "server/core/server_core.hpp"

#include <algorithm>

#include <fmt/format.h>

#include "common/wire/packets.hpp"

namespace vistel::server {

void RoomRouter::apply(const RoomCommand& c) {
  if (c.kind == RoomCommand::Kind::kAddMember) {
    room_of_member_[c.member.value] = c.room;
  } else if (c.kind == RoomCommand::Kind::kRemoveMember) {
    room_of_member_.erase(c.member.value);
  }
}

std::optional<RoomId> RoomRouter::roomOf(std::uint32_t member_id) const {
  auto it = room_of_member_.find(member_id);
  if (it == room_of_member_.end()) return std::nullopt;
  return it->second;
}

DatagramRoute routeDatagram(std::span<const std::uint8_t> datagram, const RoomRouter& router) {
  DatagramRoute route;
  const auto type = wire::peekPacketType(datagram);
  if (!type) {
    route.reason = "not a vistel datagram";
    return route;
  }
  // Every datagram is sealed (WIRE.md §3.9): shorter than a clear header and a tag, it
  // cannot be one.
  if (datagram.size() < wire::kClientHeaderBytes + wire::kSealOverheadBytes) {
    route.reason = "truncated datagram";
    return route;
  }
  switch (*type) {
    case wire::PacketType::kHello:
      route.target = DatagramRoute::Target::kLobby;
      return route;
    case wire::PacketType::kPosture:
    case wire::PacketType::kPing:
    case wire::PacketType::kVoice: {
      const auto member = wire::peekMemberId(datagram);
      const auto room = member ? router.roomOf(*member) : std::nullopt;
      if (!room) {
        route.reason = member ? "datagram for unknown member" : "truncated datagram";
        return route;
      }
      route.target = DatagramRoute::Target::kRoom;
      route.room = *room;
      return route;
    }
    default:
      route.reason = "server-bound datagram of a client-bound type";
      return route;
  }
}

ServerCore::ServerCore(const ServerConfig& config, std::uint64_t seed)
    : config_(config), lobby_(config, seed) {}

void ServerCore::settle(double now) {
  while (!fx_.room_commands.empty() || !fx_.timed_out.empty()) {
    // Room commands: create/close rooms here, forward the rest.
    std::vector<RoomCommand> commands;
    commands.swap(fx_.room_commands);
    for (const RoomCommand& c : commands) {
      router_.apply(c);
      if (c.kind == RoomCommand::Kind::kCreate) {
        rooms_[c.room.value] = std::make_unique<Room>(c.room, c.name, roomSettings(config_), now);
      } else if (c.kind == RoomCommand::Kind::kClose) {
        rooms_.erase(c.room.value);
      } else if (auto it = rooms_.find(c.room.value); it != rooms_.end()) {
        it->second->apply(c, now);
      }
    }
    // Timeouts reported by rooms go back to the lobby.
    std::vector<MemberId> timed_out;
    timed_out.swap(fx_.timed_out);
    for (MemberId m : timed_out) lobby_.onTimedOut(m, now, fx_);
  }
}

void ServerCore::onConnect(ConnId conn, double now) {
  lobby_.onConnect(conn, now, fx_);
  settle(now);
}

void ServerCore::onStreamBytes(ConnId conn, std::span<const std::uint8_t> bytes, double now) {
  lobby_.onStreamBytes(conn, bytes, now, fx_);
  settle(now);
}

void ServerCore::onDisconnect(ConnId conn, double now) {
  lobby_.onDisconnect(conn, now, fx_);
  settle(now);
}

void ServerCore::onDatagram(std::span<const std::uint8_t> datagram, const wire::Endpoint& from,
                            double now) {
  const DatagramRoute route = routeDatagram(datagram, router_);
  switch (route.target) {
    case DatagramRoute::Target::kLobby:
      lobby_.onHello(datagram, from, now, fx_);
      break;
    case DatagramRoute::Target::kRoom:
      rooms_.at(route.room.value)->onDatagram(datagram, from, now, fx_);
      break;
    case DatagramRoute::Target::kDrop:
      drops_.drop(now, route.reason,
                  fmt::format("{} bytes from {}", datagram.size(), from.toString()));
      break;
  }
  settle(now);
}

void ServerCore::update(double now) {
  lobby_.update(now, fx_);
  for (auto& [id, room] : rooms_) room->update(now, fx_);
  settle(now);
}

void ServerCore::shutdown(double now) {
  lobby_.shutdown(now, fx_);
  settle(now);
}

double ServerCore::nextWakeTime(double now) const {
  double t = now + 0.1;  // timeouts are checked at least this often
  for (const auto& [id, room] : rooms_) t = std::min(t, room->nextWakeTime());
  return t;
}

const Room* ServerCore::findRoom(std::string_view name) const {
  for (const auto& [id, room] : rooms_) {
    if (room->name() == name) return room.get();
  }
  return nullptr;
}

}  // namespace vistel::server
