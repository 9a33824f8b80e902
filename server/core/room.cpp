#include "server/core/room.hpp"

#include <algorithm>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/wire/voice_packets.hpp"

namespace vistel::server {
namespace {

// Where a member's head is taken to be before the server has its avatar (voice).
constexpr float kVoiceHeadHeightM = 1.6f;

}  // namespace

RoomSettings roomSettings(const ServerConfig& config) {
  RoomSettings s;
  s.tick_rate_hz = config.tick_rate_hz;
  s.member_timeout_s = config.member_timeout_s;
  s.forward_interval_s = config.forward_interval_s;
  s.max_capture_age_s = config.max_capture_age_s;
  s.near_members = config.interest_near_members;
  s.max_rate_divisor = config.interest_max_rate_divisor;
  s.world.gravity_mps2 = config.gravity_mps2;
  s.world.floor_height_m = config.floor_height_m;
  s.world.extent_m = config.world_extent_m;
  s.world.max_parts = config.max_interaction_datagrams;
  s.world.send_self_contact = config.send_self_contact;
  s.world.contact_window_s = static_cast<float>(config.contact_window_s);
  s.world.contact_lead_s = static_cast<float>(config.contact_lead_s);
  s.world.spawn_height_m = config.spawn_height_m;
  s.voice = config.voice;
  return s;
}

Room::Room(RoomId id, std::string name, const RoomSettings& settings, double now)
    : id_(id),
      name_(std::move(name)),
      settings_(settings),
      tick_interval_(1.0 / settings.tick_rate_hz),
      next_tick_(now + 1.0 / settings.tick_rate_hz),
      world_(settings.world),
      drops_(fmt::format("room '{}'", name_)),
      last_update_(now),
      voice_(settings.voice) {}

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
      m.in.key = c.uplink_key;
      m.out.key = c.downlink_key;
      m.joint_count = c.joint_count;
      m.decoder = wire::PostureDeltaDecoder(std::max(1, c.joint_count));
      m.last_heard = now;
      m.seat = glm::vec2(c.seat.x, c.seat.z);
      m.record_bytes.reserve(
          static_cast<std::size_t>(wire::postureRecordBytes(wire::kMaxWireJoints)));
      members_.push_back(std::move(m));
      interest_dirty_ = true;
      world_.addMember(c.member, c.seat, c.collision);
      voice_.addMember(c.member.value, now);
      voice_.setHead(c.member.value, glm::vec3(c.seat.x, kVoiceHeadHeightM, c.seat.z));
      break;
    }
    case RoomCommand::Kind::kRemoveMember:
      std::erase_if(members_, [&](const Member& m) { return m.id == c.member; });
      world_.removeMember(c.member);
      voice_.removeMember(c.member.value);
      interest_dirty_ = true;
      break;
    case RoomCommand::Kind::kBindEndpoint:
      if (Member* m = find(c.member.value)) {
        m->bound = true;
        m->endpoint = c.endpoint;
        m->last_heard = now;
      }
      break;
    case RoomCommand::Kind::kSetAvatar:
      if (Member* m = find(c.member.value)) {
        m->joint_count = c.joint_count;
        m->has_posture = false;
        m->fresh = false;
        m->decoder = wire::PostureDeltaDecoder(std::max(1, c.joint_count));
        m->has_ack = false;
        world_.setModel(c.member, c.collision);
      }
      break;
    case RoomCommand::Kind::kSpawnProp: {
      // Above the requesting member's head when there is one, else where the lobby says.
      glm::vec3 position = c.position;
      if (c.member.value != 0) {
        if (auto above = world_.spawnPointAbove(c.member)) position = *above;
      }
      if (world_.addProp(c.prop, c.prop_spec, position, c.velocity)) {
        spdlog::info("room '{}': prop {:#x} spawned at ({:.2f}, {:.2f}, {:.2f})", name_,
                     c.prop.value, position.x, position.y, position.z);
      } else {
        spdlog::warn("room '{}': prop {:#x} could not be spawned", name_, c.prop.value);
      }
      break;
    }
    case RoomCommand::Kind::kRemoveProp:
      world_.removeProp(c.prop);
      break;
    case RoomCommand::Kind::kCreate:
    case RoomCommand::Kind::kClose:
      break;  // handled by whoever owns the room objects
  }
}

