// The client's side of a session as a pure state machine (proto/SESSION.md §4): fed
// (bytes, now) from the TCP stream and the UDP socket, it decides what to send, and
// keeps the roster, a jitter buffer per remote member, the clock offset and the stats.
// No sockets, clocks or threads: NetDriver runs it over Asio; tests run it over a
// simulated network. `now` is the caller's monotonic clock in seconds throughout.
//
// States: kJoining (Join sent, waiting for the Welcome; the avatar is uploaded here if
// the server asks) -> kHandshaking (UDP hellos every hello_interval_s until acked) ->
// kLive (postures out, snapshots in, pings for the clock) -> kClosed (error() says why:
// a server ErrorReply, a disconnect, a handshake timeout, server silence, a protocol
// violation). Input that breaks the protocol from the server closes the session with a
// message; malformed datagrams are only counted. closeCause() sorts the reasons for the
// driver: what may clear by itself (a lost connection, a busy server) and what will not (a
// refusal of this client's request).
//
// UDP keys (proto/WIRE.md §3.9): the Join carries a fresh X25519 public key, the Welcome
// the server's; the derived keys seal every datagram we send and open every one we
// receive (a datagram that does not verify, or repeats a counter, is counted as rejected
// and otherwise ignored).
//
// Resuming (proto/SESSION.md §4): a session made for reconnecting carries the previous
// Welcome's member id and a proof from that session's resume secret in its Join
// (SessionSettings::resume_*; the secret never travels), so the server replaces our stale
// member instead of refusing the name. NAT rebinding: in kLive, when
// nothing came from the server for rehello_after_s, the session says hello again every
// hello_interval_s (echoing a challenge, as in the first handshake) until a plain ack:
// the server moves the member to a changed address only after that check.
//
// The shared room's collision world (DESIGN.md §6: the server owns it): the session keeps
// the room's props (static spec from the Roster, states from snapshots in a PropTrack
// each) and the newest complete interaction list the server computed (Step 1 across and
// within bodies, assembled from its parts), in the server's ids. sceneInteractions()
// maps that list onto the caller's scene: body i < members().size() is members()[i], body
// members().size() + k is props()[k] ("scene order"), and validates it.
//
// Dents (proto/SESSION.md §2.5): sendDents sends a body's elastic memory (common/scene/
// dent_record.hpp); what the server relays waits in receivedDents(), the newest per body,
// until the caller takes it (malformed ones are counted in stats().dents_rejected).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "client/net/avatar_cache.hpp"
#include "client/net/clock_sync.hpp"
#include "client/net/jitter_buffer.hpp"
#include "client/net/prop_track.hpp"
#include "client/net/session_stats.hpp"
#include "client/net/voice_inbox.hpp"
#include "common/anim/posture.hpp"
#include "common/base/result.hpp"
#include "common/deform/interactions.hpp"
#include "common/deform/prop.hpp"
#include "common/scene/dent_record.hpp"
#include "common/wire/datagram_crypto.hpp"
#include "common/wire/framing.hpp"
#include "common/wire/packets.hpp"
#include "common/wire/posture_delta.hpp"

namespace vistel::control {
class Dents;
class ServerMessage;
class Roster;
class AvatarChunk;
class Welcome;
}  // namespace vistel::control

namespace vistel::net {

inline constexpr std::uint32_t kProtocolVersion = 5;

struct SessionSettings {
  std::string room;
  std::string name;
  std::string token;  // Join.token (`vistel-server token`); empty: none sent
  // The participant's avatar file and its hash (avatarContentHash); its joint count is
  // what every posture sent must carry (0 = not checked here).
  std::shared_ptr<const std::vector<std::uint8_t>> avatar_bytes;
  std::string avatar_hash;
  int avatar_joint_count = 0;

