// Voice activity detection and noise suppression through speexdsp's preprocessor
// (Valin's preprocessor: an Ephraim-Malah denoiser that estimates each frame's probability
// of speech), with speexdsp's start/continue VAD rule on that probability, an absolute level
// floor and a hangover.
#include "common/voice/voice_activity.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include <speex/speex_preprocess.h>

namespace vistel {

void VoiceActivity::Deleter::operator()(SpeexPreprocessState_* state) const {
  speex_preprocess_state_destroy(state);
}

Result<VoiceActivity> VoiceActivity::create(const VoiceActivitySettings& settings) {
  if (settings.hangover_frames < 0) {
    return fail("voice activity: hangover {} frames is negative", settings.hangover_frames);
  }
  if (settings.prob_start_percent < 0 || settings.prob_start_percent > 100 ||
      settings.prob_continue_percent < 0 || settings.prob_continue_percent > 100) {
    return fail("voice activity: VAD probabilities {} / {} outside 0..100",
                settings.prob_start_percent, settings.prob_continue_percent);
  }
  VoiceActivity result;
  result.state_.reset(speex_preprocess_state_init(kVoiceFrameSamples, kVoiceSampleRate));
  if (!result.state_) return fail("voice activity: speexdsp preprocessor init failed");
  SpeexPreprocessState* st = result.state_.get();
  int denoise = settings.denoise ? 1 : 0;
  int off = 0;
  int suppress = settings.noise_suppress_db;
  speex_preprocess_ctl(st, SPEEX_PREPROCESS_SET_DENOISE, &denoise);
  speex_preprocess_ctl(st, SPEEX_PREPROCESS_SET_AGC, &off);
  speex_preprocess_ctl(st, SPEEX_PREPROCESS_SET_DEREVERB, &off);
  speex_preprocess_ctl(st, SPEEX_PREPROCESS_SET_NOISE_SUPPRESS, &suppress);
  result.settings_ = settings;
  result.pcm_.assign(kVoiceFrameSamples, 0);
  return result;
}

VoiceActivityDecision VoiceActivity::process(std::span<float> frame) {
  assert(frame.size() == static_cast<size_t>(kVoiceFrameSamples));
  VoiceActivityDecision decision;

  // Level before denoising, and the frame as int16 for speexdsp.
  double energy = 0.0;
  for (size_t i = 0; i < frame.size(); ++i) {
    const float x = std::clamp(frame[i], -1.0f, 1.0f);
    energy += static_cast<double>(x) * x;
    pcm_[i] = static_cast<int16_t>(std::lround(x * 32767.0f));
  }
  const double rms = std::sqrt(energy / static_cast<double>(frame.size()));
  decision.level_dbfs = rms > 1e-6 ? static_cast<float>(20.0 * std::log10(rms)) : -120.0f;

  // speexdsp: the frame's speech probability, and the denoised frame written back. The
  // start / continue thresholds are speexdsp's own VAD rule, applied here because its
  // SET_VAD switch only prints a warning and applies the same rule.
  speex_preprocess_run(state_.get(), pcm_.data());
  int probability = 0;
  speex_preprocess_ctl(state_.get(), SPEEX_PREPROCESS_GET_PROB, &probability);
  const bool vad = probability > settings_.prob_start_percent ||
                   (in_speech_ && probability > settings_.prob_continue_percent);
  in_speech_ = vad;
  decision.speech_probability = probability;
  if (settings_.denoise) {
    for (size_t i = 0; i < frame.size(); ++i) frame[i] = static_cast<float>(pcm_[i]) / 32768.0f;
  }

  // Speech, and the hangover after it.
  decision.speech = vad && decision.level_dbfs > settings_.floor_dbfs;
  if (decision.speech) {
    frames_since_speech_ = 0;
  } else if (frames_since_speech_ < (1 << 30)) {
    ++frames_since_speech_;
  }
  decision.send = frames_since_speech_ <= settings_.hangover_frames;
  return decision;
}

}  // namespace vistel
