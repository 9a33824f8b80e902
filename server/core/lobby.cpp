#include "server/core/lobby.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/auth/member_name.hpp"
#include "common/wire/packets.hpp"

namespace vistel::server {
namespace {

bool validRoomName(const std::string& s) {
  if (s.empty() || s.size() > 64) return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '.' || c == '-';
  });
}

constexpr double kMiB = 1024.0 * 1024.0;

CollisionLimits collisionLimits(const ServerConfig& config) {
  CollisionLimits limits;
  limits.max_primitives = config.max_primitives_per_avatar;
  limits.max_extent_m = config.max_primitive_extent_m;
  return limits;
}

control::PropInfo::Elasticity toProto(Elasticity e) {
  switch (e) {
    case Elasticity::kPlastic:
      return control::PropInfo::PLASTIC;
    case Elasticity::kViscoelastic:
      return control::PropInfo::VISCOELASTIC;
    case Elasticity::kElastic:
      break;
  }
  return control::PropInfo::ELASTIC;
}

}  // namespace

Lobby::Lobby(const ServerConfig& config, std::uint64_t seed)
    : config_(config),
      member_ids_(config.max_members),
      room_ids_(config.max_rooms),
      prop_ids_(std::min(65535, std::max(1, config.max_rooms * config.max_props_per_room))),
      store_(collisionLimits(config)),
      seed_(seed),
      rng_(seed) {}

std::uint64_t Lobby::newKey() {
  std::uint64_t key = 0;
  while (key == 0) {
    if (seed_ != 0) {
      key = rng_();
    } else {
      key = (static_cast<std::uint64_t>(device_()) << 32) ^ device_();
    }
  }
  return key;
}

Lobby::Member* Lobby::findMember(std::uint32_t id) {
  auto it = members_.find(id);
  return it == members_.end() ? nullptr : &it->second;
}

std::optional<RoomId> Lobby::roomOf(MemberId member) const {
  auto it = members_.find(member.value);
  if (it == members_.end()) return std::nullopt;
  return it->second.room;
}

void Lobby::send(ConnId conn, const control::ServerMessage& message, Effects& fx) {
  std::string payload;
  message.SerializeToString(&payload);
  OutFrame& f = fx.frames.emplace_back();
  f.conn = conn;
  wire::appendFrame(
      std::span(reinterpret_cast<const std::uint8_t*>(payload.data()), payload.size()), f.bytes);
}

std::vector<PropId> Lobby::propsOf(std::string_view room) const {
  std::vector<PropId> out;
  auto it = room_by_name_.find(std::string(room));
  if (it == room_by_name_.end()) return out;
  for (const PropRecord& p : rooms_.at(it->second).props) out.push_back(p.id);
  return out;
}

void Lobby::onConnect(ConnId conn, double now, Effects& /*fx*/) {
  auto [it, inserted] = connections_.try_emplace(conn, config_.max_frame_bytes);
  if (inserted) {
    it->second.opened_at = now;
    it->second.control = TokenBucket(config_.control_rate_hz, config_.control_burst, now);
  }
}

void Lobby::onStreamBytes(ConnId conn, std::span<const std::uint8_t> bytes, double now,
                          Effects& fx) {
  auto it = connections_.find(conn);
  if (it == connections_.end()) return;  // already closed by us
  Connection& c = it->second;
  if (!c.decoder.push(bytes)) {
    reject(conn, control::ErrorReply::BAD_MESSAGE, c.decoder.error(), now, fx);
    return;
  }
  // Handle every complete frame; a handler may close the connection.
  while (true) {
    auto found = connections_.find(conn);
    if (found == connections_.end()) return;
    auto payload = found->second.decoder.next();
    if (!payload) {
      if (found->second.decoder.broken()) {
        reject(conn, control::ErrorReply::BAD_MESSAGE, found->second.decoder.error(), now, fx);
      }
      return;
    }
    handleMessage(conn, found->second, *payload, now, fx);
  }
}

