// A formant synthesiser for test speech (after the source-filter model, Fant 1960).
#include "common/voice/speech_synth.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "common/voice/voice_format.hpp"

namespace vistel {
namespace {

constexpr double kTwoPi = 6.283185307179586;

struct Vowel {
  double f1, f2, f3;  // formant frequencies, Hz
};
// Approximate adult formants of /a/ /i/ /u/ /e/ /o/.
constexpr std::array<Vowel, 5> kVowels{
    {{730, 1090, 2440}, {270, 2290, 3010}, {300, 870, 2240}, {530, 1840, 2480}, {570, 840, 2410}}};

// Spectral envelope at f for formants (f1, f2, f3): a sum of resonance peaks and a tilt.
double envelope(double f, const Vowel& v) {
  auto peak = [f](double centre, double bandwidth) {
    const double x = (f - centre) / bandwidth;
    return 1.0 / (1.0 + x * x);
  };
  return (peak(v.f1, 90) + 0.7 * peak(v.f2, 120) + 0.4 * peak(v.f3, 160)) * 250.0 / (250.0 + f) +
         0.002;
}

}  // namespace

std::vector<float> synthesizeSpeech(double seconds, const SpeechSynthSettings& settings) {
  const size_t total = static_cast<size_t>(std::max(0.0, seconds) * kVoiceSampleRate);
  std::vector<float> out(total, 0.0f);
  std::mt19937 rng(settings.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> vowel_pick(0, static_cast<int>(kVowels.size()) - 1);

  constexpr int kMaxHarmonics = 64;
  std::array<double, kMaxHarmonics> phase{};
  std::array<double, kMaxHarmonics> amp{};
  size_t at = 0;
  double time = 0.0;
  Vowel current = kVowels[0];
  while (at < total) {
    // A phrase of syllables, then a pause.
    const int syllables = 3 + static_cast<int>(unit(rng) * 5);
    for (int s = 0; s < syllables && at < total; ++s) {
      const Vowel next = kVowels[static_cast<size_t>(vowel_pick(rng))];
      const size_t length = static_cast<size_t>((0.15 + 0.15 * unit(rng)) * kVoiceSampleRate);
      const double loudness = 0.6 + 0.4 * unit(rng);
      for (size_t i = 0; i < length && at < total; ++i, ++at) {
        const double u = static_cast<double>(i) / static_cast<double>(length);
        time = static_cast<double>(at) / kVoiceSampleRate;
        // Formants glide over the syllable's first third; f0 has intonation and vibrato.
        const double glide = std::min(1.0, 3.0 * u);
        const Vowel v{current.f1 + (next.f1 - current.f1) * glide,
                      current.f2 + (next.f2 - current.f2) * glide,
                      current.f3 + (next.f3 - current.f3) * glide};
        const double f0 = settings.f0_hz * (1.0 + 0.12 * std::sin(kTwoPi * 0.4 * time) +
                                            0.02 * std::sin(kTwoPi * 5.5 * time));
        const int harmonics = std::min(kMaxHarmonics, static_cast<int>(5000.0 / f0));
        // The envelope per harmonic every millisecond (it changes slowly).
        if (i % 48 == 0) {
          for (int h = 0; h < harmonics; ++h) amp[h] = envelope(f0 * (h + 1), v);
        }
        double sample = 0.0;
        for (int h = 0; h < harmonics; ++h) {
          phase[h] += kTwoPi * f0 * (h + 1) / kVoiceSampleRate;
          if (phase[h] > kTwoPi) phase[h] -= kTwoPi;
          sample += amp[h] * std::sin(phase[h]);
        }
        const double syllable_env = 0.5 - 0.5 * std::cos(kTwoPi * u);
        out[at] = static_cast<float>(settings.level * 0.35 * loudness * syllable_env * sample);
      }
      current = next;
    }
    if (settings.pauses) at += static_cast<size_t>((0.25 + 0.35 * unit(rng)) * kVoiceSampleRate);
  }
  out.resize(total);
  return out;
}

}  // namespace vistel
