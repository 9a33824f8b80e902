#include "common/sensors/io/posture_source.hpp"

#include <algorithm>
#include <chrono>
#include <thread>

#include "common/motion/auto_joint_map.hpp"
#include "common/motion/bvh.hpp"
#include "common/motion/joint_map.hpp"
#include "common/motion/retarget.hpp"
#include "common/sensors/clip_solve.hpp"
#include "common/sensors/io/cyberglove_source.hpp"
#include "common/sensors/io/fastrak_source.hpp"
#include "common/sensors/io/hid_source.hpp"
#include "common/sensors/io/serial_transport.hpp"
#include "common/sensors/io/usb_transport.hpp"

namespace vistel {
namespace {

enum class Kind { kDevices, kSim, kRecording };

// Calibration state: idle, collecting a window of frames, or done.
struct Calibrator {
  bool collecting = false;
  double start = 0.0;
  std::vector<SensorFrame> frames;
};

class SolvingSource final : public PostureSource {
 public:
  SolvingSource(Kind kind, std::unique_ptr<SensorSource> source, Skeleton avatar, JointRoles roles,
                SensorSetup setup, Posture calibration_posture, std::string calibration_pose,
                PostureSourceOptions options, std::string spec)
      : kind_(kind),
        source_(std::move(source)),
        avatar_(std::move(avatar)),
        roles_(roles),
        setup_(std::move(setup)),
        calibration_posture_(std::move(calibration_posture)),
        calibration_pose_(std::move(calibration_pose)),
        options_(std::move(options)),
        spec_(std::move(spec)) {
    calibrator_.frames.reserve(1024);
  }

  // A recording's calibration, applied once `after_frames` frames have been replayed (where
  // the live session made it), so the replay runs the solver exactly as live.
  void scheduleCalibration(const CalibrationRecord& record, std::size_t after_frames) {
    scheduled_ = record;
    scheduled_after_ = after_frames;
    auto_done_ = true;
  }

  // A recording's own calibration: the averaged readings as one frame.
  Status calibrateFrom(const CalibrationRecord& record) {
    SensorFrame f;
    f.time = record.end_time;
    f.stations = record.stations;
    f.gloves = record.gloves;
    return finishCalibration({&f, 1}, record.start_time, record.end_time, false);
  }

  PollResult poll(double timeout_s, Posture& out) override {
    if (!pending_) {
      const PollResult r = source_->poll(timeout_s, frame_);
      if (!r.isFrame()) {
        if (r.status == PollStatus::kUnplugged || r.status == PollStatus::kFailed)
          status_ = r.message;
        return r;
      }
      pending_ = true;
    }
    // Sims and recordings play at the pace they were made.
    if (options_.realtime && kind_ != Kind::kDevices) {
      const auto now = std::chrono::steady_clock::now();
      if (!paced_) {
        paced_ = true;
        wall_start_ = now;
        time_start_ = frame_.time;
      }
      const double due = frame_.time - time_start_;
      const double elapsed = std::chrono::duration<double>(now - wall_start_).count();
      if (due > elapsed) {
        if (due - elapsed > timeout_s) {
          std::this_thread::sleep_for(std::chrono::duration<double>(std::max(0.0, timeout_s)));
          return PollResult::timeout("waiting for the next frame's time");
        }
        std::this_thread::sleep_for(std::chrono::duration<double>(due - elapsed));
      }
    }
    pending_ = false;
    if (first_time_ < 0.0) first_time_ = frame_.time;
    // Live, the calibration is made on the frame that closes its window (after recording it).
    ++frames_seen_;
    if (scheduled_ && frames_seen_ == scheduled_after_) {
      if (Status s = calibrateFrom(*scheduled_); !s)
        status_ = fmt::format("recorded calibration: {}", s.error().message);
      scheduled_.reset();
    }
    if (hook_) hook_(frame_);
    if (writer_) {
      if (Status s = writer_->append(frame_); !s) {
        status_ = s.error().message;
        writer_.reset();
      }
    }
    stepCalibration();
    if (solver_) {
      solver_->solve(frame_, out);
    } else {
      out = calibration_posture_;
      out.time = frame_.time;
    }
    return PollResult::frame();
  }

  void requestCalibration() override {
    calibrator_.collecting = true;
    calibrator_.start = frame_.time;
    calibrator_.frames.clear();
    status_ = "calibrating: hold the calibration pose";
  }
  bool calibrated() const override { return solver_.has_value(); }
  // A notable event from opening (a damaged recording's report), ahead of what the opening
  // said already (a recorded calibration), until the next event.
  void noteStatus(const std::string& status) {
    status_ = status_.empty() ? status : status + "; " + status_;
  }