void Lobby::handleMessage(ConnId conn, Connection& c, std::span<const std::uint8_t> payload,
                          double now, Effects& fx) {
  control::ClientMessage msg;
  if (!msg.ParseFromArray(payload.data(), static_cast<int>(payload.size())) ||
      msg.body_case() == control::ClientMessage::BODY_NOT_SET) {
    reject(conn, control::ErrorReply::BAD_MESSAGE,
           fmt::format("unparsable control message of {} bytes", payload.size()), now, fx);
    return;
  }
  // Rate: every message but the chunks of an announced upload costs a token (an avatar
  // request one more per MiB it makes us send); a sender out of tokens is dropped.
  double cost = 1.0;
  if (msg.body_case() == control::ClientMessage::kAvatarChunk && c.upload_reserved > 0) {
    cost = 0.0;
  } else if (msg.body_case() == control::ClientMessage::kAvatarRequest) {
    if (const StoredAvatar* a = store_.find(msg.avatar_request().hash())) {
      cost += std::ceil(static_cast<double>(a->bytes->size()) / kMiB);
    }
  }
  if (cost > 0.0 && !c.control.take(now, cost)) {
    reject(conn, control::ErrorReply::RATE_LIMITED,
           fmt::format("control messages faster than {:.0f}/s (bursts of {})",
                       config_.control_rate_hz, config_.control_burst),
           now, fx, "control message rate");
    return;
  }
  // Before joining only Join is allowed; after, anything but Join.
  const bool joined = c.member.value != 0;
  switch (msg.body_case()) {
    case control::ClientMessage::kJoin:
      if (joined) {
        reject(conn, control::ErrorReply::BAD_MESSAGE, "second Join on one connection", now, fx);
      } else {
        joining_ = conn;
        handleJoin(conn, c, msg.join(), now, fx);
        joining_.reset();
      }
      return;
    case control::ClientMessage::kLeave:
      if (!joined) break;
      spdlog::info("lobby: member {:#x} leaves: {}", c.member.value,
                   msg.leave().reason().empty() ? "no reason given" : msg.leave().reason());
      endUpload(conn, c, now, fx);
      removeMember(c.member, "left", fx);
      connections_.erase(conn);
      fx.closes.push_back(conn);
      return;
    case control::ClientMessage::kAvatarChunk:
      if (!joined) break;
      handleChunk(conn, c, msg.avatar_chunk(), now, fx);
      return;
    case control::ClientMessage::kAvatarRequest:
      if (!joined) break;
      handleRequest(conn, msg.avatar_request(), now, fx);
      return;
    case control::ClientMessage::kSpawnProp:
      if (!joined) break;
      handleSpawn(c, msg.spawn_prop(), now, fx);
      return;
    case control::ClientMessage::kDents:
      if (!joined) break;
      handleDents(c, msg.dents(), now, fx);
      return;
    case control::ClientMessage::BODY_NOT_SET:
      break;
  }
  reject(conn, control::ErrorReply::BAD_MESSAGE, "expected Join as the first message", now, fx);
}

