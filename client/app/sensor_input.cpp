#include "client/app/sensor_input.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <thread>
#include <utility>

#include <fmt/format.h>

namespace vistel {
namespace {

bool startsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

// "dir/take.vrec", 2 -> "dir/take-2.vrec" (the parts of a recording split by unplugging).
std::string numberedPath(const std::string& path, int part) {
  const std::filesystem::path p(path);
  std::filesystem::path out = p.parent_path() / (p.stem().string() + "-" + std::to_string(part));
  out += p.extension();
  return out.string();
}

}  // namespace

void addSensorOptions(CLI::App& app, SensorArgs& args) {
  app.add_option("--sensors", args.sensors_path,
                 "own posture from the trackers and gloves of this sensors config (TOML, e.g. "
                 "config/sensors/fastrak.toml)");
  app.add_option("--calibrate-after", args.calibrate_after_s,
                 "with a sensor source (--sensors, --source sim: or recording:): calibrate this "
                 "many seconds after start (stand in the "
                 "calibration pose); the window's C key calibrates at any time")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--record", args.record_path,
                 "record the raw sensor stream (--sensors or --source sim:/recording:) to this "
                 ".vrec file");
}

Result<std::string> sensorSpec(const SensorArgs& args, const std::string& source_text) {
  if (!args.sensors_path.empty()) {
    if (!source_text.empty()) {
      return fail("--sensors {} and --source {} both give the own posture: use one",
                  args.sensors_path, source_text);
    }
    return args.sensors_path;
  }
  if (startsWith(source_text, "sim:") || startsWith(source_text, "recording:")) return source_text;
  if (!source_text.empty() && !startsWith(source_text, "bvh:")) {
    return fail("--source {}: expected bvh:FILE, sim:CLIP.bvh or recording:FILE.vrec", source_text);
  }
  if (!args.record_path.empty()) {
    return fail(
        "--record {}: there is no sensor stream to record (give --sensors FILE.toml or "
        "--source sim:CLIP.bvh)",
        args.record_path);
  }
  if (args.calibrate_after_s >= 0.0)
    return fail("--calibrate-after needs --sensors FILE.toml (a sensor source)");
  return std::string();
}

SensorInput::SensorInput(SensorInputOptions options, Skeleton avatar)
    : options_(std::move(options)), avatar_(std::move(avatar)), latest_(restPosture(avatar_)) {}

SensorInput::~SensorInput() = default;

Result<std::unique_ptr<SensorInput>> SensorInput::open(const SensorInputOptions& options,
                                                       const Skeleton& avatar) {
  std::unique_ptr<SensorInput> input(new SensorInput(options, avatar));
  if (Status s = input->reopen(options.record_path); !s) return s.error();
  return input;
}

Status SensorInput::reopen(const std::string& record_to) {
  PostureSourceOptions o;
  o.config_dir = options_.config_dir;
  o.calibrate_after_s = options_.calibrate_after_s;
  o.realtime = true;
  o.record_path = record_to;
  Result<std::unique_ptr<PostureSource>> opened = openPostureSource(options_.spec, avatar_, o);
  if (!opened) return opened.error();
  source_ = std::move(*opened);
  recordVoiceTo(record_to);
  std::lock_guard lock(summary_mutex_);
  description_ = source_->describe();
  if (!record_to.empty()) recordings_ += (recordings_.empty() ? "" : ", ") + record_to;
  return {};
}

void SensorInput::recordVoiceTo(const std::string& path) {
  std::unique_ptr<RecordingWriter> writer;
  if (!path.empty()) {
    auto opened = RecordingWriter::appendTo(path);
    if (opened) {
      writer = std::move(*opened);
    } else {
      report("voice not recorded: " + opened.error().message, true);
    }
  }
  std::lock_guard lock(voice_mutex_);
  voice_writer_ = std::move(writer);
  have_offset_ = false;
}

void SensorInput::noteFrameClock(double frame_time, double arrival) {
  std::lock_guard lock(voice_mutex_);
  const double offset = frame_time - arrival;
  if (!have_offset_ || offset > clock_offset_) clock_offset_ = offset;
  have_offset_ = true;
}

void SensorInput::recordVoice(double capture_s, std::span<const std::uint8_t> packet) {
  std::lock_guard lock(voice_mutex_);
  if (!voice_writer_) return;
  if (!have_offset_) {
    ++voice_early_;
    return;
  }
  if (Status s = voice_writer_->appendVoice(capture_s + clock_offset_, packet); !s) {
    report("voice recording stopped: " + s.error().message, true);
    voice_writer_.reset();
    return;
  }
  ++voice_recorded_;
}

void SensorInput::report(const std::string& line, bool problem) const {
  std::FILE* to = problem ? stderr : stdout;
  std::fprintf(to, "vistel-client: sensors: %s\n", line.c_str());
  std::fflush(to);
}

void SensorInput::publish(const Posture& posture) {
  std::lock_guard lock(latest_mutex_);
  latest_ = posture;  // same size every time: no allocation
}

void SensorInput::copyLatest(Posture& out) const {
  std::lock_guard lock(latest_mutex_);
  out = latest_;
}

void SensorInput::requestCalibration() { calibrate_ = true; }

void SensorInput::onKeys(const std::string& keys) {
  if (keys.find('C') != std::string::npos) requestCalibration();
}

