// Summing spatialised voices, with a peak limiter on the sum.
#include "common/voice/mixer.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace vistel {

StereoLimiter::StereoLimiter(const LimiterSettings& settings)
    : settings_(settings),
      release_coefficient_(1.0f -
                           std::exp(-1.0f / (settings.release_ms * 0.001f * kVoiceSampleRate))) {}

void StereoLimiter::process(std::span<float> stereo) {
  for (size_t i = 0; i + 1 < stereo.size(); i += 2) {
    // The gain this pair needs; drop to it at once, recover slowly.
    const float peak = std::max(std::abs(stereo[i]), std::abs(stereo[i + 1]));
    const float needed = peak > settings_.ceiling ? settings_.ceiling / peak : 1.0f;
    if (needed < gain_) {
      gain_ = needed;
    } else {
      gain_ += (1.0f - gain_) * release_coefficient_;
      gain_ = std::min(gain_, needed);
    }
    stereo[i] *= gain_;
    stereo[i + 1] *= gain_;
  }
}

VoiceMixer::VoiceMixer(const SpatialSettings& spatial, const LimiterSettings& limiter)
    : spatial_(spatial), limiter_(limiter), bus_(2 * kVoiceFrameSamples, 0.0f) {}

void VoiceMixer::beginBlock() { std::fill(bus_.begin(), bus_.end(), 0.0f); }

void VoiceMixer::addSpeaker(const HeadPose& listener, const glm::vec3& p_source_world,
                            std::span<const float> mono, SpatialSourceState& state) {
  assert(mono.size() == static_cast<size_t>(kVoiceFrameSamples));
  spatialiseAdd(mono, spatialParams(spatial_, listener, p_source_world), state, bus_);
}

void VoiceMixer::finishBlock(std::span<float> out_stereo) {
  assert(out_stereo.size() >= bus_.size());
  limiter_.process(bus_);
  std::copy(bus_.begin(), bus_.end(), out_stereo.begin());
}

}  // namespace vistel
