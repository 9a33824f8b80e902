// The voice side of a client session (proto/WIRE.md §3.10): frames to send, frames received.
//
// ClientSession seals an OutgoingVoice into a Voice datagram (sendVoice) and puts every
// VoiceForward datagram it opens from a roster member other than itself into its
// VoiceInbox, with the arrival time; the voice engine (client/voice) takes them from there
// on its own thread (NetDriver::takeVoice). The inbox is a bounded queue: when nobody takes
// (no audio), the oldest frames go and are counted. Sizes: a frame holds its Opus payload
// inline (at most wire::kMaxVoicePayloadBytes), so the queue allocates once.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "common/wire/voice_packets.hpp"

namespace vistel::net {

// One 20 ms frame the own voice engine sends.
struct OutgoingVoice {
  std::uint32_t capture_time = 0;                // samples at 48 kHz, of the frame's first sample
  std::uint8_t level = wire::kVoiceLevelSilent;  // -dBFS (wire::voiceLevelField)
  std::span<const std::uint8_t> payload;         // one Opus packet, 1..400 bytes
};

// One frame of another member as it arrived.
struct ReceivedVoice {
  std::uint32_t speaker_id = 0;
  std::uint16_t sequence = 0;
  std::uint32_t capture_time = 0;  // the speaker's, samples at 48 kHz
  std::uint8_t level = wire::kVoiceLevelSilent;
  double arrival = 0.0;  // the session's clock (seconds)
  std::uint16_t size = 0;
  std::array<std::uint8_t, wire::kMaxVoicePayloadBytes> payload{};
  std::span<const std::uint8_t> bytes() const { return {payload.data(), size}; }
};

struct VoiceCounters {
  std::uint64_t sent = 0;        // Voice datagrams sealed and queued
  std::uint64_t bytes_sent = 0;  // their sealed bytes
  std::uint64_t received = 0;    // VoiceForward datagrams accepted
  std::uint64_t bytes_received = 0;
  std::uint64_t rejected = 0;    // malformed, or from a speaker not in the roster
  std::uint64_t overflowed = 0;  // dropped from a full inbox (nobody took them)
};

class VoiceInbox {
 public:
  static constexpr std::size_t kCapacity = 256;  // 5 s of one speaker, 0.8 s of six

  VoiceInbox() { frames_.resize(kCapacity); }

  // A slot for the next frame (the oldest is overwritten when full).
  ReceivedVoice& push() {
    if (count_ == kCapacity) {
      head_ = (head_ + 1) % kCapacity;
      --count_;
      ++counters.overflowed;
    }
    ReceivedVoice& slot = frames_[(head_ + count_) % kCapacity];
    ++count_;
    return slot;
  }
  // Appends every queued frame to out, oldest first, and empties the queue.
  void takeAll(std::vector<ReceivedVoice>& out) {
    for (std::size_t i = 0; i < count_; ++i) out.push_back(frames_[(head_ + i) % kCapacity]);
    head_ = 0;
    count_ = 0;
  }
  std::size_t size() const { return count_; }

  VoiceCounters counters;

 private:
  std::vector<ReceivedVoice> frames_;
  std::size_t head_ = 0;
  std::size_t count_ = 0;
};

}  // namespace vistel::net