  Status startRecording(const std::string& path) override {
    RecordingHeader header;
    header.participant = setup_.participant;
    header.source = spec_;
    for (const StationMapping& m : setup_.tracker.stations)
      header.stations.push_back({m.station, m.site});
    for (const GloveDeviceConfig& g : setup_.gloves)
      header.gloves.push_back({g.hand, g.format.sensor_count});
    header.calibration = last_calibration_;
    header.config_text = setup_.text;
    Result<std::unique_ptr<RecordingWriter>> w = RecordingWriter::create(path, header);
    if (!w) return w.error();
    writer_ = std::move(*w);
    return {};
  }
  void stopRecording() override { writer_.reset(); }
  void setFrameHook(std::function<void(const SensorFrame&)> hook) override {
    hook_ = std::move(hook);
  }
  const SensorFrame& lastFrame() const override { return frame_; }
  std::string describe() const override { return source_->describe(); }
  std::string status() const override { return status_; }

 private:
  void stepCalibration() {
    // Automatic calibration: devices after calibrate_after_s; the simulator on its hold.
    if (!solver_ && !calibrator_.collecting && !auto_done_) {
      const double since = frame_.time - first_time_;
      const double window = setup_.calibration.window_s;
      bool start = false;
      if (kind_ == Kind::kSim) start = since >= std::max(0.0, setup_.sim.hold_s - window);
      if (kind_ == Kind::kDevices && options_.calibrate_after_s >= 0.0)
        start = since >= options_.calibrate_after_s;
      if (kind_ == Kind::kRecording) start = true;
      if (start) {
        auto_done_ = true;
        requestCalibration();
      }
    }
    if (!calibrator_.collecting) return;
    if (calibrator_.frames.size() < calibrator_.frames.capacity())
      calibrator_.frames.push_back(frame_);
    double window = setup_.calibration.window_s;
    if (kind_ == Kind::kSim) window = std::min(window, setup_.sim.hold_s);
    if (frame_.time - calibrator_.start >= window) {
      calibrator_.collecting = false;
      if (Status s = finishCalibration(calibrator_.frames, calibrator_.start, frame_.time, true);
          !s) {
        status_ = fmt::format("calibration failed: {}", s.error().message);
      }
    }
  }

  Status finishCalibration(std::span<const SensorFrame> frames, double start, double end,
                           bool record) {
    Result<BodyCalibration> cal =
        calibrateBody(avatar_, roles_, calibration_posture_, frames, setup_.calibration);
    if (!cal) return cal.error();
    CalibrationRecord rec;
    rec.start_time = start;
    rec.end_time = end;
    rec.pose = calibration_pose_;
    rec.stations = cal->reference;
    rec.gloves = cal->glove_zero;
    Result<PostureSolver> solver =
        PostureSolver::create(avatar_, roles_, std::move(*cal), setup_.solver);
    if (!solver) return solver.error();
    solver_ = std::move(*solver);
    last_calibration_ = rec;
    if (record && writer_) {
      if (Status s = writer_->appendCalibration(rec); !s) status_ = s.error().message;
    }
    status_ = fmt::format("calibrated on {} frames", frames.size());
    return {};
  }