void Lobby::handleJoin(ConnId conn, Connection& c, const control::Join& join, double now,
                       Effects& fx) {
  // Validate the request.
  if (join.protocol_version() != kProtocolVersion) {
    reject(conn, control::ErrorReply::VERSION_MISMATCH,
           fmt::format("protocol version {} (server speaks {})", join.protocol_version(),
                       kProtocolVersion),
           now, fx);
    return;
  }
  if (!admitToken(conn, join, now, fx)) return;
  if (!validRoomName(join.room())) {
    reject(conn, control::ErrorReply::BAD_JOIN,
           "room name must be 1-64 characters of A-Z a-z 0-9 _ . -", now, fx);
    return;
  }
  if (Status name = auth::validateMemberName(join.name()); !name) {
    reject(conn, control::ErrorReply::BAD_JOIN, name.error().message, now, fx, "bad name");
    return;
  }
  if (!isContentHash(join.avatar_hash())) {
    reject(conn, control::ErrorReply::BAD_JOIN,
           "avatar hash must be 64 lowercase hex characters (SHA-256)", now, fx);
    return;
  }
  const StoredAvatar* stored = store_.find(join.avatar_hash());
  if (stored == nullptr &&
      (join.avatar_size() == 0 || join.avatar_size() > config_.max_avatar_bytes)) {
    reject(conn, control::ErrorReply::AVATAR_REJECTED,
           fmt::format("avatar of {} bytes (the server accepts 1..{})", join.avatar_size(),
                       config_.max_avatar_bytes),
           now, fx);
    return;
  }

  // The UDP key exchange (WIRE.md §3.9): our half now, so that a bad public key is refused
  // before anything is created; the keys once the member id is known.
  auto exchange = wire::KeyExchange::generate();
  if (!exchange) {
    reject(conn, control::ErrorReply::SERVER_FULL, "key generation failed", now, fx, {}, 5.0f);
    return;
  }
  auto shared = exchange->sharedSecret(
      std::span(reinterpret_cast<const std::uint8_t*>(join.udp_public_key().data()),
                join.udp_public_key().size()));
  if (!shared) {
    reject(conn, control::ErrorReply::BAD_JOIN,
           "udp_public_key must be a 32-byte X25519 public key: " + shared.error().message, now,
           fx);
    return;
  }
  // A resumed session (Join.resume_*): the stale member it replaces leaves first, so the
  // name and (when free) the seat pass to the new one. Only the holder of that member's id
  // and a proof from that member's resume secret over this Join's public key can do this: a
  // name alone evicts nobody, and a proof seen on the wire is worth nothing with another key.
  int preferred_seat = -1;
  // The evicted member's reference to the avatar would free a file the new member needs:
  // held for the rest of this function (the new member takes its own).
  struct AvatarHold {
    AvatarStore* store = nullptr;
    std::string hash;
    ~AvatarHold() {
      if (store != nullptr) store->release(hash);
    }
  } hold;
  if (join.resume_member_id() != 0) {
    auto it = room_by_name_.find(join.room());
    Member* stale =
        member_ids_.live(join.resume_member_id()) ? findMember(join.resume_member_id()) : nullptr;
    if (stale != nullptr && it != room_by_name_.end() && stale->room.value == it->second &&
        stale->name == join.name() && stale->conn != conn &&
        wire::resumeProofMatches(
            stale->keys.resume,
            std::span(reinterpret_cast<const std::uint8_t*>(join.udp_public_key().data()),
                      join.udp_public_key().size()),
            std::span(reinterpret_cast<const std::uint8_t*>(join.resume_proof().data()),
                      join.resume_proof().size()))) {
      preferred_seat = stale->seat;
      if (stored != nullptr) {
        store_.addRef(join.avatar_hash());
        hold.store = &store_;
        hold.hash = join.avatar_hash();
      }
      spdlog::info("lobby: '{}' (member {:#x}) resumes on connection {}: the stale member goes",
                   stale->name, stale->id.value, conn);
      reject(stale->conn, control::ErrorReply::TIMEOUT,
             "replaced by a resumed session of the same member", now, fx, "resumed elsewhere");
      stored = store_.find(join.avatar_hash());
    }
  }

  // Find or create the room; check capacity and the name.
  RoomRecord* room = nullptr;
  if (auto it = room_by_name_.find(join.room()); it != room_by_name_.end()) {
    room = &rooms_.at(it->second);
    if (static_cast<int>(room->members.size()) >= config_.max_members_per_room) {
      reject(conn, control::ErrorReply::ROOM_FULL,
             fmt::format("room '{}' is full ({} members)", join.room(), room->members.size()), now,
             fx);
      return;
    }
    for (MemberId other : room->members) {
      if (members_.at(other.value).name == join.name()) {
        reject(conn, control::ErrorReply::NAME_TAKEN,
               fmt::format("name '{}' is taken in room '{}'", join.name(), join.room()), now, fx);
        return;
      }
    }
  }
  if (static_cast<int>(members_.size()) >= config_.max_members) {
    reject(conn, control::ErrorReply::SERVER_FULL, "the server is full", now, fx, {}, 5.0f);
    return;
  }
  // An upload reserves its offered size against the server's total; a join whose avatar
  // is being uploaded already waits for that upload instead.
  const bool wait_for_upload = stored == nullptr && uploader_of_.count(join.avatar_hash()) > 0;
  if (stored == nullptr && !wait_for_upload &&
      upload_bytes_in_flight_ + join.avatar_size() > config_.max_upload_bytes_total) {
    reject(conn, control::ErrorReply::SERVER_FULL,
           fmt::format("too many avatar uploads in progress ({} of {} bytes reserved); try "
                       "again later",
                       upload_bytes_in_flight_, config_.max_upload_bytes_total),
           now, fx, "upload capacity", 1.0f);
    return;
  }
  if (room == nullptr && !mayCreateRoom(conn, c, now, fx)) return;
  if (room == nullptr) {
    const std::uint32_t rid = room_ids_.allocate();
    if (rid == 0) {
      reject(conn, control::ErrorReply::SERVER_FULL, "no more rooms on this server", now, fx, {},
             5.0f);
      return;
    }
    RoomRecord& r = rooms_[rid];
    r.id = RoomId{rid};
    r.name = join.room();
    r.created_at = now;
    r.seat_taken.assign(static_cast<std::size_t>(config_.max_members_per_room), false);
    room_by_name_[r.name] = rid;
    roomOpened(r, c);
    RoomCommand cmd;
    cmd.kind = RoomCommand::Kind::kCreate;
    cmd.room = r.id;
    cmd.name = r.name;
    fx.room_commands.push_back(cmd);
    spdlog::info("lobby: room '{}' created", r.name);
    room = &r;
    // The props every room starts with.
    for (const RoomPropConfig& p : config_.room_props) {
      spawnProp(r, p.spec, MemberId{}, p.position, p.velocity, fx);
    }
  }

  // Create the member: id, key, seat, avatar state.
  const std::uint32_t mid = member_ids_.allocate();
  if (mid == 0) {
    reject(conn, control::ErrorReply::SERVER_FULL, "the server is full", now, fx, {}, 5.0f);
    return;
  }
  wire::PublicKey client_public{};
  std::copy(join.udp_public_key().begin(), join.udp_public_key().end(), client_public.begin());
  auto keys =
      wire::deriveSessionKeys(*shared, client_public, exchange->publicKey(), mid, room->name);
  if (!keys) {
    member_ids_.release(mid);
    reject(conn, control::ErrorReply::SERVER_FULL, "key derivation failed", now, fx, {}, 5.0f);
    return;
  }
  Member& m = members_[mid];
  m.id = MemberId{mid};
  m.keys = *keys;
  m.hello_in.key = keys->client_to_server;
  m.hello_out.key = keys->server_hello;
  m.conn = conn;
  m.room = room->id;
  m.name = join.name();
  m.avatar_hash = join.avatar_hash();
  m.avatar_size = join.avatar_size();
  m.joined_at = now;
  m.dents_bytes = TokenBucket(config_.dents_bytes_per_s, 4.0 * config_.dents_bytes_per_s, now);
  auto free_seat = std::find(room->seat_taken.begin(), room->seat_taken.end(), false);
  if (preferred_seat >= 0 && static_cast<std::size_t>(preferred_seat) < room->seat_taken.size() &&
      !room->seat_taken[static_cast<std::size_t>(preferred_seat)]) {
    free_seat = room->seat_taken.begin() + preferred_seat;  // a resumed member keeps its seat
  }
  m.seat = static_cast<int>(free_seat - room->seat_taken.begin());
  *free_seat = true;
  if (stored != nullptr) {
    m.avatar_ready = true;
    m.joint_count = stored->joint_count;
    store_.addRef(m.avatar_hash);
  } else if (!wait_for_upload) {
    beginUpload(conn, c, m.avatar_hash, m.avatar_size, now);
  }
  room->members.push_back(m.id);
  c.member = m.id;
  ++joins_accepted_;

  RoomCommand add;
  add.kind = RoomCommand::Kind::kAddMember;
  add.room = room->id;
  add.member = m.id;
  add.uplink_key = m.keys.client_to_server;
  add.downlink_key = m.keys.server_to_client;
  add.joint_count = m.joint_count;
  add.seat = seatPlacement(m.seat, config_.seat_layout);
  if (stored != nullptr) add.collision = stored->collision;
  fx.room_commands.push_back(add);

  // Welcome, then the new roster to everyone in the room.
  control::ServerMessage msg;
  control::Welcome& w = *msg.mutable_welcome();
  w.set_protocol_version(kProtocolVersion);
  w.set_member_id(m.id.value);
  w.set_udp_public_key(exchange->publicKey().data(), exchange->publicKey().size());
  w.set_tick_rate_hz(config_.tick_rate_hz);
  w.set_server_time(now);
  w.set_room(room->name);
  w.set_upload_avatar(!m.avatar_ready && !wait_for_upload);
  w.set_avatar_pending(wait_for_upload);
  w.set_max_chunk_bytes(static_cast<std::uint32_t>(config_.avatar_chunk_bytes));
  w.set_max_avatar_bytes(config_.max_avatar_bytes);
  w.set_max_datagram_bytes(static_cast<std::uint32_t>(wire::kMaxDatagramBytes));
  send(conn, msg, fx);
  spdlog::info("lobby: '{}' joined room '{}' as member {:#x} (seat {}, avatar {}{})", m.name,
               room->name, m.id.value, m.seat, m.avatar_hash.substr(0, 12),
               m.avatar_ready    ? ""
               : wait_for_upload ? ", waiting for its upload by another member"
                                 : ", upload requested");
  sendRoster(*room, fx);
  sendKeptDents(*room, conn, fx);
}

