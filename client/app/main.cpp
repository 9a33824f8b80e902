// vistel-client: the site client (DESIGN.md §1, §6).
//
//   vistel-client --server HOST:PORT --room R --name N [--token T] [--avatar FILE]
//                 [--tls [--tls-ca FILE | --tls-pin SHA256]] [--source bvh:FILE]
//                 [--headless] [--duration S] [--screenshot FILE] [--stats-json FILE]
//                 [--stereo off|side-by-side|anaglyph] [--view room|first-person]
//                 [--frames DIR [--frames-every N]] [--config FILE] [--ball] [--rigid-only]
//                 [--sensors FILE.toml [--calibrate-after S] | --source sim:CLIP.bvh
//                  | --source recording:FILE.vrec] [--record FILE.vrec]
//                 [--forces-out FILE.csv] [--force-feedback SENSORS.toml] [--log-level LEVEL]
//                 [--netsim SPEC] [--record-room FILE.glb] [--audio-in FILE.wav]
//                 [--audio-out FILE.wav] [--mute] [--no-audio] [--no-echo-cancel]
//   vistel-client --version   (the project version and the protocol versions it speaks)
//
// With sensors (client/app/sensor_input.hpp) a sensor thread reads the devices (or the
// simulated rig, or a recording), solves the own posture and sends it; C in the window
// calibrates. Every drawn body whose avatar carries an implicit model (the default avatar,
// built avatars, balls) is deformed after skinning (client/deform RoomDeformer; Step 1 from
// the server's snapshots when it fits, [deform] in the config; --rigid-only turns it off).
// Dents are shared with the other sites (client/deform/dent_sync.hpp): the own avatar's,
// and a prop's while the own avatar dents it, go to the server, which relays them; the
// other sites' replace what this one draws of their bodies.
// Joins room R, streams its own posture (a clip with --source, else the avatar's rest
// posture), receives everyone's into jitter buffers, and draws the room (RoomView: a
// window with a display, EGL offscreen without one). --headless draws nothing but
// still samples every remote posture each frame. --frames writes every Nth frame
// (--frames-every, default 1) as a PNG into DIR; --screenshot writes the last frame at
// exit (without --duration it runs 3 s).
// --stats-json writes, on exit, the receive rates, latency and frames rendered, and for
// rendered frames frame_ms {p50, p99, max} (the frame's work, without the wait for the next
// one), deform_share (the deformable component's part of it) and the bodies per frame
// deformed at full rate, at a lower rate, or drawn rigid (the level of detail's tiers),
// and own_forces: the own avatar's contact force per body part (its implicit primitives;
// client/deform/own_forces.hpp) — frames in contact, peak and mean per part, the last
// frame's forces, and dent_sync: dent records sent and adopted. --forces-out streams those forces
// as CSV, a row per frame per part in contact (and one when it lets go); a [force_feedback] section
// in the sensors config
// (--sensors, or --force-feedback naming a sensors config) sends them to a HID
// force-feedback device, at most at the frame rate. The stats' "playback" object says
// how each remote member was shown (client/net/playback_stats.hpp): frames interpolated,
// held and extrapolated, and the shown posture's age p50/p99. --netsim SPEC (or [network]
// netsim) puts a simulated bad network between the client and the server on UDP
// (client/net/net_sim.hpp: loss, latency, jitter, duplication, reordering).
// --record-room FILE.glb writes, at exit, what the session showed as a skinned glTF
// animation (client/record: every member's avatar and joint tracks, the props).
// Voice (client/voice/voice_engine.hpp, proto/VOICE.md): the default microphone and
// speakers through PortAudio, or --audio-in FILE.wav (spoken once the session is live) and
// --audio-out FILE.wav (the stereo mix heard, written at exit; with --frames and no
// --audio-out, DIR/heard.wav); --mute sends nothing (M in the window toggles it),
// --no-audio turns voice off. Remote voices are spatialised from the speakers' heads; a
// speaking avatar lifts its chin (or opens its jaw) with what is heard from it.
//
// Threads: this (main) thread owns the window/GL and renders; a network thread runs
// Asio (NetDriver); a source thread produces the own postures; the room view skins in
// its worker pool. Exit status: 0, 1 on an error (the session's reason is printed; a
// session the server refused until the end counts), 2 on bad usage (an unknown
// --log-level too). SIGINT/SIGTERM leave the room cleanly.
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include "client/app/sensor_input.hpp"
#include "client/app/server_interactions.hpp"
#include "client/deform/dent_sync.hpp"
#include "client/deform/own_forces.hpp"
#include "client/deform/room_deformer.hpp"
#include "client/net/asio.hpp"
#include "client/net/client_config.hpp"
#include "client/net/clip_player.hpp"
#include "client/net/data_dir.hpp"
#include "client/net/net_driver.hpp"
#include "client/net/playback_stats.hpp"
#include "client/net/prop_models.hpp"
#include "client/net/remote_jitter.hpp"
#include "client/net/tls_options.hpp"
#include "client/record/session_sampling.hpp"
#include "client/view/room_view.hpp"
#include "client/voice/voice_cli.hpp"
#include "client/voice/voice_engine.hpp"
#include "client/voice/voice_scene.hpp"
#include "common/avatar/avatar_io.hpp"
#include "common/base/file.hpp"
#include "common/motion/bvh.hpp"
#include "common/wire/packets.hpp"
#include "vistel_version.hpp"

