#include "server/core/room.hpp"

#include <algorithm>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

namespace vistel::server {

Room::Room(RoomId id, std::string name, const RoomSettings& settings, double now)
    : id_(id),
      name_(std::move(name)),
      settings_(settings),
      tick_interval_(1.0 / settings.tick_rate_hz),
      next_tick_(now + 1.0 / settings.tick_rate_hz),
      drops_(fmt::format("room '{}'", name_)) {}

Room::Member* Room::find(std::uint32_t member_id) {
  for (Member& m : members_) {
    if (m.id.value == member_id) return &m;
  }
  return nullptr;
}

void Room::apply(const RoomCommand& c, double now) {
  if (c.room != id_) return;
  switch (c.kind) {
    case RoomCommand::Kind::kAddMember: {
      if (find(c.member.value) != nullptr) return;
      Member m;
      m.id = c.member;
      m.key = c.key;
      m.joint_count = c.joint_count;
      m.last_heard = now;
      members_.push_back(std::move(m));
      break;
    }
    case RoomCommand::Kind::kRemoveMember:
      std::erase_if(members_, [&](const Member& m) { return m.id == c.member; });
      break;
    case RoomCommand::Kind::kBindEndpoint:
      if (Member* m = find(c.member.value)) {
        m->bound = true;
        m->endpoint = c.endpoint;
        m->last_heard = now;
      }
      break;
    case RoomCommand::Kind::kSetAvatar:
      if (Member* m = find(c.member.value)) m->joint_count = c.joint_count;
      break;
    case RoomCommand::Kind::kCreate:
    case RoomCommand::Kind::kClose:
      break;  // handled by whoever owns the room objects
  }
}

Room::Member* Room::authenticate(std::uint32_t member_id, std::uint64_t key,
                                 const wire::Endpoint& from, double now, std::string_view what) {
  Member* m = find(member_id);
  if (m == nullptr) {
    drops_.drop(now, "unknown member",
                fmt::format("{} for member {:#x} from {}", what, member_id, from.toString()));
    return nullptr;
  }
  if (m->key != key) {
    drops_.drop(now, "bad key",
                fmt::format("{} for member {:#x} from {}", what, member_id, from.toString()));
    return nullptr;
  }
  if (!m->bound) {
    drops_.drop(now, "endpoint not bound",
                fmt::format("{} for member {:#x} from {} before its hello", what, member_id,
                            from.toString()));
    return nullptr;
  }
  if (!(m->endpoint == from)) {
    drops_.drop(now, "wrong endpoint",
                fmt::format("{} for member {:#x} from {}, bound to {}", what, member_id,
                            from.toString(), m->endpoint.toString()));
    return nullptr;
  }
  return m;
}

void Room::onDatagram(std::span<const std::uint8_t> datagram, const wire::Endpoint& from,
                      double now, Effects& fx) {
  const auto type = wire::peekPacketType(datagram);
  if (type == wire::PacketType::kPosture) {
    onPosture(datagram, from, now, fx);
  } else if (type == wire::PacketType::kPing) {
    onPing(datagram, from, now, fx);
  } else {
    drops_.drop(now, "unexpected datagram",
                fmt::format("{} bytes from {}", datagram.size(), from.toString()));
  }
}

void Room::onPosture(std::span<const std::uint8_t> datagram, const wire::Endpoint& from, double now,
                     Effects& /*fx*/) {
  // Decode the whole packet (range-checked, exact length).
  wire::PosturePacket& p = scratch_posture_;
  if (!wire::read(datagram, p)) {
    drops_.drop(now, "malformed posture",
                fmt::format("{} bytes from {}", datagram.size(), from.toString()));
    return;
  }
  Member* m = authenticate(p.header.member_id, p.header.key, from, now, "posture");
  if (m == nullptr) return;
  m->last_heard = now;

  // Semantic checks: the avatar's joint count, a plausible capture time, newest wins.
  if (m->joint_count == 0) {
    drops_.drop(now, "avatar not ready",
                fmt::format("posture from member {:#x} before its avatar", m->id.value));
    return;
  }
  if (p.record.joint_count != m->joint_count) {
    drops_.drop(now, "wrong joint count",
                fmt::format("member {:#x} sent {} joints, its avatar has {}", m->id.value,
                            p.record.joint_count, m->joint_count));
    return;
  }
  const double capture = wire::fromWireTime(p.record.time, now);
  if (capture > now + 1.0) {
    drops_.drop(now, "capture time in the future",
                fmt::format("member {:#x}: {:.3f} s ahead", m->id.value, capture - now));
    return;
  }
  if (m->has_posture && !wire::sequenceNewer(p.record.sequence, m->sequence)) {
    return;  // duplicate or reordered: newest wins (normal on a lossy network, not logged)
  }

  // Keep the record's bytes exactly as received: snapshots copy them.
  const auto record = datagram.subspan(wire::kClientHeaderBytes);
  m->record_bytes.assign(record.begin(), record.end());
  m->sequence = p.record.sequence;
  m->has_posture = true;
  ++postures_accepted_;
}

void Room::onPing(std::span<const std::uint8_t> datagram, const wire::Endpoint& from, double now,
                  Effects& fx) {
  wire::PingPacket ping;
  if (!wire::read(datagram, ping)) {
    drops_.drop(now, "malformed ping",
                fmt::format("{} bytes from {}", datagram.size(), from.toString()));
    return;
  }
  Member* m = authenticate(ping.header.member_id, ping.header.key, from, now, "ping");
  if (m == nullptr) return;
  m->last_heard = now;

  // Answer at once with the server clock (22 bytes for a 26-byte ping).
  wire::PongPacket pong;
  pong.ping_id = ping.ping_id;
  pong.client_time = ping.client_time;
  pong.server_time = now;
  OutDatagram& out = fx.datagrams.emplace_back();
  out.to = from;
  wire::write(pong, out.bytes);
}

void Room::update(double now, Effects& fx) {
  // Timeouts: members silent too long are reported once; the lobby removes them.
  for (Member& m : members_) {
    if (!m.timeout_reported && now - m.last_heard > settings_.member_timeout_s) {
      m.timeout_reported = true;
      spdlog::info("room '{}': member {:#x} silent for {:.1f} s: timing out", name_, m.id.value,
                   now - m.last_heard);
      fx.timed_out.push_back(m.id);
    }
  }

  // Tick: one snapshot round when due; missed ticks are skipped.
  if (now < next_tick_) return;
  ++tick_;
  sendSnapshots(now, fx);
  next_tick_ += tick_interval_;
  if (next_tick_ <= now) next_tick_ = now + tick_interval_;
}

void Room::sendSnapshots(double now, Effects& fx) {
  wire::SnapshotHeader header;
  header.tick = tick_;
  header.server_time = now;
  for (const Member& to : members_) {
    if (!to.bound) continue;
    // Pack the other members' records into as few datagrams as fit.
    std::vector<std::uint8_t>* packet = nullptr;
    int count = 0;
    for (const Member& from : members_) {
      if (from.id == to.id || !from.has_posture) continue;
      const std::size_t entry = wire::kSnapshotEntryOverhead + from.record_bytes.size();
      if (packet != nullptr && (packet->size() + entry > wire::kMaxDatagramBytes || count == 255)) {
        wire::finishSnapshot(static_cast<std::uint8_t>(count), *packet);
        packet = nullptr;
      }
      if (packet == nullptr) {
        OutDatagram& out = fx.datagrams.emplace_back();
        out.to = to.endpoint;
        out.bytes.reserve(wire::kMaxDatagramBytes);
        wire::beginSnapshot(header, out.bytes);
        packet = &out.bytes;
        count = 0;
      }
      wire::appendSnapshotEntry(from.id.value, from.record_bytes, *packet);
      ++count;
    }
    if (packet != nullptr) wire::finishSnapshot(static_cast<std::uint8_t>(count), *packet);
  }
}

}  // namespace vistel::server
