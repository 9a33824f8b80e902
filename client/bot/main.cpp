// vistel-bot: headless participants replaying a motion clip or a sensor recording
// (DESIGN.md §6: bots are clients with no window whose source is a recording or a mocap
// clip).
//
//   vistel-bot --server HOST:PORT --room R --name N (--bvh FILE | --recording FILE)
//              [--avatar FILE] [--loop] [--duration S] [--count K] [--config FILE]
//              [--stats-json FILE] [--log-level LEVEL] [--netsim SPEC] [--token T ...]
//              [--tls [--tls-ca FILE | --tls-pin SHA256]]
//              [--voice FILE.wav] [--audio-out FILE.wav] [--mute] [--no-audio]
//   vistel-bot --version
//
// K participants (named N-1 .. N-K when K > 1, else N) join room R, each with the avatar
// (default: default.vavatar in the data folder), and stream the clip retargeted onto
// that avatar at the clip's own frame rate (at most the room's tick rate: faster would
// only be dropped by the server's newest-wins). A .vrec recording is replayed through the
// posture solver (client/bot/recording_input.hpp) once for all K participants; a damaged
// one up to its last good record, saying where it broke. Ends at the clip's or recording's
// end (without --loop), after --duration seconds, or on SIGINT/SIGTERM, leaving the room
// cleanly. A join refused for a transient reason (the server full, say) is tried again
// with a jittered backoff (NetDriver). --stats-json writes, at the end, each
// participant's join time, retries, bytes and latency (client/bot/bot_report.hpp), and
// how it would have shown the others: at each send it samples every remote member's
// jitter buffer as a client's frame would ([playback] delay and extrapolation; no
// blending) and counts frames interpolated, held and extrapolated and the shown age.
// --netsim SPEC (or [network] netsim) puts a simulated bad network between each
// participant and the server on UDP (client/net/net_sim.hpp), seeded per participant.
// --token: the join token(s) for a server that requires them (`vistel-server token`), one
// per participant in name order (a token admits one name).
// Voice: every participant speaks (client/voice/voice_engine.hpp) the --voice FILE.wav, or
// else a --recording's own voice track (record type 4; the log says which), in step with
// the motion: a speaking bot holds the clip's first frame until the first participant is
// live and its clock has converged, then starts motion and voice together from that moment
// (the WAV's first sample, or the track's first packet at its recorded offset after the
// first frame); with --loop both restart with each pass of the motion (a WAV longer than a
// pass restarts at the next pass after its end). --audio-out FILE.wav writes what the
// first participant hears (spatialised from the seats). Bots never open audio devices.
// --mute joins with voice muted, --no-audio without voice. At the end each speaker prints
// when its first voice frame was captured after the replay's start ("voice onset").
// Never initialises GLFW. Exit status: 0, 1 on an error (a participant the server refused
// or dropped included: the refusal is printed), 2 on bad usage (an unknown --log-level too).

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "client/bot/bot_report.hpp"
#include "client/bot/recording_input.hpp"
#include "client/net/asio.hpp"
#include "client/net/client_config.hpp"
#include "client/net/clip_player.hpp"
#include "client/net/data_dir.hpp"
#include "client/net/net_driver.hpp"
#include "client/net/playback_stats.hpp"
#include "client/net/tls_options.hpp"
#include "client/voice/voice_cli.hpp"
#include "client/voice/voice_engine.hpp"
#include "client/voice/voice_scene.hpp"
#include "common/avatar/avatar_io.hpp"
#include "common/base/file.hpp"
#include "common/motion/bvh.hpp"
#include "common/wire/packets.hpp"
#include "vistel_version.hpp"

namespace {

std::atomic<bool> g_stop{false};

extern "C" void onSignal(int) { g_stop = true; }

}  // namespace

