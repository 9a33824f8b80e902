// The spatialiser and the mixer: level and time differences for a source at the left,
// distance attenuation, smoothness of a moving source, and the limiter.
#include "common/voice/spatialiser.hpp"

#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "common/voice/audio_compare.hpp"
#include "common/voice/mixer.hpp"
#include "common/voice/speech_synth.hpp"

namespace vistel {
namespace {

struct Stereo {
  std::vector<float> left, right;
};

// Renders mono through a fixed or moving source, block by block.
Stereo render(const std::vector<float>& mono, const SpatialSettings& settings,
              const HeadPose& listener, glm::vec3 from, glm::vec3 to) {
  SpatialSourceState state;
  Stereo out;
  std::vector<float> block(2 * kVoiceFrameSamples);
  const size_t blocks = mono.size() / kVoiceFrameSamples;
  for (size_t b = 0; b < blocks; ++b) {
    const float t = blocks > 1 ? static_cast<float>(b) / static_cast<float>(blocks - 1) : 0.0f;
    const glm::vec3 p = from + (to - from) * t;
    std::fill(block.begin(), block.end(), 0.0f);
    spatialiseAdd(std::span<const float>(mono.data() + b * kVoiceFrameSamples, kVoiceFrameSamples),
                  spatialParams(settings, listener, p), state, block);
    for (int i = 0; i < kVoiceFrameSamples; ++i) {
      out.left.push_back(block[2 * i]);
      out.right.push_back(block[2 * i + 1]);
    }
  }
  return out;
}

TEST(Spatialiser, ASourceAtTheLeftIsLouderAndEarlierInTheLeftEar) {
  const auto speech = synthesizeSpeech(2.0, {.pauses = false});
  const SpatialSettings settings;
  HeadPose listener;
  const auto out = render(speech, settings, listener, {2, 0, 0}, {2, 0, 0});  // +X: left
  const double ild = levelDbfs(out.left) - levelDbfs(out.right);
  // The right channel trails the left by the ITD: find it by correlation.
  int best_lag = 0;
  double best = -2.0;
  for (int lag = 0; lag < 60; ++lag) {
    const double c = correlationAtLag(out.left, out.right, lag);
    if (c > best) best = c, best_lag = lag;
  }
  const double expected_itd =
      settings.head_radius / settings.speed_of_sound * (1.5707963 + 1.0) * kVoiceSampleRate;
  std::printf(
      "source at the left, 2 m: left - right %.1f dB, right trails by %d samples "
      "(Woodworth %.1f)\n",
      ild, best_lag, expected_itd);
  EXPECT_GE(ild, 6.0);
  EXPECT_NEAR(best_lag, expected_itd, 1.5);

  // Turning the head by 180 degrees puts the same source at the right.
  listener.orientation = glm::angleAxis(3.14159265f, glm::vec3(0, 1, 0));
  const auto turned = render(speech, settings, listener, {2, 0, 0}, {2, 0, 0});
  EXPECT_LE(levelDbfs(turned.left) - levelDbfs(turned.right), -6.0);
  // A source straight ahead is centred.
  const auto ahead = render(speech, settings, HeadPose{}, {0, 0, 2}, {0, 0, 2});
  EXPECT_NEAR(levelDbfs(ahead.left) - levelDbfs(ahead.right), 0.0, 0.01);
}

TEST(Spatialiser, DoublingTheDistanceIsMinus6dBAndBeyondTheRadiusIsSilent) {
  const SpatialSettings settings;
  const HeadPose listener;
  const glm::vec3 direction = glm::normalize(glm::vec3(0.3f, 0.1f, 1.0f));
  const auto near = spatialParams(settings, listener, direction * 3.0f);
  const auto far = spatialParams(settings, listener, direction * 6.0f);
  for (int ear = 0; ear < 2; ++ear) {
    EXPECT_NEAR(20.0 * std::log10(far.gain[ear] / near.gain[ear]), -6.02, 0.01);
    EXPECT_FLOAT_EQ(near.delay[ear], far.delay[ear]);
  }
  const auto inside = spatialParams(settings, listener, direction * 0.5f);
  const auto at_reference = spatialParams(settings, listener, direction * 1.0f);
  EXPECT_FLOAT_EQ(inside.gain[0], at_reference.gain[0]);
  const auto beyond = spatialParams(settings, listener, direction * 25.0f);
  EXPECT_EQ(beyond.gain[0], 0.0f);
  EXPECT_EQ(beyond.gain[1], 0.0f);
}

TEST(Spatialiser, AMovingSourceHasNoDiscontinuity) {
  // A steady 300 Hz tone; the source sweeps from the far left to the far right at 1 m
  // within a second (and then jumps back): the sample-to-sample step must stay near the
  // tone's own largest step.
  std::vector<float> tone(kVoiceSampleRate);
  for (size_t i = 0; i < tone.size(); ++i) {
    tone[i] = 0.5f * static_cast<float>(std::sin(6.283185307179586 * 300.0 * i / 48000.0));
  }
  const SpatialSettings settings;
  const auto out = render(tone, settings, HeadPose{}, {1, 0, 0.01f}, {-1, 0, 0.01f});
  const auto still = render(tone, settings, HeadPose{}, {1, 0, 0.01f}, {1, 0, 0.01f});
  auto max_step = [](const std::vector<float>& x) {
    float step = 0.0f;
    for (size_t i = 1; i < x.size(); ++i) step = std::max(step, std::abs(x[i] - x[i - 1]));
    return step;
  };
  const float still_step = std::max(max_step(still.left), max_step(still.right));
  const float moving_step = std::max(max_step(out.left), max_step(out.right));
  std::printf("moving source: largest sample step %.5f (a still source: %.5f)\n", moving_step,
              still_step);
  EXPECT_LE(moving_step, 1.1f * still_step);

  // A jump across the head within one block is still spread over the block.
  SpatialSourceState state;
  std::vector<float> block(2 * kVoiceFrameSamples, 0.0f);
  const std::span<const float> first(tone.data(), kVoiceFrameSamples);
  const std::span<const float> second(tone.data() + kVoiceFrameSamples, kVoiceFrameSamples);
  spatialiseAdd(first, spatialParams(settings, HeadPose{}, {3, 0, 0}), state, block);
  const float last_left = block[2 * (kVoiceFrameSamples - 1)];
  std::fill(block.begin(), block.end(), 0.0f);
  spatialiseAdd(second, spatialParams(settings, HeadPose{}, {-3, 0, 0}), state, block);
  EXPECT_LT(std::abs(block[0] - last_left), 0.05f);
}

TEST(Mixer, SixteenLoudSpeakersNeverClip) {
  VoiceMixer mixer;
  std::vector<SpatialSourceState> states(16);
  std::vector<std::vector<float>> voices;
  for (int s = 0; s < 16; ++s) {
    voices.push_back(synthesizeSpeech(1.0, {.f0_hz = 100.0f + 10.0f * s,
                                            .level = 0.9f,
                                            .pauses = false,
                                            .seed = static_cast<uint32_t>(s)}));
  }
  std::vector<float> out(2 * kVoiceFrameSamples);
  float peak = 0.0f;
  double energy = 0.0;
  for (int b = 0; b < 50; ++b) {
    mixer.beginBlock();
    for (int s = 0; s < 16; ++s) {
      const float angle = 0.39f * static_cast<float>(s);
      mixer.addSpeaker(
          HeadPose{}, {std::sin(angle), 0.0f, std::cos(angle)},
          std::span<const float>(voices[s].data() + b * kVoiceFrameSamples, kVoiceFrameSamples),
          states[s]);
    }
    mixer.finishBlock(out);
    for (float x : out) {
      peak = std::max(peak, std::abs(x));
      energy += static_cast<double>(x) * x;
    }
  }
  std::printf(
      "16 speakers at 1 m: mixed peak %.4f (ceiling %.3f), limiter gain at the end "
      "%.3f\n",
      peak, LimiterSettings{}.ceiling, mixer.limiter().gain());
  EXPECT_LE(peak, LimiterSettings{}.ceiling + 1e-6f);
  EXPECT_GT(energy, 0.0);
  EXPECT_LT(mixer.limiter().gain(), 1.0f);
}

TEST(Mixer, QuietVoicesPassUnchanged) {
  StereoLimiter limiter;
  std::vector<float> block = {0.1f, -0.2f, 0.3f, 0.0f};
  const auto before = block;
  limiter.process(block);
  EXPECT_EQ(block, before);
}

}  // namespace
}  // namespace vistel
