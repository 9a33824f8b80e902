// The lobby: the TCP control side of the session server (proto/SESSION.md §2). It owns
// connections, membership, rooms' rosters and seats, the avatar store and the UDP hello
// handshake; rooms mirror what they need through RoomCommands. Pure: fed (bytes, now),
// it appends to Effects.
//
// Bad input never takes more than its sender down: an unparsable, oversized or
// out-of-order control frame, or an invalid upload, gets an ErrorReply and the
// connection is closed (logged with the reason); a bad hello (unknown member, not sealed
// with the member's key, replayed) is dropped (counted, logged) and never answered. A
// hello is answered with no more bytes than it carried.
//
// Keys: a Join carries the client's X25519 public key; the Welcome the server's; the
// member's datagram keys and resume secret follow (WIRE.md §3.9) and go to its room with
// kAddMember. The lobby opens hellos and seals hello acks.
//
// Resuming: a Join carrying the id of a live member with the same room and name and a
// proof from that member's resume secret (Join.resume_member_id/resume_proof, WIRE.md
// §3.9; a client reconnecting before the server noticed its old connection died) replaces
// that member: the stale one is closed (TIMEOUT,
// "replaced by a resumed session") and the new one takes its seat when free. Without the
// matching key a taken name is refused NAME_TAKEN as before. A UDP address change of a
// member (NAT rebinding) is handled by onHello's challenge.
//
// Concurrent joins with one avatar the server lacks share one upload: the first joiner
// uploads, the others wait (Welcome.avatar_pending) and become ready with it; should the
// upload fail, a waiting member takes it over (UploadAvatar).
//
// Limits against floods (ServerConfig [limits]): control messages per connection through
// a token bucket (control_rate_hz sustained, control_burst at once; an AvatarRequest
// costs one more token per MiB or part of one it makes the server send; avatar chunks of the
// offered upload are free, bounded by the offered size instead): a faster sender is dropped with
// RATE_LIMITED. Upload memory: a join whose avatar must be uploaded reserves its offered
// size against max_upload_bytes_total (refused with SERVER_FULL beyond), released when the
// upload ends either way; an upload without progress for upload_stall_timeout_s drops its
// sender (TIMEOUT); so does one slower than upload_min_rate_bytes_per_s over a window
// after its grace, or one unfinished by its deadline (scaled by its size) — its slot goes
// to a waiting member or the next newcomer. Rooms: a join that would open more rooms than
// max_rooms_per_address created from its connection's address (setConnectionAddress) is
// refused with SERVER_FULL ("rooms per address"). Prop spawns: one per member per spawn_interval_s;
// faster requests are ignored (logged).
//
// Props: the lobby owns each room's prop list (ids, specs; the Roster carries them) and
// tells rooms to spawn and remove; rooms decide positions and step them. A room starts
// with the config's [[prop]] entries.
//
// Dents (proto/SESSION.md §2.5; lobby_dents.cpp): a member's Dents for its own avatar or a
// prop of its room is checked (common/scene/dent_record.hpp, [limits] max_dent_vertices),
// kept as the body's newest and relayed to the rest of the room; a joiner gets every one
// the room keeps after its Roster. Dents for another member's avatar or an unknown body,
// malformed ones, ones faster than dents_interval_s per body and sender, and ones past the
// sender's dents_bytes_per_s (each is relayed to the whole room) are ignored (counted,
// logged; the sender stays). A body's dents go with it (member left, prop
// removed), so a room keeps at most one message per body.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "common/scene/seat_layout.hpp"
#include "common/wire/datagram_crypto.hpp"
#include "common/wire/endpoint.hpp"
#include "common/wire/framing.hpp"
#include "control.pb.h"
#include "server/core/avatar_store.hpp"
#include "server/core/drop_log.hpp"
#include "server/core/effects.hpp"
#include "server/core/handles.hpp"
#include "server/core/rate_limit.hpp"
#include "server/core/server_config.hpp"