Room::Member* Room::authenticate(std::span<const std::uint8_t> datagram, const wire::Endpoint& from,
                                 double now, std::string_view what,
                                 std::span<const std::uint8_t>& plain) {
  const auto member_id = wire::peekMemberId(datagram);
  Member* m = member_id ? find(*member_id) : nullptr;
  if (m == nullptr) {
    drops_.drop(
        now, "unknown member",
        fmt::format("{} for member {:#x} from {}", what, member_id.value_or(0), from.toString()));
    return nullptr;
  }
  if (!m->bound) {
    drops_.drop(now, "endpoint not bound",
                fmt::format("{} for member {:#x} from {} before its hello", what, m->id.value,
                            from.toString()));
    return nullptr;
  }
  if (!(m->endpoint == from)) {
    drops_.drop(now, "wrong endpoint",
                fmt::format("{} for member {:#x} from {}, bound to {}", what, m->id.value,
                            from.toString(), m->endpoint.toString()));
    return nullptr;
  }
  // The seal (WIRE.md §3.9): a fresh counter, then the tag under the member's key. What
  // fails was not sent by the member, or was sent before (a replay): dropped, counted.
  if (datagram.size() > wire::kMaxDatagramBytes) {
    drops_.drop(now, "oversized datagram",
                fmt::format("{} of {} bytes from {}", what, datagram.size(), from.toString()));
    return nullptr;
  }
  scratch_datagram_.assign(datagram.begin(), datagram.end());
  std::size_t plain_size = 0;
  std::string_view refused;
  if (!m->in.open(wire::kClientHeaderBytes, scratch_datagram_, plain_size, refused)) {
    drops_.drop(now, refused,
                fmt::format("{} for member {:#x} from {}", what, m->id.value, from.toString()));
    return nullptr;
  }
  plain = std::span(scratch_datagram_).first(plain_size);
  return m;
}

void Room::onDatagram(std::span<const std::uint8_t> datagram, const wire::Endpoint& from,
                      double now, Effects& fx) {
  const auto type = wire::peekPacketType(datagram);
  if (type == wire::PacketType::kPosture) {
    onPosture(datagram, from, now, fx);
  } else if (type == wire::PacketType::kPing) {
    onPing(datagram, from, now, fx);
  } else if (type == wire::PacketType::kVoice) {
    onVoice(datagram, from, now, fx);
  } else {
    drops_.drop(now, "unexpected datagram",
                fmt::format("{} bytes from {}", datagram.size(), from.toString()));
  }
}