void Lobby::handleChunk(ConnId conn, Connection& c, const control::AvatarChunk& chunk, double now,
                        Effects& fx) {
  Member* m = findMember(c.member.value);
  if (m == nullptr) return;
  if (m->avatar_ready || c.upload_reserved == 0) return;  // someone else uploaded it meanwhile
  // The chunk must continue exactly the offered file.
  std::string problem;
  if (chunk.hash() != m->avatar_hash) {
    problem = "chunk for another hash than the one offered at join";
  } else if (chunk.total_size() != m->avatar_size) {
    problem = fmt::format("total size {} differs from the offered {}", chunk.total_size(),
                          m->avatar_size);
  } else if (chunk.offset() != c.upload.size()) {
    problem = fmt::format("chunk at offset {}, expected {}", chunk.offset(), c.upload.size());
  } else if (chunk.data().empty() || chunk.data().size() > config_.avatar_chunk_bytes) {
    problem = fmt::format("chunk of {} bytes (1..{} allowed)", chunk.data().size(),
                          config_.avatar_chunk_bytes);
  } else if (c.upload.size() + chunk.data().size() > m->avatar_size) {
    problem = "chunk runs past the offered size";
  }
  if (!problem.empty()) {
    reject(conn, control::ErrorReply::AVATAR_REJECTED, "avatar upload: " + problem, now, fx);
    return;
  }
  c.upload.insert(c.upload.end(), chunk.data().begin(), chunk.data().end());
  c.upload_progress_at = now;
  if (c.upload.size() < m->avatar_size) return;

  // Complete: validate and store, then everyone waiting for it is ready.
  const std::string hash = m->avatar_hash;
  Status added =
      store_.add(hash, std::move(c.upload), fmt::format("avatar upload from '{}'", m->name));
  if (!added) {
    reject(conn, control::ErrorReply::AVATAR_REJECTED, added.error().message, now, fx);
    return;
  }
  spdlog::info("lobby: avatar {} uploaded by '{}' ({} bytes)", hash.substr(0, 12), m->name,
               m->avatar_size);
  endUpload(conn, c, now, fx);
  avatarBecameReady(hash, fx);
}

void Lobby::avatarBecameReady(const std::string& hash, Effects& fx) {
  const StoredAvatar* stored = store_.find(hash);
  if (stored == nullptr) return;
  std::vector<std::uint32_t> touched_rooms;
  for (auto& [id, m] : members_) {
    if (m.avatar_ready || m.avatar_hash != hash) continue;
    m.avatar_ready = true;
    m.joint_count = stored->joint_count;
    store_.addRef(hash);
    // A member still uploading the same file need not finish (nor hand it over: the
    // store holds the file now).
    if (auto conn = connections_.find(m.conn); conn != connections_.end()) {
      endUpload(m.conn, conn->second, 0.0, fx);
    }
    RoomCommand cmd;
    cmd.kind = RoomCommand::Kind::kSetAvatar;
    cmd.room = m.room;
    cmd.member = m.id;
    cmd.joint_count = m.joint_count;
    cmd.collision = stored->collision;
    fx.room_commands.push_back(cmd);
    control::ServerMessage msg;
    msg.mutable_avatar_accepted()->set_hash(hash);
    send(m.conn, msg, fx);
    if (std::find(touched_rooms.begin(), touched_rooms.end(), m.room.value) ==
        touched_rooms.end()) {
      touched_rooms.push_back(m.room.value);
    }
  }
  store_.pruneUnreferenced();
  for (std::uint32_t rid : touched_rooms) sendRoster(rooms_.at(rid), fx);
}