namespace vistel::server {

inline constexpr std::uint32_t kProtocolVersion = 5;

// What a spectator (server/web) may see of a room: its members as the roster names them.
// Times are the lobby's clock (the `now` it is fed), seconds.
struct LobbyMemberView {
  std::uint32_t id = 0;
  std::string name;
  std::string avatar_hash;  // content hash (64 hex) of its .vavatar
  bool avatar_ready = false;
  int seat = 0;  // seat index (seatPlacement with the config's layout)
  double joined_at = 0.0;
};
struct LobbyRoomView {
  std::uint32_t id = 0;
  std::string name;
  double created_at = 0.0;
  std::vector<LobbyMemberView> members;  // join order
};

class Lobby {
 public:
  // seed 0: keys from std::random_device; otherwise a deterministic generator (tests).
  Lobby(const ServerConfig& config, std::uint64_t seed);

  void onConnect(ConnId conn, double now, Effects& fx);
  // The source address of a connection (any stable spelling, e.g. "203.0.113.7"), for
  // the per-address room limit; empty or never set: the connection is not limited.
  void setConnectionAddress(ConnId conn, std::string address);
  void onStreamBytes(ConnId conn, std::span<const std::uint8_t> bytes, double now, Effects& fx);
  void onDisconnect(ConnId conn, double now, Effects& fx);
  // A datagram of type hello (any other is ignored).
  void onHello(std::span<const std::uint8_t> datagram, const wire::Endpoint& from, double now,
               Effects& fx);
  // A room reports a member silent past the timeout: it is told so and removed.
  void onTimedOut(MemberId member, double now, Effects& fx);
  // Closes connections that have not joined within the join timeout, and uploads that
  // stalled. Call every few hundred ms; a longer gap is a pause of the server, which the
  // join and upload clocks skip.
  void update(double now, Effects& fx);
  // Tells every connection the server is shutting down and closes it.
  void shutdown(double now, Effects& fx);

  int connectionCount() const { return static_cast<int>(connections_.size()); }
  int memberCount() const { return static_cast<int>(members_.size()); }
  int roomCount() const { return static_cast<int>(rooms_.size()); }
  // Joins accepted since the start.
  std::uint64_t joinsAccepted() const { return joins_accepted_; }
  // Joins refused since the start, by reason (the DropLog reason: "BAD_JOIN", "bad name",
  // "token expired", ...); a subset of drops().
  const std::map<std::string, std::uint64_t, std::less<>>& joinsRefused() const {
    return joins_refused_;
  }
  // The wall clock join tokens are checked against (unix seconds; default: the system
  // clock). For tests.
  void setUnixClock(std::function<std::int64_t()> clock) { unix_clock_ = std::move(clock); }
  const AvatarStore& avatars() const { return store_; }
  const DropLog& drops() const { return drops_; }
  // Bytes reserved by unfinished avatar uploads (all connections).
  std::uint64_t uploadBytesInFlight() const { return upload_bytes_in_flight_; }
  // Avatar uploads in progress (one per hash).
  int uploadsInProgress() const { return static_cast<int>(uploader_of_.size()); }
  // Props of a room (by name) in spawn order; empty for an unknown room.
  std::vector<PropId> propsOf(std::string_view room) const;
  // The room of a live member.
  std::optional<RoomId> roomOf(MemberId member) const;
  // Spectators (server/web): every open room (by name), or one; O(members) (lobby_view.cpp).
  std::vector<LobbyRoomView> roomViews() const;
  std::optional<LobbyRoomView> roomView(std::string_view name) const;
  // A live member's session keys (nullptr for an unknown member): for tests that play its
  // client.
  const wire::SessionKeys* keysOf(std::uint32_t member) const {
    auto it = members_.find(member);
    return it == members_.end() ? nullptr : &it->second.keys;
  }