void Room::onPosture(std::span<const std::uint8_t> datagram, const wire::Endpoint& from, double now,
                     Effects& fx) {
  // The sender and the seal first, then the header, then the delta-coded record against
  // the sender's history (range-checked, exact length).
  std::span<const std::uint8_t> plain;
  Member* m = authenticate(datagram, from, now, "posture", plain);
  if (m == nullptr) return;
  wire::ClientHeader header;
  std::span<const std::uint8_t> coded;
  if (!wire::readPostureDatagram(plain, header, coded)) {
    drops_.drop(now, "malformed posture",
                fmt::format("{} bytes from {}", datagram.size(), from.toString()));
    return;
  }
  m->last_heard = now;
  if (m->joint_count == 0) {
    drops_.drop(now, "avatar not ready",
                fmt::format("posture from member {:#x} before its avatar", m->id.value));
    return;
  }
  wire::PostureRecord& record = scratch_record_;
  const wire::DeltaDecodeResult decoded = m->decoder.decode(coded, record);
  if (decoded.status == wire::DeltaStatus::kMissingReference) {
    // A lost datagram took the reference: ask for a keyframe (not an error).
    m->want_keyframe = true;
    ++postures_without_reference_;
    return;
  }
  if (!decoded.ok()) {
    drops_.drop(
        now, "malformed posture",
        fmt::format("member {:#x}: {} ({} bytes)", m->id.value, decoded.reason, coded.size()));
    return;
  }
  if (decoded.keyframe) m->want_keyframe = false;

  // Order: newer by 1..kMaxSequenceJump is news; a record farther from the stored one in
  // either direction is a sender that skipped or started over (a bug, or a very long
  // loss): only a keyframe may resynchronise the member there, so one wild sequence number
  // never leaves the member's real stream looking old (frozen) for minutes.
  bool resync = false;
  if (m->has_ack) {
    const auto ahead = static_cast<std::uint16_t>(record.sequence - m->ack);
    const auto behind = static_cast<std::uint16_t>(m->ack - record.sequence);
    if (ahead > kMaxSequenceJump && behind > kMaxSequenceJump) {
      if (!decoded.keyframe) {
        m->want_keyframe = true;
        drops_.drop(now, "sequence jump",
                    fmt::format("member {:#x}: sequence {} after {}", m->id.value, record.sequence,
                                m->ack));
        return;
      }
      resync = true;
    }
  }
  if (!m->has_ack || resync || wire::sequenceNewer(record.sequence, m->ack)) {
    m->ack = record.sequence;
  }
  m->has_ack = true;

  // Semantic checks: the avatar's joint count, a plausible capture time, newest wins.
  if (record.joint_count != m->joint_count) {
    drops_.drop(now, "wrong joint count",
                fmt::format("member {:#x} sent {} joints, its avatar has {}", m->id.value,
                            record.joint_count, m->joint_count));
    return;
  }
  const double capture = wire::fromWireTime(record.time, now);
  if (capture > now + 1.0) {
    drops_.drop(now, "capture time in the future",
                fmt::format("member {:#x}: {:.3f} s ahead", m->id.value, capture - now));
    return;
  }
  if (capture < now - settings_.max_capture_age_s) {
    drops_.drop(now, "capture time too old",
                fmt::format("member {:#x}: {:.3f} s ago", m->id.value, now - capture));
    return;
  }
  if (m->has_posture && !resync && !wire::sequenceNewer(record.sequence, m->sequence)) {
    return;  // duplicate or reordered: newest wins (normal on a lossy network, not logged)
  }

  // Keep the record's §3.3 bytes: posture batches copy them.
  m->record_bytes.clear();
  wire::writeRecord(record, m->record_bytes);
  m->sequence = record.sequence;
  m->has_posture = true;
  m->fresh = true;
  ++m->accepted;
  world_.setPosture(m->id, record);
  ++postures_accepted_;

  // On to the others: now when the last batch is long enough ago, else with the next.
  if (!forward_pending_) {
    forward_pending_ = true;
    next_forward_ = std::max(now, last_forward_ + settings_.forward_interval_s);
  }
  if (now >= next_forward_) forward(now, fx);
}

void Room::onPing(std::span<const std::uint8_t> datagram, const wire::Endpoint& from, double now,
                  Effects& fx) {
  std::span<const std::uint8_t> plain;
  Member* m = authenticate(datagram, from, now, "ping", plain);
  if (m == nullptr) return;
  wire::PingPacket ping;
  if (!wire::read(plain, ping)) {
    drops_.drop(now, "malformed ping",
                fmt::format("{} bytes from {}", datagram.size(), from.toString()));
    return;
  }
  m->last_heard = now;

  // Answer at once with the server clock (38 bytes sealed for a 42-byte ping).
  wire::PongPacket pong;
  pong.ping_id = ping.ping_id;
  pong.server_time = now;
  OutDatagram& out = fx.datagrams.emplace_back();
  out.to = from;
  wire::write(pong, out.bytes);
  m->out.seal(wire::kServerHeaderBytes, out.bytes);
}