namespace {

using namespace vistel;
using namespace vistel::net;

std::atomic<bool> g_stop{false};
extern "C" void onSignal(int) { g_stop = true; }

using Clock = std::chrono::steady_clock;

Clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

bool hasDisplay() {
  for (const char* var : {"DISPLAY", "WAYLAND_DISPLAY"}) {
    const char* v = std::getenv(var);
    if (v != nullptr && *v != '\0') return true;
  }
  return false;
}

// The participant's own postures, produced on the source thread, read by the renderer.
class OwnSource {
 public:
  OwnSource(std::unique_ptr<ClipPlayer> player, Posture rest, double rate_hz)
      : player_(std::move(player)), latest_(std::move(rest)), rate_hz_(rate_hz) {}

  // Sends a posture per frame of the clip (or rate_hz of the rest posture) until stop.
  void run(NetDriver& driver, const std::atomic<bool>& stop) {
    const double interval = player_ ? player_->frameTime() : 1.0 / rate_hz_;
    const auto start = Clock::now();
    Posture p = latest_;
    for (std::int64_t frame = 0; !stop; ++frame) {
      const double t = static_cast<double>(frame) * interval;
      std::this_thread::sleep_until(start + seconds(t));
      if (player_) player_->sample(t, /*loop=*/true, p);
      driver.sendPosture(p);
      std::lock_guard lock(mutex_);
      latest_ = p;
    }
  }

  Posture latest() const {
    std::lock_guard lock(mutex_);
    return latest_;
  }

 private:
  std::unique_ptr<ClipPlayer> player_;
  mutable std::mutex mutex_;
  Posture latest_;
  double rate_hz_;
};

// One roster member as the frame sees it (copied out under the session lock).
struct FrameMember {
  std::uint32_t id = 0;
  std::string name;
  std::string avatar_hash;
  Seat seat;
  bool is_self = false;
  bool has_posture = false;
  Posture posture;
  double shown_time = 0.0;  // the playback time it was sampled at (server clock)
};

// Per-frame figures of the rendered frames, summarised for --stats-json.
class FrameFigures {
 public:
  FrameFigures() { frame_ms_.reserve(kMaxSamples); }

  void add(double frame_ms, double deform_ms, int full, int reduced, int rigid) {
    if (frame_ms_.size() < kMaxSamples) frame_ms_.push_back(frame_ms);  // no allocation
    total_ms_ += frame_ms;
    deform_ms_ += deform_ms;
    full_ += full;
    reduced_ += reduced;
    rigid_ += rigid;
    last_ = {full, reduced, rigid};
    ++frames_;
  }

  // The fields as JSON members (no braces), keys indented by two spaces.
  std::string json() const {
    std::vector<double> sorted = frame_ms_;
    std::sort(sorted.begin(), sorted.end());
    auto pick = [&](double p) {
      if (sorted.empty()) return 0.0;
      const auto i = static_cast<std::size_t>(p / 100.0 * static_cast<double>(sorted.size() - 1));
      return sorted[i];
    };
    const double n = frames_ > 0 ? static_cast<double>(frames_) : 1.0;
    return fmt::format(
        "  \"frame_ms\": {{\"p50\": {:.3f}, \"p99\": {:.3f}, \"max\": {:.3f}}},\n"
        "  \"deform_share\": {:.4f},\n"
        "  \"bodies_per_frame\": {{\"full\": {:.2f}, \"reduced\": {:.2f}, \"rigid\": "
        "{:.2f}}},\n"
        "  \"bodies_last_frame\": {{\"full\": {}, \"reduced\": {}, \"rigid\": {}}}",
        pick(50.0), pick(99.0), sorted.empty() ? 0.0 : sorted.back(),
        total_ms_ > 0.0 ? deform_ms_ / total_ms_ : 0.0, full_ / n, reduced_ / n, rigid_ / n,
        last_[0], last_[1], last_[2]);
  }

