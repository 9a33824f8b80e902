// A per-speaker adaptive playout (jitter) buffer for 20 ms voice packets.
//
// The receiver pushes each packet with its arrival time and pulls one decision per 20 ms
// playout tick; the buffer holds no codec (SpeakerPlayout adds the Opus decoder), so it
// can be run over simulated hours in a test.
//
// Clocks. A packet carries its sender's frame sequence (uint16, +1 per packet sent) and
// capture time (uint32, the sender's clock in samples at 48 kHz, of the frame's first
// sample); both wrap and are extended to int64 against the newest seen. Arrival and pull
// times are the receiver's clock in samples at 48 kHz (int64). The two clocks are unrelated
// (offset and a drift of some hundred ppm).
//
// Delay. For every packet the offset o = arrival - capture is recorded over a window of
// recent packets (window_packets). The playout aims at a target offset D = the percentile
// (percentile) of o over the window + margin_samples: a frame captured at c is pulled at
// about c + D, so packets later than that percentile are few. D rises as soon as jitter
// rises and falls as the window forgets. Frames are played on the pull grid, so the real
// offset lies in [D, D + one frame).
//
// Talkspurts. A packet whose sequence follows the previous one but whose capture time
// jumps forward starts a new talkspurt (the sender stopped sending in silence). Between
// talkspurts the buffer outputs silence and starts the next talkspurt at the first pull
// where it is due, which re-aligns the delay to D for free.
//
// Inside a talkspurt: a missing packet is recovered from the FEC of the next packet when
// that one is buffered and directly follows it (kFec), else concealed (kConceal: codec
// PLC); after max_conceal_frames concealed frames with no newer packet continuing the
// talkspurt (same spacing in sequence and capture time, within max_conceal_frames) the
// talkspurt is over, so a gap in sequence left by a forwarding server that skipped this
// speaker for a while costs at most max_conceal_frames of concealment. When the real offset leaves
// [D - early_slack, D + frame + hysteresis] (jitter fell, jitter rose, or clock drift between
// sender and receiver accumulated) one frame is dropped (too much delay) or one concealment frame
// is inserted (too little), so the delay follows D and does not grow over an hour: a sender 200 ppm
// fast costs one dropped frame every 100 s of continuous speech, and none when it pauses.
//
// Bad input: packets with an empty or oversized payload are rejected (push returns false);
// late packets (their frame already played or concealed), duplicates and packets too far
// ahead of the playout (more than capacity frames) are dropped and counted. Cost: push
// O(window_packets) when it recomputes the percentile (every 8th packet, or at once for a
// packet later than the target), else O(1); pull O(capacity); no allocation after
// construction.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "common/voice/voice_format.hpp"

