// The voice pipeline's one sample format and frame size.
//
// Every buffer in common/voice is 48 kHz float samples in [-1, 1] (int16 only at the
// file and speexdsp boundaries). Mono buffers hold one sample per tick; stereo buffers are
// interleaved left, right. One voice frame is 20 ms = 960 samples (per channel). Times
// inside the pipeline are counted in samples at 48 kHz (int64 on the receiver, the
// sender's capture clock as uint32 on the wire, wrapping every 24.8 hours).
#pragma once

#include <cstdint>

namespace vistel {

inline constexpr int kVoiceSampleRate = 48000;  // Hz
inline constexpr int kVoiceFrameSamples = 960;  // 20 ms at 48 kHz, per channel
inline constexpr int kVoiceFrameMs = 20;
inline constexpr int kVoiceMaxPacketBytes = 400;  // an Opus voice packet at <= 32 kbit/s is < 100

// Seconds to samples at 48 kHz (rounded) and back.
inline constexpr int64_t voiceSamplesFromSeconds(double seconds) {
  return static_cast<int64_t>(seconds * kVoiceSampleRate + (seconds >= 0 ? 0.5 : -0.5));
}
inline constexpr double voiceSecondsFromSamples(int64_t samples) {
  return static_cast<double>(samples) / kVoiceSampleRate;
}

}  // namespace vistel
