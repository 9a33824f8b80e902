// Voice end to end (issue 22): vistel-server on loopback, a vistel-bot speaking a WAV the
// test synthesizes (common/voice/speech_synth), and a headless vistel-client that listens
// (--mute) and writes what it hears (--audio-out). Checked: what the client heard matches
// what the bot said (normalised correlation after alignment, on the ear nearer the speaker:
// the far ear is shadowed and delayed by design), the mouth-to-ear latency the client
// measured is present and sane (printed; its goals are in bench_voice), and the speaker is
// louder in the ear on its side, by what the spatialiser gives a source there (the client's
// stats say where the speaker's head was in the listener's head space; the seats put it
// about 30 degrees to the side, so the 6 dB of a source on the ear's axis is the unit
// tests' to check). A second run sends over a bad uplink (10% loss, 0..50 ms jitter) and
// checks that the speech survives (correlation >= 0.8). About 8 s each.
//
// Lip sync (issue 22: the jaw and the sound within 45 ms, the broadcast tolerance): the
// client writes, next to what it heard, the jaw opening it posed for the speaker each frame
// with that frame's time in the WAV's own timeline (heard.jaw.csv, VoiceEngine::noteMouth).
// The test cross-correlates that drawn envelope against the level envelope of the WAV the
// client wrote (the nearer ear, 20 ms windows) and checks the lag of the best match: two
// independent records, so a jaw driven from the frame just decoded instead of the one
// heard, a frame loop or mixer that falls behind, or a wrong playout lag shows as an
// offset (tried: the jaw driven 3 ticks late measured +66.7 ms and failed). Bandwidth (issue 22: <=
// 32 kbit/s upstream per speaking member): the first run's bot speaks at the default bitrate and
// says what its sealed voice datagrams came to.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <span>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/base/file.hpp"
#include "common/voice/audio_compare.hpp"
#include "common/voice/spatialiser.hpp"
#include "common/voice/speech_synth.hpp"
#include "common/voice/voice_format.hpp"
#include "common/voice/wav_file.hpp"
#include "tests/integration/program.hpp"
#include "tests/integration/session_scratch.hpp"