 private:
  static constexpr std::size_t kMaxSamples = 1u << 18;  // about 73 minutes at 60 Hz
  std::vector<double> frame_ms_;
  double total_ms_ = 0.0;
  double deform_ms_ = 0.0;
  double full_ = 0.0;
  double reduced_ = 0.0;
  double rigid_ = 0.0;
  std::array<int, 3> last_ = {0, 0, 0};
  std::int64_t frames_ = 0;
};

// The JSON object `json` ("{...}\n") with `fields` added as its last members.
std::string withFields(const std::string& json, const std::string& fields) {
  const std::size_t close = json.rfind('}');
  if (close == std::string::npos) return json;
  std::size_t end = close;
  while (end > 0 && (json[end - 1] == '\n' || json[end - 1] == ' ')) --end;
  return json.substr(0, end) + ",\n" + fields + "\n" + json.substr(close);
}

glm::mat4 seatPlacement(const Seat& seat) {
  return glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(seat.x, 0.0f, seat.z)), seat.yaw,
                     glm::vec3(0.0f, 1.0f, 0.0f));
}

}  // namespace

int main(int argc, char** argv) {
  // Command line.
  CLI::App app{"vistel-client: join a room, stream your posture, see everyone"};
  std::string server_text, room, name, avatar_path, source_text, screenshot, stats_path;
  std::string frames_dir, stereo_text = "off", view_text = "room";
  std::string config_path = "config/client.toml";
  bool headless = false;
  double duration = 0.0;
  int frames_every = 1;
  app.add_option("--server", server_text, "session server HOST:PORT")->required();
  app.add_option("--room", room, "room to join")->required();
  app.add_option("--name", name, "participant name")->required();
  std::string token;
  app.add_option("--token", token,
                 "join token for this room and name (`vistel-server token`), for a server that "
                 "requires one");
  app.add_option("--avatar", avatar_path, "avatar file (.vavatar; default: the data folder's)");
  tls::ClientTlsSettings tls_settings;
  addTlsOptions(app, tls_settings);
  app.add_option("--source", source_text,
                 "own posture source: bvh:FILE, sim:CLIP.bvh (simulated sensor rig) or "
                 "recording:FILE.vrec (default: rest posture)");
  app.add_flag("--headless", headless, "no window and no rendering");
  bool ball = false;  // once live: ask the server for a ball above our head
  app.add_flag("--ball", ball, "once joined, drop a ball above your head (the server places it)");
  bool rigid_only = false;
  app.add_flag("--rigid-only", rigid_only,
               "draw skinned avatars without the deformable component ([deform] enabled = false)");
  app.add_option("--duration", duration, "leave after this many seconds")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--screenshot", screenshot, "write the last frame as PNG at exit");
  app.add_option("--stats-json", stats_path, "write receive statistics as JSON at exit");
  app.add_option("--stereo", stereo_text, "off, side-by-side or anaglyph")
      ->check(CLI::IsMember({"off", "side-by-side", "anaglyph"}));
  app.add_option("--view", view_text, "room or first-person")
      ->check(CLI::IsMember({"room", "first-person"}));
  app.add_option("--frames", frames_dir, "write rendered frames as PNG into this folder");
  app.add_option("--frames-every", frames_every, "with --frames: write every Nth frame")
      ->check(CLI::Range(1, 100000));
  app.add_option("--config", config_path, "client settings (TOML); built-in defaults if absent");
  std::string forces_path, force_feedback_path;
  app.add_option("--forces-out", forces_path,
                 "stream the own avatar's contact force per body part as CSV to this file");
  app.add_option("--force-feedback", force_feedback_path,
                 "sensors config whose [force_feedback] device gets the own contact forces "
                 "(default: the --sensors file)");
  SensorArgs sensor_args;
  addSensorOptions(app, sensor_args);
  std::string netsim_text;
  auto* netsim_opt = app.add_option(
      "--netsim", netsim_text,
      "simulate a bad network on UDP: comma-separated loss=P, latency=D, jitter=D, "
      "jitter_dist=uniform|normal, dup=P, reorder=P, reorder_delay=D, dir=both|in|out, seed=N "
      "(e.g. loss=0.1,latency=30ms,jitter=50ms; overrides [network] netsim)");
  std::string record_room_path;  // client/record: the session as a skinned glTF animation
  app.add_option("--record-room", record_room_path,
                 "write what the session showed (every member's avatar and joint tracks, the "
                 "props) as a skinned glTF animation to this .glb at exit");
  VoiceOptions voice_options;
  bool no_audio = false;
  app.add_option("--audio-in", voice_options.audio_in,
                 "speak this audio file (WAV) instead of the microphone");
  app.add_option("--audio-out", voice_options.audio_out,
                 "write what is heard to this WAV file (stereo, 48 kHz) instead of the speakers");
  addSharedVoiceOptions(app, voice_options, no_audio, "start with the own voice muted (M toggles)",
                        "no voice at all: nothing captured, sent or played");
  bool no_echo_cancel = false;
  app.add_flag("--no-echo-cancel", no_echo_cancel,
               "keep what the speakers play in the microphone's capture (headphones)");
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error, off (default: info)");
  app.set_version_flag("--version",
                       vistel::versionLine("vistel-client", vistel::net::kProtocolVersion,
                                           vistel::wire::kWireVersion));
  CLI11_PARSE(app, argc, argv);
  spdlog::set_default_logger(spdlog::stderr_color_mt("vistel-client"));
  // spdlog reads an unknown name as "off": refuse it rather than go silent.
  if (log_level != "off" && spdlog::level::from_str(log_level) == spdlog::level::off) {
    std::fprintf(stderr,
                 "vistel-client: --log-level '%s': expected trace, debug, info, warn, error or "
                 "off\n",
                 log_level.c_str());
    return 2;
  }
  spdlog::set_level(spdlog::level::from_str(log_level));

  if (headless && (!screenshot.empty() || !frames_dir.empty())) {
    std::fprintf(stderr,
                 "vistel-client: --screenshot and --frames need rendering (drop "
                 "--headless)\n");
    return 2;
  }
  if (const std::string tls_error = checkTlsOptions(tls_settings); !tls_error.empty()) {
    std::fprintf(stderr, "vistel-client: %s\n", tls_error.c_str());
    return 2;
  }
  if (!record_room_path.empty()) {
    if (Status st = record::checkRecordPath(record_room_path); !st) {
      std::fprintf(stderr, "vistel-client: --record-room %s\n", st.error().message.c_str());
      return 2;
    }
  }
  if (!screenshot.empty() && duration == 0.0) duration = 3.0;
  const Result<std::string> sensor_spec = sensorSpec(sensor_args, source_text);
  if (!sensor_spec) {
    std::fprintf(stderr, "vistel-client: %s\n", sensor_spec.error().message.c_str());
    return 2;
  }

  // Settings, address, own avatar.
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
    std::fprintf(stderr, "vistel-client: %s\n", netsim.error().message.c_str());
    return 2;
  }
  if (avatar_path.empty()) avatar_path = defaultAvatarPath();
  auto avatar_bytes = readFileBytes(avatar_path, 1u << 30);
  if (!avatar_bytes) {
    spdlog::error("avatar: {}", avatar_bytes.error().message);
    return 1;
  }
  const std::string own_hash = avatarContentHash(*avatar_bytes);
  auto cache = std::make_shared<AvatarCache>(avatarCacheFolder(config->cache_dir));
  auto own_avatar = cache->insert(own_hash, *avatar_bytes);
  if (!own_avatar) {
    spdlog::error("{}: {}", avatar_path, own_avatar.error().message);
    return 1;
  }
  const Skeleton& own_skeleton = (*own_avatar)->skeleton;

  // The own avatar's contact forces per body part: stats, CSV, force-feedback device.
  std::unique_ptr<OwnForces> own_forces;
  if ((*own_avatar)->implicit || !forces_path.empty() || !force_feedback_path.empty()) {
    OwnForcesOptions options;
    options.csv_path = forces_path;
    options.force_feedback_config =
        force_feedback_path.empty() ? sensor_args.sensors_path : force_feedback_path;
    options.frame_rate_hz = config->frame_rate_hz;
    options.require_force_feedback = !force_feedback_path.empty();
    auto created = OwnForces::create(**own_avatar, options);
    if (!created) {
      spdlog::error("{}", created.error().message);
      return 1;
    }
    own_forces = std::move(*created);
    for (const std::string& w : own_forces->warnings()) spdlog::warn("{}", w);
  }

  // Own posture from sensors (solved on the sensor thread), else from a clip or at rest.
  std::unique_ptr<SensorInput> sensors;
  if (!sensor_spec->empty()) {
    auto opened = SensorInput::open({.spec = *sensor_spec,
                                     .calibrate_after_s = sensor_args.calibrate_after_s,
                                     .record_path = sensor_args.record_path,
                                     .idle_rate_hz = config->idle_rate_hz},
                                    own_skeleton);
    if (!opened) {
      spdlog::error("{}", opened.error().message);
      return 1;
    }
    sensors = std::move(*opened);
  }
  std::unique_ptr<ClipPlayer> player;
  if (!source_text.empty() && !sensors) {
    if (source_text.rfind("bvh:", 0) != 0) {
      std::fprintf(stderr,
                   "vistel-client: --source %s: expected bvh:FILE, sim:CLIP.bvh or "
                   "recording:FILE.vrec\n",
                   source_text.c_str());
      return 2;
    }
    auto clip = loadBvh(source_text.substr(4));
    if (!clip) {
      spdlog::error("{}", clip.error().message);
      return 1;
    }
    auto created = ClipPlayer::create(std::move(*clip), own_skeleton);
    if (!created) {
      spdlog::error("{}", created.error().message);
      return 1;
    }
    player = std::move(*created);
  }
  OwnSource source(std::move(player), restPosture(own_skeleton), config->idle_rate_hz);

  // The view (unless headless): offscreen without a display; falls back to headless
  // with a warning if no GL context can be made.
  std::unique_ptr<RoomView> view;
  if (!headless) {
    ViewOptions options;
    options.width = config->width;
    options.height = config->height;
    options.offscreen = !hasDisplay();
    options.worker_threads = config->worker_threads;
    options.gpu_skinning = config->gpu_skinning;
    options.skinning = config->skinning;
    options.stereo = stereo_text == "side-by-side" ? StereoMode::kSideBySide
                     : stereo_text == "anaglyph"   ? StereoMode::kAnaglyph
                                                   : StereoMode::kOff;
    options.view = view_text == "first-person" ? ViewMode::kFirstPerson : ViewMode::kRoom;
    options.title = "vistel - " + room + " - " + name;
    auto created = RoomView::create(options);
    if (created) {
      view = std::move(*created);
      std::printf("vistel-client: rendering with %s\n", view->backendDescription().c_str());
    } else {
      std::printf("vistel-client: no rendering (%s); continuing headless\n",
                  created.error().message.c_str());
    }
    if (view && !frames_dir.empty()) {
      std::error_code ec;
      std::filesystem::create_directories(frames_dir, ec);
      std::printf("vistel-client: writing frames to %s\n", frames_dir.c_str());
    }
  }

  // Network thread, source thread.
  SessionSettings settings = config->session;
  settings.room = room;
  settings.name = name;
  settings.token = token;
  settings.avatar_hash = own_hash;
  settings.avatar_bytes =
      std::make_shared<const std::vector<std::uint8_t>>(std::move(*avatar_bytes));
  settings.avatar_joint_count = own_skeleton.jointCount();
  asio::io_context io;
  auto work = asio::make_work_guard(io);
  auto driver = NetDriver::create(io, *server, settings, cache, {}, tls_settings);
  driver->setNetSim(*netsim);
  voice_options.echo_cancel = !no_echo_cancel;
  // Voice: its own thread on a 20 ms grid (client/voice).
  std::unique_ptr<VoiceEngine> voice;
  if (!no_audio) {
    if (voice_options.audio_out.empty() && view && !frames_dir.empty()) {
      voice_options.audio_out = frames_dir + "/heard.wav";
    }
    voice_options.label = "vistel-client: voice";
    // --record: what is sent goes into the recording too (client/app/sensor_input.hpp).
    if (sensors) {
      voice_options.on_sent = [s = sensors.get()](double t, std::span<const std::uint8_t> p) {
        s->recordVoice(t, p);
      };
    }
    auto started = VoiceEngine::start(driver, voice_options);
    if (!started) {
      spdlog::error("{}", started.error().message);
      return 1;
    }
    voice = std::move(*started);
  }
  VoiceScene voice_scene;
  driver->start();
  std::thread network([&io] { io.run(); });
  std::atomic<bool> stop_source{false};
  std::thread source_thread([&] {
    if (sensors) {
      sensors->run(*driver, stop_source);
    } else {
      source.run(*driver, stop_source);
    }
  });
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  std::printf("vistel-client: joining room '%s' on %s as '%s'\n", room.c_str(), server_text.c_str(),
              name.c_str());
  std::fflush(stdout);

  // Frame loop: sample every member at (server now - delay), render or just sample.
  const double frame_interval = 1.0 / config->frame_rate_hz;
  const auto start = Clock::now();
  std::vector<FrameMember> members;
  std::vector<std::pair<std::uint32_t, BallSpec>> props;  // (prop id, ball), sampled below
  std::vector<float> prop_restitution;                    // per entry of props
  std::vector<PropSample> prop_states;
  PropModels prop_models;
  std::vector<MemberView> views;
  // The deformable component on every drawn body with an implicit model (client/deform).
  std::unique_ptr<RoomDeformer> deformer;
  if (view && config->deform && !rigid_only) {
    deformer = std::make_unique<RoomDeformer>();
    if (Status st = deformer->setLod(config->lod); !st) spdlog::warn("{}", st.error().message);
  }
  if (own_forces && !deformer && (!forces_path.empty() || !force_feedback_path.empty())) {
    spdlog::warn(
        "own contact forces need the deformable component (rendering, [deform] enabled, no "
        "--rigid-only): they stay zero");
  }
  // Dents shared with the other sites (proto/SESSION.md §2.5).
  DentSync dent_sync;
  std::vector<DentBody> dent_props;
  std::vector<BodyDents> dents_in;
  double frame_server_now = 0.0;
  FrameFigures figures;
  PlaybackStats playback;  // how each remote member was shown
  // The jitter drawn against sent, for --stats-json only (forward kinematics per member).
  std::unique_ptr<RemoteJitter> remote_jitter;
  if (!stats_path.empty()) remote_jitter = std::make_unique<RemoteJitter>();
  ServerInteractions server_lists;
  InteractionList received_list;
  std::unordered_map<std::string, std::shared_ptr<const AvatarModel>> models;
  models[own_hash] = *own_avatar;
  std::unique_ptr<record::RoomRecorder> recorder;
  Posture record_own;      // the own posture for the recorder, copied when a sample is due
  Posture record_scratch;  // a remote member's posture while sampling
  if (!record_room_path.empty()) {
    recorder = std::make_unique<record::RoomRecorder>(
        record::RecorderOptions{.max_extrapolation_s = config->max_extrapolation_s});
  }
  std::int64_t frame = 0;
  int exit_code = 0;
  while (!g_stop) {
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    if (duration > 0.0 && elapsed >= duration) break;
    if (ball && driver->state() == SessionState::kLive) ball = !driver->requestBall();
    if (driver->state() == SessionState::kClosed) {
      std::fprintf(stderr, "vistel-client: session ended: %s\n", driver->error().c_str());
      exit_code = 1;
      break;
    }
    if (recorder && recorder->due(elapsed)) {
      if (sensors) {
        sensors->copyLatest(record_own);
      } else {
        record_own = source.latest();
      }
    }
    // Copy the roster and postures out under the session lock.
    driver->withSession([&](const ClientSession& s, double now) {
      const double server_now = s.serverTime(now);
      frame_server_now = server_now;
      const double play_time = server_now - config->interpolation_delay_s;
      members.resize(s.members().size());
      for (std::size_t i = 0; i < members.size(); ++i) {
        const RemoteMember& m = *s.members()[i];
        FrameMember& f = members[i];
        f.id = m.id;
        f.name = m.name;
        f.avatar_hash = m.avatar_hash;
        f.seat = m.seat;
        f.is_self = m.is_self;
        f.has_posture = false;
        if (!m.is_self) {
          double captured = 0.0;
          const JitterBuffer::Shown shown =
              m.buffer.sampleShown(play_time, config->max_extrapolation_s, f.posture, &captured);
          f.has_posture = shown != JitterBuffer::Shown::kNone;
          f.shown_time = play_time;
          if (s.state() == SessionState::kLive) playback.add(m.name, shown, server_now - captured);
          if (remote_jitter) remote_jitter->collect(m);
        }
      }
      props.clear();
      prop_restitution.clear();
      prop_states.resize(s.props().size());
      for (const auto& p : s.props()) {
        if (p->track.sample(play_time, prop_states[props.size()])) {
          props.emplace_back(p->id, p->ball);
          prop_restitution.push_back(p->restitution);
        }
      }
      if (recorder) {
        record::sampleSession(*recorder, s, elapsed, play_time, record_own, record_scratch);
      }
      return 0;
    });
    if (remote_jitter) {
      for (const FrameMember& f : members) {
        if (f.is_self || !f.has_posture) continue;
        if (auto model = cache->find(f.avatar_hash)) {
          remote_jitter->measure(f.id, f.name, model->skeleton, f.shown_time, f.posture, playback);
        }
      }
      remote_jitter->endFrame();
    }
    // Voice: every head for the spatialiser (self is the listener).
    if (voice) {
      // A member's avatar: the own one (never in the cache when nobody else offered it) or
      // the cache's.
      const auto voice_model = [&](const std::string& hash) {
        auto found = models.find(hash);
        return found != models.end() ? found->second : cache->find(hash);
      };
      voice_scene.begin();
      for (const FrameMember& f : members) {
        auto model = voice_model(f.avatar_hash);
        Posture own;
        if (f.is_self && sensors) {
          sensors->copyLatest(own);
        } else if (f.is_self) {
          own = source.latest();
        }
        const Posture* posture = f.is_self ? &own : f.has_posture ? &f.posture : nullptr;
        voice_scene.add(f.id, f.is_self, model ? &model->skeleton : nullptr, posture,
                        seatPlacement(f.seat));
      }
      voice_scene.commit(*voice);
      // Lip sync: the jaw (or chin) follows what is heard from each member now, on the
      // posture drawn (and, headless, the one that would be); the opening goes to the jaw
      // timeline next to --audio-out.
      for (FrameMember& f : members) {
        if (f.is_self || !f.has_posture) continue;
        if (auto model = voice_model(f.avatar_hash)) {
          voice->noteMouth(
              f.id, applyVoiceToPosture(model->skeleton, mouthOpening(voice->speakingLevel(f.id)),
                                        f.posture));
        }
      }
    }
    // Draw (the view skins every avatar in its worker pool).
    if (view) {
      const Clock::time_point frame_start = Clock::now();
      view->pollEvents();
      if (view->shouldClose()) break;
      const std::string keys = view->takeKeyPresses();
      if (sensors) sensors->onKeys(keys);
      if (voice && keys.find('M') != std::string::npos) {
        voice->toggleMute();
        std::printf("vistel-client: voice %s\n", voice->muted() ? "muted" : "on");
        std::fflush(stdout);
      }
      views.resize(members.size());
      std::optional<std::uint32_t> self_view;
      for (std::size_t i = 0; i < members.size(); ++i) {
        const FrameMember& f = members[i];
        MemberView& v = views[i];
        if (f.is_self && !self_view) self_view = f.id;
        auto found = models.find(f.avatar_hash);
        if (found == models.end()) {
          if (auto model = cache->find(f.avatar_hash))
            found = models.emplace(f.avatar_hash, model).first;
        }
        v.id = f.id;
        v.name = f.name;
        v.avatar = found != models.end() ? found->second : nullptr;
        v.is_self = f.is_self;
        v.placement = seatPlacement(f.seat);
        if (f.is_self && sensors) {
          sensors->copyLatest(v.posture);
        } else if (f.is_self) {
          v.posture = source.latest();
        } else if (f.has_posture) {
          v.posture = f.posture;  // with the lip sync applied above
        } else if (v.avatar) {
          v.posture = restPosture(v.avatar->skeleton);
        }
      }
      // Props: balls drawn as one-joint avatars at their interpolated centres.
      for (std::size_t k = 0; k < props.size(); ++k) {
        MemberView& v = views.emplace_back();
        v.id = propViewId(props[k].first);
        view->setFramed(v.id, false);
        v.avatar = prop_models.ball(props[k].second);
        ballPosture(prop_states[k].position, v.posture);
      }
      if (deformer) {
        if (Status st = deformer->sync(views, *view); !st) spdlog::warn("{}", st.error().message);
        for (std::size_t k = 0; k < props.size(); ++k) {  // the balls' motion: restitution
          deformer->setMotion(propViewId(props[k].first), prop_states[k].velocity,
                              prop_restitution[k]);
        }
        const bool use_server =
            config->server_interactions && driver->withSession([&](const ClientSession& s, double) {
              return server_lists.map(s, *deformer, received_list);
            });
        if (Status st = deformer->prepare(elapsed, use_server ? &received_list : nullptr); !st) {
          spdlog::warn("{}", st.error().message);
        }
      }
      view->render(views);
      if (deformer) deformer->finish();
      // Dents: ours (own avatar, props it dents) out, the other sites' in.
      if (deformer && self_view) {
        const DentBody self{false, *self_view, *self_view};
        dent_props.clear();
        for (const auto& p : props) dent_props.push_back({true, p.first, propViewId(p.first)});
        for (const OutgoingDents& o : dent_sync.collect(*deformer, elapsed, self, dent_props)) {
          driver->sendDents({o.body.prop, o.body.id, 0, frame_server_now, o.record});
        }
        driver->takeDents(dents_in);
        for (const BodyDents& d : dents_in) {
          const DentBody body{d.prop, d.body_id, d.prop ? propViewId(d.body_id) : d.body_id};
          const double age = std::max(0.0, frame_server_now - d.server_time);
          if (Status st = dent_sync.receive(*deformer, elapsed, self, body, d.record, age); !st) {
            spdlog::warn("{}", st.error().message);
          }
        }
      }
      if (own_forces) {
        if (Status st = own_forces->frame(elapsed, deformer.get(), self_view); !st) {
          spdlog::warn("{}", st.error().message);
        }
      }
      {
        // This frame's figures: the deformation's wall time is prepare() plus Steps 2-3
        // spread over the view's threads.
        const double frame_ms =
            std::chrono::duration<double, std::milli>(Clock::now() - frame_start).count();
        const int drawn = view->lastStats().members_drawn;
        if (deformer) {
          const DeformFrameStats& d = deformer->lastStats();
          const double deform_ms =
              d.prepare_ms + d.deform_cpu_ms / static_cast<double>(view->workerThreads());
          figures.add(frame_ms, deform_ms, d.full, d.reduced,
                      std::max(drawn - d.full - d.reduced, 0));
        } else {
          figures.add(frame_ms, 0.0, 0, 0, drawn);
        }
      }
      if (!frames_dir.empty() && frame % frames_every == 0) {
        const std::string path = fmt::format("{}/frame_{:05d}.png", frames_dir, frame);
        if (Status st = view->saveFrame(path); !st) spdlog::warn("{}", st.error().message);
      }
    }
    ++frame;
    std::this_thread::sleep_until(start + seconds(static_cast<double>(frame) * frame_interval));
  }

  // The session's recording (at the end of the loop: duration, window closed, SIGINT/SIGTERM).
  if (recorder) {
    auto written = recorder->write(record_room_path,
                                   [&cache](const std::string& hash) { return cache->find(hash); });
    if (!written) {
      std::fprintf(stderr, "vistel-client: --record-room: %s\n", written.error().message.c_str());
      exit_code = 1;
    } else {
      for (const std::string& w : written->warnings) spdlog::warn("--record-room: {}", w);
      std::printf(
          "vistel-client: recorded %d members and %d props over %.1f s (%lld keys) to %s: %.2f "
          "MiB\n",
          written->members, written->props, written->duration_s,
          static_cast<long long>(written->keys), record_room_path.c_str(),
          static_cast<double>(written->bytes) / (1024.0 * 1024.0));
    }
  }

  // Screenshot, stats, leave.
  if (view && !screenshot.empty()) {
    if (Status st = view->saveScreenshot(screenshot); !st) {
      spdlog::error("{}", st.error().message);
      exit_code = 1;
    } else {
      std::printf("vistel-client: screenshot written to %s\n", screenshot.c_str());
    }
  }
  const int frames_rendered = view ? view->framesRendered() : 0;
  const auto [json, summary] = driver->withSession([&](const ClientSession& s, double) {
    std::string text =
        statsJson(s.stats(), frames_rendered, s.clock().offset(), s.clock().roundTrip());
    std::string line;
    for (const auto& [member, m] : s.stats().members) {
      line +=
          fmt::format(" {}: {} postures at {:.1f} Hz;", member, m.postures_received, m.rateHz());
    }
    line +=
        fmt::format(" latency mean {:.2f} ms, p99 {:.2f} ms; {} frames rendered",
                    s.stats().latency.mean(), s.stats().latency.percentile(99.0), frames_rendered);
    line += "; shown: " + playbackSummary(playback.total());
    return std::make_pair(text, line);
  });
  if (voice) {
    if (Status st = voice->stop(); !st) {
      spdlog::error("{}", st.error().message);
      exit_code = 1;
    }
    std::printf("vistel-client: %s\n", voice->summary().c_str());
  }
  if (!stats_path.empty()) {
    const std::string fields = figures.json() + ",\n  \"playback\": " + playbackJson(playback) +
                               (voice ? ",\n  \"voice\": " + voice->json() : std::string()) +
                               (own_forces ? ",\n" + own_forces->json() : std::string()) +
                               (deformer ? ",\n" + dent_sync.json() : std::string());
    if (Status st = writeFileText(stats_path, withFields(json, fields)); !st) {
      spdlog::error("{}", st.error().message);
      exit_code = 1;
    }
  }
  std::printf("vistel-client:%s\n", summary.c_str());
  std::fflush(stdout);
  // Refused (or unanswered) until the end: not a successful run.
  if (exit_code == 0 && driver->secondsToLive() < 0.0) {
    std::string error = driver->error();
    if (error.empty()) error = driver->lastCloseReason();
    std::fprintf(stderr, "vistel-client: never joined room '%s'%s%s\n", room.c_str(),
                 error.empty() ? "" : ": ", error.c_str());
    exit_code = 1;
  }

  stop_source = true;
  source_thread.join();
  if (sensors) std::printf("vistel-client: sensors: %s\n", sensors->summary().c_str());
  if (deformer) {
    std::printf(
        "vistel-client: deformable component on %d bodies (scene rebuilt %d times); Step 1 "
        "from the server in %llu frames (%llu lists did not fit)\n",
        deformer->bodyCount(), deformer->rebuilds(),
        static_cast<unsigned long long>(server_lists.used()),
        static_cast<unsigned long long>(server_lists.refused()));
  }
  if (own_forces) {
    if (Status st = own_forces->close(); !st) spdlog::warn("{}", st.error().message);
    std::printf("vistel-client: %s\n", own_forces->summary().c_str());
  }
  std::fflush(stdout);
  driver->stop("client exiting");
  work.reset();
  const auto deadline = Clock::now() + std::chrono::seconds(3);
  while (!io.stopped() && Clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  io.stop();
  network.join();
  view.reset();
  return exit_code;
}
