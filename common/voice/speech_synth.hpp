// A speech-like test signal made by the project (no recordings needed): a voiced source
// (harmonics of a gliding fundamental, up to 5 kHz) shaped by three formant resonances
// that move from vowel to vowel, syllable by syllable (150..300 ms each, a raised-cosine
// amplitude envelope), in phrases of 3..7 syllables separated by pauses (250..600 ms of
// silence) when pauses is true. Deterministic for a seed. Mono, 48 kHz, peak about level.
// Cost: about 40 harmonics per sample (some 0.1 s of CPU per 10 s of signal).
#pragma once

#include <cstdint>
#include <vector>

namespace vistel {

struct SpeechSynthSettings {
  float f0_hz = 120.0f;  // mean fundamental (a low voice; 200 for a higher one)
  float level = 0.3f;    // about the peak amplitude
  bool pauses = true;    // silences between phrases
  uint32_t seed = 1;
};

std::vector<float> synthesizeSpeech(double seconds, const SpeechSynthSettings& settings = {});

}  // namespace vistel
