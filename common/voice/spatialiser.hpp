// The spatialiser: a mono voice at a position in the room, heard by a listener's head.
//
// Space: world space, metres, +Y up. The listener's head pose is its position and
// orientation in world space; in head space the head faces +Z, its left ear is on +X
// (the avatar convention). For a source at p_world the direction in head space gives:
// - interaural time difference (Woodworth's spherical head): tau = (a / c)(theta + sin
//   theta), theta = the lateral angle (asin of the direction's +X component), a = head
//   radius, c = speed of sound; the far ear is delayed by tau (at most ~0.66 ms, 31.5
//   samples at 48 kHz, for a = 8.75 cm), less the head-shadow filter's own low-frequency
//   group delay so that the two together give Woodworth's ITD;
// - interaural level difference by a level model: each ear's gain in dB is
//   (ild_db / 2) * cos(angle between the source and that ear's axis), so a source on the
//   interaural axis is ild_db louder in the near ear; and a head shadow: a one-pole
//   low-pass on the ear facing away, its corner falling to shadow_cutoff_hz for a source
//   straight behind that ear;
// - distance attenuation, inverse distance clamped: gain = reference / d for d in
//   [reference, max_distance] (1 within the reference; doubling d is -6.02 dB), 0 beyond
//   max_distance (the hearing radius).
// spatialiseAdd renders one block with the gains, delays (fractional, linear
// interpolation) and filter coefficients interpolated sample by sample from the previous
// block's values to this block's, so a moving source makes no clicks. It adds into a
// stereo (interleaved) buffer. Cost: O(block) per source, no allocation.
#pragma once

#include <array>
#include <span>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/voice/voice_format.hpp"

namespace vistel {

struct HeadPose {
  glm::vec3 position{0.0f};                       // world space, metres
  glm::quat orientation{1.0f, 0.0f, 0.0f, 0.0f};  // head space to world space
};

struct SpatialSettings {
  float reference_distance = 1.0f;   // metres: full level at and within
  float max_distance = 20.0f;        // metres: the hearing radius, silent beyond
  float head_radius = 0.0875f;       // metres (Woodworth)
  float speed_of_sound = 343.0f;     // metres per second
  float ild_db = 10.0f;              // near minus far ear level for a source on the axis
  float shadow_cutoff_hz = 2000.0f;  // the shadowed ear's low-pass corner, source behind it
};

// Per ear (0 left, 1 right): what spatialiseAdd applies.
struct SpatialParams {
  std::array<float, 2> gain{1.0f, 1.0f};    // linear, distance included
  std::array<float, 2> delay{0.0f, 0.0f};   // samples at 48 kHz (delay line), >= 0
  std::array<float, 2> shadow{1.0f, 1.0f};  // one-pole coefficient in (0, 1]; 1 = no filter
};

// What one source sounds like from the listener's head.
SpatialParams spatialParams(const SpatialSettings& settings, const HeadPose& listener,
                            const glm::vec3& p_source_world);

// Per source and listener: the delay line and what was applied last (sized once).
struct SpatialSourceState {
  static constexpr int kHistory = 64;  // past samples kept: > the largest ITD + 1
  bool primed = false;                 // false: the first block starts at its target
  SpatialParams last;
  std::array<float, 2> filter{0.0f, 0.0f};  // the one-pole low-passes' memory
  // History, then this block, then one spare sample (read with weight 0 at zero delay).
  std::array<float, kHistory + kVoiceFrameSamples + 1> line{};
};

// Renders mono (at most kVoiceFrameSamples samples) moving from state.last to target, and
// adds it into stereo_out (interleaved, 2 * mono.size()).
void spatialiseAdd(std::span<const float> mono, const SpatialParams& target,
                   SpatialSourceState& state, std::span<float> stereo_out);

}  // namespace vistel