  double hello_interval_s = 0.1;
  double hello_timeout_s = 5.0;  // kHandshaking longer than this: closed
  double join_timeout_s = 10.0;  // kJoining longer than this (upload included): closed
  double ping_interval_s = 1.0;
  int fast_pings = 10;  // the first pings go out faster, to converge quickly
  double fast_ping_interval_s = 0.05;
  int clock_window = 16;           // ClockSync window
  double server_timeout_s = 10.0;  // no datagram from the server this long: closed
  double rehello_after_s = 2.0;    // kLive, no datagram this long: hellos again
  // Reconnecting (NetDriver): after a live session is lost, join again for this long
  // (seconds from the loss) before giving up; 0: never reconnect.
  double reconnect_give_up_s = 180.0;
  // The previous Welcome's member id and that session's resume secret when this session
  // resumes one (the Join carries the id and a proof from the secret, WIRE.md §3.9; 0: a
  // first join).
  std::uint32_t resume_member_id = 0;
  wire::ResumeSecret resume_secret{};
  // Tests and fuzzing only: a fixed X25519 private key for the UDP key exchange, so that a
  // recorded session replays (all zero, the default: a fresh random key pair per Join).
  std::array<std::uint8_t, 32> fixed_udp_private_key{};
  int jitter_capacity = 32;                  // postures kept per remote member
  int prop_track_capacity = 32;              // states kept per prop
  std::size_t max_frame_bytes = 1u << 20;    // control frames accepted from the server
  std::size_t max_avatar_bytes = 64u << 20;  // avatar files accepted from the server
  bool fetch_avatars = true;                 // request unknown avatars (needs a cache)
};

enum class SessionState { kJoining, kHandshaking, kLive, kClosed };
const char* sessionStateName(SessionState state);

// Why a session closed.
enum class CloseCause {
  kNone,     // not closed
  kLeft,     // leave()
  kRefused,  // refused for good: protocol version, bad room/name/hash, avatar rejected, a
             // message the server called bad, rate limited, no avatar file to upload
  kTaken,    // NAME_TAKEN or ROOM_FULL: final for a first join, may clear when resuming
  kBusy,     // a transient refusal: retryAfter() > 0 (server full, no Welcome in time)
  kLost,     // the connection dropped, the server went silent or shut down, dropped us
             // (TIMEOUT), the UDP handshake timed out, or the server broke the protocol
};

struct Seat {
  float x = 0.0f;
  float z = 0.0f;
  float yaw = 0.0f;  // radians about +Y
};

// A roster entry, with its stream state.
struct RemoteMember {
  std::uint32_t id = 0;
  std::string name;
  std::string avatar_hash;
  int joint_count = 0;  // of its avatar (0 until the server has it)
  bool avatar_ready = false;
  Seat seat;
  bool is_self = false;
  JitterBuffer buffer;  // its postures, server clock (empty for self)
};

// A prop of the room (Roster), with its states (snapshots).
struct RemoteProp {
  std::uint32_t id = 0;          // prop id (its own id space, apart from member ids)
  BallSpec ball;                 // radius, reach, stiffness (kRigidStiffness: rigid),
                                 // elasticity, time constant: makeBall(ball) draws it
  float mass = 0.0f;             // kg
  float restitution = 0.0f;      // [0, 1]
  std::uint32_t spawned_by = 0;  // member id; 0 = the server's config
  PropTrack track;               // centre and velocity over time, server clock
};

// One end of a received interaction pair, in the server's names.
struct ServerBodyPrim {
  bool is_prop = false;
  std::uint32_t id = 0;    // member id or prop id
  std::uint16_t prim = 0;  // primitive index in that body's PrimitiveSet
};
struct ServerPair {
  ServerBodyPrim a;
  ServerBodyPrim b;
};

// The newest complete interaction list (all parts of one tick).
struct ReceivedInteractions {
  std::uint32_t tick = 0;
  double server_time = 0.0;   // of the tick (the postures and prop states it was computed from)
  bool truncated = false;     // the server had more pairs than it sent (self-contact first)
  bool self_omitted = false;  // only pairs between bodies: self-contact is computed here
  std::vector<ServerPair> pairs;
};

// A body's dents as they travel: the sender's own avatar or a prop of the room.
struct BodyDents {
  bool prop = false;
  std::uint32_t body_id = 0;  // member id (its avatar) or prop id
  std::uint32_t member = 0;   // received: the member that sent it
  double server_time = 0.0;   // when the sender sampled it (server clock)
  DentRecord record;
};

// What the session wants sent; the driver (or test) takes it and clears it.
struct SessionOutbox {
  std::vector<std::uint8_t> stream;                  // bytes for the TCP stream, in order
  std::vector<std::vector<std::uint8_t>> datagrams;  // UDP payloads for the server
  bool close = false;                                // close the TCP connection after `stream`
  void clear() {
    stream.clear();
    datagrams.clear();
    close = false;
  }
};

class ClientSession {
 public:
  // cache may be null (then avatars are not fetched). Call start() once connected.
  ClientSession(SessionSettings settings, std::shared_ptr<AvatarCache> cache);
  ~ClientSession();

