// The voice options vistel-client and vistel-bot share on their command lines:
// --voice-kbps (the Opus bitrate; its default is OpusVoiceSettings's), --mute and
// --no-audio. `options` and `no_audio` must outlive the parse.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

#include "client/voice/voice_engine.hpp"

namespace vistel {

inline void addSharedVoiceOptions(CLI::App& app, VoiceOptions& options, bool& no_audio,
                                  const std::string& mute_help, const std::string& no_audio_help) {
  app.add_option_function<int>(
         "--voice-kbps", [&options](int kbps) { options.opus.bitrate_bps = 1000 * kbps; },
         "Opus bitrate of the own voice, 16..32 kbit/s (default " +
             std::to_string(OpusVoiceSettings{}.bitrate_bps / 1000) + ")")
      ->check(CLI::Range(16, 32));
  app.add_flag("--mute", options.muted, mute_help);
  app.add_flag("--no-audio", no_audio, no_audio_help);
}

}  // namespace vistel
