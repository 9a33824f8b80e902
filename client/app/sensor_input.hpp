// SensorInput: the site client's own posture from sensors (DESIGN.md §5, §6 "Threads") —
// `--sensors FILE.toml` (the trackers and gloves the file names), `--source sim:CLIP.bvh`
// (the simulated rig) or `--source recording:FILE.vrec`, optionally recording the raw
// stream (`--record FILE.vrec`) and calibrating after a delay (`--calibrate-after S`) or on
// request (the window's C key).
//
// Threads: run() is the sensor thread's body. It polls the PostureSource (devices, solver,
// recording: everything between the sensors and a Posture happens there), publishes each
// solved posture to a newest-wins slot that the render thread copies (copyLatest, a short
// copy under a mutex), and hands the newest posture to the network side (NetDriver::
// sendPosture, which queues one datagram for the network thread) at most at the room's tick
// rate: frames arriving faster replace each other. Nothing here waits on the render or the
// network thread.
//
// When the sensors stop (unplugged, or a device failing), the client keeps running: it
// says so once (on stderr), keeps showing and sending the last solved posture at the idle
// rate (so the participant stays in the room, frozen, rather than vanishing or snapping to
// a default pose), and tries to reopen the devices every reopen_interval_s. A reopened
// device must be calibrated again (C, or the --calibrate-after delay counts from the
// reopening); a recording in progress continues into FILE-2.vrec, FILE-3.vrec, ... so
// nothing recorded is overwritten. A clip (sim:) or a recording played as the source loops:
// it is reopened at its end (a --record recording holds its first pass only).
//
// Voice in the recording: recordVoice (the VoiceEngine's on_sent, on the voice thread)
// appends every voice frame the client sends to the recording in progress as a voice record
// (common/sensors/recording.hpp, type 4), through a second writer on the same file (whole
// records: RecordingWriter::appendTo), so a muted or silent stretch has no records. Clock
// mapping: a voice frame's capture time is on net::monotonicSeconds; the frames' times are
// on the sensor clock (a device's clock, or a clip's time for sim:, paced to real time).
// The sensor thread stamps each frame as it comes out of poll() and keeps the offset
// (frame time - arrival time) of the quickest frame since the recording (re)started: the
// sensor clock minus the monotonic one, short of the least delay between a reading and
// its arrival (a few ms: the reading, the solve). A voice frame captured at monotonic time c
// is recorded at sensor time c + offset; frames before the first sensor frame (no offset
// yet) are not recorded (counted in summary()). The voice stops being recorded with the
// frames: when the sensors are unplugged (a reopened device's FILE-2.vrec gets it again) and
// after the first pass of a sim: or recording: source.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <string>

#include <CLI/CLI.hpp>

#include "client/net/net_driver.hpp"
#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"
#include "common/base/result.hpp"
#include "common/sensors/io/posture_source.hpp"
#include "common/sensors/recording.hpp"

namespace vistel {

// The command-line options for sensor input.
struct SensorArgs {
  std::string sensors_path;         // --sensors FILE.toml
  double calibrate_after_s = -1.0;  // --calibrate-after S (< 0: on request only)
  std::string record_path;          // --record FILE.vrec
};

// Adds --sensors, --calibrate-after and --record to a command line.
void addSensorOptions(CLI::App& app, SensorArgs& args);

// The PostureSource spec the command line asks for: the --sensors file, or a --source of
// the form sim:CLIP.bvh / recording:FILE.vrec; empty when the own posture comes from
// elsewhere (no --source, or bvh:FILE). Errors are usage errors (the message names the
// options): --sensors with --source, --record or --calibrate-after without a sensor source,
// an unknown --source kind.
Result<std::string> sensorSpec(const SensorArgs& args, const std::string& source_text);

struct SensorInputOptions {
  std::string spec;  // see sensorSpec
  std::string config_dir = "config";
  double calibrate_after_s = -1.0;
  std::string record_path;         // empty: no recording
  double idle_rate_hz = 30.0;      // sends of the held posture while the sensors are gone
  double reopen_interval_s = 2.0;  // devices: retry period after unplugging
};

class SensorInput {
 public:
  // Opens the source (errors name the spec, the device or the file and the reason, as
  // openPostureSource does). avatar: the own avatar's skeleton (postures are sized for it).
  static Result<std::unique_ptr<SensorInput>> open(const SensorInputOptions& options,
                                                   const Skeleton& avatar);
  ~SensorInput();
  SensorInput(const SensorInput&) = delete;
  SensorInput& operator=(const SensorInput&) = delete;

  // The sensor thread: polls, solves, publishes and sends until stop turns true, then
  // closes the devices (and the recording). Call once.
  void run(net::NetDriver& driver, const std::atomic<bool>& stop);

  // Thread-safe. Starts a calibration on the sensor thread's next frame (the participant
  // holds the calibration pose for the config's window).
  void requestCalibration();
  // Keys from the window (RoomView::takeKeyPresses): C calibrates.
  void onKeys(const std::string& keys);
  // Copies the newest solved posture into out (the calibration posture until the first
  // frame). Reuses out's storage; blocks only for the copy.
  void copyLatest(Posture& out) const;

  // One line for the exit report: the source, frames read, calibration, postures sent,
  // recording (with the voice frames recorded).
  std::string summary() const;

  // Thread-safe (the voice thread): records one voice frame sent, captured at capture_s
  // (net::monotonicSeconds), into the recording in progress (see above); nothing without
  // one. A write error is reported once and ends the voice recording.
  void recordVoice(double capture_s, std::span<const std::uint8_t> packet);

 private:
  explicit SensorInput(SensorInputOptions options, Skeleton avatar);
  // Opens source_ (record_to: the recording file for this opening, or empty).
  Status reopen(const std::string& record_to);
  void publish(const Posture& posture);
  void report(const std::string& line, bool problem = false) const;
  // The voice's writer for a recording file (empty: stop recording voice). Sensor thread.
  void recordVoiceTo(const std::string& path);
  // A frame came out of poll() at monotonic time arrival: the sensor clock's offset.
  void noteFrameClock(double frame_time, double arrival);

  SensorInputOptions options_;
  Skeleton avatar_;
  std::unique_ptr<PostureSource> source_;  // sensor thread only (null while unplugged)
  std::atomic<bool> calibrate_{false};

  mutable std::mutex latest_mutex_;
  Posture latest_;  // newest solved posture (avatar joints)

  // Counters for summary() (written by the sensor thread).
  std::atomic<std::uint64_t> frames_{0};
  std::atomic<std::uint64_t> sent_{0};
  std::atomic<bool> calibrated_{false};
  mutable std::mutex summary_mutex_;  // the three below (written by the sensor thread)
  std::string description_;           // what source_ reads (its describe())
  std::string recordings_;            // the files written, comma separated
  std::string last_problem_;

  // The voice track (recordVoice).
  mutable std::mutex voice_mutex_;
  std::unique_ptr<RecordingWriter> voice_writer_;
  bool have_offset_ = false;
  double clock_offset_ = 0.0;  // sensor clock - net::monotonicSeconds
  std::uint64_t voice_recorded_ = 0;
  std::uint64_t voice_early_ = 0;  // before the first frame: not recorded
};

}  // namespace vistel
