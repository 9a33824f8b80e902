#include "common/voice/echo_canceller.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include <speex/speex_echo.h>

#include "common/voice/voice_format.hpp"

namespace vistel {
namespace {

constexpr int kBlock = kVoiceFrameSamples / 2;  // 10 ms

std::int16_t toPcm(float x) {
  return static_cast<std::int16_t>(std::lround(std::clamp(x, -1.0f, 1.0f) * 32767.0f));
}

}  // namespace

void EchoCanceller::Deleter::operator()(SpeexEchoState_* state) const {
  speex_echo_state_destroy(state);
}

Result<EchoCanceller> EchoCanceller::create(const EchoCancellerSettings& settings) {
  if (settings.tail_ms < 20 || settings.tail_ms > 1000) {
    return fail("echo canceller: tail {} ms outside 20..1000", settings.tail_ms);
  }
  EchoCanceller result;
  const int tail = settings.tail_ms * kVoiceSampleRate / 1000;
  result.state_.reset(speex_echo_state_init(kBlock, tail));
  if (!result.state_) return fail("echo canceller: speexdsp init failed");
  int rate = kVoiceSampleRate;
  speex_echo_ctl(result.state_.get(), SPEEX_ECHO_SET_SAMPLING_RATE, &rate);
  result.captured_.assign(kVoiceFrameSamples, 0);
  result.played_.assign(kVoiceFrameSamples, 0);
  result.out_.assign(kVoiceFrameSamples, 0);
  return result;
}

void EchoCanceller::cancel(std::span<float> captured, std::span<const float> played) {
  assert(captured.size() == static_cast<std::size_t>(kVoiceFrameSamples));
  assert(played.size() == static_cast<std::size_t>(kVoiceFrameSamples));
  for (std::size_t i = 0; i < captured.size(); ++i) {
    captured_[i] = toPcm(captured[i]);
    played_[i] = toPcm(played[i]);
  }
  for (int b = 0; b < kVoiceFrameSamples; b += kBlock) {
    speex_echo_cancellation(state_.get(), captured_.data() + b, played_.data() + b,
                            out_.data() + b);
  }
  for (std::size_t i = 0; i < captured.size(); ++i) {
    captured[i] = static_cast<float>(out_[i]) / 32767.0f;
  }
}

void EchoCanceller::reset() { speex_echo_state_reset(state_.get()); }

}  // namespace vistel