namespace vistel {

struct VoicePacketView {
  uint16_t sequence = 0;             // +1 per packet sent, wraps
  uint32_t capture_time = 0;         // sender clock, samples at 48 kHz, wraps
  std::span<const uint8_t> payload;  // one Opus packet (1..kVoiceMaxPacketBytes bytes)
};

struct JitterBufferSettings {
  int window_packets = 500;       // arrival statistics: the last 10 s of speech
  double percentile = 0.97;       // of the arrival - capture offsets
  int margin_samples = 240;       // 5 ms on top of the percentile
  int hysteresis_samples = 480;   // 10 ms beyond a frame of excess delay before a drop
  int early_slack_samples = 120;  // 2.5 ms short of the target before an insert
  int max_delay_samples = 24000;  // 500 ms: the target never exceeds min offset + this
  int max_conceal_frames = 4;     // concealed with nothing newer buffered: talkspurt over
  int capacity = 64;              // packets held (1.28 s)
};

enum class PlayoutKind : uint8_t {
  kSilence,  // nothing to play (between talkspurts, or before the first packet)
  kDecode,   // decode `packet`
  kFec,      // recover the missing frame from `packet` (the one after it) by its FEC
  kConceal,  // codec packet-loss concealment (a missing frame, or an inserted one)
};

struct PlayoutDecision {
  PlayoutKind kind = PlayoutKind::kSilence;
  std::span<const uint8_t> packet;  // kDecode / kFec; valid until the next push or pull
  int64_t capture_time = -1;        // sender clock (extended), samples: the frame played;
                                    // -1 for silence and inserted concealment
  int64_t sequence = -1;            // extended sequence of the frame played, or -1
};

struct JitterBufferStats {
  int64_t received = 0;  // accepted into the buffer
  int64_t invalid = 0;   // rejected payloads
  int64_t late = 0;      // arrived after their frame was played or concealed
  int64_t duplicate = 0;
  int64_t too_far = 0;  // beyond the buffer's capacity ahead of the playout
  int64_t decoded = 0;  // pulls by kind
  int64_t fec = 0;
  int64_t concealed = 0;  // missing frames concealed (not counting inserted ones)
  int64_t silence = 0;
  int64_t dropped = 0;   // buffered frames skipped to shorten the delay
  int64_t inserted = 0;  // concealment frames inserted to lengthen the delay
  int64_t talkspurts = 0;
};

class VoiceJitterBuffer {
 public:
  explicit VoiceJitterBuffer(const JitterBufferSettings& settings = {});

  // Offers one packet that arrived at arrival_time (receiver clock, samples). Returns false
  // for a rejected payload; late, duplicate and too-far packets return true but are counted
  // and dropped.
  bool push(const VoicePacketView& packet, int64_t arrival_time);

  // What to play for the 20 ms starting at now (receiver clock, samples; one call per
  // tick, now increasing by kVoiceFrameSamples).
  PlayoutDecision pull(int64_t now);

  // The target offset D (receiver minus sender clock, samples), valid once a packet came.
  int64_t targetOffset() const { return target_offset_; }
  // D minus the smallest offset in the window: the delay added for jitter, samples.
  int64_t jitterDelay() const { return target_offset_ - min_offset_; }
  // now - capture time of the last frame played (decoded, FEC or concealed), samples.
  int64_t lastPlayoutOffset() const { return last_playout_offset_; }
  bool playing() const { return playing_; }
  const JitterBufferStats& stats() const { return stats_; }
  const JitterBufferSettings& settings() const { return settings_; }

 private:
  struct Slot {
    bool used = false;
    int64_t sequence = 0;
    int64_t capture_time = 0;
    uint16_t size = 0;
    std::array<uint8_t, kVoiceMaxPacketBytes> bytes{};
  };

  Slot* find(int64_t sequence);
  Slot* earliest();
  PlayoutDecision emit(PlayoutKind kind, const Slot* slot, int64_t capture, int64_t sequence);
  void recordOffset(int64_t offset);

  JitterBufferSettings settings_;
  std::vector<Slot> slots_;       // capacity, indexed by sequence mod capacity
  std::vector<int64_t> offsets_;  // window_packets: arrival - capture, a ring
  std::vector<int64_t> scratch_;  // window_packets: for the percentile
  size_t offsets_count_ = 0;
  size_t offsets_next_ = 0;
  int since_update_ = 0;  // packets since the percentile was last computed
  std::array<uint8_t, kVoiceMaxPacketBytes> out_packet_{};  // what the decision points at

  bool have_reference_ = false;  // any packet seen (the extension reference is valid)
  int64_t newest_sequence_ = 0;  // extended
  int64_t newest_capture_ = 0;   // extended
  int64_t target_offset_ = 0;
  int64_t min_offset_ = 0;

  bool playing_ = false;
  bool have_horizon_ = false;
  int64_t next_sequence_ = 0;  // the next frame to play (playing) / the lowest acceptable
  int64_t play_capture_ = 0;   // its capture time (playing)
  int missing_run_ = 0;        // consecutive concealed frames with nothing newer buffered
  int64_t last_playout_offset_ = 0;
  JitterBufferStats stats_;
};

}  // namespace vistel
