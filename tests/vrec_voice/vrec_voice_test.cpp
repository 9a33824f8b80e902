// The .vrec voice track end to end (issue 22: "a .vrec recording can carry its voice track
// too, so a replayed participant speaks as they moved"). On loopback:
//  1. a vistel-client on the simulated rig (--source sim:wave.bvh) records a take with
//     --record while speaking a synthesized WAV (--audio-in): the file must hold a voice
//     track (record type 4) of about the utterance's length, 20 ms apart within a talkspurt,
//     placed among the frames on their clock;
//  2. a vistel-bot replays the take (--recording) and speaks its track, heard by a muted
//     observer client that writes heard.wav: what it heard must match the recorded voice
//     (the track decoded, correlation >= 0.8 after alignment), and the bot's voice onset
//     after its replay's first frame must be the recorded one (the first packet's time
//     after the first frame) within 45 ms;
//  3. at the same time, in another room, a bot replays the take with --voice said.wav: the
//     WAV replaces the track (said in the log) and starts at the replay's first frame.
// About 12 s in Release. Needs the build's default avatar and gesture clip (or
// VISTEL_DATA_DIR pointing at a data folder): skipped without them.
#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "client/net/data_dir.hpp"
#include "common/base/file.hpp"
#include "common/sensors/recording.hpp"
#include "common/voice/audio_compare.hpp"
#include "common/voice/opus_voice.hpp"
#include "common/voice/speech_synth.hpp"
#include "common/voice/voice_format.hpp"
#include "common/voice/wav_file.hpp"
#include "tests/integration/program.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

using test::logOf;
using test::Program;

// "...<key> X ms..." in a log: X, or NaN.
double numberAfter(const std::string& log, const std::string& key) {
  const std::size_t at = log.find(key);
  if (at == std::string::npos) return std::nan("");
  return std::strtod(log.c_str() + at + key.size(), nullptr);
}

// The track decoded as the bot does: sample 0 at the first frame's time.
std::vector<float> decodeTrack(const Recording& rec) {
  std::vector<float> out;
  auto decoder = OpusVoiceDecoder::create();
  EXPECT_TRUE(decoder);
  if (!decoder) return out;
  for (const VoiceRecord& v : rec.voice) {
    const std::int64_t at = voiceSamplesFromSeconds(v.time - rec.frames.front().time);
    if (at < 0) continue;
    const auto from = static_cast<std::size_t>(at);
    out.resize(std::max(out.size(), from + kVoiceFrameSamples));
    EXPECT_TRUE(decoder->decode(v.packet, std::span<float>(out).subspan(from, kVoiceFrameSamples)));
  }
  return out;
}

class VrecVoice : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::scratchDir();
    setenv("XDG_CACHE_HOME", (dir_ + "/cache").c_str(), 1);
    const std::string data = net::findDataDir();
    avatar_ = data + "/default.vavatar";
    clip_ = data + "/gestures/wave.bvh";
    if (!std::filesystem::exists(avatar_) || !std::filesystem::exists(clip_)) {
      GTEST_SKIP() << "no default avatar or gesture clip in " << data
                   << " (build the vistel_assets target, or set VISTEL_DATA_DIR)";
    }
  }
  std::vector<std::string> clientArgs(const std::string& room, const std::string& name) const {
    return {"--server", address_,   "--room", room,        "--name",
            name,       "--avatar", avatar_,  "--headless"};
  }
  std::string dir_, avatar_, clip_, address_;
};