int main(int argc, char** argv) {
  using namespace vistel;
  using namespace vistel::net;

  // Command line.
  CLI::App app{"vistel-bot: headless participants replaying a motion clip"};
  std::string server_text, room, name, bvh_path, recording_path, avatar_path;
  std::string config_path = "config/client.toml";
  std::string stats_path;
  bool loop = false;
  double duration = 0.0;
  int count = 1;
  app.add_option("--server", server_text, "session server HOST:PORT")->required();
  app.add_option("--room", room, "room to join")->required();
  app.add_option("--name", name, "participant name (N-1..N-K with --count K > 1)")->required();
  std::vector<std::string> tokens;
  app.add_option("--token", tokens,
                 "join token (`vistel-server token`) for a server that requires one; with "
                 "--count K give K, for N-1..N-K in order");
  auto* bvh_opt = app.add_option("--bvh", bvh_path, "BVH motion clip to replay");
  auto* rec_opt = app.add_option("--recording", recording_path, ".vrec sensor recording to replay");
  bvh_opt->excludes(rec_opt);
  app.add_option("--avatar", avatar_path, "avatar file (.vavatar; default: the data folder's)");
  tls::ClientTlsSettings tls_settings;
  addTlsOptions(app, tls_settings);
  app.add_flag("--loop", loop, "replay the clip endlessly");
  app.add_option("--duration", duration, "stop after this many seconds")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--count", count, "number of participants")->check(CLI::Range(1, 1000));
  app.add_option("--config", config_path, "client settings (TOML); built-in defaults if absent");
  app.add_option("--stats-json", stats_path,
                 "write each participant's join time, bytes and latency as JSON at the end");
  VoiceOptions voice_options;
  bool no_audio = false;
  app.add_option("--voice,--audio-in", voice_options.audio_in,
                 "audio file (WAV) every participant speaks from the clip's first frame (looping "
                 "with it under --loop); replaces a recording's own voice track");
  app.add_option("--audio-out", voice_options.audio_out,
                 "write what the first participant hears to this WAV file (stereo, 48 kHz)");
  addSharedVoiceOptions(app, voice_options, no_audio, "join with the voice muted",
                        "no voice at all");
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error, off (default: info)");
  std::string netsim_text;
  auto* netsim_opt = app.add_option(
      "--netsim", netsim_text,
      "simulate a bad network on UDP for every participant: comma-separated loss=P, latency=D, "
      "jitter=D, jitter_dist=uniform|normal, dup=P, reorder=P, reorder_delay=D, dir=both|in|out, "
      "seed=N (e.g. loss=0.1,latency=30ms,jitter=50ms; overrides [network] netsim)");
  app.set_version_flag("--version",
                       versionLine("vistel-bot", net::kProtocolVersion, wire::kWireVersion));
  CLI11_PARSE(app, argc, argv);
  spdlog::set_default_logger(spdlog::stderr_color_mt("vistel-bot"));
  // spdlog reads an unknown name as "off": refuse it rather than go silent.
  if (log_level != "off" && spdlog::level::from_str(log_level) == spdlog::level::off) {
    std::fprintf(stderr,
                 "vistel-bot: --log-level '%s': expected trace, debug, info, warn, error or off\n",
                 log_level.c_str());
    return 2;
  }
  spdlog::set_level(spdlog::level::from_str(log_level));

  if (!tokens.empty() && static_cast<int>(tokens.size()) != count) {
    std::fprintf(stderr, "vistel-bot: %zu --token for %d participant(s): give one each\n",
                 tokens.size(), count);
    return 2;
  }
  if (const std::string tls_error = checkTlsOptions(tls_settings); !tls_error.empty()) {
    std::fprintf(stderr, "vistel-bot: %s\n", tls_error.c_str());
    return 2;
  }

  if (bvh_opt->count() == 0 && rec_opt->count() == 0) {
    std::fprintf(stderr, "vistel-bot: give a source: --bvh FILE or --recording FILE\n");
    return 2;
  }
  if (rec_opt->count() > 0 && !std::filesystem::is_regular_file(recording_path)) {
    std::fprintf(stderr, "vistel-bot: --recording %s: no such file\n", recording_path.c_str());
    return 2;
  }

  // Settings, address, avatar, clip.
  auto config = loadClientConfig(config_path);
  if (!config) {
    spdlog::error("{}", config.error().message);
    return 1;
  }
  auto server = parseServerAddress(server_text);
  if (!server) {
    spdlog::error("{}", server.error().message);
    return 2;
  }
  const auto netsim = parseNetSimSpec(netsim_opt->count() > 0 ? netsim_text : config->netsim);
  if (!netsim) {
    std::fprintf(stderr, "vistel-bot: %s\n", netsim.error().message.c_str());
    return 2;
  }
  if (avatar_path.empty()) avatar_path = defaultAvatarPath();
  auto avatar_bytes = readFileBytes(avatar_path, 1u << 30);
  if (!avatar_bytes) {
    spdlog::error("avatar: {}", avatar_bytes.error().message);
    return 1;
  }
  auto avatar = decodeAvatar(*avatar_bytes, avatar_path);
  if (!avatar) {
    spdlog::error("{}", avatar.error().message);
    return 1;
  }
  // The source: a recording solved once for every participant (they replay the same
  // file), or a clip with one player per participant (players keep scratch state).
  std::unique_ptr<RecordingReplay> replay;
  std::vector<std::unique_ptr<ClipPlayer>> players;
  std::string source_line;
  double clip_rate = 0.0;
  if (!recording_path.empty()) {
    auto opened = RecordingReplay::open(recording_path, avatar->skeleton, loop);
    if (!opened) {
      spdlog::error("{}", opened.error().message);
      return 1;
    }
    replay = std::move(*opened);
    clip_rate = replay->frameRateHz();
    source_line = replay->describe();
    if (!replay->damage().empty()) {
      std::printf(
          "vistel-bot: the recording is damaged, replaying up to its last good record: %s\n",
          replay->damage().c_str());
    }
  } else {
    auto clip = loadBvh(bvh_path);
    if (!clip) {
      spdlog::error("{}", clip.error().message);
      return 1;
    }
    for (int i = 0; i < count; ++i) {
      auto player = ClipPlayer::create(*clip, avatar->skeleton);
      if (!player) {
        spdlog::error("{}", player.error().message);
        return 1;
      }
      players.push_back(std::move(*player));
    }
    clip_rate = 1.0 / players[0]->frameTime();
    source_line = fmt::format("{} ({:.1f} s at {:.0f} Hz{})", clip->source, players[0]->duration(),
                              clip_rate, players[0]->retargeted() ? ", retargeted" : "");
  }

  // Participants: one driver each, all on one network thread.
  SessionSettings settings = config->session;
  settings.room = room;
  settings.avatar_hash = avatarContentHash(*avatar_bytes);
  settings.avatar_bytes =
      std::make_shared<const std::vector<std::uint8_t>>(std::move(*avatar_bytes));
  settings.avatar_joint_count = avatar->skeleton.jointCount();
  settings.fetch_avatars = false;  // bots draw nothing
  std::printf("vistel-bot: %d participant(s) joining room '%s' on %s, replaying %s\n", count,
              room.c_str(), server_text.c_str(), source_line.c_str());
  std::fflush(stdout);
  asio::io_context io;
  auto work = asio::make_work_guard(io);
  const double started_at = monotonicSeconds();
  std::vector<std::shared_ptr<NetDriver>> drivers;
  std::vector<std::string> names;
  for (int i = 0; i < count; ++i) {
    settings.name = count > 1 ? name + "-" + std::to_string(i + 1) : name;
    names.push_back(settings.name);
    if (!tokens.empty()) settings.token = tokens[static_cast<std::size_t>(i)];
    drivers.push_back(NetDriver::create(io, *server, settings, nullptr, {}, tls_settings));
    drivers.back()->setNetSim(*netsim);
  }
  // Voice: an engine per speaking participant (and for the first one's ears with
  // --audio-out); files only, never devices. What they say: --voice, else the recording's
  // voice track; scheduled from the replay's start (below).
  std::vector<std::unique_ptr<VoiceEngine>> voices(drivers.size());
  const bool track = replay && replay->voice().samples != nullptr;
  if (track && !voice_options.audio_in.empty()) {
    std::printf("vistel-bot: voice: %s (the recording's own voice track is not used)\n",
                voice_options.audio_in.c_str());
  } else if (track && !no_audio) {
    voice_options.input_samples = replay->voice().samples;
    std::printf(
        "vistel-bot: voice: the recording's own voice track (%zu packets, %.1f s, first %.3f s "
        "after the first frame)\n",
        replay->voice().packets, replay->voice().seconds, replay->voice().first_offset_s);
  }
  const bool speaking =
      !no_audio && (!voice_options.audio_in.empty() || voice_options.input_samples);
  if (!no_audio) {
    for (std::size_t i = 0; i < drivers.size(); ++i) {
      VoiceOptions options = voice_options;
      options.capture = speaking;
      options.scheduled_input = speaking;
      options.playback = i == 0 && !options.audio_out.empty();
      if (!options.capture && !options.playback) continue;
      if (i > 0) options.audio_out.clear();
      options.loop_input = loop;
      options.label = "vistel-bot: " + names[i] + ": voice";
      auto started = VoiceEngine::start(drivers[i], options);
      if (!started) {
        spdlog::error("{}", started.error().message);
        return 1;
      }
      voices[i] = std::move(*started);
    }
  }
  for (auto& driver : drivers) driver->start();
  std::thread network([&io] { io.run(); });
  VoiceScene voice_scene;  // the first participant's ears: heads above the seats

  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);

  // The source loop: every participant's posture at each frame time, paced on the
  // steady clock (the send rate is fixed once the server's tick rate is known).
  const auto start = std::chrono::steady_clock::now();
  const double start_mono = monotonicSeconds();  // the same moment on the voice's clock
  // The replay's start, in seconds after `start`: at once, or for a speaking bot once the
  // first participant can speak (live, clock converged), motion and voice together.
  double replay_origin = speaking ? -1.0 : 0.0;
  const double pass_s = replay ? replay->passSeconds() : players[0]->duration();
  double interval = 1.0 / clip_rate;
  bool rate_fixed = false;
  Posture posture;
  std::vector<PlaybackStats> playback(drivers.size());  // what each participant would show
  std::int64_t frame = 0;
  int exit_code = 0;
  while (!g_stop) {
    const double t = static_cast<double>(frame) * interval;
    if (duration > 0.0 && t >= duration) break;
    std::this_thread::sleep_until(start +
                                  std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                      std::chrono::duration<double>(t)));
    if (replay_origin < 0.0 && drivers[0]->withSession([](const ClientSession& s, double) {
          return s.state() == SessionState::kLive && s.clock().sampleCount() >= 3;
        })) {
      // The first speaker's frame grid decides (its first frame whole); the motion follows.
      double origin = -1.0;
      for (auto& v : voices) {
        if (!v) continue;
        const double at =
            v->startInputAt(origin < 0.0 ? start_mono + t : origin, loop ? pass_s : 0.0);
        if (origin < 0.0) origin = at;
      }
      replay_origin = origin < 0.0 ? t : origin - start_mono;
      spdlog::info("replay and voice start {:.3f} s after joining began", replay_origin);
    }
    const double rt = replay_origin < 0.0 ? 0.0 : std::max(0.0, t - replay_origin);  // replay time
    if (!replay && !loop && rt > players[0]->duration() + 1e-9) break;
    // Once live: cap the rate at the room's tick rate.
    if (!rate_fixed && drivers[0]->state() == SessionState::kLive) {
      const double tick =
          drivers[0]->withSession([](const ClientSession& s, double) { return s.tickRateHz(); });
      if (tick > 0.0 && clip_rate > tick) {
        interval = 1.0 / tick;
        frame = static_cast<std::int64_t>(t / interval);
      }
      rate_fixed = true;
      spdlog::info("sending {:.1f} postures/s per participant", 1.0 / interval);
    }
    // A recording: solved once per send for everyone; its end (without --loop) ends the run.
    if (replay && !replay->advanceTo(rt, posture)) {
      std::printf("vistel-bot: replay finished after %zu frames: %s\n", replay->framesSolved(),
                  replay->endMessage().c_str());
      break;
    }
    // Send; stop when every participant's session has ended.
    int open = 0;
    for (int i = 0; i < count; ++i) {
      if (drivers[static_cast<std::size_t>(i)]->state() == SessionState::kClosed) continue;
      ++open;
      if (!replay) players[static_cast<std::size_t>(i)]->sample(rt, loop, posture);
      drivers[static_cast<std::size_t>(i)]->sendPosture(posture);
      // What a client's frame would show of each remote member now.
      drivers[static_cast<std::size_t>(i)]->withSession([&](const ClientSession& s, double now) {
        if (s.state() != SessionState::kLive) return 0;
        const double server_now = s.serverTime(now);
        const double play_time = server_now - config->interpolation_delay_s;
        for (const auto& m : s.members()) {
          if (m->is_self) continue;
          double captured = 0.0;
          const auto shown = m->buffer.classify(play_time, config->max_extrapolation_s, &captured);
          playback[static_cast<std::size_t>(i)].add(shown, server_now - captured);
        }
        return 0;
      });
    }
    if (open == 0) break;
    if (voices[0]) {
      voice_scene.begin();
      drivers[0]->withSession([&](const ClientSession& s, double) {
        for (const auto& m : s.members()) {
          const glm::mat4 placement =
              glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(m->seat.x, 0.0f, m->seat.z)),
                          m->seat.yaw, glm::vec3(0.0f, 1.0f, 0.0f));
          voice_scene.add(m->id, m->is_self, nullptr, nullptr, placement);
        }
        return 0;
      });
      voice_scene.commit(*voices[0]);
    }
    ++frame;
  }

  // Leave cleanly, report, and wait for the network thread (bounded).
  if (!stats_path.empty()) {
    const double end = monotonicSeconds();
    std::vector<ParticipantReport> reports;
    for (std::size_t i = 0; i < drivers.size(); ++i) {
      ParticipantReport& r = reports.emplace_back();
      r.name = names[i];
      r.state = sessionStateName(drivers[i]->state());
      r.error = drivers[i]->error();
      r.join_s = drivers[i]->secondsToLive();
      r.rejoins = drivers[i]->rejoins();
      r.live_s = r.join_s < 0.0 ? 0.0 : std::max(0.0, end - started_at - r.join_s);
      r.stats = drivers[i]->withSession([](const ClientSession& s, double) { return s.stats(); });
      r.playback = playback[i];
    }
    if (Status st = writeFileText(stats_path, botReportJson(reports)); !st) {
      spdlog::error("--stats-json: {}", st.error().message);
      exit_code = 1;
    }
  }
  for (std::size_t i = 0; i < voices.size(); ++i) {
    if (!voices[i]) continue;
    if (Status st = voices[i]->stop(); !st) {
      spdlog::error("{}", st.error().message);
      exit_code = 1;
    }
    std::printf("vistel-bot: %s: %s\n", names[i].c_str(), voices[i]->summary().c_str());
    const double first = voices[i]->report().first_sent_capture_s;
    if (speaking && replay_origin >= 0.0 && first >= 0.0) {
      std::printf(
          "vistel-bot: %s: voice onset %.1f ms after the replay's first frame (the first frame "
          "sent, captured from then)\n",
          names[i].c_str(), 1e3 * (first - (start_mono + replay_origin)));
    }
  }
  for (std::size_t i = 0; i < drivers.size(); ++i) {
    const std::string error = drivers[i]->error();
    const auto sent = drivers[i]->withSession(
        [](const ClientSession& s, double) { return s.stats().postures_sent; });
    if (drivers[i]->state() == SessionState::kClosed && !error.empty()) {
      std::fprintf(stderr, "vistel-bot: %s: %s\n", names[i].c_str(), error.c_str());
      exit_code = 1;
    } else if (drivers[i]->secondsToLive() < 0.0) {
      // Refused (or unanswered) until the end: the run did not do what was asked.
      const std::string why = error.empty() ? drivers[i]->lastCloseReason() : error;
      std::fprintf(stderr, "vistel-bot: %s: never joined room '%s'%s%s\n", names[i].c_str(),
                   room.c_str(), why.empty() ? "" : ": ", why.c_str());
      exit_code = 1;
    }
    std::printf("vistel-bot: %s sent %llu postures\n", names[i].c_str(),
                static_cast<unsigned long long>(sent));
    drivers[i]->stop("bot finished");
  }
  std::fflush(stdout);
  work.reset();
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(3);
  while (!io.stopped() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  io.stop();
  network.join();
  return exit_code;
}