  Kind kind_;
  std::unique_ptr<SensorSource> source_;
  Skeleton avatar_;
  JointRoles roles_;
  SensorSetup setup_;
  Posture calibration_posture_;
  std::string calibration_pose_;
  PostureSourceOptions options_;
  std::string spec_;
  std::optional<PostureSolver> solver_;
  std::optional<CalibrationRecord> last_calibration_;
  std::optional<CalibrationRecord> scheduled_;
  std::size_t scheduled_after_ = 0;
  std::size_t frames_seen_ = 0;
  Calibrator calibrator_;
  bool auto_done_ = false;
  SensorFrame frame_;
  bool pending_ = false;
  double first_time_ = -1.0;
  bool paced_ = false;
  std::chrono::steady_clock::time_point wall_start_;
  double time_start_ = 0.0;
  std::function<void(const SensorFrame&)> hook_;
  std::unique_ptr<RecordingWriter> writer_;
  std::string status_;
};

// A clip's first frame retargeted onto the avatar: the simulated participant's calibration
// pose as the avatar would hold it.
Result<Posture> clipPoseOnAvatar(const ClipBody& clip, const Skeleton& avatar,
                                 std::span<const JointMap> maps) {
  Result<JointMapChoice> clip_map = chooseJointMap(maps, clip.skeleton);
  if (!clip_map) return clip_map.error();
  Result<JointMapChoice> avatar_map = chooseJointMap(maps, avatar);
  if (!avatar_map) return avatar_map.error();
  Result<Retargeter> retargeter =
      Retargeter::create(clip.skeleton, clip_map->map, avatar, avatar_map->map);
  if (!retargeter) return retargeter.error();
  Posture first;
  samplePosture(clip.clip, 0, first);
  Posture out;
  retargeter->apply(first, out);
  return out;
}

}  // namespace

SensorRig::SensorRig(std::unique_ptr<SensorSource> tracker,
                     std::vector<std::unique_ptr<SensorSource>> gloves)
    : tracker_(std::move(tracker)),
      gloves_(std::move(gloves)),
      glove_dead_(gloves_.size(), false) {}

PollResult SensorRig::poll(double timeout_s, SensorFrame& frame) {
  const PollResult r = tracker_->poll(timeout_s, state_);
  if (!r.isFrame()) return r;
  const double time = state_.time;
  const std::uint64_t sequence = state_.sequence;
  for (std::size_t i = 0; i < gloves_.size(); ++i) {
    if (glove_dead_[i]) continue;
    const PollResult g = gloves_[i]->poll(0.0, state_);
    if (g.status == PollStatus::kUnplugged || g.status == PollStatus::kFailed) {
      glove_dead_[i] = true;
      glove_status_ = g.message;
    }
  }
  state_.time = time;
  state_.sequence = sequence;
  frame = state_;
  return r;
}

std::string SensorRig::describe() const {
  std::string s = tracker_->describe();
  for (const auto& g : gloves_) s += " + " + g->describe();
  return s;
}

Result<std::unique_ptr<SensorSource>> openSensorDevices(const SensorSetup& setup) {
  std::unique_ptr<SensorSource> tracker;
  if (setup.tracker_kind == TrackerKind::kFastrak) {
    std::unique_ptr<ByteTransport> transport;
    if (setup.tracker.transport == TrackerTransport::kSerial) {
      Result<std::unique_ptr<SerialTransport>> serial =
          SerialTransport::open(setup.tracker.port, setup.tracker.baud);
      if (!serial) return withContext(setup.source, serial.error());
      transport = std::move(*serial);
    } else {
      Result<std::unique_ptr<UsbBulkDevice>> usb = openLibusbDevice(setup.tracker.usb);
      if (!usb) return withContext(setup.source, usb.error());
      transport = std::make_unique<UsbTransport>(std::move(*usb), setup.tracker.usb);
    }
    Result<std::unique_ptr<FastrakSource>> fastrak =
        FastrakSource::open(std::move(transport), setup.tracker);
    if (!fastrak) return withContext(setup.source, fastrak.error());
    tracker = std::move(*fastrak);
  } else if (setup.tracker_kind == TrackerKind::kHid) {
    Result<std::unique_ptr<HidDevice>> hid = openHidapiDevice(setup.hid);
    if (!hid) return withContext(setup.source, hid.error());
    tracker = std::make_unique<HidSource>(std::move(*hid), setup.hid);
  } else {
    return fail("{}: no tracker configured ([tracker] kind = \"none\")", setup.source);
  }
  std::vector<std::unique_ptr<SensorSource>> gloves;
  for (const GloveDeviceConfig& g : setup.gloves) {
    Result<std::unique_ptr<SerialTransport>> serial = SerialTransport::open(g.port, g.baud);
    if (!serial) return withContext(setup.source, serial.error());
    Result<std::unique_ptr<CyberGloveSource>> glove = CyberGloveSource::open(std::move(*serial), g);
    if (!glove) return withContext(setup.source, glove.error());
    gloves.push_back(std::move(*glove));
  }
  return std::unique_ptr<SensorSource>(new SensorRig(std::move(tracker), std::move(gloves)));
}

Result<std::unique_ptr<PostureSource>> openPostureSource(const std::string& spec,
                                                         const Skeleton& avatar,
                                                         const PostureSourceOptions& options) {
  // The avatar's joints by role.
  Result<std::vector<JointMap>> maps = loadJointMaps(options.config_dir);
  if (!maps) return maps.error();
  Result<JointRoles> roles = resolveJointRoles(avatar, nullptr);
  if (!roles) {
    Result<JointMapChoice> map = chooseJointMap(*maps, avatar);
    if (!map) return withContext("the avatar's skeleton", map.error());
    roles = resolveJointRoles(avatar, &map->map);
    if (!roles) return withContext("the avatar's skeleton", roles.error());
  }

  const bool is_sim = spec.rfind("sim:", 0) == 0;
  const bool is_recording = spec.rfind("recording:", 0) == 0 ||
                            (spec.size() > 5 && spec.compare(spec.size() - 5, 5, ".vrec") == 0);
  std::string config_path = options.config_path;
  if (config_path.empty())
    config_path = is_sim ? "config/sensors/sim.toml" : is_recording ? "" : spec;
  SensorSetup setup;
  if (!config_path.empty()) {
    Result<SensorSetup> loaded = loadSensorSetup(config_path);
    if (!loaded) return loaded.error();
    setup = std::move(*loaded);
  }

  std::unique_ptr<SensorSource> source;
  Posture calibration_posture = standardCalibrationPosture(avatar, *roles);
  std::string pose_name = "standard";
  std::string opening_status;  // a notable event of opening, for status()
  Kind kind = Kind::kDevices;
  std::optional<CalibrationRecord> recorded_calibration;
  std::size_t recorded_after = 0;  // frames before the recorded calibration
  std::shared_ptr<ClipBody> clip_keepalive;
  if (is_sim) {
    kind = Kind::kSim;
    const std::string clip_path = spec.substr(4);
    Result<ClipBody> clip = loadClipBody(clip_path, options.config_dir);
    if (!clip) return withContext(spec, clip.error());
    clip_keepalive = std::make_shared<ClipBody>(std::move(*clip));
    if (Result<Posture> pose = clipPoseOnAvatar(*clip_keepalive, avatar, *maps)) {
      calibration_posture = std::move(*pose);
      pose_name = "sim:" + clip_path;
    }
    const MotionClip* clip_ptr = &clip_keepalive->clip;
    // The sampler keeps the clip alive with it.
    PostureSampler sampler = [clip_keepalive, clip_ptr](double t, Posture& out) {
      samplePostureAt(*clip_ptr, t, out);
    };
    const double duration =
        std::max(0, clip_keepalive->clip.frame_count - 1) * clip_keepalive->clip.frame_time;
    Result<std::unique_ptr<RigSimulator>> sim = RigSimulator::create(
        clip_keepalive->skeleton, clip_keepalive->roles, std::move(sampler), duration, setup.sim);
    if (!sim) return withContext(spec, sim.error());
    source = std::move(*sim);
  } else if (is_recording) {
    kind = Kind::kRecording;
    const std::string path = spec.rfind("recording:", 0) == 0 ? spec.substr(10) : spec;
    Result<Recording> rec = loadRecording(path);
    if (!rec) return rec.error();
    if (config_path.empty() && !rec->header.config_text.empty()) {
      if (Result<SensorSetup> recorded =
              parseSensorSetup(rec->header.config_text, path + " (recorded config)")) {
        setup = std::move(*recorded);
      }
    }
    recorded_calibration = rec->header.calibration;
    if (!recorded_calibration && !rec->calibrations.empty()) {
      recorded_calibration = rec->calibrations.front();
      recorded_after = rec->calibration_after.front();
    }
    if (recorded_calibration && recorded_calibration->pose.rfind("sim:", 0) == 0) {
      if (Result<ClipBody> clip =
              loadClipBody(recorded_calibration->pose.substr(4), options.config_dir)) {
        if (Result<Posture> pose = clipPoseOnAvatar(*clip, avatar, *maps))
          calibration_posture = std::move(*pose);
      }
    }
    pose_name = recorded_calibration ? recorded_calibration->pose : "standard";
    // What the reader skipped (where and why), for the caller's log.
    if (!rec->complete) opening_status = "recording damaged: " + rec->stop_reason;
    source = std::make_unique<RecordingSource>(std::move(*rec), path);
  } else {
    Result<std::unique_ptr<SensorSource>> devices = openSensorDevices(setup);
    if (!devices) return devices.error();
    source = std::move(*devices);
  }

  auto out =
      std::make_unique<SolvingSource>(kind, std::move(source), avatar, *roles, setup,
                                      std::move(calibration_posture), pose_name, options, spec);
  if (recorded_calibration && recorded_after == 0) {
    if (Status s = out->calibrateFrom(*recorded_calibration); !s) {
      return withContext(fmt::format("{}: the recorded calibration", spec), s.error());
    }
  } else if (recorded_calibration) {
    out->scheduleCalibration(*recorded_calibration, recorded_after);
  }
  if (!opening_status.empty()) out->noteStatus(opening_status);
  if (!options.record_path.empty()) {
    if (Status s = out->startRecording(options.record_path); !s) return s.error();
  }
  return std::unique_ptr<PostureSource>(std::move(out));
}

}  // namespace vistel