void Lobby::handleRequest(ConnId conn, const control::AvatarRequest& request, double /*now*/,
                          Effects& fx) {
  const StoredAvatar* stored = store_.find(request.hash());
  control::ServerMessage msg;
  if (stored == nullptr) {
    msg.mutable_avatar_missing()->set_hash(request.hash().substr(0, 64));
    send(conn, msg, fx);
    return;
  }
  // The file in chunks, in order.
  const std::vector<std::uint8_t>& bytes = *stored->bytes;
  control::AvatarChunk& chunk = *msg.mutable_avatar_chunk();
  chunk.set_hash(request.hash());
  chunk.set_total_size(bytes.size());
  for (std::size_t offset = 0; offset < bytes.size(); offset += config_.avatar_chunk_bytes) {
    const std::size_t n = std::min(config_.avatar_chunk_bytes, bytes.size() - offset);
    chunk.set_offset(offset);
    chunk.set_data(reinterpret_cast<const char*>(bytes.data() + offset), n);
    send(conn, msg, fx);
  }
}

void Lobby::beginUpload(ConnId conn, Connection& c, const std::string& hash, std::uint64_t size,
                        double now) {
  c.upload_reserved = size;
  c.upload_hash = hash;
  c.upload_progress_at = now;
  c.upload_started_at = now;
  c.upload_window_at = now;
  c.upload_window_bytes = 0;
  c.upload.clear();
  upload_bytes_in_flight_ += size;
  uploader_of_[hash] = conn;
}

void Lobby::endUpload(ConnId conn, Connection& c, double now, Effects& fx) {
  upload_bytes_in_flight_ -= std::min(upload_bytes_in_flight_, c.upload_reserved);
  c.upload_reserved = 0;
  c.upload = {};  // gives the memory back
  const std::string hash = std::move(c.upload_hash);
  c.upload_hash.clear();
  auto it = uploader_of_.find(hash);
  if (hash.empty() || it == uploader_of_.end() || it->second != conn) return;
  uploader_of_.erase(it);
  if (store_.find(hash) != nullptr) return;  // complete: the waiting members are ready

  // The upload failed or its member left: the longest-waiting member with the same
  // avatar (lowest id among those not ready) takes it over.
  Member* next = nullptr;
  for (auto& [id, m] : members_) {
    if (m.avatar_ready || m.avatar_hash != hash || m.conn == conn) continue;
    if (!connections_.count(m.conn)) continue;
    if (next == nullptr || m.id.value < next->id.value) next = &m;
  }
  if (next == nullptr) return;
  Connection& nc = connections_.at(next->conn);
  if (upload_bytes_in_flight_ + next->avatar_size > config_.max_upload_bytes_total) {
    reject(next->conn, control::ErrorReply::SERVER_FULL,
           "the avatar upload this join waited for failed, and the server has no upload "
           "capacity left; try again later",
           now, fx, "upload capacity", 1.0f);
    return;
  }
  beginUpload(next->conn, nc, hash, next->avatar_size, now);
  spdlog::info("lobby: '{}' (member {:#x}) takes over the upload of avatar {}", next->name,
               next->id.value, hash.substr(0, 12));
  control::ServerMessage msg;
  msg.mutable_upload_avatar()->set_hash(hash);
  msg.mutable_upload_avatar()->set_max_chunk_bytes(
      static_cast<std::uint32_t>(config_.avatar_chunk_bytes));
  send(next->conn, msg, fx);
}

void Lobby::handleSpawn(Connection& c, const control::SpawnProp& spawn, double now, Effects& fx) {
  Member* m = findMember(c.member.value);
  if (m == nullptr) return;
  // Validate: a known kind, props enabled, the member's avatar here, not too often.
  std::string_view problem;
  if (spawn.kind() != control::SpawnProp::BALL) {
    problem = "unknown prop kind";
  } else if (config_.max_props_per_room == 0) {
    problem = "props disabled";
  } else if (!m->avatar_ready) {
    problem = "avatar not ready";
  } else if (now - m->last_spawn < config_.spawn_interval_s) {
    problem = "spawn rate";
  }
  if (!problem.empty()) {
    drops_.drop(now, problem, fmt::format("spawn request of member {:#x} ignored", m->id.value));
    return;
  }
  // Make room: the oldest prop a client spawned goes.
  RoomRecord& room = rooms_.at(m->room.value);
  if (static_cast<int>(room.props.size()) >= config_.max_props_per_room) {
    auto oldest = std::find_if(room.props.begin(), room.props.end(),
                               [](const PropRecord& p) { return p.spawned_by.value != 0; });
    if (oldest == room.props.end()) {
      drops_.drop(now, "room full of props",
                  fmt::format("spawn request of member {:#x} ignored", m->id.value));
      return;
    }
    RoomCommand remove;
    remove.kind = RoomCommand::Kind::kRemoveProp;
    remove.room = room.id;
    remove.prop = oldest->id;
    fx.room_commands.push_back(remove);
    prop_ids_.release(oldest->id.value);
    room.dents.erase(dentsKey(true, oldest->id.value));
    room.props.erase(oldest);
  }
  // Above the member's head (the room knows its posture); the seat's column as fallback.
  const SeatPlacement seat = seatPlacement(m->seat, config_.seat_layout);
  const glm::vec3 fallback(seat.x, 2.3f, seat.z);
  if (!spawnProp(room, config_.spawn_ball, m->id, fallback, glm::vec3(0.0f), fx)) {
    drops_.drop(now, "no free prop id",
                fmt::format("spawn request of member {:#x} ignored", m->id.value));
    return;
  }
  m->last_spawn = now;
  spdlog::info("lobby: '{}' spawned a ball in room '{}'", m->name, room.name);
  sendRoster(room, fx);
}