namespace vistel {
namespace {

using Child = test::Program;

using test::logOf;

// What a listener wrote, against what was said: the ear nearer the speaker (the far ear is
// shadowed and delayed by design), aligned coarsely by onsets, then exactly within 50 ms.
struct Heard {
  double correlation = 0.0;  // the whole utterance at one lag
  // Half-second pieces each at its own lag (within 50 ms of the whole's), energy-weighted:
  // the playout buffer may insert or drop a frame mid-utterance when the delay it measures
  // changes (a loaded machine), which shifts the rest by 20 ms; this is what was heard
  // regardless.
  double segmented = 0.0;
  double delay_s = 0.0;  // of the match, from the start of the file
  double left_db = -120.0, right_db = -120.0;
};
Heard compareHeard(const std::vector<float>& reference, const AudioClip& heard) {
  Heard out;
  std::vector<float> left(heard.frames()), right(heard.frames());
  for (std::size_t i = 0; i < heard.frames(); ++i) {
    left[i] = heard.samples[2 * i];
    right[i] = heard.samples[2 * i + 1];
  }
  out.left_db = levelDbfs(left);
  out.right_db = levelDbfs(right);
  const std::vector<float>& near = out.left_db >= out.right_db ? left : right;
  const std::ptrdiff_t said_at = soundOnset(reference, 0.01f);
  const std::ptrdiff_t heard_at = soundOnset(near, 0.005f);
  if (said_at < 0 || heard_at < 0) return out;
  constexpr std::ptrdiff_t kSlack = 2400;
  const std::ptrdiff_t from = std::max<std::ptrdiff_t>(0, heard_at - said_at - kSlack);
  if (from >= static_cast<std::ptrdiff_t>(near.size())) return out;
  const auto match = alignedCorrelation(
      reference, std::span<const float>(near).subspan(static_cast<std::size_t>(from)), 2 * kSlack);
  out.correlation = match.correlation;
  out.delay_s = static_cast<double>(from + match.lag) / kVoiceSampleRate;
  // Piece by piece around that lag.
  constexpr std::size_t kPiece = kVoiceSampleRate / 2;
  const std::ptrdiff_t lag = from + match.lag;
  double weighted = 0.0, energy = 0.0;
  for (std::size_t at = 0; at + kPiece <= reference.size(); at += kPiece) {
    const auto piece = std::span<const float>(reference).subspan(at, kPiece);
    double e = 0.0;
    for (float v : piece) e += static_cast<double>(v) * v;
    const std::ptrdiff_t start = lag + static_cast<std::ptrdiff_t>(at) - kSlack;
    if (e <= 0.0 || start < 0 ||
        start + static_cast<std::ptrdiff_t>(kPiece) + 2 * kSlack >
            static_cast<std::ptrdiff_t>(near.size())) {
      continue;
    }
    const auto m = alignedCorrelation(
        piece, std::span<const float>(near).subspan(static_cast<std::size_t>(start)), 2 * kSlack);
    weighted += e * m.correlation;
    energy += e;
  }
  out.segmented = energy > 0.0 ? weighted / energy : 0.0;
  return out;
}

// The jaw drawn against the sound written: the lag (ms; positive: the jaw late) at which the
// drawn opening best matches the written level envelope, and how well (Pearson r).
struct LipSync {
  double offset_ms = 0.0;
  double correlation = 0.0;
  double max_opening = 0.0;
  std::size_t rows = 0;
};
LipSync measureLipSync(const AudioClip& heard, const std::string& csv_text, std::uint32_t speaker) {
  LipSync out;
  // The drawn openings of this speaker: (time in the WAV's timeline, opening).
  std::vector<std::pair<double, double>> jaw;
  std::size_t at = csv_text.find('\n');  // past the header
  while (at != std::string::npos && at + 1 < csv_text.size()) {
    const std::size_t end = csv_text.find('\n', at + 1);
    const std::string line = csv_text.substr(at + 1, end == std::string::npos ? end : end - at - 1);
    double t = 0.0, opening = 0.0;
    unsigned long id = 0;
    if (std::sscanf(line.c_str(), "%lf,%lu,%lf", &t, &id, &opening) == 3 && id == speaker) {
      jaw.emplace_back(t, opening);
      out.max_opening = std::max(out.max_opening, opening);
    }
    at = end;
  }
  out.rows = jaw.size();
  if (jaw.size() < 60) return out;
  // The nearer ear's level (dB) over 20 ms centred on each millisecond.
  std::vector<float> near(heard.frames());
  double left = 0.0, right = 0.0;
  for (std::size_t i = 0; i < heard.frames(); ++i) {
    left += static_cast<double>(heard.samples[2 * i]) * heard.samples[2 * i];
    right += static_cast<double>(heard.samples[2 * i + 1]) * heard.samples[2 * i + 1];
  }
  const int ear = left >= right ? 0 : 1;
  for (std::size_t i = 0; i < heard.frames(); ++i) near[i] = heard.samples[2 * i + ear];
  constexpr std::size_t kMs = kVoiceSampleRate / 1000;
  constexpr std::size_t kHalfWindow = 10 * kMs;
  const std::size_t ms_count = near.size() / kMs;
  std::vector<double> sound(ms_count, -100.0);
  for (std::size_t m = 0; m < ms_count; ++m) {
    const std::size_t centre = m * kMs;
    if (centre < kHalfWindow || centre + kHalfWindow > near.size()) continue;
    double sum = 0.0;
    for (std::size_t i = centre - kHalfWindow; i < centre + kHalfWindow; ++i)
      sum += static_cast<double>(near[i]) * near[i];
    sound[m] = std::max(-100.0, 10.0 * std::log10(sum / (2 * kHalfWindow) + 1e-12));
  }
  // The drawn opening held from each frame to the next, per millisecond of the WAV.
  std::vector<double> drawn(ms_count, std::nan(""));
  for (std::size_t k = 0; k + 1 < jaw.size(); ++k) {
    const auto from = static_cast<std::ptrdiff_t>(std::ceil(jaw[k].first * 1e3));
    const auto to = static_cast<std::ptrdiff_t>(std::ceil(jaw[k + 1].first * 1e3));
    for (std::ptrdiff_t m = std::max<std::ptrdiff_t>(from, 0);
         m < std::min<std::ptrdiff_t>(to, static_cast<std::ptrdiff_t>(ms_count)); ++m) {
      drawn[static_cast<std::size_t>(m)] = jaw[k].second;
    }
  }
  // Pearson r of drawn(t) against sound(t - lag), lag in -200..200 ms.
  constexpr int kMaxLag = 200;
  std::vector<double> r(2 * kMaxLag + 1, -2.0);
  for (int lag = -kMaxLag; lag <= kMaxLag; ++lag) {
    double n = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
    for (std::size_t m = 0; m < ms_count; ++m) {
      const auto a = static_cast<std::ptrdiff_t>(m) - lag;
      if (std::isnan(drawn[m]) || a < 0 || a >= static_cast<std::ptrdiff_t>(ms_count)) continue;
      const double x = drawn[m], y = sound[static_cast<std::size_t>(a)];
      n += 1, sx += x, sy += y, sxx += x * x, syy += y * y, sxy += x * y;
    }
    const double vx = sxx - sx * sx / n, vy = syy - sy * sy / n;
    if (n > 100 && vx > 0 && vy > 0) r[lag + kMaxLag] = (sxy - sx * sy / n) / std::sqrt(vx * vy);
  }
  const auto best = static_cast<int>(std::max_element(r.begin(), r.end()) - r.begin());
  out.correlation = r[best];
  double offset = best - kMaxLag;
  if (best > 0 && best + 1 < static_cast<int>(r.size())) {  // a parabola through the peak
    const double a = r[best - 1], b = r[best], c = r[best + 1];
    if (a - 2 * b + c < 0) offset += 0.5 * (a - c) / (a - 2 * b + c);
  }
  out.offset_ms = offset;
  return out;
}

// "... voice: sent N frames (X kbit/s of datagrams while speaking, Opus Y)": X and Y, or -1.
std::pair<double, double> sentKbps(const std::string& log) {
  const std::size_t at = log.find("voice: sent ");
  double sealed = -1.0, opus = -1.0;
  int frames = 0;
  if (at != std::string::npos) {
    std::sscanf(log.c_str() + at,
                "voice: sent %d frames (%lf kbit/s of datagrams while speaking, Opus %lf", &frames,
                &sealed, &opus);
  }
  return {sealed, opus};
}

// 3 s of continuous synthetic speech written as a WAV, and what the file holds.
std::vector<float> writeSpeech(const std::string& path) {
  SpeechSynthSettings speech;
  speech.pauses = false;
  speech.seed = 5;
  AudioClip said;
  said.samples = synthesizeSpeech(3.0, speech);
  EXPECT_TRUE(writeWavFile(path, said));
  auto read = readAudioFile(path);  // 16-bit, as the bot reads it
  EXPECT_TRUE(read);
  return read ? monoMix(*read) : std::vector<float>{};
}

class VoiceSession : public test::SessionScratch {
 protected:
  // A server, the speech a bot will say (said_path_, reference_) and a muted listening
  // client ("ears", 6 s) that writes what it hears (heard_path_) and its stats
  // (stats_path_), through its UDP handshake.
  void startListener() {
    said_path_ = dir_ + "/said.wav";
    reference_ = writeSpeech(said_path_);
    ASSERT_FALSE(reference_.empty());
    server_ = std::make_unique<Child>("vistel-server", std::vector<std::string>{"--port", "0"},
                                      dir_ + "/server.log", true);
    address_ = test::serverAddress(*server_);
    ASSERT_FALSE(address_.empty());
    heard_path_ = dir_ + "/heard.wav";
    stats_path_ = dir_ + "/stats.json";
    client_ = std::make_unique<Child>(
        "vistel-client",
        std::vector<std::string>{"--server", address_, "--room", "voice", "--name", "ears",
                                 "--avatar", avatar_path_, "--headless", "--duration", "6",
                                 "--mute", "--audio-out", heard_path_, "--stats-json", stats_path_},
        dir_ + "/client.log", false);
    ASSERT_TRUE(client_->waitForLog("UDP handshake done", 20.0)) << logOf(dir_ + "/client.log");
  }