 private:
  struct Connection {
    explicit Connection(std::size_t max_frame) : decoder(max_frame) {}
    wire::FrameDecoder decoder;
    double opened_at = 0.0;
    MemberId member;                      // 0 until joined
    TokenBucket control;                  // control message budget
    std::vector<std::uint8_t> upload;     // avatar bytes received so far
    std::uint64_t upload_reserved = 0;    // bytes counted in upload_bytes_in_flight_
    std::string upload_hash;              // the avatar this connection uploads (or empty)
    double upload_progress_at = 0.0;      // last chunk (or the join)
    double upload_started_at = 0.0;       // the upload's start (grace and deadline)
    double upload_window_at = 0.0;        // start of the current rate window
    std::size_t upload_window_bytes = 0;  // upload.size() then
    std::string address;                  // source address ("" = not limited per address)
  };
  struct Member {
    MemberId id;
    ConnId conn = 0;
    RoomId room;
    std::string name;
    std::string avatar_hash;
    std::uint64_t avatar_size = 0;
    wire::SessionKeys keys;          // from the Join's key exchange
    wire::DatagramOpener hello_in;   // its hellos (client -> server key, replay window)
    wire::DatagramSealer hello_out;  // our hello acks (the server hello key)
    int seat = 0;
    bool avatar_ready = false;
    int joint_count = 0;
    bool bound = false;
    wire::Endpoint endpoint;
    wire::Endpoint challenged;    // the address the last challenge went to
    std::uint64_t challenge = 0;  // ... and its cookie (0: none)
    double last_spawn = -1e300;
    std::vector<std::pair<std::uint64_t, double>> dents_sent_at;  // (body key, lobby clock)
    TokenBucket dents_bytes;                                      // Dents bytes relayed
    double joined_at = 0.0;                                       // lobby clock
  };
  struct PropRecord {
    PropId id;
    PropSpec spec;
    MemberId spawned_by;  // 0: the config
  };
  struct RoomRecord {
    RoomId id;
    std::string name;
    std::vector<MemberId> members;  // join order
    std::vector<bool> seat_taken;   // per seat
    std::vector<PropRecord> props;  // spawn order
    // Each body's newest Dents as the framed ServerMessage sent to the room (by dentsKey).
    std::unordered_map<std::uint64_t, std::vector<std::uint8_t>> dents;
    std::string creator_address;  // counted in rooms_by_address_ ("" = not counted)
    double created_at = 0.0;      // lobby clock
  };
  LobbyRoomView viewOf(const RoomRecord& room) const;

