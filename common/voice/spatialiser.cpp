// Binaural cues for a spherical head: Woodworth & Schlosberg 1954 (ITD), a level model
// with a one-pole head shadow after Brown & Duda 1998 (ILD), inverse distance clamped.
#include "common/voice/spatialiser.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace vistel {

SpatialParams spatialParams(const SpatialSettings& settings, const HeadPose& listener,
                            const glm::vec3& p_source_world) {
  SpatialParams params;
  // The source in head space: +Z ahead, +X the left ear.
  const glm::vec3 p_head =
      glm::inverse(listener.orientation) * (p_source_world - listener.position);
  const float distance = glm::length(p_head);
  const glm::vec3 direction = distance > 1e-6f ? p_head / distance : glm::vec3(0, 0, 1);

  // Distance: inverse distance clamped, silent beyond the hearing radius.
  float distance_gain = 0.0f;
  if (distance <= settings.max_distance) {
    distance_gain = settings.reference_distance / std::max(distance, settings.reference_distance);
  }

  // ITD (Woodworth): the far ear is delayed.
  const float lateral = std::asin(std::clamp(direction.x, -1.0f, 1.0f));  // + = left
  const float itd_seconds = settings.head_radius / settings.speed_of_sound *
                            (std::abs(lateral) + std::sin(std::abs(lateral)));
  const float itd = itd_seconds * static_cast<float>(kVoiceSampleRate);
  params.delay =
      lateral >= 0.0f ? std::array<float, 2>{0.0f, itd} : std::array<float, 2>{itd, 0.0f};

  // ILD: level per ear from the angle to its axis, and the shadow on the far side.
  const float shadow_min =
      1.0f - std::exp(-2.0f * 3.14159265f * settings.shadow_cutoff_hz / kVoiceSampleRate);
  for (int ear = 0; ear < 2; ++ear) {
    const float cos_ear = ear == 0 ? direction.x : -direction.x;
    const float level_db = 0.5f * settings.ild_db * cos_ear;
    params.gain[ear] = distance_gain * std::pow(10.0f, level_db / 20.0f);
    const float shadow_amount = std::max(0.0f, -cos_ear);
    params.shadow[ear] = 1.0f + (shadow_min - 1.0f) * shadow_amount;
    // The shadow low-pass delays low frequencies by (1 - b) / b samples: take that off
    // the delay line so the interaural delay stays Woodworth's.
    const float filter_delay = (1.0f - params.shadow[ear]) / params.shadow[ear];
    params.delay[ear] = std::max(0.0f, params.delay[ear] - filter_delay);
  }
  return params;
}

void spatialiseAdd(std::span<const float> mono, const SpatialParams& target,
                   SpatialSourceState& state, std::span<float> stereo_out) {
  constexpr int kHistory = SpatialSourceState::kHistory;
  const int n = static_cast<int>(mono.size());
  assert(n <= kVoiceFrameSamples && stereo_out.size() >= 2 * mono.size());
  if (!state.primed) {
    state.last = target;
    state.primed = true;
  }
  // The delay line: kHistory past samples, then this block.
  std::copy(mono.begin(), mono.end(), state.line.begin() + kHistory);

  // Each ear: interpolate gain, delay and shadow across the block.
  const float inv_n = n > 0 ? 1.0f / static_cast<float>(n) : 0.0f;
  for (int ear = 0; ear < 2; ++ear) {
    const float g0 = state.last.gain[ear], g1 = target.gain[ear];
    const float d0 = state.last.delay[ear], d1 = target.delay[ear];
    const float s0 = state.last.shadow[ear], s1 = target.shadow[ear];
    float y = state.filter[ear];
    for (int i = 0; i < n; ++i) {
      const float t = static_cast<float>(i + 1) * inv_n;
      const float delay = std::clamp(d0 + (d1 - d0) * t, 0.0f, kHistory - 2.0f);
      const float position = static_cast<float>(kHistory + i) - delay;
      const int index = static_cast<int>(position);
      const float frac = position - static_cast<float>(index);
      const float x = state.line[index] + frac * (state.line[index + 1] - state.line[index]);
      y += (s0 + (s1 - s0) * t) * (x - y);
      stereo_out[2 * i + ear] += (g0 + (g1 - g0) * t) * y;
    }
    state.filter[ear] = std::abs(y) < 1e-20f ? 0.0f : y;  // no denormals in silence
  }
  // Keep the last kHistory samples for the next block's delays.
  std::copy(state.line.begin() + n, state.line.begin() + n + kHistory, state.line.begin());
  state.last = target;
}

}  // namespace vistel
