// The echo canceller (speexdsp's) on a simulated room: the far end's voice played by the
// speakers comes back into the microphone 40 ms later with a 70 ms reflection; the near
// end's own voice must go out and the echo must not.
#include <algorithm>
#include <cstdio>
#include <vector>

#include <gtest/gtest.h>

#include "common/voice/audio_compare.hpp"
#include "common/voice/echo_canceller.hpp"
#include "common/voice/speech_synth.hpp"
#include "common/voice/voice_format.hpp"

namespace vistel {
namespace {

constexpr int kSeconds = 10;
constexpr int kNearStartS = 6;  // the near end starts talking here (double talk after)

struct Room {
  std::vector<float> far, near, mic;
};

// The microphone: the near end (from kNearStartS on) plus the far end's echo.
Room simulate() {
  Room r;
  r.far = synthesizeSpeech(kSeconds, {.f0_hz = 120.0f, .level = 0.3f, .pauses = true, .seed = 1});
  r.near = synthesizeSpeech(kSeconds, {.f0_hz = 210.0f, .level = 0.3f, .pauses = true, .seed = 2});
  const std::size_t n = std::min(r.far.size(), r.near.size());
  r.far.resize(n);
  r.near.resize(n);
  std::fill(r.near.begin(), r.near.begin() + kNearStartS * kVoiceSampleRate, 0.0f);
  r.mic.assign(n, 0.0f);
  for (std::size_t i = 0; i < n; ++i) {
    float echo = 0.0f;
    if (i >= 1920) echo += 0.6f * r.far[i - 1920];   // 40 ms: device latency and direct path
    if (i >= 3360) echo += 0.25f * r.far[i - 3360];  // 70 ms: a wall
    r.mic[i] = r.near[i] + echo;
  }
  return r;
}

// The microphone through the canceller, tick by tick, the far end as what was played.
std::vector<float> cancelled(const Room& r, EchoCanceller& aec) {
  std::vector<float> out = r.mic;
  for (std::size_t at = 0; at + kVoiceFrameSamples <= out.size(); at += kVoiceFrameSamples) {
    aec.cancel(std::span<float>(out).subspan(at, kVoiceFrameSamples),
               std::span<const float>(r.far).subspan(at, kVoiceFrameSamples));
  }
  return out;
}

std::span<const float> seconds(const std::vector<float>& s, int from, int to) {
  return std::span<const float>(s).subspan(static_cast<std::size_t>(from) * kVoiceSampleRate,
                                           static_cast<std::size_t>(to - from) * kVoiceSampleRate);
}

TEST(EchoCanceller, RemovesTheEchoAndKeepsTheNearVoice) {
  const Room room = simulate();
  auto aec = EchoCanceller::create();
  ASSERT_TRUE(aec.ok()) << aec.error().message;
  const std::vector<float> out = cancelled(room, *aec);

  // Far end alone, once the filter has converged (seconds 4 to 6): the echo's level drops.
  const double echo_in = levelDbfs(seconds(room.mic, 4, kNearStartS));
  const double echo_out = levelDbfs(seconds(out, 4, kNearStartS));
  // Double talk (seconds 7 to 10): what goes out is the near voice, not the far one.
  const double near_before =
      correlationAtLag(seconds(room.near, 7, kSeconds), seconds(room.mic, 7, kSeconds), 0);
  const double near_after =
      correlationAtLag(seconds(room.near, 7, kSeconds), seconds(out, 7, kSeconds), 0);
  std::printf(
      "[ measure  ] echo alone: %.1f dBFS in, %.1f dBFS out (%.1f dB removed); double talk: "
      "near voice correlation %.3f in, %.3f out\n",
      echo_in, echo_out, echo_in - echo_out, near_before, near_after);
  EXPECT_GE(echo_in - echo_out, 10.0);
  EXPECT_GT(near_after, near_before + 0.1);
  EXPECT_GE(near_after, 0.85);
}

TEST(EchoCanceller, LeavesTheVoiceAloneWhenNothingPlays) {
  const Room room = simulate();
  auto aec = EchoCanceller::create();
  ASSERT_TRUE(aec.ok());
  std::vector<float> out = room.near;
  const std::vector<float> silence(kVoiceFrameSamples, 0.0f);
  for (std::size_t at = 0; at + kVoiceFrameSamples <= out.size(); at += kVoiceFrameSamples) {
    aec->cancel(std::span<float>(out).subspan(at, kVoiceFrameSamples), silence);
  }
  // Unchanged but for speexdsp's DC notch, which takes some of this voice's 120-210 Hz
  // fundamental: correlation about 0.93.
  EXPECT_GE(correlationAtLag(seconds(room.near, kNearStartS, kSeconds),
                             seconds(out, kNearStartS, kSeconds), 0),
            0.9);
}

TEST(EchoCanceller, RefusesAnUnreasonableTail) {
  EXPECT_FALSE(EchoCanceller::create({.tail_ms = 5}).ok());
  EXPECT_FALSE(EchoCanceller::create({.tail_ms = 5000}).ok());
}

}  // namespace
}  // namespace vistel