TEST_F(VrecVoice, ReplayedTakeSpeaksAsRecordedInStepWithItsMotion) {
  // 1.5 s of continuous speech.
  SpeechSynthSettings speech;
  speech.pauses = false;
  speech.seed = 11;
  AudioClip said;
  said.samples = synthesizeSpeech(1.5, speech);
  const std::string said_path = dir_ + "/said.wav";
  ASSERT_TRUE(writeWavFile(said_path, said));

  Program server("vistel-server", {"--port", "0"}, dir_ + "/server.log", true);
  address_ = test::serverAddress(server);
  ASSERT_FALSE(address_.empty()) << server.log();

  // 1. The take: the simulated rig, recorded with the voice the client sends.
  const std::string take = dir_ + "/take.vrec";
  {
    auto args = clientArgs("studio", "actor");
    for (const char* a : {"--source"}) args.push_back(a);
    args.push_back("sim:" + clip_);
    for (const std::string& a : {std::string("--record"), take, std::string("--audio-in"),
                                 said_path, std::string("--audio-out"), dir_ + "/actor_heard.wav",
                                 std::string("--duration"), std::string("4")}) {
      args.push_back(a);
    }
    Program actor("vistel-client", args, dir_ + "/actor.log");
    ASSERT_EQ(actor.wait(60.0).value_or(-999), 0) << actor.log();
    std::printf("[ actor    ] %s", actor.log().c_str());
    EXPECT_NE(actor.log().find("voice frames"), std::string::npos) << actor.log();
  }
  auto rec = loadRecording(take);
  ASSERT_TRUE(rec) << rec.error().message;
  EXPECT_TRUE(rec->complete) << rec->stop_reason;
  ASSERT_GE(rec->frames.size(), 100u);
  // 1.5 s = 75 frames; the voice activity detector may trim a frame or two at the ends.
  ASSERT_GE(rec->voice.size(), 65u);
  EXPECT_LE(rec->voice.size(), 80u);
  const double first_frame = rec->frames.front().time;
  const double recorded_offset = rec->voice.front().time - first_frame;
  std::printf(
      "[ measure  ] take: %zu frames over %.2f s, %zu voice packets from %.3f s to %.3f s "
      "after the first frame\n",
      rec->frames.size(), rec->frames.back().time - first_frame, rec->voice.size(), recorded_offset,
      rec->voice.back().time - first_frame);
  EXPECT_GT(recorded_offset, 0.0);
  EXPECT_LT(rec->voice.back().time, rec->frames.back().time + 0.1);
  int steps = 0;
  for (std::size_t i = 1; i < rec->voice.size(); ++i) {
    const double step = rec->voice[i].time - rec->voice[i - 1].time;
    EXPECT_GT(step, 0.0199) << i;
    steps += std::abs(step - 0.02) < 1e-6;
  }
  EXPECT_GE(steps, static_cast<int>(rec->voice.size()) - 4) << "not one talkspurt on 20 ms";
  const std::vector<float> track = decodeTrack(*rec);
  const auto track_onset =
      static_cast<std::size_t>(std::max<std::int64_t>(0, voiceSamplesFromSeconds(recorded_offset)));
  ASSERT_GT(track.size(), track_onset);
  const std::vector<float> reference(track.begin() + static_cast<std::ptrdiff_t>(track_onset),
                                     track.end());
  // The track is the utterance (codec aside). Either may lead: the codec delays the track,
  // the voice activity detector may leave out its first frame.
  {
    const auto trails = alignedCorrelation(said.samples, reference, 2400);
    const auto leads = alignedCorrelation(reference, said.samples, 2400);
    const double best = std::max(trails.correlation, leads.correlation);
    std::printf(
        "[ measure  ] recorded track vs said: correlation %.3f (track %d samples late, or "
        "%.3f %d samples early)\n",
        trails.correlation, trails.lag, leads.correlation, leads.lag);
    EXPECT_GE(best, 0.9);
  }

  // 2. The observer, then the bot replaying the take with its track; 3. in another room at
  // the same time, a bot replaying it with --voice.
  const std::string heard_path = dir_ + "/heard.wav";
  auto ears_args = clientArgs("replay", "ears");
  for (const std::string& a :
       {std::string("--mute"), std::string("--audio-out"), heard_path, std::string("--duration"),
        std::string("7"), std::string("--stats-json"), dir_ + "/ears.json"}) {
    ears_args.push_back(a);
  }
  Program ears("vistel-client", ears_args, dir_ + "/ears.log");
  ASSERT_TRUE(ears.waitForLog("UDP handshake done", 20.0)) << ears.log();
  Program bot("vistel-bot",
              {"--server", address_, "--room", "replay", "--name", "replayed", "--avatar", avatar_,
               "--recording", take},
              dir_ + "/bot.log");
  Program wav_bot("vistel-bot",
                  {"--server", address_, "--room", "elsewhere", "--name", "dubbed", "--avatar",
                   avatar_, "--recording", take, "--voice", said_path},
                  dir_ + "/wav_bot.log");
  EXPECT_EQ(bot.wait(40.0).value_or(-999), 0) << bot.log();
  EXPECT_EQ(wav_bot.wait(40.0).value_or(-999), 0) << wav_bot.log();
  ASSERT_EQ(ears.wait(40.0).value_or(-999), 0) << ears.log();
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait(20.0).value_or(-999), 0) << server.log();
  std::printf("[ bot      ] %s[ wav bot  ] %s", bot.log().c_str(), wav_bot.log().c_str());

  // The track, in step with the motion: its onset after the replay's first frame.
  EXPECT_NE(bot.log().find("voice: the recording's own voice track"), std::string::npos);
  const double onset_ms = numberAfter(bot.log(), "voice onset ");
  std::printf(
      "[ measure  ] track replayed: voice onset %.1f ms after the replay's first frame, "
      "recorded %.1f ms (difference %+.1f ms)\n",
      onset_ms, 1e3 * recorded_offset, onset_ms - 1e3 * recorded_offset);
  ASSERT_FALSE(std::isnan(onset_ms)) << bot.log();
  EXPECT_LE(std::abs(onset_ms - 1e3 * recorded_offset), 45.0);
  EXPECT_NE(bot.log().find("replay finished"), std::string::npos) << bot.log();

  // --voice replaces the track, from the replay's first frame.
  EXPECT_NE(wav_bot.log().find("the recording's own voice track is not used"), std::string::npos)
      << wav_bot.log();
  const double wav_onset_ms = numberAfter(wav_bot.log(), "voice onset ");
  const double said_onset_ms =
      1e3 * static_cast<double>(std::max<std::ptrdiff_t>(0, soundOnset(said.samples, 0.01f))) /
      kVoiceSampleRate;
  std::printf(
      "[ measure  ] --voice with --recording: voice onset %.1f ms after the replay's first "
      "frame (the WAV's own onset %.1f ms)\n",
      wav_onset_ms, said_onset_ms);
  ASSERT_FALSE(std::isnan(wav_onset_ms)) << wav_bot.log();
  EXPECT_LE(std::abs(wav_onset_ms - said_onset_ms), 45.0);

  // What the observer heard: the recorded voice.
  auto text = readFileText(dir_ + "/ears.json");
  ASSERT_TRUE(text) << ears.log();
  const auto stats = nlohmann::json::parse(*text);
  std::printf("[ measure  ] observer voice stats: %s\n", stats["voice"].dump().c_str());
  ASSERT_TRUE(stats["members"].contains("replayed")) << *text;
  EXPECT_GE(stats["members"]["replayed"]["postures_received"].get<int>(), 60) << *text;
  auto heard = readAudioFile(heard_path);
  ASSERT_TRUE(heard) << heard.error().message;
  ASSERT_EQ(heard->channels, 2);
  std::vector<float> left(heard->frames()), right(heard->frames());
  for (std::size_t i = 0; i < heard->frames(); ++i) {
    left[i] = heard->samples[2 * i];
    right[i] = heard->samples[2 * i + 1];
  }
  const std::vector<float>& near = levelDbfs(left) >= levelDbfs(right) ? left : right;
  const std::ptrdiff_t heard_at = soundOnset(near, 0.005f);
  const std::ptrdiff_t said_at = soundOnset(reference, 0.01f);
  ASSERT_GE(heard_at, 0) << "the observer heard nothing: " << ears.log();
  ASSERT_GE(said_at, 0);
  constexpr std::ptrdiff_t kSlack = 2400;
  const std::ptrdiff_t from = std::max<std::ptrdiff_t>(0, heard_at - said_at - kSlack);
  const auto match = alignedCorrelation(
      reference, std::span<const float>(near).subspan(static_cast<std::size_t>(from)), 2 * kSlack);
  std::printf("[ measure  ] heard vs recorded voice (nearer ear): correlation %.3f\n",
              match.correlation);
  EXPECT_GE(match.correlation, 0.8);
}

}  // namespace
}  // namespace vistel
