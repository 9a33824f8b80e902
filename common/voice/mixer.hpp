// The voice mixer: spatialised speakers summed into one stereo block, then limited.
//
// beginBlock() clears the bus; addSpeaker() spatialises one speaker's mono block from its
// position relative to the listener's head (spatialiser.hpp) into the bus; finishBlock()
// runs the limiter and writes the block out. Blocks are kVoiceFrameSamples per channel,
// stereo interleaved. The limiter guarantees |sample| <= ceiling: instant attack on a
// peak above the ceiling (so nothing clips, at the cost of a little distortion on that
// peak), exponential release back to unity gain. Cost: O(block) per speaker; no
// allocation after construction.
#pragma once

#include <span>
#include <vector>

#include "common/voice/spatialiser.hpp"

namespace vistel {

struct LimiterSettings {
  float ceiling = 0.891f;    // linear peak (-1 dBFS)
  float release_ms = 80.0f;  // time constant back to unity gain
};

class StereoLimiter {
 public:
  explicit StereoLimiter(const LimiterSettings& settings = {});
  // Limits interleaved stereo in place.
  void process(std::span<float> stereo);
  float gain() const { return gain_; }

 private:
  LimiterSettings settings_;
  float release_coefficient_;
  float gain_ = 1.0f;
};

class VoiceMixer {
 public:
  explicit VoiceMixer(const SpatialSettings& spatial = {}, const LimiterSettings& limiter = {});

  void beginBlock();
  // mono: kVoiceFrameSamples samples of one speaker; state: that speaker's, for this listener.
  void addSpeaker(const HeadPose& listener, const glm::vec3& p_source_world,
                  std::span<const float> mono, SpatialSourceState& state);
  // Limits the bus and copies it to out_stereo (2 * kVoiceFrameSamples).
  void finishBlock(std::span<float> out_stereo);

  const SpatialSettings& spatialSettings() const { return spatial_; }
  const StereoLimiter& limiter() const { return limiter_; }

 private:
  SpatialSettings spatial_;
  StereoLimiter limiter_;
  std::vector<float> bus_;  // 2 * kVoiceFrameSamples, interleaved
};

}  // namespace vistel