  // The listener's end (its duration), then the server stopped; each exits with 0. The
  // bots given are waited for in between.
  void finishListening(std::initializer_list<std::pair<Child*, std::string>> bots) {
    const auto client_status = client_->wait(40.0);
    ASSERT_TRUE(client_status.has_value()) << logOf(dir_ + "/client.log");
    EXPECT_EQ(*client_status, 0) << logOf(dir_ + "/client.log");
    for (const auto& [bot, log] : bots) EXPECT_EQ(bot->wait(30.0).value_or(-999), 0) << logOf(log);
    server_->signal(SIGTERM);
    EXPECT_EQ(server_->wait(30.0).value_or(-999), 0) << logOf(dir_ + "/server.log");
  }

  std::string said_path_, address_, heard_path_, stats_path_;
  std::vector<float> reference_;
  std::unique_ptr<Child> server_, client_;
};

TEST_F(VoiceSession, BotSpeaksObserverHearsItFromWhereItStands) {
  // What the bot says: 3 s of continuous synthetic speech (writeSpeech).
  ASSERT_NO_FATAL_FAILURE(startListener());
  // Seats go round the ring so that the first two face each other: a silent bot takes the
  // seat facing the listener, and the speaker stands at the listener's side.
  Child filler("vistel-bot",
               {"--server", address_, "--room", "voice", "--name", "opposite", "--avatar",
                avatar_path_, "--bvh", bvh_path_, "--loop", "--duration", "6"},
               dir_ + "/filler.log", false);
  ASSERT_TRUE(client_->waitForLog("member 'opposite'", 20.0)) << logOf(dir_ + "/client.log");
  Child bot("vistel-bot",
            {"--server", address_, "--room", "voice", "--name", "mouth", "--avatar", avatar_path_,
             "--bvh", bvh_path_, "--loop", "--duration", "5", "--voice", said_path_},
            dir_ + "/bot.log", false);

  ASSERT_NO_FATAL_FAILURE(
      finishListening({{&bot, dir_ + "/bot.log"}, {&filler, dir_ + "/filler.log"}}));
  std::printf("[ measure  ] client: %s\n", logOf(dir_ + "/client.log").c_str());
  // Upstream: the bot speaks at the default bitrate; its sealed datagrams while speaking.
  const auto [sealed_kbps, opus_kbps] = sentKbps(logOf(dir_ + "/bot.log"));
  std::printf(
      "[ measure  ] upstream at the default bitrate: %.1f kbit/s of sealed voice datagrams "
      "while speaking (Opus payload %.1f)\n",
      sealed_kbps, opus_kbps);
  EXPECT_GT(sealed_kbps, 0.0) << logOf(dir_ + "/bot.log");
  EXPECT_LE(sealed_kbps, 32.0);

  // The client's voice stats.
  auto text = readFileText(stats_path_);
  ASSERT_TRUE(text) << logOf(dir_ + "/client.log");
  const auto stats = nlohmann::json::parse(*text);
  ASSERT_TRUE(stats.contains("voice")) << *text;
  const auto& voice = stats["voice"];
  std::printf("[ measure  ] voice stats: %s\n", voice.dump().c_str());
  EXPECT_GE(voice["frames_received"].get<int>(), 140) << *text;  // 3 s = 150 frames
  // A frame may beat the roster (TCP) that names its speaker: a few are turned away.
  EXPECT_LE(voice["frames_rejected"].get<int>(), 5);
  ASSERT_EQ(voice["speakers"].size(), 1u) << *text;  // the silent bot sends nothing
  const double p50 = voice["mouth_to_ear_ms"]["p50"].get<double>();
  const double p99 = voice["mouth_to_ear_ms"]["p99"].get<double>();
  std::printf("[ measure  ] mouth to ear on loopback: p50 %.1f ms, p99 %.1f ms\n", p50, p99);
  // Capture framing (20 ms) and the output buffer (20 ms) are in it by definition; far
  // beyond half a second something is broken (not a speed goal: bench_voice has those).
  EXPECT_GE(p50, 40.0);
  EXPECT_LT(p99, 500.0);

  // What it heard: the ear nearer the speaker against what was said.
  auto heard = readAudioFile(heard_path_);
  ASSERT_TRUE(heard) << heard.error().message;
  ASSERT_EQ(heard->channels, 2);
  const Heard match = compareHeard(reference_, *heard);
  const double left_db = match.left_db, right_db = match.right_db;
  std::printf(
      "[ measure  ] heard vs said (nearer ear, no loss): correlation %.3f (half-second pieces "
      "%.3f), lag %.3f s after the client started; levels left %.1f dBFS, right %.1f dBFS\n",
      match.correlation, match.segmented, match.delay_s, left_db, right_db);
  // Loopback loses nothing, but a loaded machine can still deliver a packet after its
  // playout time: the buffer then conceals that frame and inserts one (the stats count
  // both). Without such frames the no-loss target holds; with them, the lossy one.
  const int late = voice["late"].get<int>() + voice["inserted"].get<int>();
  if (late == 0) {
    EXPECT_GE(match.segmented, 0.95);
  } else {
    std::printf("[ measure  ] %d frames late or inserted (a loaded machine): held to 0.8\n", late);
    EXPECT_GE(match.segmented, 0.8);
  }

  // Panning: the speaker's side (+X is the listener's left) is the louder ear, by as much as
  // the spatialiser gives a source there (the said signal rendered at that place).
  const auto& where = voice["speakers"][0]["head_space_m"];
  const glm::vec3 place(where[0].get<float>(), where[1].get<float>(), where[2].get<float>());
  const SpatialParams params = spatialParams(SpatialSettings{}, HeadPose{}, place);
  SpatialSourceState state;
  std::vector<float> rendered(2 * reference_.size(), 0.0f);
  for (std::size_t i = 0; i + kVoiceFrameSamples <= reference_.size(); i += kVoiceFrameSamples) {
    spatialiseAdd(std::span<const float>(reference_).subspan(i, kVoiceFrameSamples), params, state,
                  std::span<float>(rendered).subspan(2 * i, 2 * kVoiceFrameSamples));
  }
  std::vector<float> rendered_left(reference_.size()), rendered_right(reference_.size());
  for (std::size_t i = 0; i < reference_.size(); ++i) {
    rendered_left[i] = rendered[2 * i];
    rendered_right[i] = rendered[2 * i + 1];
  }
  const double expected_db = levelDbfs(rendered_left) - levelDbfs(rendered_right);
  const double heard_db = left_db - right_db;
  std::printf(
      "[ measure  ] speaker at (%.2f, %.2f, %.2f) m in the listener's head space (+X left): "
      "left - right heard %.1f dB, the spatialiser's own %.1f dB\n",
      place.x, place.y, place.z, heard_db, expected_db);
  ASSERT_GT(std::abs(place.x), 0.3f) << "the seats put the speaker straight ahead or behind";
  EXPECT_GT(place.x > 0.0f ? heard_db : -heard_db, 3.0) << "the speaker's side is louder";
  EXPECT_NEAR(heard_db, expected_db, 1.5);

  // Lip sync: the jaw the client posed, against the sound it wrote.
  const std::string jaw_path = dir_ + "/heard.jaw.csv";
  auto jaw_text = readFileText(jaw_path);
  ASSERT_TRUE(jaw_text) << "no jaw timeline: " << logOf(dir_ + "/client.log");
  const LipSync lips =
      measureLipSync(*heard, *jaw_text, voice["speakers"][0]["id"].get<std::uint32_t>());
  std::printf(
      "[ measure  ] lip sync: the drawn jaw %+.1f ms from the sound written (positive: jaw "
      "late), envelope correlation %.3f over %zu drawn frames, widest opening %.2f\n",
      lips.offset_ms, lips.correlation, lips.rows, lips.max_opening);
  ASSERT_GE(lips.rows, 200u) << "the client drew too few frames of the speaker";
  EXPECT_GT(lips.max_opening, 0.5) << "the jaw hardly moved";
  EXPECT_GT(lips.correlation, 0.6) << "the jaw does not follow the sound";
  EXPECT_LE(std::abs(lips.offset_ms), 45.0) << "jaw and sound out of sync";
}

// The same speaker sending over a bad uplink (10% loss, 0..50 ms jitter): FEC and
// concealment keep the speech intelligible, and the playout buffer's delay grows with the
// jitter only.
TEST_F(VoiceSession, SpeechSurvivesTenPercentLossAndJitter) {
  ASSERT_NO_FATAL_FAILURE(startListener());
  Child bot("vistel-bot",
            {"--server", address_, "--room", "voice", "--name", "mouth", "--avatar", avatar_path_,
             "--bvh", bvh_path_, "--loop", "--duration", "5", "--voice", said_path_, "--netsim",
             "loss=0.1,jitter=50ms,dir=out,seed=3"},
            dir_ + "/bot.log", false);
  ASSERT_NO_FATAL_FAILURE(finishListening({{&bot, dir_ + "/bot.log"}}));

  auto text = readFileText(stats_path_);
  ASSERT_TRUE(text) << logOf(dir_ + "/client.log");
  const auto voice = nlohmann::json::parse(*text)["voice"];
  std::printf("[ measure  ] voice stats (10%% loss, 50 ms jitter): %s\n", voice.dump().c_str());
  EXPECT_GT(voice["fec"].get<int>() + voice["concealed"].get<int>(), 0) << "nothing was lost?";
  const double p50 = voice["mouth_to_ear_ms"]["p50"].get<double>();
  const double p99 = voice["mouth_to_ear_ms"]["p99"].get<double>();
  std::printf("[ measure  ] mouth to ear, 10%% loss and 50 ms jitter: p50 %.1f ms, p99 %.1f ms\n",
              p50, p99);
  EXPECT_LT(p99, 500.0);
  auto heard = readAudioFile(heard_path_);
  ASSERT_TRUE(heard) << heard.error().message;
  const Heard match = compareHeard(reference_, *heard);
  std::printf(
      "[ measure  ] heard vs said (nearer ear, 10%% loss, 50 ms jitter): correlation %.3f "
      "(half-second pieces %.3f)\n",
      match.correlation, match.segmented);
  EXPECT_GE(match.segmented, 0.8);
}

}  // namespace
}  // namespace vistel
