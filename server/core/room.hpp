// A room's share of the session protocol: the UDP side of its members (latest posture,
// clock pings), its collision world (RoomWorld: members' primitives, props, Step 1), the
// forwarding of postures as they arrive, and the fixed-rate tick that steps the world and
// sends every member the prop states and the interaction list (DESIGN.md §6,
// proto/SESSION.md §3, proto/WIRE.md §3.6). Pure: fed (bytes, endpoint, now), it appends
// to Effects; no sockets, no clocks, no threads (the shell runs each room on its own
// strand). Membership and props come from the lobby as RoomCommands.
//
// Forwarding: a posture accepted is sent on to the other members within
// forward_interval_s (batched: every member gets the postures that arrived since the last
// batch, packed into as few datagrams as fit), not at the next tick. Interest: a member
// hears its near_members nearest others (by seat) at every posture; the next
// near_members at every second, the next at every third, and the rest at every
// max_rate_divisor-th, so a member's downlink grows with the log of the room's size up
// to 3 * near_members others and by 1/max_rate_divisor per member past that.
//
// Cost per posture: O(members) to forward it; per tick, the world step (O(primitives)
// posing, stepBall per prop, Step 1) plus one or more world datagrams per member; no
// heap allocation once the room's buffers and the Effects' datagram slots have grown to
// its size (reuse one Effects across calls).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/wire/datagram_crypto.hpp"
#include "common/wire/endpoint.hpp"
#include "common/wire/packets.hpp"
#include "common/wire/posture_delta.hpp"
#include "server/core/drop_log.hpp"
#include "server/core/effects.hpp"
#include "server/core/room_world.hpp"
#include "server/core/server_config.hpp"
#include "server/core/voice_forwarding.hpp"

namespace vistel::server {

struct RoomSettings {
  double tick_rate_hz = 60.0;
  double member_timeout_s = 10.0;     // silence on UDP (from join, until the first packet)
  double forward_interval_s = 0.002;  // postures wait at most this long to be forwarded
  double max_capture_age_s = 5.0;     // postures captured longer ago are dropped
  int near_members = 16;              // heard at full rate (and the size of each rate band)
  int max_rate_divisor = 4;           // the farthest are heard at 1 / this of their rate
  WorldSettings world;
  VoiceSettings voice;  // selective forwarding of voice frames (voice_forwarding.hpp)
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
  // Postures accepted into the room so far (all members), and entries forwarded (one per
  // posture and recipient).
  std::uint64_t posturesAccepted() const { return postures_accepted_; }
  std::uint64_t entriesForwarded() const { return entries_forwarded_; }
  // Delta-coded postures whose reference the room did not hold (a keyframe is then asked
  // for): normal after a lost datagram.
  std::uint64_t posturesWithoutReference() const { return postures_without_reference_; }
  // Voice frames admitted, forwarded (copies), refused by the rate limits, and so on.
  const VoiceForwardingStats& voiceStats() const { return voice_.stats(); }

  // Mirrors a lobby decision (add/remove/bind/set avatar); commands for other rooms or
  // unknown members are ignored.
  void apply(const RoomCommand& command, double now);

  // A sealed posture or ping datagram addressed (by member id) to this room. Accepted only
  // from a member's bound endpoint, sealed with its uplink key under a counter its replay
  // window has not seen (WIRE.md §3.9); postures must carry the member's joint count, a
  // capture time within (now - max_capture_age_s, now + 1 s], and a sequence newer than
  // the last accepted one by at most kMaxSequenceJump (farther only as a keyframe, which
  // resynchronises). Everything else is dropped with a counted, logged reason. A ping is
  // answered with a pong (smaller than the ping). Every datagram the room sends is sealed
  // with the recipient's downlink key.
  void onDatagram(std::span<const std::uint8_t> datagram, const wire::Endpoint& from, double now,
                  Effects& fx);

  // Forwards the postures waiting when their batch is due; if a tick is due, steps the
  // world and sends each bound member the world's datagrams (prop states, interaction
  // list); reports members silent for longer than the timeout (once each, in
  // fx.timed_out). Missed ticks are skipped, not replayed. Call at least at the tick
  // rate, and at nextWakeTime(). A gap of more than a second between calls is a pause of
  // the server, not silence of its members: their timeouts restart after it.
  void update(double now, Effects& fx);