  // The TCP connection is up: sends Join.
  void start(double now);
  void onStreamBytes(std::span<const std::uint8_t> bytes, double now);
  // A datagram from the server's endpoint (the driver filters other senders).
  void onDatagram(std::span<const std::uint8_t> datagram, double now);
  void onDisconnected(const std::string& reason, double now);
  // Timers: hello retries, pings, timeouts. Call often (every few ms to 50 ms).
  void update(double now);

  // Sends the participant's posture, stamped with the server time of `now`. Only in
  // kLive once the server holds our avatar (else false, nothing sent); false as well
  // when its joint count is not the avatar's. Allocates only the datagram.
  bool sendPosture(const Posture& posture, double now);
  // Sends one voice frame (WIRE.md §3.10), sealed like postures. Only in kLive; false
  // (nothing sent) otherwise or for a payload out of range. Frames received from others
  // wait in voiceInbox().
  bool sendVoice(const OutgoingVoice& frame);
  VoiceInbox& voiceInbox() { return voice_; }
  const VoiceInbox& voiceInbox() const { return voice_; }
  // Sends Leave and asks the driver to close; the state becomes kClosed.
  void leave(const std::string& reason);
  // Asks the server for a ball above our head (SpawnProp over TCP; the server rate-limits
  // and places it). False, nothing sent, before the Welcome or after closing.
  bool requestBall();
  // Sends a body's dents (Dents over TCP): only in kLive, and only a well-formed record with a
  // finite time (else false, nothing sent). The server relays it to the room and keeps the
  // newest per body for later joiners; it ignores one faster than its dents_interval_s per
  // body.
  bool sendDents(const BodyDents& dents);
  // Dents received since the caller last took them: the newest per body, in arrival order
  // of the bodies. Take them by swapping or clearing.
  std::vector<BodyDents>& receivedDents() { return received_dents_; }

  SessionState state() const { return state_; }
  const std::string& error() const { return error_; }
  // Closed by a refusal the server called transient (ErrorReply.retry_after_s, or no
  // Welcome in time): seconds it suggests waiting before joining again; 0 otherwise.
  double retryAfter() const { return retry_after_s_; }
  CloseCause closeCause() const { return close_cause_; }
  // From the Welcome (0 before it): what a later session needs to resume this one.
  std::uint32_t memberId() const { return member_id_; }
  // The resume secret derived with the Welcome (zero before it; never sent).
  const wire::ResumeSecret& resumeSecret() const { return keys_.resume; }
  const std::string& roomName() const { return room_name_; }
  // Re-saying hello in kLive (the server's datagrams stopped) until the server acks.
  bool rehelloing() const { return rebinding_; }
  double tickRateHz() const { return tick_rate_hz_; }
  const ClockSync& clock() const { return clock_; }
  double serverTime(double now) const { return clock_.serverTime(now); }
  // The roster, self included, in the server's order.
  const std::vector<std::unique_ptr<RemoteMember>>& members() const { return members_; }
  const RemoteMember* findMember(std::uint32_t id) const;
  // The posture of a remote member at a server time (see JitterBuffer::sample).
  bool samplePosture(std::uint32_t member_id, double server_time, Posture& out) const;
  const SessionStats& stats() const { return stats_; }
  // A session replacing a lost one continues its counters (NetDriver), and counts the
  // reconnection once live again.
  void carryStats(SessionStats previous) { stats_ = std::move(previous); }
  void countReconnect() { ++stats_.reconnects; }

  // The room's props, in the server's order (the Roster's).
  const std::vector<std::unique_ptr<RemoteProp>>& props() const { return props_; }
  const RemoteProp* findProp(std::uint32_t id) const;
  // A prop's state at a server time (PropTrack::sample). False for an unknown prop or one
  // without states yet.
  bool sampleProp(std::uint32_t prop_id, double server_time, PropSample& out) const;

  // The newest complete interaction list, in server ids; its tick and time say how fresh
  // it is (none yet: empty, tick 0). interactionsVersion() counts the lists received.
  const ReceivedInteractions& latestInteractions() const { return interactions_; }
  std::uint64_t interactionsVersion() const { return interactions_version_; }
  // Maps the newest list onto the caller's scene (`bodies` in scene order, see above:
  // members() then props(), posed by the caller; a null posed set marks a body it does not
  // have, e.g. an avatar not yet fetched): pairs naming a body that is not in the scene or
  // not posed are left out (counted in *dropped), the rest are finalized for
  // bodies.size() bodies and checked with validateInteractions. On a failed check (a
  // primitive the body does not have, a pair its graph forbids: the caller's avatar is not
  // the server's) `out` is left empty and the error names the pair. Allocation-free once
  // `out` has grown. Where the server left each body's own pairs out, they are added from
  // `bodies`' poses, unless own_pairs is false (a caller that adds them itself, for the
  // bodies it deforms: DeformScene::addSelfInteractions).
  Status sceneInteractions(std::span<const BodyView> bodies, InteractionList& out,
                           int* dropped = nullptr, bool own_pairs = true) const;
  // Increments whenever the roster changes (for callers that rebuild views).
  std::uint64_t rosterVersion() const { return roster_version_; }

