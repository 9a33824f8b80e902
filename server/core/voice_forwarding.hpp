// Selective forwarding of voice (proto/SESSION.md §3 "Voice", proto/VOICE.md §5): which
// listeners get a speaker's voice frame. No mixing and no decoding: the server passes each
// frame on unchanged to the members that should hear it.
//
// For each listener the forwarder keeps a set of at most max_speakers speakers. A frame
// from speaker S reaches listener L (L != S) when S's head is within hearing_radius_m of
// L's head and S is in L's set. S enters a set with a free place at once; in a full set it
// replaces the weakest speaker (ranked by loudness at L: the speaker's level smoothed over
// 200 ms minus 20 log10 of the distance, at least 1 m) once it has outranked that speaker
// for hold_s, so no one is cut off mid-word by a momentary peak. A speaker silent for
// silence_s, out of range, or gone leaves the set. So a listener receives at most
// max_speakers streams however large the room.
//
// Each speaker is rate-limited (token buckets: frames per second and bytes per second, with
// bursts): frames past either limit are refused (`admit`), before any forwarding work.
//
// Positions are world (room) space metres, set by the room once per tick. Member ids are
// the room's. Cost per frame: O(members) (and O(max_speakers) per listener); no allocation
// once the members' state has grown. Not thread-safe (the room's strand).
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "server/core/rate_limit.hpp"

namespace vistel::server {

struct VoiceSettings {
  bool enabled = true;             // false: voice datagrams are dropped ("voice disabled")
  float hearing_radius_m = 20.0f;  // the spatialiser's max_distance: nothing audible beyond
  int max_speakers = 6;            // per listener
  double hold_s = 0.5;             // a speaker in a set is replaced after being outranked this long
  double silence_s = 0.5;          // ... and leaves it after this long without a frame
  double max_frames_per_s = 60.0;  // per speaker (Opus 20 ms: 50); burst max_frames_burst
  double max_frames_burst = 20.0;
  double max_bytes_per_s = 8000.0;  // per speaker, datagram bytes (64 kbit/s); burst 4x
};

struct VoiceForwardingStats {
  std::uint64_t frames = 0;        // admitted frames
  std::uint64_t forwarded = 0;     // frame copies sent (one per frame and listener)
  std::uint64_t out_of_range = 0;  // (frame, listener) pairs beyond the hearing radius
  std::uint64_t not_selected = 0;  // ... within it but not among the listener's speakers
  std::uint64_t rate_limited = 0;  // frames refused by admit
  std::uint64_t replacements = 0;  // speakers that took a place from a weaker one
};

class VoiceForwarding {
 public:
  explicit VoiceForwarding(const VoiceSettings& settings = {});

  void addMember(std::uint32_t id, double now);
  void removeMember(std::uint32_t id);
  // The member's head in room space (it starts at the origin until set).
  void setHead(std::uint32_t id, const glm::vec3& head);

  // Whether a frame of `bytes` datagram bytes from `speaker` is within its rate limits
  // (false for an unknown member); counts refusals.
  bool admit(std::uint32_t speaker, std::size_t bytes, double now);
  // An admitted frame with its level (-dBFS, 0..127) from `speaker`: fills `listeners`
  // (cleared first) with the ids that should receive it.
  void route(std::uint32_t speaker, std::uint8_t level, double now,
             std::vector<std::uint32_t>& listeners);

  // The speakers currently in a listener's set (for tests and metrics), in slot order.
  std::vector<std::uint32_t> speakersOf(std::uint32_t listener) const;
  const VoiceForwardingStats& stats() const { return stats_; }
  const VoiceSettings& settings() const { return settings_; }

 private:
  struct Slot {
    std::uint32_t speaker = 0;
    double outranked_since = -1.0;  // < 0: not outranked
    double outranked_last = -1.0;   // the last time a challenger beat it
  };
  struct Member {
    std::uint32_t id = 0;
    glm::vec3 head{0.0f};
    float loudness_db = -127.0f;  // smoothed level, dBFS
    double last_frame = -1e300;   // when its last admitted frame came
    TokenBucket frames;
    TokenBucket bytes;
    std::vector<Slot> slots;  // its set as a listener (<= max_speakers)
  };

  Member* find(std::uint32_t id);
  const Member* find(std::uint32_t id) const;
  // Loudness of speaker s at listener l in dB; -inf beyond the radius.
  float score(const Member& s, const Member& l) const;

  VoiceSettings settings_;
  std::vector<Member> members_;
  VoiceForwardingStats stats_;
};

}  // namespace vistel::server
