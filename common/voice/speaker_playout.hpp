// One remote speaker's receive side: the playout buffer and the Opus decoder.
//
// push() takes a packet from the network with its arrival time (receiver clock, samples at
// 48 kHz); pull() fills one 20 ms mono frame for the playout tick starting at now, decoding,
// recovering by FEC or concealing as the buffer decides (see jitter_buffer.hpp), or writing
// silence. A packet libopus rejects is concealed and counted (decode_errors). Cost: one
// libopus call per pull while the speaker talks; no allocation after create().
#pragma once

#include <span>

#include "common/base/result.hpp"
#include "common/voice/jitter_buffer.hpp"
#include "common/voice/opus_voice.hpp"

namespace vistel {

class SpeakerPlayout {
 public:
  static Result<SpeakerPlayout> create(const JitterBufferSettings& settings = {});

  bool push(const VoicePacketView& packet, int64_t arrival_time) {
    return buffer_.push(packet, arrival_time);
  }

  // Writes kVoiceFrameSamples samples to out and says what they are.
  PlayoutDecision pull(int64_t now, std::span<float> out);

  const VoiceJitterBuffer& buffer() const { return buffer_; }
  int64_t decodeErrors() const { return decode_errors_; }

 private:
  SpeakerPlayout(VoiceJitterBuffer buffer, OpusVoiceDecoder decoder)
      : buffer_(std::move(buffer)), decoder_(std::move(decoder)) {}

  VoiceJitterBuffer buffer_;
  OpusVoiceDecoder decoder_;
  bool decoder_active_ = false;  // the decoder has state from the current talkspurt
  int64_t decode_errors_ = 0;
};

}  // namespace vistel
