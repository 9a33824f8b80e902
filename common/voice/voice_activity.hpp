// Voice activity: which captured frames are sent (issue 22's "capture -> VAD").
//
// Each 20 ms mono frame goes through speexdsp's preprocessor (speex_preprocess_run at
// 48 kHz, frame 960), which suppresses stationary noise in place (when denoise is on) and
// estimates the frame's probability of speech (SPEEX_PREPROCESS_GET_PROB). speexdsp's VAD
// rule decides on it: speech starts above prob_start_percent and continues above
// prob_continue_percent (applied here: speexdsp's SET_VAD switch applies the same rule but
// prints a warning that its VAD "has been replaced by a hack"). A frame counts as speech
// when that rule says so and its level is above an absolute floor (speexdsp adapts to the
// noise it sees, so on near-digital silence its probability alone is unreliable). Frames are
// sent while speech lasts and for hangover_frames after it (200 ms by default) so that
// word ends and the gaps between syllables are not clipped.
//
// Cost: one speexdsp preprocess run per frame (an FFT of 1920 points), no allocation
// after create().
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "common/base/result.hpp"
#include "common/voice/voice_format.hpp"

struct SpeexPreprocessState_;

namespace vistel {

struct VoiceActivitySettings {
  bool denoise = true;             // speexdsp noise suppression applied to the frame in place
  int noise_suppress_db = -20;     // speexdsp's maximum noise attenuation (negative dB)
  int prob_start_percent = 60;     // speexdsp VAD: probability to enter speech
  int prob_continue_percent = 40;  // speexdsp VAD: probability to stay in speech
  float floor_dbfs = -55.0f;       // frames quieter than this (RMS, dB full scale) are silence
  int hangover_frames = 10;        // frames still sent after the last speech frame
};

struct VoiceActivityDecision {
  bool speech = false;         // this frame is speech (VAD and above the floor)
  bool send = false;           // speech, or within the hangover after speech
  float level_dbfs = -120.0f;  // the frame's RMS before denoising, dB full scale
  int speech_probability = 0;  // speexdsp's estimate, percent
};

class VoiceActivity {
 public:
  // Errors: hangover < 0, probabilities outside 0..100, speexdsp failure.
  static Result<VoiceActivity> create(const VoiceActivitySettings& settings = {});

  // Classifies one frame (kVoiceFrameSamples samples) and, with denoise, replaces it by its
  // noise-suppressed version.
  VoiceActivityDecision process(std::span<float> frame);

  const VoiceActivitySettings& settings() const { return settings_; }

 private:
  VoiceActivity() = default;  // through create() only

  struct Deleter {
    void operator()(SpeexPreprocessState_* state) const;
  };
  std::unique_ptr<SpeexPreprocessState_, Deleter> state_;
  VoiceActivitySettings settings_;
  std::vector<int16_t> pcm_;  // kVoiceFrameSamples: the frame as int16 for speexdsp
  bool in_speech_ = false;    // the VAD rule's state (start / continue)
  int frames_since_speech_ = 1 << 30;
};

}  // namespace vistel