  // Server time of the next due tick, and of the last one (-1 before the first).
  double nextTickTime() const { return next_tick_; }
  // When update() next has work: the next tick, or sooner a batch of postures to forward.
  double nextWakeTime() const;
  // Whether update() just ran a tick (for callers that time ticks).
  bool ticked() const { return ticked_; }
  double lastTickTime() const { return last_tick_time_; }

  // The collision world as of the last tick.
  const RoomWorld& world() const { return world_; }

  // Spectators (server/web): f(member id, the newest accepted posture record's §3.3
  // bytes) for every member that has one, in join order. The bytes live until the next
  // call that changes the room.
  template <typename F>
  void forEachPosture(F&& f) const {
    for (const Member& m : members_) {
      if (m.has_posture) f(m.id.value, std::span<const std::uint8_t>(m.record_bytes));
    }
  }

 private:
  // A posture sequence further than this from the last one decoded is a jump (Room::onDatagram).
  static constexpr std::uint16_t kMaxSequenceJump = 1024;

  struct Member {
    MemberId id;
    wire::DatagramOpener in;   // its datagrams: uplink key, replay window
    wire::DatagramSealer out;  // ours to it: downlink key, counter
    bool bound = false;
    wire::Endpoint endpoint;
    int joint_count = 0;   // 0 = avatar not ready: postures are refused
    glm::vec2 seat{0.0f};  // where it stands (x, z), for interest
    bool has_posture = false;
    bool fresh = false;                      // accepted since the last forwarding batch
    std::uint32_t accepted = 0;              // postures accepted (decimates far recipients)
    std::uint16_t sequence = 0;              // of the stored posture
    std::vector<std::uint8_t> record_bytes;  // the newest posture record, §3.3 bytes
    wire::PostureDeltaDecoder decoder;       // its uplink (delta-coded postures)
    bool has_ack = false;                    // a posture decoded: ack it in snapshots
    std::uint16_t ack = 0;                   // the newest sequence decoded
    bool want_keyframe = false;              // a delta came without its reference
    double last_heard = 0.0;
    bool timeout_reported = false;
  };

  Member* find(std::uint32_t member_id);
  void onPosture(std::span<const std::uint8_t> datagram, const wire::Endpoint& from, double now,
                 Effects& fx);
  void onPing(std::span<const std::uint8_t> datagram, const wire::Endpoint& from, double now,
              Effects& fx);
  // A voice frame (WIRE.md §3.10): authenticated, rate-limited, then sealed on to the
  // listeners VoiceForwarding picks.
  void onVoice(std::span<const std::uint8_t> datagram, const wire::Endpoint& from, double now,
               Effects& fx);
  // Every member's head for voice forwarding (at each tick, after the world's step).
  void updateVoiceHeads();
  // Common checks of a client datagram: a known member at its bound endpoint, sealed with
  // its key under a fresh counter. On success `plain` is the opened plain layout (in a
  // scratch buffer, valid until the next call); logs, counts and returns nullptr on failure.
  Member* authenticate(std::span<const std::uint8_t> datagram, const wire::Endpoint& from,
                       double now, std::string_view what, std::span<const std::uint8_t>& plain);
  // Sends every member the fresh postures its interest lets through.
  void forward(double now, Effects& fx);
  void sendWorld(double now, Effects& fx);
  // Rate divisors per (recipient, source) in members_ order, from the seats.
  void updateInterest();

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
  std::uint64_t postures_without_reference_ = 0;
  std::uint64_t entries_forwarded_ = 0;
  bool forward_pending_ = false;
  double next_forward_ = 0.0;
  double last_forward_ = -1e300;
  bool ticked_ = false;
  static constexpr double kStallSeconds = 1.0;  // update() gaps longer than this are pauses
  double last_update_;
  bool interest_dirty_ = true;
  std::vector<std::uint8_t> interest_;  // [recipient * n + source]: divisor (0 for self)
  std::vector<std::pair<float, int>> scratch_order_;
  // The snapshot header a member gets: the room's, with its own posture acknowledgement.
  static void acknowledge(const Member& to, wire::SnapshotHeader& header);
  // Reused per datagram, so steady state allocates nothing.
  wire::PostureRecord scratch_record_;
  std::vector<std::uint8_t> scratch_datagram_;  // a datagram being opened
  VoiceForwarding voice_;
  std::vector<std::uint32_t> scratch_listeners_;  // a voice frame's recipients
  std::vector<std::uint8_t> scratch_forward_;     // its VoiceForward, plain
};

}  // namespace vistel::server