bool Lobby::spawnProp(RoomRecord& room, const PropSpec& spec, MemberId requester,
                      const glm::vec3& position, const glm::vec3& velocity, Effects& fx) {
  const std::uint32_t id = prop_ids_.allocate();
  if (id == 0) return false;
  room.props.push_back({PropId{id}, spec, requester});
  RoomCommand cmd;
  cmd.kind = RoomCommand::Kind::kSpawnProp;
  cmd.room = room.id;
  cmd.prop = PropId{id};
  cmd.prop_spec = spec;
  cmd.member = requester;
  cmd.position = position;
  cmd.velocity = velocity;
  fx.room_commands.push_back(cmd);
  return true;
}

void Lobby::onHello(std::span<const std::uint8_t> datagram, const wire::Endpoint& from, double now,
                    Effects& fx) {
  // Who claims to send (clear header), then the seal under that member's key with a fresh
  // counter (WIRE.md §3.9): a hello nobody with the member's key sealed, or one seen
  // before, is dropped unanswered, so a forged or replayed hello cannot move a member.
  const auto claimed = wire::peekMemberId(datagram);
  Member* m = claimed && member_ids_.live(*claimed) ? findMember(*claimed) : nullptr;
  if (m == nullptr) {
    drops_.drop(now, "hello for unknown member",
                fmt::format("{} bytes from {}", datagram.size(), from.toString()));
    return;
  }
  if (datagram.size() > wire::kMaxDatagramBytes) {
    drops_.drop(now, "malformed hello",
                fmt::format("{} bytes from {}", datagram.size(), from.toString()));
    return;
  }
  scratch_datagram_.assign(datagram.begin(), datagram.end());
  std::size_t plain_size = 0;
  std::string_view refused;
  if (!m->hello_in.open(wire::kClientHeaderBytes, scratch_datagram_, plain_size, refused)) {
    drops_.drop(now, refused == "bad datagram tag" ? "hello with bad tag" : refused,
                fmt::format("hello for member {:#x} from {}", m->id.value, from.toString()));
    return;
  }
  wire::HelloPacket hello;
  if (!wire::read(std::span(scratch_datagram_).first(plain_size), hello)) {
    drops_.drop(now, "malformed hello",
                fmt::format("{} bytes from {}", datagram.size(), from.toString()));
    return;
  }
  // An address is bound only once it has shown that it receives what is sent to it: the
  // first hello from it gets a challenge (a random cookie, 18 bytes for the 26 of the
  // hello), and only a hello echoing that cookie binds it. So a forged source address gets
  // one small datagram and no stream. A bound member's hello from a new address (NAT
  // rebinding) goes through the same check and then moves the member there.
  const bool at_bound_address = m->bound && m->endpoint == from;
  if (!at_bound_address) {
    if (hello.cookie == 0 || hello.cookie != m->challenge || !(m->challenged == from)) {
      // One challenge per address until it is answered: hellos retried while the first
      // challenge travels get the same cookie, so a slow link cannot chase a new one.
      if (m->challenge == 0 || !(m->challenged == from)) {
        m->challenged = from;
        m->challenge = newKey();
      }
      wire::HelloAckPacket challenge;
      challenge.member_id = m->id.value;
      challenge.attempt = hello.attempt;
      challenge.cookie = m->challenge;
      OutDatagram& out = fx.datagrams.emplace_back();
      out.to = from;
      wire::write(challenge, out.bytes);
      m->hello_out.seal(wire::kServerHeaderBytes, out.bytes);
      return;
    }
    auto taken = member_by_endpoint_.find(from);
    if (taken != member_by_endpoint_.end()) {
      drops_.drop(now, "endpoint already bound",
                  fmt::format("{} belongs to member {:#x}", from.toString(), taken->second));
      return;
    }
    if (m->bound) {
      spdlog::info("lobby: member {:#x} '{}' moves from {} to {}", m->id.value, m->name,
                   m->endpoint.toString(), from.toString());
      member_by_endpoint_.erase(m->endpoint);
    } else {
      spdlog::info("lobby: member {:#x} '{}' bound UDP endpoint {}", m->id.value, m->name,
                   from.toString());
    }
    m->bound = true;
    m->endpoint = from;
    m->challenge = 0;
    member_by_endpoint_[from] = m->id.value;
    RoomCommand cmd;
    cmd.kind = RoomCommand::Kind::kBindEndpoint;
    cmd.room = m->room;
    cmd.member = m->id;
    cmd.endpoint = from;
    fx.room_commands.push_back(cmd);
  }
  // Bound here: ack (18 bytes for a 26-byte hello; repeated hellos get repeated acks).
  wire::HelloAckPacket ack;
  ack.member_id = m->id.value;
  ack.attempt = hello.attempt;
  OutDatagram& out = fx.datagrams.emplace_back();
  out.to = from;
  wire::write(ack, out.bytes);
  m->hello_out.seal(wire::kServerHeaderBytes, out.bytes);
}

