// The whole voice path of one speaker to one listener, run in simulated time (no sockets,
// no devices, no sleeping): capture in 20 ms frames -> optional voice activity (sending
// only what it selects) -> Opus encode -> a simulated network (random loss, a base delay
// plus a uniform random jitter, the sender's clock running sender_clock_ppm fast) ->
// SpeakerPlayout (jitter buffer and decoder) pulled every 20 ms on the receiver's clock ->
// spatialiser and mixer (the speaker 2 m ahead and to the left) -> a device buffer.
//
// Mouth-to-ear latency of a frame played from a packet (decoded or FEC) is the time its
// samples leave the device minus the time they were captured, both on the receiver's
// clock: pull time + output_buffer_samples - capture time. The frame's capture time marks
// its first sample, so the 20 ms of capture framing is included. heard is the decoded
// mono voice laid on the sender's timeline by each frame's capture time (what the listener
// heard of each captured sample; zeros for frames never played), for correlation with the
// input after the codec's small delay. Deterministic for a seed.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "common/base/result.hpp"
#include "common/voice/jitter_buffer.hpp"
#include "common/voice/opus_voice.hpp"
#include "common/voice/voice_activity.hpp"

namespace vistel {

struct VoiceLinkSettings {
  OpusVoiceSettings codec;
  JitterBufferSettings buffer;
  bool use_vad = false;
  VoiceActivitySettings vad;
  double loss = 0.0;              // probability that a packet is lost
  double base_delay_s = 0.0;      // one-way network delay
  double jitter_s = 0.0;          // plus a delay uniform in [0, jitter_s]
  double sender_clock_ppm = 0.0;  // the sender's clock rate error
  uint32_t seed = 1;
  int pull_phase_samples = 317;  // the receiver's tick against the sender's frames
  int output_buffer_samples = kVoiceFrameSamples;  // device buffering after the pull
  bool spatialise = true;                          // run the spatialiser and mixer on the output
};

struct VoiceLinkResult {
  std::vector<float> heard;       // sender timeline, speech.size() samples
  std::vector<float> stereo;      // what the device played (interleaved), if spatialised
  std::vector<double> latency_s;  // per frame played from a packet: mouth to ear
  JitterBufferStats stats;
  int64_t packets_sent = 0;
  int64_t bytes_sent = 0;       // Opus payload bytes
  int codec_delay_samples = 0;  // the encoder's lookahead
};

Result<VoiceLinkResult> simulateVoiceLink(std::span<const float> speech,
                                          const VoiceLinkSettings& settings);

// The q-quantile (0..1) of values (copied and partially sorted); 0 for none.
double quantile(std::vector<double> values, double q);

}  // namespace vistel