void Room::onVoice(std::span<const std::uint8_t> datagram, const wire::Endpoint& from, double now,
                   Effects& fx) {
  if (!settings_.voice.enabled) {
    drops_.drop(now, "voice disabled",
                fmt::format("{} bytes from {}", datagram.size(), from.toString()));
    return;
  }
  std::span<const std::uint8_t> plain;
  Member* m = authenticate(datagram, from, now, "voice", plain);
  if (m == nullptr) return;
  wire::VoicePacket voice;
  if (Status st = wire::readVoice(plain, voice); !st) {
    drops_.drop(now, "malformed voice",
                fmt::format("member {:#x}: {}", m->id.value, st.error().message));
    return;
  }
  m->last_heard = now;
  if (!voice_.admit(m->id.value, datagram.size(), now)) {
    drops_.drop(now, "voice rate limit",
                fmt::format("member {:#x}: over its voice frame or byte rate", m->id.value));
    return;
  }
  voice_.route(m->id.value, voice.frame.level, now, scratch_listeners_);
  if (scratch_listeners_.empty()) return;
  // The forward's plain bytes once; each recipient gets them sealed with its own key.
  wire::VoiceForwardPacket forward;
  forward.speaker_id = m->id.value;
  forward.frame = voice.frame;
  forward.payload = voice.payload;
  scratch_forward_.clear();
  if (!wire::writeVoiceForward(forward, scratch_forward_)) return;  // readVoice checked it
  for (std::uint32_t id : scratch_listeners_) {
    Member* to = find(id);
    if (to == nullptr || !to->bound) continue;
    OutDatagram& out = fx.datagrams.emplace_back();
    out.to = to->endpoint;
    out.bytes.reserve(wire::kMaxDatagramBytes);
    out.bytes.assign(scratch_forward_.begin(), scratch_forward_.end());
    to->out.seal(wire::kServerHeaderBytes, out.bytes);
  }
}

void Room::updateVoiceHeads() {
  for (const Member& m : members_) {
    const auto head = world_.headPosition(m.id);
    voice_.setHead(m.id.value, head ? *head : glm::vec3(m.seat.x, kVoiceHeadHeightM, m.seat.y));
  }
}

double Room::nextWakeTime() const {
  return forward_pending_ ? std::min(next_tick_, next_forward_) : next_tick_;
}

void Room::update(double now, Effects& fx) {
  ticked_ = false;
  if (forward_pending_ && now >= next_forward_) forward(now, fx);

  // A pause of the server (a stopped process, a starved thread: update() runs at least
  // every 0.1 s otherwise) is not the members' silence: what they sent meanwhile is still
  // queued. Their silence clocks skip the pause.
  if (now - last_update_ > kStallSeconds) {
    const double pause = now - last_update_;
    spdlog::warn("room '{}': the server paused for {:.1f} s; members' timeouts restart", name_,
                 pause);
    for (Member& m : members_) m.last_heard += pause;
  }
  last_update_ = now;

  // Timeouts: members silent too long are reported once; the lobby removes them.
  for (Member& m : members_) {
    if (!m.timeout_reported && now - m.last_heard > settings_.member_timeout_s) {
      m.timeout_reported = true;
      spdlog::info("room '{}': member {:#x} silent for {:.1f} s: timing out", name_, m.id.value,
                   now - m.last_heard);
      fx.timed_out.push_back(m.id);
    }
  }

  // Tick: step the world and send one snapshot round when due; missed ticks are skipped.
  if (now < next_tick_) return;
  ticked_ = true;
  ++tick_;
  world_.step(last_tick_time_ < 0.0 ? tick_interval_ : now - last_tick_time_);
  last_tick_time_ = now;
  updateVoiceHeads();
  sendWorld(now, fx);
  next_tick_ += tick_interval_;
  if (next_tick_ <= now) next_tick_ = now + tick_interval_;
}