void Lobby::onDisconnect(ConnId conn, double now, Effects& fx) {
  auto it = connections_.find(conn);
  if (it == connections_.end()) return;
  endUpload(conn, it->second, now, fx);
  if (it->second.member.value != 0) removeMember(it->second.member, "disconnected", fx);
  connections_.erase(it);
}

void Lobby::onTimedOut(MemberId member, double now, Effects& fx) {
  Member* m = findMember(member.value);
  if (m == nullptr) return;
  reject(m->conn, control::ErrorReply::TIMEOUT,
         fmt::format("no UDP traffic for {:.0f} s", config_.member_timeout_s), now, fx);
}

void Lobby::update(double now, Effects& fx) {
  // A pause of the server is nobody's slowness: join and upload clocks skip it.
  if (now - last_update_ > kStallSeconds) {
    const double pause = now - last_update_;
    for (auto& [conn, c] : connections_) {
      c.opened_at += pause;
      c.upload_progress_at += pause;
      c.upload_started_at += pause;
      c.upload_window_at += pause;
    }
  }
  last_update_ = now;
  std::vector<ConnId> late;
  for (const auto& [conn, c] : connections_) {
    if (c.member.value == 0 && now - c.opened_at > config_.join_timeout_s) late.push_back(conn);
  }
  for (ConnId conn : late) {
    reject(conn, control::ErrorReply::TIMEOUT,
           fmt::format("no Join within {:.0f} s", config_.join_timeout_s), now, fx);
  }
  checkUploads(now, fx);
}

Lobby::UploadProblem Lobby::uploadProblem(const Connection& c, double now) const {
  if (now - c.upload_progress_at > config_.upload_stall_timeout_s) {
    return {"upload stalled", fmt::format("avatar upload stalled (no chunk for {:.0f} s)",
                                          config_.upload_stall_timeout_s)};
  }
  const double deadline =
      config_.upload_deadline_base_s +
      static_cast<double>(c.upload_reserved) / config_.upload_deadline_rate_bytes_per_s;
  if (now - c.upload_started_at > deadline) {
    return {"upload deadline",
            fmt::format("avatar upload unfinished at its deadline ({} of {} bytes after {:.0f} s); "
                        "aborted",
                        c.upload.size(), c.upload_reserved, deadline)};
  }
  // The rate floor, over whole windows after the grace: the window must have carried the
  // floor's worth, or the rest of the file when that is less.
  const double window = now - c.upload_window_at;
  if (config_.upload_min_rate_bytes_per_s > 0.0 &&
      now - c.upload_started_at >= config_.upload_grace_s + config_.upload_rate_window_s &&
      window >= config_.upload_rate_window_s) {
    const std::uint64_t moved = c.upload.size() - c.upload_window_bytes;
    const std::uint64_t left = c.upload_reserved - c.upload_window_bytes;
    const double wanted = std::min(static_cast<double>(left), config_.upload_min_rate_bytes_per_s *
                                                                  config_.upload_rate_window_s);
    if (static_cast<double>(moved) < wanted) {
      return {"upload too slow",
              fmt::format("avatar upload too slow ({:.0f} bytes/s over the last {:.1f} s; the "
                          "floor is {:.0f} bytes/s); aborted",
                          static_cast<double>(moved) / window, window,
                          config_.upload_min_rate_bytes_per_s)};
    }
  }
  return {};
}

void Lobby::checkUploads(double now, Effects& fx) {
  // Find the uploads to abort (rejecting may hand an upload to another connection).
  std::vector<std::pair<ConnId, UploadProblem>> aborted;
  for (auto& [conn, c] : connections_) {
    if (c.upload_reserved == 0) continue;
    UploadProblem problem = uploadProblem(c, now);
    if (!problem.reason.empty()) {
      aborted.emplace_back(conn, std::move(problem));
    } else if (now - c.upload_window_at >= config_.upload_rate_window_s) {
      c.upload_window_at = now;  // a new rate window
      c.upload_window_bytes = c.upload.size();
    }
  }
  // Abort them: the ErrorReply says why; the slot goes to a waiting member or a newcomer.
  for (auto& [conn, problem] : aborted) {
    reject(conn, control::ErrorReply::TIMEOUT, problem.message, now, fx, problem.reason, 1.0f);
  }
}

void Lobby::setConnectionAddress(ConnId conn, std::string address) {
  auto it = connections_.find(conn);
  if (it != connections_.end()) it->second.address = std::move(address);
}

bool Lobby::mayCreateRoom(ConnId conn, const Connection& c, double now, Effects& fx) {
  if (config_.max_rooms_per_address <= 0 || c.address.empty()) return true;
  auto it = rooms_by_address_.find(c.address);
  const int open = it == rooms_by_address_.end() ? 0 : it->second;
  if (open < config_.max_rooms_per_address) return true;
  reject(conn, control::ErrorReply::SERVER_FULL,
         fmt::format("{} rooms created from {} are open already (the limit per address)", open,
                     c.address),
         now, fx, "rooms per address", 5.0f);
  return false;
}

void Lobby::roomOpened(RoomRecord& room, const Connection& c) {
  if (c.address.empty()) return;
  room.creator_address = c.address;
  ++rooms_by_address_[c.address];
}