void SensorInput::run(net::NetDriver& driver, const std::atomic<bool>& stop) {
  const bool replayed = startsWith(options_.spec, "sim:") ||
                        startsWith(options_.spec, "recording:") || options_.spec.ends_with(".vrec");
  const double idle_interval = 1.0 / std::max(options_.idle_rate_hz, 0.1);
  double send_interval = 1.0 / 60.0;  // until the room's tick rate is known
  bool rate_known = false;
  double next_send = 0.0;
  double last_send = -1e9;
  double next_reopen = 0.0;
  int record_part = 1;
  bool looped = false;
  std::string last_status;
  Posture posture;
  copyLatest(posture);
  report(fmt::format("reading {} ({})", description_,
                     startsWith(options_.spec, "sim:") ? "calibrates on the clip's first pose"
                     : replayed                        ? "calibrated as recorded"
                     : options_.calibrate_after_s >= 0.0
                         ? fmt::format("calibrating {:.1f} s after start: stand in the "
                                       "calibration pose",
                                       options_.calibrate_after_s)
                         : "press C in the window to calibrate in the calibration pose"));
  if (!options_.record_path.empty()) report("recording the raw stream to " + options_.record_path);

  auto send = [&](double now) {
    if (driver.sendPosture(posture)) ++sent_;
    last_send = now;
  };

  while (!stop) {
    const double now = net::monotonicSeconds();
    // Once live: the room's tick rate caps the send rate (faster would only be dropped).
    if (!rate_known && driver.state() == net::SessionState::kLive) {
      const double tick =
          driver.withSession([](const net::ClientSession& s, double) { return s.tickRateHz(); });
      if (tick > 0.0) send_interval = 1.0 / tick;
      rate_known = true;
    }

    // The sensors are gone: keep the last posture in the room, retry the devices now and then.
    if (!source_) {
      if (now - last_send >= idle_interval) send(now);
      if (now >= next_reopen) {
        next_reopen = now + options_.reopen_interval_s;
        const std::string record_to = options_.record_path.empty() || replayed
                                          ? ""
                                          : numberedPath(options_.record_path, record_part + 1);
        if (reopen(record_to)) {
          if (!record_to.empty()) ++record_part;
          report(fmt::format("{} is back{}{}", description_,
                             options_.calibrate_after_s >= 0.0
                                 ? fmt::format("; calibrating in {:.1f} s: stand in the "
                                               "calibration pose",
                                               options_.calibrate_after_s)
                                 : "; press C in the calibration pose to calibrate again",
                             record_to.empty() ? "" : "; recording continues in " + record_to));
          last_status.clear();
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      continue;
    }

    if (calibrate_.exchange(false)) source_->requestCalibration();
    const PollResult r = source_->poll(0.05, posture);
    switch (r.status) {
      case PollStatus::kFrame: {
        ++frames_;
        noteFrameClock(source_->lastFrame().time, net::monotonicSeconds());
        publish(posture);
        calibrated_ = source_->calibrated();
        if (now - next_send > send_interval) next_send = now;  // after a gap: start afresh
        if (now >= next_send) {
          send(now);
          next_send += send_interval;
        }
        break;
      }
      case PollStatus::kTimeout:
        // A silent device: keep the participant present with the held posture.
        if (now - last_send >= idle_interval) send(now);
        break;
      case PollStatus::kEnd:
        // A clip or recording played as the source loops; a --record file keeps its first
        // pass only (the frames' times start over with each pass).
        if (!looped) {
          report(fmt::format(
              "{}; looping{}", r.message,
              options_.record_path.empty()
                  ? ""
                  : "; the recording " + options_.record_path + " holds the first pass"));
          looped = true;
        }
        source_.reset();
        recordVoiceTo("");
        if (Status s = reopen(""); !s) {
          report(fmt::format("cannot reopen {}: {}; holding the last posture", options_.spec,
                             s.error().message),
                 true);
          next_reopen = now + options_.reopen_interval_s;
        }
        break;
      case PollStatus::kUnplugged:
      case PollStatus::kFailed: {
        const std::string what =
            fmt::format("{}; holding the last posture and retrying every {:.0f} s", r.message,
                        options_.reopen_interval_s);
        {
          std::lock_guard lock(summary_mutex_);
          last_problem_ = what;
        }
        report(what, true);
        source_.reset();  // closes the devices and the recording (every frame so far is kept)
        recordVoiceTo("");
        next_reopen = now + options_.reopen_interval_s;
        break;
      }
    }
    // The source's notable events: calibrating, calibrated, calibration failed.
    if (source_) {
      const std::string status = source_->status();
      if (status != last_status) {
        last_status = status;
        if (!status.empty()) report(status, status.find("failed") != std::string::npos);
      }
    }
  }
  source_.reset();
  recordVoiceTo("");
}

std::string SensorInput::summary() const {
  std::lock_guard lock(summary_mutex_);
  std::string s = fmt::format("{}: {} frames, {}, {} postures sent", description_, frames_.load(),
                              calibrated_ ? "calibrated" : "not calibrated", sent_.load());
  if (!recordings_.empty()) {
    s += "; recorded to " + recordings_;
    std::lock_guard voice_lock(voice_mutex_);
    s += fmt::format(" with {} voice frames", voice_recorded_);
    if (voice_early_ > 0)
      s += fmt::format(" ({} before the first sensor frame left out)", voice_early_);
  }
  if (!last_problem_.empty()) s += "; last problem: " + last_problem_;
  return s;
}

}  // namespace vistel