void Room::updateInterest() {
  const std::size_t n = members_.size();
  interest_.assign(n * n, 0);
  const int near = std::max(1, settings_.near_members);
  const int max_divisor = std::clamp(settings_.max_rate_divisor, 1, 255);
  for (std::size_t to = 0; to < n; ++to) {
    // The others by distance from this seat (ties by room order), ranked.
    scratch_order_.clear();
    for (std::size_t from = 0; from < n; ++from) {
      if (from == to) continue;
      scratch_order_.emplace_back(glm::distance(members_[to].seat, members_[from].seat),
                                  static_cast<int>(from));
    }
    std::sort(scratch_order_.begin(), scratch_order_.end());
    for (std::size_t rank = 0; rank < scratch_order_.size(); ++rank) {
      const int divisor = std::min(max_divisor, 1 + static_cast<int>(rank) / near);
      interest_[to * n + static_cast<std::size_t>(scratch_order_[rank].second)] =
          static_cast<std::uint8_t>(divisor);
    }
  }
  interest_dirty_ = false;
}

void Room::acknowledge(const Member& to, wire::SnapshotHeader& header) {
  header.posture_ack = to.ack;
  header.ack_flags = static_cast<std::uint8_t>((to.has_ack ? wire::kAckValid : 0) |
                                               (to.want_keyframe ? wire::kAckWantKeyframe : 0));
}

void Room::forward(double now, Effects& fx) {
  if (interest_dirty_) updateInterest();
  const std::size_t n = members_.size();
  wire::SnapshotHeader header;
  header.tick = tick_;
  header.server_time = now;
  for (std::size_t t = 0; t < n; ++t) {
    Member& to = members_[t];
    if (!to.bound) continue;
    acknowledge(to, header);
    // The fresh records this member hears, in room order, packed into as few datagrams
    // as fit (entries only: no world part).
    OutDatagram* out = nullptr;
    int count = 0;
    for (std::size_t f = 0; f < n; ++f) {
      const Member& from = members_[f];
      const std::uint8_t divisor = interest_[t * n + f];
      if (!from.fresh || divisor == 0 || from.accepted % divisor != 0) continue;
      const std::size_t entry = wire::kSnapshotEntryOverhead + from.record_bytes.size();
      if (out != nullptr &&
          (out->bytes.size() + entry > wire::kMaxPlainDatagramBytes || count == 255)) {
        wire::finishSnapshot(static_cast<std::uint8_t>(count), out->bytes);
        to.out.seal(wire::kServerHeaderBytes, out->bytes);
        out = nullptr;
      }
      if (out == nullptr) {
        out = &fx.datagrams.emplace_back();
        out->to = to.endpoint;
        out->bytes.reserve(wire::kMaxDatagramBytes);
        wire::beginSnapshot(header, out->bytes);
        count = 0;
      }
      wire::appendSnapshotEntry(from.id.value, from.record_bytes, out->bytes);
      ++count;
      ++entries_forwarded_;
    }
    if (out != nullptr) {
      wire::finishSnapshot(static_cast<std::uint8_t>(count), out->bytes);
      to.out.seal(wire::kServerHeaderBytes, out->bytes);
    }
  }
  for (Member& m : members_) m.fresh = false;
  forward_pending_ = false;
  last_forward_ = now;
}

void Room::sendWorld(double now, Effects& fx) {
  const auto parts = world_.parts();
  wire::SnapshotHeader header;
  header.tick = tick_;
  header.server_time = now;
  for (Member& to : members_) {
    if (!to.bound) continue;
    acknowledge(to, header);
    for (std::size_t part = 0; part < parts.size(); ++part) {
      OutDatagram& out = fx.datagrams.emplace_back();
      out.to = to.endpoint;
      out.bytes.reserve(wire::kMaxDatagramBytes);
      header.prop_count = parts[part].prop_count;
      header.part = static_cast<std::uint8_t>(part);
      header.part_count = static_cast<std::uint8_t>(parts.size());
      wire::beginSnapshot(header, out.bytes);
      wire::appendSnapshotWorld(parts[part].bytes, out.bytes);
      wire::finishSnapshot(0, out.bytes);
      to.out.seal(wire::kServerHeaderBytes, out.bytes);
    }
  }
}

}  // namespace vistel::server
