#include "client/net/client_session.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "control.pb.h"

namespace vistel::net {
namespace {

constexpr std::size_t kPendingPings = 16;

// True when tick a is after tick b (serial arithmetic on u32).
bool tickAfter(std::uint32_t a, std::uint32_t b) { return static_cast<std::int32_t>(a - b) > 0; }

// The ball a PropInfo describes, or nullopt when a field is out of range.
std::optional<BallSpec> ballOf(const control::PropInfo& info) {
  const auto in = [](float v, float lo, float hi) {
    return std::isfinite(v) && v >= lo && v <= hi;
  };
  if (info.kind() != control::PropInfo::BALL || !in(info.radius(), 0.01f, 2.0f) ||
      !in(info.reach(), 1.05f, 4.0f) || !in(info.stiffness(), 0.0f, 1e12f) ||
      !in(info.time_constant(), 1e-4f, 1e4f) || !in(info.mass(), 1e-6f, 1e6f) ||
      !in(info.restitution(), 0.0f, 1.0f) || info.elasticity() < 0 || info.elasticity() > 2) {
    return std::nullopt;
  }
  BallSpec b;
  b.radius = info.radius();
  b.reach = info.reach();
  b.stiffness = info.stiffness() > 0.0f ? info.stiffness() : kRigidStiffness;
  b.elasticity = static_cast<Elasticity>(info.elasticity());
  b.time_constant = info.time_constant();
  return b;
}

std::span<const std::uint32_t> dentValues(const google::protobuf::RepeatedField<std::uint32_t>& f) {
  return {f.data(), static_cast<std::size_t>(f.size())};
}

}  // namespace

const char* sessionStateName(SessionState state) {
  switch (state) {
    case SessionState::kJoining:
      return "joining";
    case SessionState::kHandshaking:
      return "handshaking";
    case SessionState::kLive:
      return "live";
    case SessionState::kClosed:
      return "closed";
  }
  return "?";
}

ClientSession::ClientSession(SessionSettings settings, std::shared_ptr<AvatarCache> cache)
    : settings_(std::move(settings)),
      cache_(std::move(cache)),
      decoder_(settings_.max_frame_bytes),
      clock_(settings_.clock_window) {}

ClientSession::~ClientSession() = default;

void ClientSession::sendControl(const std::string& payload) {
  wire::appendFrame(
      std::span(reinterpret_cast<const std::uint8_t*>(payload.data()), payload.size()),
      outbox_.stream);
}

void ClientSession::close(const std::string& reason, CloseCause cause) {
  if (state_ == SessionState::kClosed) return;
  state_ = SessionState::kClosed;
  error_ = reason;
  close_cause_ = cause;
  outbox_.close = true;
}

void ClientSession::start(double now) {
  state_ = SessionState::kJoining;
  state_since_ = now;
  control::ClientMessage msg;
  control::Join& join = *msg.mutable_join();
  join.set_protocol_version(kProtocolVersion);
  join.set_room(settings_.room);
  join.set_name(settings_.name);
  if (!settings_.token.empty()) join.set_token(settings_.token);
  join.set_avatar_hash(settings_.avatar_hash);
  join.set_avatar_size(settings_.avatar_bytes ? settings_.avatar_bytes->size() : 0);
  const bool fixed_key =
      std::any_of(settings_.fixed_udp_private_key.begin(), settings_.fixed_udp_private_key.end(),
                  [](std::uint8_t b) { return b != 0; });
  auto exchange = fixed_key ? wire::KeyExchange::fromPrivateKey(settings_.fixed_udp_private_key)
                            : wire::KeyExchange::generate();
  if (!exchange) {
    close("UDP key generation failed: " + exchange.error().message);
    return;
  }
  exchange_.emplace(std::move(*exchange));
  join.set_udp_public_key(exchange_->publicKey().data(), exchange_->publicKey().size());
  if (settings_.resume_member_id != 0) {
    join.set_resume_member_id(settings_.resume_member_id);
    const wire::ResumeProof proof =
        wire::resumeProof(settings_.resume_secret, exchange_->publicKey());
    join.set_resume_proof(proof.data(), proof.size());
  }
  sendControl(msg.SerializeAsString());
}

bool ClientSession::requestBall() {
  if (state_ != SessionState::kHandshaking && state_ != SessionState::kLive) return false;
  control::ClientMessage msg;
  msg.mutable_spawn_prop()->set_kind(control::SpawnProp::BALL);
  sendControl(msg.SerializeAsString());
  return true;
}

bool ClientSession::sendDents(const BodyDents& dents) {
  if (state_ != SessionState::kLive) return false;
  const DentRecord& r = dents.record;
  if (!checkDents(r.vertex_count, r.gaps, r.depths, r.gaps.size()) ||
      !std::isfinite(dents.server_time)) {
    return false;
  }
  control::ClientMessage msg;
  control::Dents& d = *msg.mutable_dents();
  d.set_body_id(dents.body_id);
  d.set_prop(dents.prop);
  d.set_vertex_count(r.vertex_count);
  d.set_server_time(dents.server_time);
  d.mutable_gaps()->Add(r.gaps.begin(), r.gaps.end());
  d.mutable_depths()->Add(r.depths.begin(), r.depths.end());
  sendControl(msg.SerializeAsString());
  ++stats_.dents_sent;
  return true;
}

void ClientSession::handleDents(const control::Dents& dents) {
  if (Status st =
          checkDents(dents.vertex_count(), dentValues(dents.gaps()), dentValues(dents.depths()),
                     static_cast<std::size_t>(dents.gaps_size()));
      !st || !std::isfinite(dents.server_time())) {
    ++stats_.dents_rejected;
    spdlog::warn("server relayed {} {:#x}'s dents from member {:#x}: {}",
                 dents.prop() ? "prop" : "avatar", dents.body_id(), dents.member(),
                 st ? std::string("a non-finite time") : st.error().message);
    return;
  }
  ++stats_.dents_received;
  auto it = std::find_if(received_dents_.begin(), received_dents_.end(), [&](const BodyDents& d) {
    return d.prop == dents.prop() && d.body_id == dents.body_id();
  });
  BodyDents& out = it != received_dents_.end() ? *it : received_dents_.emplace_back();
  out.prop = dents.prop();
  out.body_id = dents.body_id();
  out.member = dents.member();
  out.server_time = dents.server_time();
  out.record.vertex_count = dents.vertex_count();
  out.record.gaps.assign(dents.gaps().begin(), dents.gaps().end());
  out.record.depths.assign(dents.depths().begin(), dents.depths().end());
}

void ClientSession::leave(const std::string& reason) {
  if (state_ == SessionState::kClosed) return;
  control::ClientMessage msg;
  msg.mutable_leave()->set_reason(reason);
  sendControl(msg.SerializeAsString());
  close("left: " + reason, CloseCause::kLeft);
  error_.clear();
}

// ---------------------------------------------------------------- TCP

void ClientSession::onStreamBytes(std::span<const std::uint8_t> bytes, double now) {
  if (state_ == SessionState::kClosed) return;
  if (!decoder_.push(bytes)) {
    close("server stream: " + decoder_.error());
    return;
  }
  while (state_ != SessionState::kClosed) {
    auto payload = decoder_.next();
    if (!payload) {
      if (decoder_.broken()) close("server stream: " + decoder_.error());
      return;
    }
    control::ServerMessage msg;
    if (!msg.ParseFromArray(payload->data(), static_cast<int>(payload->size())) ||
        msg.body_case() == control::ServerMessage::BODY_NOT_SET) {
      close(fmt::format("server sent an unparsable control message ({} bytes)", payload->size()));
      return;
    }
    handleMessage(msg, now);
  }
}

void ClientSession::handleMessage(const control::ServerMessage& msg, double now) {
  switch (msg.body_case()) {
    case control::ServerMessage::kWelcome: {
      const control::Welcome& w = msg.welcome();
      if (state_ != SessionState::kJoining || w.member_id() == 0 ||
          !(w.tick_rate_hz() > 0.0 && w.tick_rate_hz() <= 1000.0)) {
        close("server sent an unexpected or invalid Welcome");
        return;
      }
      member_id_ = w.member_id();
      if (!deriveKeys(w)) return;
      room_name_ = w.room();
      tick_rate_hz_ = w.tick_rate_hz();
      clock_.seed(w.server_time(), now);
      spdlog::info("joined room '{}' as member {:#x} ({} Hz ticks)", w.room(), member_id_,
                   tick_rate_hz_);
      if (w.upload_avatar()) {
        avatar_pending_ = true;  // postures wait until the server has the avatar
        uploadAvatar(std::clamp<std::size_t>(w.max_chunk_bytes(), 256, 1u << 20));
      } else if (w.avatar_pending()) {
        avatar_pending_ = true;  // another member uploads the same file
        spdlog::info("the server is receiving our avatar from another member; waiting");
      }
      // Start the UDP handshake at once.
      state_ = SessionState::kHandshaking;
      state_since_ = now;
      next_hello_ = now;
      sendHello(now);
      return;
    }
    case control::ServerMessage::kRoster:
      handleRoster(msg.roster());
      return;
    case control::ServerMessage::kDents:
      handleDents(msg.dents());
      return;
    case control::ServerMessage::kAvatarChunk:
      handleChunk(msg.avatar_chunk());
      return;
    case control::ServerMessage::kAvatarAccepted:
      if (msg.avatar_accepted().hash() == settings_.avatar_hash) avatar_pending_ = false;
      spdlog::info("server accepted our avatar {}", msg.avatar_accepted().hash().substr(0, 12));
      return;
    case control::ServerMessage::kAvatarMissing: {
      auto it = downloads_.find(msg.avatar_missing().hash());
      if (it != downloads_.end()) downloads_.erase(it);  // retried on the next roster
      return;
    }
    case control::ServerMessage::kUploadAvatar:
      // The upload we waited for failed: ours takes over.
      if (msg.upload_avatar().hash() != settings_.avatar_hash) return;
      avatar_pending_ = true;
      uploadAvatar(std::clamp<std::size_t>(msg.upload_avatar().max_chunk_bytes(), 256, 1u << 20));
      return;
    case control::ServerMessage::kError: {
      // Sorted for the driver: busy (a hint), gone (the server went away or dropped us),
      // taken (name or room), or refused for good.
      const float hint = msg.error().retry_after_s();
      const bool busy = std::isfinite(hint) && hint > 0.0f;
      CloseCause cause = CloseCause::kRefused;
      switch (msg.error().code()) {
        case control::ErrorReply::TIMEOUT:
        case control::ErrorReply::SHUTTING_DOWN:
          cause = CloseCause::kLost;
          break;
        case control::ErrorReply::NAME_TAKEN:
        case control::ErrorReply::ROOM_FULL:
          cause = CloseCause::kTaken;
          break;
        default:
          break;
      }
      if (busy) cause = CloseCause::kBusy;
      close(fmt::format("server: {}: {}", control::ErrorReply::Code_Name(msg.error().code()),
                        msg.error().message()),
            cause);
      if (busy) retry_after_s_ = std::min(3600.0, double{hint});
      return;
    }
    case control::ServerMessage::BODY_NOT_SET:
      return;
  }
}

void ClientSession::uploadAvatar(std::size_t chunk_bytes) {
  if (!settings_.avatar_bytes || settings_.avatar_bytes->empty()) {
    close("the server asks for our avatar but we have no avatar file", CloseCause::kRefused);
    return;
  }
  const std::vector<std::uint8_t>& bytes = *settings_.avatar_bytes;
  control::ClientMessage msg;
  control::AvatarChunk& chunk = *msg.mutable_avatar_chunk();
  chunk.set_hash(settings_.avatar_hash);
  chunk.set_total_size(bytes.size());
  for (std::size_t offset = 0; offset < bytes.size(); offset += chunk_bytes) {
    const std::size_t n = std::min(chunk_bytes, bytes.size() - offset);
    chunk.set_offset(offset);
    chunk.set_data(reinterpret_cast<const char*>(bytes.data() + offset), n);
    sendControl(msg.SerializeAsString());
  }
  spdlog::info("uploading our avatar ({} bytes)", bytes.size());
}

void ClientSession::handleRoster(const control::Roster& roster) {
  // Rebuild the list in the server's order, keeping existing members' buffers.
  std::vector<std::unique_ptr<RemoteMember>> next;
  for (const control::MemberInfo& info : roster.members()) {
    std::unique_ptr<RemoteMember> m;
    for (auto& old : members_) {
      if (old && old->id == info.member_id()) m = std::move(old);
    }
    if (!m) {
      m = std::make_unique<RemoteMember>();
      m->buffer = JitterBuffer(settings_.jitter_capacity);
      if (info.member_id() != member_id_) {
        spdlog::info("member '{}' ({:#x}) is in the room", info.name(), info.member_id());
      }
    }
    m->id = info.member_id();
    m->name = info.name();
    m->avatar_hash = info.avatar_hash();
    const int joints = static_cast<int>(std::min<std::uint32_t>(info.joint_count(), 255));
    if (joints != m->joint_count) m->buffer.clear();
    m->joint_count = joints;
    m->avatar_ready = info.avatar_ready();
    m->seat = Seat{info.seat().x(), info.seat().z(), info.seat().yaw()};
    m->is_self = m->id == member_id_;
    next.push_back(std::move(m));
  }
  for (auto& old : members_) {
    if (old) spdlog::info("member '{}' ({:#x}) left the room", old->name, old->id);
  }
  members_ = std::move(next);
  handleProps(roster);
  ++roster_version_;
  requestMissingAvatars();
}

void ClientSession::handleProps(const control::Roster& roster) {
  // The new list in the server's order, keeping the tracks of props that stay.
  std::vector<std::unique_ptr<RemoteProp>> next;
  for (const control::PropInfo& info : roster.props()) {
    const auto ball = ballOf(info);
    if (!ball) {
      spdlog::warn("prop {:#x}: invalid description from the server: ignored", info.prop_id());
      continue;
    }
    std::unique_ptr<RemoteProp> p;
    for (auto& old : props_) {
      if (old && old->id == info.prop_id()) p = std::move(old);
    }
    if (!p) {
      p = std::make_unique<RemoteProp>();
      p->track = PropTrack(settings_.prop_track_capacity);
    }
    p->id = info.prop_id();
    p->ball = *ball;
    p->mass = info.mass();
    p->restitution = info.restitution();
    p->spawned_by = info.spawned_by();
    next.push_back(std::move(p));
  }
  props_ = std::move(next);
}

void ClientSession::requestMissingAvatars() {
  if (!cache_ || !settings_.fetch_avatars) return;
  for (const auto& m : members_) {
    if (m->is_self || !m->avatar_ready || downloads_.count(m->avatar_hash)) continue;
    if (cache_->find(m->avatar_hash)) continue;
    downloads_[m->avatar_hash] = Download{};
    control::ClientMessage msg;
    msg.mutable_avatar_request()->set_hash(m->avatar_hash);
    sendControl(msg.SerializeAsString());
    spdlog::info("fetching avatar {} of '{}'", m->avatar_hash.substr(0, 12), m->name);
  }
}

void ClientSession::handleChunk(const control::AvatarChunk& chunk) {
  auto it = downloads_.find(chunk.hash());
  if (it == downloads_.end() || it->second.failed) return;  // not asked for
  Download& d = it->second;
  // The chunks must continue one file of a sane size.
  if (d.bytes.empty()) d.total = chunk.total_size();
  if (chunk.total_size() != d.total || d.total == 0 || d.total > settings_.max_avatar_bytes ||
      chunk.offset() != d.bytes.size() || chunk.data().empty() ||
      d.bytes.size() + chunk.data().size() > d.total) {
    spdlog::warn("avatar {}: inconsistent chunk from the server (offset {}, {} bytes of {})",
                 chunk.hash().substr(0, 12), chunk.offset(), chunk.data().size(),
                 chunk.total_size());
    d.failed = true;
    d.bytes.clear();
    return;
  }
  d.bytes.insert(d.bytes.end(), chunk.data().begin(), chunk.data().end());
  if (d.bytes.size() < d.total) return;
  auto model = cache_->insert(chunk.hash(), d.bytes);
  d.bytes = {};
  if (!model) {
    spdlog::warn("{}", model.error().message);
    d.failed = true;
    return;
  }
  spdlog::info("avatar {} received ({} joints)", chunk.hash().substr(0, 12),
               (*model)->skeleton.jointCount());
}

void ClientSession::onDisconnected(const std::string& reason, double /*now*/) {
  if (state_ != SessionState::kClosed) close("disconnected: " + reason);
}

// ---------------------------------------------------------------- UDP

bool ClientSession::deriveKeys(const control::Welcome& w) {
  const auto server_public = std::span(
      reinterpret_cast<const std::uint8_t*>(w.udp_public_key().data()), w.udp_public_key().size());
  auto shared = exchange_ ? exchange_->sharedSecret(server_public)
                          : Result<std::array<std::uint8_t, 32>>(fail("no key pair"));
  if (!shared) {
    close("server sent a Welcome without a valid UDP public key: " + shared.error().message);
    return false;
  }
  wire::PublicKey server{};
  std::copy(server_public.begin(), server_public.end(), server.begin());
  auto keys =
      wire::deriveSessionKeys(*shared, exchange_->publicKey(), server, member_id_, w.room());
  if (!keys) {
    close("UDP key derivation failed: " + keys.error().message);
    return false;
  }
  keys_ = *keys;
  uplink_ = wire::DatagramSealer{keys_.client_to_server};
  downlink_ = wire::DatagramOpener{keys_.server_to_client, {}};
  hello_downlink_ = wire::DatagramOpener{keys_.server_hello, {}};
  exchange_.reset();  // the private key is not needed again
  return true;
}

void ClientSession::sendHello(double now) {
  wire::HelloPacket hello;
  hello.header.member_id = member_id_;
  hello.attempt = ++hello_attempt_;
  hello.cookie = hello_cookie_;
  std::vector<std::uint8_t>& out = outbox_.datagrams.emplace_back();
  wire::write(hello, out);
  uplink_.seal(wire::kClientHeaderBytes, out);
  next_hello_ = now + settings_.hello_interval_s;
}

void ClientSession::sendPing(double now) {
  wire::PingPacket ping;
  ping.header.member_id = member_id_;
  ping.ping_id = ++ping_id_;
  ping.client_time = now;
  std::vector<std::uint8_t>& out = outbox_.datagrams.emplace_back();
  wire::write(ping, out);
  uplink_.seal(wire::kClientHeaderBytes, out);
  if (pending_pings_.size() >= kPendingPings) pending_pings_.erase(pending_pings_.begin());
  pending_pings_.emplace_back(ping.ping_id, now);
  const bool fast = static_cast<int>(ping_id_) < settings_.fast_pings;
  next_ping_ = now + (fast ? settings_.fast_ping_interval_s : settings_.ping_interval_s);
}

void ClientSession::onDatagram(std::span<const std::uint8_t> sealed, double now) {
  if (state_ != SessionState::kHandshaking && state_ != SessionState::kLive) return;
  stats_.datagram_bytes_received += sealed.size();
  const auto type = wire::peekPacketType(sealed);
  if (!type) {
    ++stats_.datagrams_rejected;
    return;
  }
  // Open it (WIRE.md §3.9): hello acks under the lobby's key, the rest under the room's;
  // a datagram that does not verify, or one seen before, is rejected unread.
  scratch_datagram_.assign(sealed.begin(), sealed.end());
  wire::DatagramOpener& opener = *type == wire::PacketType::kHelloAck ? hello_downlink_ : downlink_;
  std::size_t plain_size = 0;
  std::string_view refused;
  if (!opener.open(wire::kServerHeaderBytes, scratch_datagram_, plain_size, refused)) {
    ++stats_.datagrams_rejected;
    return;
  }
  const std::span<const std::uint8_t> datagram = std::span(scratch_datagram_).first(plain_size);
  if (type == wire::PacketType::kHelloAck) {
    wire::HelloAckPacket ack;
    if (!wire::read(datagram, ack) || ack.member_id != member_id_) {
      ++stats_.datagrams_rejected;
      return;
    }
    if (ack.cookie != 0) {
      // A challenge: our address is bound once we echo it (WIRE.md §3.2). In kLive it
      // means the server sees us at a new address (NAT rebinding). A challenge is not a
      // sign of life: a server that only challenges still times out.
      if ((state_ == SessionState::kHandshaking || rebinding_) && ack.cookie != hello_cookie_) {
        hello_cookie_ = ack.cookie;
        rebind_challenged_ = rebinding_;
        sendHello(now);
      }
      return;
    }
    last_server_datagram_ = now;
    if (state_ == SessionState::kHandshaking) {
      state_ = SessionState::kLive;
      state_since_ = now;
      next_ping_ = now;
      spdlog::info("UDP handshake done after {} hello(s)", hello_attempt_);
    } else if (rebinding_) {
      rebinding_ = false;
      ++stats_.udp_rehellos;
      if (rebind_challenged_) ++stats_.udp_rebinds;
      spdlog::info(rebind_challenged_ ? "the server moved us to our new UDP address"
                                      : "the server answers our UDP hellos again");
    }
  } else if (type == wire::PacketType::kPong) {
    wire::PongPacket pong;
    if (!wire::read(datagram, pong)) {
      ++stats_.datagrams_rejected;
      return;
    }
    // Only answers to our own recent pings count.
    auto it = std::find_if(pending_pings_.begin(), pending_pings_.end(),
                           [&](const auto& p) { return p.first == pong.ping_id; });
    if (it == pending_pings_.end()) {
      ++stats_.datagrams_rejected;
      return;
    }
    const double sent_at = it->second;
    pending_pings_.erase(it);
    last_server_datagram_ = now;
    clock_.addSample(sent_at, pong.server_time, now);
  } else if (type == wire::PacketType::kSnapshot) {
    handleSnapshot(datagram, now);
  } else if (type == wire::PacketType::kVoiceForward) {
    handleVoice(datagram, now);
  } else {
    ++stats_.datagrams_rejected;
  }
}

void ClientSession::handleSnapshot(std::span<const std::uint8_t> datagram, double now) {
  if (!wire::readSnapshot(datagram, snapshot_)) {
    ++stats_.datagrams_rejected;
    return;
  }
  const wire::SnapshotHeader& header = snapshot_.header;
  last_server_datagram_ = now;
  ++stats_.snapshots_received;
  // What the server holds of our posture stream.
  if (encoder_) {
    if ((header.ack_flags & wire::kAckValid) != 0) encoder_->acknowledge(header.posture_ack);
    if ((header.ack_flags & wire::kAckWantKeyframe) != 0) encoder_->requestKeyframe();
  }
  // Prop states of roster props.
  for (const wire::PropStateRecord& state : snapshot_.props) {
    for (auto& p : props_) {
      if (p->id != state.prop_id) continue;
      p->track.push(header.tick, PropSample{header.server_time, wire::propPosition(state),
                                            wire::propVelocity(state)});
    }
  }
  if (header.part_count > 0) handleInteractionPart(snapshot_);
  for (const wire::SnapshotEntry& e : snapshot_.entries) {
    // Only roster members, with the joint count their avatar has.
    RemoteMember* m = nullptr;
    for (auto& candidate : members_) {
      if (candidate->id == e.member_id) m = candidate.get();
    }
    if (m == nullptr || m->is_self || e.record.joint_count != m->joint_count) continue;
    wire::decodePostureRecord(e.record, header.server_time, scratch_posture_);
    if (m->buffer.push(e.record.sequence, scratch_posture_) != JitterBuffer::Push::kAccepted) {
      continue;
    }
    // Stats: distinct postures per sender; latency once the clock is measured.
    MemberReceiveStats& s = stats_.members[m->name];
    if (s.postures_received == 0) s.first_arrival = now;
    s.last_arrival = now;
    ++s.postures_received;
    if (clock_.synced()) {
      stats_.latency.add((clock_.serverTime(now) - scratch_posture_.time) * 1e3);
    }
  }
}

void ClientSession::handleInteractionPart(const wire::Snapshot& snapshot) {
  const wire::SnapshotHeader& h = snapshot.header;
  // Parts of ticks older than the newest complete list are late; a newer tick restarts
  // the assembly.
  if (interactions_version_ > 0 && !tickAfter(h.tick, interactions_.tick)) return;
  if (pending_part_count_ == 0 || tickAfter(h.tick, pending_interactions_.tick)) {
    pending_interactions_.tick = h.tick;
    pending_interactions_.server_time = h.server_time;
    pending_interactions_.truncated = false;
    pending_interactions_.self_omitted = false;
    pending_interactions_.pairs.clear();
    pending_part_count_ = h.part_count;
    pending_parts_ = 0;
  } else if (h.tick != pending_interactions_.tick) {
    return;  // older than the one being assembled
  }
  const std::uint32_t bit = 1u << h.part;
  if (h.part_count != pending_part_count_ || (pending_parts_ & bit) != 0) return;
  pending_parts_ |= bit;

  // This part's pairs, named by the server's ids.
  const wire::InteractionSection& x = snapshot.interactions;
  const auto m = x.member_ids.size();
  const auto ref = [&](std::uint8_t body, std::uint16_t prim) {
    ServerBodyPrim r;
    r.is_prop = body >= m;
    r.id = r.is_prop ? x.prop_ids[body - m] : x.member_ids[body];
    r.prim = prim;
    return r;
  };
  for (const wire::WirePair& p : x.pairs) {
    pending_interactions_.pairs.push_back({ref(p.body_a, p.prim_a), ref(p.body_b, p.prim_b)});
  }
  if ((x.flags & wire::kInteractionsTruncated) != 0) pending_interactions_.truncated = true;
  if ((x.flags & wire::kInteractionsSelfOmitted) != 0) pending_interactions_.self_omitted = true;

  // All parts here: it becomes the newest list.
  const std::uint32_t all =
      pending_part_count_ >= 32 ? 0xFFFFFFFFu : (1u << pending_part_count_) - 1u;
  if (pending_parts_ == all) {
    std::swap(interactions_, pending_interactions_);
    ++interactions_version_;
    pending_part_count_ = 0;
  }
}

void ClientSession::handleVoice(std::span<const std::uint8_t> datagram, double now) {
  wire::VoiceForwardPacket packet;
  const RemoteMember* speaker = nullptr;
  if (wire::readVoiceForward(datagram, packet)) speaker = findMember(packet.speaker_id);
  if (speaker == nullptr || speaker->is_self) {
    ++stats_.datagrams_rejected;
    ++voice_.counters.rejected;
    return;
  }
  last_server_datagram_ = now;
  ++voice_.counters.received;
  voice_.counters.bytes_received += datagram.size() + wire::kSealOverheadBytes;
  ReceivedVoice& frame = voice_.push();
  frame.speaker_id = packet.speaker_id;
  frame.sequence = packet.frame.sequence;
  frame.capture_time = packet.frame.capture_time;
  frame.level = packet.frame.level;
  frame.arrival = now;
  frame.size = static_cast<std::uint16_t>(packet.payload.size());
  std::copy(packet.payload.begin(), packet.payload.end(), frame.payload.begin());
}

bool ClientSession::sendVoice(const OutgoingVoice& frame) {
  if (state_ != SessionState::kLive) return false;
  wire::VoicePacket packet;
  packet.header.member_id = member_id_;
  packet.frame.sequence = static_cast<std::uint16_t>(voice_sequence_ + 1);
  packet.frame.capture_time = frame.capture_time;
  packet.frame.level = frame.level;
  packet.payload = frame.payload;
  std::vector<std::uint8_t>& out = outbox_.datagrams.emplace_back();
  if (!wire::writeVoice(packet, out)) {
    outbox_.datagrams.pop_back();
    return false;
  }
  ++voice_sequence_;
  uplink_.seal(wire::kClientHeaderBytes, out);
  ++voice_.counters.sent;
  voice_.counters.bytes_sent += out.size();
  return true;
}

bool ClientSession::sendPosture(const Posture& posture, double now) {
  if (state_ != SessionState::kLive || avatar_pending_) return false;
  if (settings_.avatar_joint_count > 0 &&
      static_cast<int>(posture.rotations.size()) != settings_.avatar_joint_count) {
    return false;
  }
  // Delta-coded against what the server acknowledged (proto/WIRE.md §3.4); the encoder is
  // made for the joint count of the first posture (the avatar's).
  const int joints = static_cast<int>(posture.rotations.size());
  if (!encoder_ || encoder_->options().joint_count != joints) {
    if (joints < 1 || joints > wire::kMaxWireJoints) return false;
    wire::PostureDeltaOptions options;
    options.joint_count = joints;
    encoder_ = std::make_unique<wire::PostureDeltaEncoder>(options);
  }
  scratch_record_bytes_.clear();
  if (!encoder_->encode(posture, ++sequence_, clock_.serverTime(now), false,
                        scratch_record_bytes_)) {
    return false;
  }
  wire::writePostureDatagram({member_id_, 0}, scratch_record_bytes_,
                             outbox_.datagrams.emplace_back());
  uplink_.seal(wire::kClientHeaderBytes, outbox_.datagrams.back());
  ++stats_.postures_sent;
  stats_.posture_bytes_sent += outbox_.datagrams.back().size();
  return true;
}

// ---------------------------------------------------------------- timers

void ClientSession::update(double now) {
  switch (state_) {
    case SessionState::kJoining:
      if (now - state_since_ > settings_.join_timeout_s) {
        close(fmt::format("no Welcome from the server within {:.0f} s", settings_.join_timeout_s),
              CloseCause::kBusy);
        retry_after_s_ = 1.0;  // a busy server: worth another try
      }
      break;
    case SessionState::kHandshaking:
      if (now - state_since_ > settings_.hello_timeout_s) {
        close(
            fmt::format("UDP handshake timed out after {} hellos ({:.0f} s): is UDP to the "
                        "server's port blocked?",
                        hello_attempt_, settings_.hello_timeout_s));
      } else if (now >= next_hello_) {
        sendHello(now);
      }
      break;
    case SessionState::kLive:
      if (now - last_server_datagram_ > settings_.server_timeout_s) {
        close(
            fmt::format("no UDP traffic from the server for {:.0f} s", settings_.server_timeout_s));
        break;
      }
      // The server's datagrams stopped: hello again (a fresh challenge if our address
      // changed) until a plain ack says the server has us at this address.
      if (!rebinding_ && now - last_server_datagram_ > settings_.rehello_after_s) {
        rebinding_ = true;
        rebind_challenged_ = false;
        hello_cookie_ = 0;
        next_hello_ = now;
        spdlog::info("nothing from the server over UDP for {:.1f} s: saying hello again",
                     now - last_server_datagram_);
      }
      if (rebinding_ && now >= next_hello_) sendHello(now);
      if (now >= next_ping_) sendPing(now);
      break;
    case SessionState::kClosed:
      break;
  }
}

// ---------------------------------------------------------------- queries

const RemoteMember* ClientSession::findMember(std::uint32_t id) const {
  for (const auto& m : members_) {
    if (m->id == id) return m.get();
  }
  return nullptr;
}

bool ClientSession::samplePosture(std::uint32_t member_id, double server_time, Posture& out) const {
  const RemoteMember* m = findMember(member_id);
  return m != nullptr && m->buffer.sample(server_time, out);
}

const RemoteProp* ClientSession::findProp(std::uint32_t id) const {
  for (const auto& p : props_) {
    if (p->id == id) return p.get();
  }
  return nullptr;
}

bool ClientSession::sampleProp(std::uint32_t prop_id, double server_time, PropSample& out) const {
  const RemoteProp* p = findProp(prop_id);
  return p != nullptr && p->track.sample(server_time, out);
}

int ClientSession::sceneIndex(const ServerBodyPrim& body) const {
  if (body.is_prop) {
    for (std::size_t k = 0; k < props_.size(); ++k) {
      if (props_[k]->id == body.id) return static_cast<int>(members_.size() + k);
    }
  } else {
    for (std::size_t i = 0; i < members_.size(); ++i) {
      if (members_[i]->id == body.id) return static_cast<int>(i);
    }
  }
  return -1;
}

Status ClientSession::sceneInteractions(std::span<const BodyView> bodies, InteractionList& out,
                                        int* dropped, bool own_pairs) const {
  // Server ids -> scene indices; pairs with a body the caller does not have are left out.
  out.pairs.clear();
  int left_out = 0;
  for (const ServerPair& p : interactions_.pairs) {
    const int a = sceneIndex(p.a);
    const int b = sceneIndex(p.b);
    const auto posed = [&](int i) {
      return i >= 0 && static_cast<std::size_t>(i) < bodies.size() &&
             bodies[static_cast<std::size_t>(i)].posed != nullptr;
    };
    if (!posed(a) || !posed(b)) {
      ++left_out;
      continue;
    }
    out.pairs.push_back(
        {static_cast<std::uint16_t>(a), p.a.prim, static_cast<std::uint16_t>(b), p.b.prim});
  }
  if (dropped != nullptr) *dropped = left_out;
  // Self-contact the server left out: each posed body's own, from the poses given here
  // (the ones drawn).
  if (interactions_.self_omitted && own_pairs) {
    for (std::size_t b = 0; b < bodies.size(); ++b) {
      const BodyView& body = bodies[b];
      if (body.posed == nullptr || body.graph == nullptr) continue;
      appendSelfInteractions(*body.graph, *body.posed, static_cast<std::uint16_t>(b), out.pairs);
    }
  }
  // Canonical order, then the same checks a locally built list would pass.
  finalizeInteractions(out, static_cast<int>(bodies.size()));
  if (Status st = validateInteractions(out, bodies); !st) {
    out.pairs.clear();
    finalizeInteractions(out, static_cast<int>(bodies.size()));
    return fail("interactions of tick {}: {}", interactions_.tick, st.error().message);
  }
  return {};
}

}  // namespace vistel::net