  void handleMessage(ConnId conn, Connection& c, std::span<const std::uint8_t> payload, double now,
                     Effects& fx);
  void handleJoin(ConnId conn, Connection& c, const control::Join& join, double now, Effects& fx);
  // With a join secret (config [auth]): false, and the connection refused UNAUTHORIZED,
  // unless the Join carries a valid token for its room and name (lobby_auth.cpp).
  bool admitToken(ConnId conn, const control::Join& join, double now, Effects& fx);
  void handleChunk(ConnId conn, Connection& c, const control::AvatarChunk& chunk, double now,
                   Effects& fx);
  void handleRequest(ConnId conn, const control::AvatarRequest& request, double now, Effects& fx);
  void handleSpawn(Connection& c, const control::SpawnProp& spawn, double now, Effects& fx);
  // Dents (lobby_dents.cpp): check, keep, relay; a joiner gets what its room keeps.
  void handleDents(Connection& c, const control::Dents& dents, double now, Effects& fx);
  void sendKeptDents(const RoomRecord& room, ConnId conn, Effects& fx) const;
  static std::uint64_t dentsKey(bool prop, std::uint32_t body_id) {
    return (std::uint64_t{prop ? 1u : 0u} << 32) | body_id;
  }
  // A prop into a room: allocates its id, tells the room (which places it: above
  // `requester`'s head, else at position) and records it. False when no id is free.
  bool spawnProp(RoomRecord& room, const PropSpec& spec, MemberId requester,
                 const glm::vec3& position, const glm::vec3& velocity, Effects& fx);
  // Reserves an upload of `hash` (`size` bytes) for a connection: it becomes the one
  // uploader of that hash.
  void beginUpload(ConnId conn, Connection& c, const std::string& hash, std::uint64_t size,
                   double now);
  // Gives back a connection's upload reservation and buffer. When it was uploading an
  // avatar the store still lacks, a member waiting for the same file takes the upload over
  // (UploadAvatar), or is refused with SERVER_FULL when the capacity is gone.
  void endUpload(ConnId conn, Connection& c, double now, Effects& fx);
  // Every member waiting for this hash becomes ready (their rooms learn the joint count
  // and get a new roster).
  void avatarBecameReady(const std::string& hash, Effects& fx);
  // Aborts uploads that stalled, fell below the rate floor or passed their deadline
  // (called by update()).
  void checkUploads(double now, Effects& fx);
  // Why an upload should be aborted now (empty reason: it may go on).
  struct UploadProblem {
    std::string_view
        reason;           // counted drop reason: "upload stalled", "... too slow", "... deadline"
    std::string message;  // the ErrorReply's text
  };
  UploadProblem uploadProblem(const Connection& c, double now) const;
  // Per-address room limit: false (and the connection refused) when a room created by
  // this connection would pass it; roomOpened/roomClosed keep the count.
  bool mayCreateRoom(ConnId conn, const Connection& c, double now, Effects& fx);
  void roomOpened(RoomRecord& room, const Connection& c);
  void roomClosed(const RoomRecord& room);
  // Sends an ErrorReply, closes the connection and removes its member (logged and counted
  // under `reason`, by default the code's name).
  // retry_after_s > 0 marks the refusal transient (ErrorReply.retry_after_s).
  void reject(ConnId conn, control::ErrorReply::Code code, const std::string& message, double now,
              Effects& fx, std::string_view reason = {}, float retry_after_s = 0.0f);
  void removeMember(MemberId id, std::string_view reason, Effects& fx);
  void sendRoster(const RoomRecord& room, Effects& fx);
  void send(ConnId conn, const control::ServerMessage& message, Effects& fx);
  std::uint64_t newKey();
  Member* findMember(std::uint32_t id);

  ServerConfig config_;
  HandlePool member_ids_;
  HandlePool room_ids_;
  HandlePool prop_ids_;
  std::unordered_map<ConnId, Connection> connections_;
  std::unordered_map<std::uint32_t, Member> members_;    // by MemberId value
  std::unordered_map<std::uint32_t, RoomRecord> rooms_;  // by RoomId value
  std::unordered_map<std::string, std::uint32_t> room_by_name_;
  std::unordered_map<wire::Endpoint, std::uint32_t, wire::EndpointHash> member_by_endpoint_;
  AvatarStore store_;
  std::uint64_t upload_bytes_in_flight_ = 0;
  std::uint64_t joins_accepted_ = 0;
  static constexpr double kStallSeconds = 1.0;  // update() gaps longer than this are pauses
  double last_update_ = 0.0;
  // The one connection uploading each avatar hash; later joins with that hash wait for it.
  std::unordered_map<std::string, ConnId> uploader_of_;
  // Rooms open that were created from each (limited) address.
  std::unordered_map<std::string, int> rooms_by_address_;
  DropLog drops_{"lobby"};
  std::optional<ConnId>
      joining_;  // the connection whose Join is being handled (its refusals count)
  std::map<std::string, std::uint64_t, std::less<>> joins_refused_;
  std::function<std::int64_t()> unix_clock_;
  std::uint64_t seed_;
  std::mt19937_64 rng_;
  std::vector<std::uint8_t> scratch_datagram_;  // a hello being opened (reused)
  std::random_device device_;
};

}  // namespace vistel::server