  SessionOutbox& outbox() { return outbox_; }

 private:
  struct Download {
    std::vector<std::uint8_t> bytes;
    std::uint64_t total = 0;
    bool failed = false;
  };

  void handleMessage(const control::ServerMessage& msg, double now);
  void handleRoster(const control::Roster& roster);
  void handleChunk(const control::AvatarChunk& chunk);
  void handleSnapshot(std::span<const std::uint8_t> datagram, double now);
  void handleVoice(std::span<const std::uint8_t> datagram, double now);
  void handleProps(const control::Roster& roster);
  void handleInteractionPart(const wire::Snapshot& snapshot);
  void handleDents(const control::Dents& dents);
  // Scene index of a server body, or -1.
  int sceneIndex(const ServerBodyPrim& body) const;
  void uploadAvatar(std::size_t chunk_bytes);
  void requestMissingAvatars();
  // The UDP keys from the Welcome's public key (closes the session and returns false on a
  // bad one).
  bool deriveKeys(const control::Welcome& w);
  void sendHello(double now);
  void sendPing(double now);
  void sendControl(const std::string& payload);
  void close(const std::string& reason, CloseCause cause = CloseCause::kLost);

  SessionSettings settings_;
  std::shared_ptr<AvatarCache> cache_;
  SessionState state_ = SessionState::kJoining;
  std::string error_;
  CloseCause close_cause_ = CloseCause::kNone;
  double retry_after_s_ = 0.0;
  std::string room_name_;
  wire::FrameDecoder decoder_;
  SessionOutbox outbox_;

  std::uint32_t member_id_ = 0;
  // The UDP keys (WIRE.md §3.9): our key pair until the Welcome, then the derived keys,
  // the sender of our datagrams and the openers of the room's and the lobby's.
  std::optional<wire::KeyExchange> exchange_;
  wire::SessionKeys keys_;
  wire::DatagramSealer uplink_;
  wire::DatagramOpener downlink_;
  wire::DatagramOpener hello_downlink_;
  std::vector<std::uint8_t> scratch_datagram_;  // a datagram being opened
  double tick_rate_hz_ = 0.0;
  bool avatar_pending_ = false;  // uploaded, not yet accepted
  double state_since_ = 0.0;
  double last_server_datagram_ = 0.0;

  std::uint32_t hello_attempt_ = 0;
  std::uint64_t hello_cookie_ = 0;  // the server's challenge to our address (0: none yet)
  double next_hello_ = 0.0;
  bool rebinding_ = false;          // kLive: hellos again until a plain ack
  bool rebind_challenged_ = false;  // ... and the server challenged us (a new address)

  std::uint32_t ping_id_ = 0;
  double next_ping_ = 0.0;
  std::vector<std::pair<std::uint32_t, double>> pending_pings_;  // (id, t0), recent
  ClockSync clock_;

  std::uint16_t sequence_ = 0;
  std::vector<std::unique_ptr<RemoteMember>> members_;
  std::uint64_t roster_version_ = 0;
  std::unordered_map<std::string, Download> downloads_;  // by hash

  SessionStats stats_;
  std::vector<std::unique_ptr<RemoteProp>> props_;
  ReceivedInteractions interactions_;  // newest complete list
  std::uint64_t interactions_version_ = 0;
  ReceivedInteractions pending_interactions_;  // the tick being assembled
  std::uint8_t pending_part_count_ = 0;        // 0: none pending
  std::uint32_t pending_parts_ = 0;            // bit per part received

  // Scratch, reused per datagram.
  wire::Snapshot snapshot_;
  Posture scratch_posture_;
  std::unique_ptr<wire::PostureDeltaEncoder> encoder_;  // our posture stream (first send)
  std::vector<std::uint8_t> scratch_record_bytes_;
  VoiceInbox voice_;
  std::uint16_t voice_sequence_ = 0;
  std::vector<BodyDents> received_dents_;
};

}  // namespace vistel::net
