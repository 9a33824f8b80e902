// Voice activity: silence and low noise are not sent, speech is, and the hangover keeps
// sending after the last speech frame.
#include "common/voice/voice_activity.hpp"

#include <cstdio>
#include <random>

#include <gtest/gtest.h>

#include "common/voice/speech_synth.hpp"

namespace vistel {
namespace {

std::vector<VoiceActivityDecision> classify(VoiceActivity& vad, std::vector<float> signal) {
  std::vector<VoiceActivityDecision> out;
  for (size_t at = 0; at + kVoiceFrameSamples <= signal.size(); at += kVoiceFrameSamples) {
    out.push_back(vad.process(std::span<float>(signal.data() + at, kVoiceFrameSamples)));
  }
  return out;
}

std::vector<float> noise(double seconds, float rms, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> gauss(0.0f, rms);
  std::vector<float> out(static_cast<size_t>(seconds * kVoiceSampleRate));
  for (float& x : out) x = gauss(rng);
  return out;
}

TEST(VoiceActivity, SilenceAndQuietNoiseAreNotSent) {
  auto vad = VoiceActivity::create();
  ASSERT_TRUE(vad.ok());
  const auto silent = classify(*vad, std::vector<float>(2 * kVoiceSampleRate, 0.0f));
  const auto hiss = classify(*vad, noise(3.0, 0.0005f, 1));  // about -66 dBFS
  int sent = 0;
  for (const auto& d : silent) sent += d.send ? 1 : 0;
  for (const auto& d : hiss) sent += d.send ? 1 : 0;
  EXPECT_EQ(sent, 0);
}

TEST(VoiceActivity, SpeechIsSentAndTheHangoverCoversWordEnds) {
  auto vad = VoiceActivity::create();
  ASSERT_TRUE(vad.ok());
  // 1 s of quiet noise (the denoiser learns it), 2 s of continuous speech over it, 1 s of
  // the noise alone.
  auto signal = noise(4.0, 0.0005f, 2);
  const auto speech = synthesizeSpeech(2.0, {.pauses = false, .seed = 4});
  for (size_t i = 0; i < speech.size(); ++i) signal[kVoiceSampleRate + i] += speech[i];
  const auto decisions = classify(*vad, signal);
  ASSERT_EQ(decisions.size(), 200u);

  // Speech frames (50..149): nearly all sent.
  int speech_sent = 0;
  for (int k = 50; k < 150; ++k) speech_sent += decisions[k].send ? 1 : 0;
  // After the last speech frame: sent for the hangover, then no more.
  int last_speech = -1;
  for (int k = 0; k < 200; ++k) {
    if (decisions[k].speech) last_speech = k;
  }
  int sent_before = 0;
  for (int k = 0; k < 50; ++k) sent_before += decisions[k].send ? 1 : 0;
  std::printf("speech frames sent %d / 100, last speech frame %d, sent before speech %d\n",
              speech_sent, last_speech, sent_before);
  EXPECT_GE(speech_sent, 90);
  EXPECT_EQ(sent_before, 0);
  ASSERT_GE(last_speech, 140);
  ASSERT_LT(last_speech, 150 + 5);
  const int hangover = vad->settings().hangover_frames;
  for (int k = last_speech + 1; k <= last_speech + hangover && k < 200; ++k) {
    EXPECT_TRUE(decisions[k].send) << "frame " << k << " inside the hangover";
    EXPECT_FALSE(decisions[k].speech);
  }
  for (int k = last_speech + hangover + 1; k < 200; ++k) {
    EXPECT_FALSE(decisions[k].send) << "frame " << k << " after the hangover";
  }
}

TEST(VoiceActivity, RejectsBadSettings) {
  EXPECT_FALSE(VoiceActivity::create({.hangover_frames = -1}).ok());
  EXPECT_FALSE(VoiceActivity::create({.prob_start_percent = 120}).ok());
}

}  // namespace
}  // namespace vistel
