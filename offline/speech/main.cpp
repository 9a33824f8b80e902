// vistel-speech: a speech-like WAV made by the project's formant synthesiser
// (common/voice/speech_synth.hpp): no recordings needed, nothing downloaded.
//
//   vistel-speech --out FILE.wav [--seconds S] [--f0 HZ] [--level L] [--seed N]
//                 [--no-pauses]
//
// Writes mono 16-bit PCM at 48 kHz: syllables of gliding vowels in phrases, separated by
// pauses unless --no-pauses. Deterministic for a seed. Exit status: 0, 1 when the file
// cannot be written, 2 on bad usage.
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "common/voice/speech_synth.hpp"
#include "common/voice/wav_file.hpp"

int main(int argc, char** argv) {
  CLI::App app{"vistel-speech: write a speech-like test WAV (formant synthesiser)"};
  std::string out;
  double seconds = 6.0;
  vistel::SpeechSynthSettings settings;
  bool no_pauses = false;
  app.add_option("--out", out, "WAV file to write")->required();
  app.add_option("--seconds", seconds, "length")->check(CLI::Range(0.02, 3600.0));
  app.add_option("--f0", settings.f0_hz, "mean fundamental, Hz (120 low, 200 higher)")
      ->check(CLI::Range(50.0, 400.0));
  app.add_option("--level", settings.level, "about the peak amplitude")
      ->check(CLI::Range(0.01, 0.9));
  app.add_option("--seed", settings.seed, "which utterance");
  app.add_flag("--no-pauses", no_pauses, "one continuous phrase");
  CLI11_PARSE(app, argc, argv);
  settings.pauses = !no_pauses;

  vistel::AudioClip clip;
  clip.channels = 1;
  clip.samples = vistel::synthesizeSpeech(seconds, settings);
  if (vistel::Status st = vistel::writeWavFile(out, clip); !st) {
    std::fprintf(stderr, "vistel-speech: %s\n", st.error().message.c_str());
    return 1;
  }
  std::printf("vistel-speech: wrote %.2f s of speech (f0 %.0f Hz, seed %u) to %s\n",
              static_cast<double>(clip.frames()) / 48000.0, static_cast<double>(settings.f0_hz),
              settings.seed, out.c_str());
  return 0;
}