void Lobby::roomClosed(const RoomRecord& room) {
  if (room.creator_address.empty()) return;
  auto it = rooms_by_address_.find(room.creator_address);
  if (it != rooms_by_address_.end() && --it->second <= 0) rooms_by_address_.erase(it);
}

void Lobby::shutdown(double now, Effects& fx) {
  std::vector<ConnId> all;
  for (const auto& [conn, c] : connections_) all.push_back(conn);
  for (ConnId conn : all) {
    reject(conn, control::ErrorReply::SHUTTING_DOWN, "the server is shutting down", now, fx);
  }
}

void Lobby::reject(ConnId conn, control::ErrorReply::Code code, const std::string& message,
                   double now, Effects& fx, std::string_view reason, float retry_after_s) {
  auto it = connections_.find(conn);
  if (it == connections_.end()) return;
  const std::string who = it->second.member.value != 0
                              ? fmt::format("member {:#x}", it->second.member.value)
                              : fmt::format("connection {}", conn);
  if (code == control::ErrorReply::SHUTTING_DOWN) {
    spdlog::debug("lobby: closing {}: {}", who, message);
  } else {
    const std::string_view key =
        reason.empty() ? std::string_view(control::ErrorReply::Code_Name(code)) : reason;
    drops_.drop(now, key, fmt::format("{}: {}", who, message));
    if (conn == joining_) ++joins_refused_[std::string(key)];
  }
  control::ServerMessage msg;
  msg.mutable_error()->set_code(code);
  msg.mutable_error()->set_message(message);
  if (retry_after_s > 0.0f) msg.mutable_error()->set_retry_after_s(retry_after_s);
  send(conn, msg, fx);
  fx.closes.push_back(conn);
  // The member goes first, so that a handed-over upload cannot pick it.
  const MemberId member = it->second.member;
  it->second.member = MemberId{};
  if (member.value != 0) removeMember(member, message, fx);
  if (auto again = connections_.find(conn); again != connections_.end()) {
    endUpload(conn, again->second, now, fx);
  }
  connections_.erase(conn);
}

void Lobby::removeMember(MemberId id, std::string_view reason, Effects& fx) {
  auto it = members_.find(id.value);
  if (it == members_.end()) return;
  Member& m = it->second;
  RoomRecord& room = rooms_.at(m.room.value);

  // Out of the room: seat, roster, dents, the room's mirror.
  std::erase(room.members, id);
  room.dents.erase(dentsKey(false, id.value));
  room.seat_taken[static_cast<std::size_t>(m.seat)] = false;
  RoomCommand cmd;
  cmd.kind = RoomCommand::Kind::kRemoveMember;
  cmd.room = room.id;
  cmd.member = id;
  fx.room_commands.push_back(cmd);
  spdlog::info("lobby: '{}' (member {:#x}) left room '{}': {}", m.name, id.value, room.name,
               reason);

  // Release what it held.
  if (m.avatar_ready) store_.release(m.avatar_hash);
  if (m.bound) member_by_endpoint_.erase(m.endpoint);
  member_ids_.release(id.value);
  members_.erase(it);

  // An empty room closes; otherwise the others get the new roster.
  if (room.members.empty()) {
    RoomCommand close;
    close.kind = RoomCommand::Kind::kClose;
    close.room = room.id;
    fx.room_commands.push_back(close);
    spdlog::info("lobby: room '{}' closed (empty)", room.name);
    for (const PropRecord& p : room.props) prop_ids_.release(p.id.value);
    const std::uint32_t rid = room.id.value;
    room_by_name_.erase(room.name);
    roomClosed(room);
    room_ids_.release(rid);
    rooms_.erase(rid);
  } else {
    sendRoster(room, fx);
  }
}

void Lobby::sendRoster(const RoomRecord& room, Effects& fx) {
  control::ServerMessage msg;
  control::Roster& roster = *msg.mutable_roster();
  for (MemberId id : room.members) {
    const Member& m = members_.at(id.value);
    control::MemberInfo& info = *roster.add_members();
    info.set_member_id(m.id.value);
    info.set_name(m.name);
    info.set_avatar_hash(m.avatar_hash);
    info.set_joint_count(static_cast<std::uint32_t>(m.joint_count));
    info.set_avatar_ready(m.avatar_ready);
    const SeatPlacement seat = seatPlacement(m.seat, config_.seat_layout);
    info.mutable_seat()->set_x(seat.x);
    info.mutable_seat()->set_z(seat.z);
    info.mutable_seat()->set_yaw(seat.yaw);
  }
  for (const PropRecord& p : room.props) {
    control::PropInfo& info = *roster.add_props();
    info.set_prop_id(p.id.value);
    info.set_kind(control::PropInfo::BALL);
    info.set_radius(p.spec.ball.radius);
    info.set_reach(p.spec.ball.reach);
    info.set_mass(p.spec.mass);
    info.set_restitution(p.spec.restitution);
    info.set_stiffness(std::isinf(p.spec.ball.stiffness) ? 0.0f : p.spec.ball.stiffness);
    info.set_elasticity(toProto(p.spec.ball.elasticity));
    info.set_time_constant(p.spec.ball.time_constant);
    info.set_spawned_by(p.spawned_by.value);
  }
  for (MemberId id : room.members) send(members_.at(id.value).conn, msg, fx);
}

}  // namespace vistel::server
