// PostureSource: everything between the sensors and a Posture on the avatar's skeleton —
// what the client's sensor thread and the bot run (DESIGN.md §1, §5).
//
//   spec                      frames from
//   path/to/sensors.toml      the devices the file names (FASTRAK-class serial or USB
//                             tracker, or a HID tracker; CyberGlove-class gloves)
//   sim:CLIP.bvh              the simulated rig on the clip's body (options from [sim] of
//                             the config, default config/sensors/sim.toml)
//   recording:FILE.vrec       a recording (a spec ending in .vrec works too)
//
// Calibration: devices calibrate on request (requestCalibration(), or calibrate_after_s
// after the start) over the config's window while the participant holds the standard pose
// (arms hanging, palms on the thighs); the simulator calibrates on its hold of the clip's
// first pose (retargeted onto the avatar); a recording uses its calibration record. Until
// calibrated, poll() returns kFrame with the avatar's calibration posture.
// Recording: record_path (or startRecording) writes every raw frame to a .vrec, and the
// calibration when it happens; setFrameHook sees every frame too.
// Sims and recordings are paced to real time unless realtime = false.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"
#include "common/base/result.hpp"
#include "common/sensors/calibration.hpp"
#include "common/sensors/posture_solver.hpp"
#include "common/sensors/recording.hpp"
#include "common/sensors/sensor_config.hpp"
#include "common/sensors/sensor_source.hpp"

namespace vistel {

struct PostureSourceOptions {
  std::string config_path;  // sensors config; empty: the spec itself, or sim.toml for sims
  std::string config_dir = "config";  // joint maps (config_dir/skeletons)
  double calibrate_after_s = -1.0;  // devices: calibrate this long after opening (< 0: on request)
  bool realtime = true;             // pace sims and recordings to their timestamps
  std::string record_path;          // record raw frames here (.vrec) when not empty
};

class PostureSource {
 public:
  virtual ~PostureSource() = default;
  // Waits at most timeout_s for the next sensor frame and solves it. kFrame: `out` is the
  // avatar's posture (resized once). kTimeout: nothing new. kEnd: the clip or recording is
  // over. kUnplugged / kFailed: the device is gone or broken (message says which).
  virtual PollResult poll(double timeout_s, Posture& out) = 0;
  // Starts a calibration over the next window of frames (the participant stands in the
  // calibration pose until calibrated() turns true).
  virtual void requestCalibration() = 0;
  virtual bool calibrated() const = 0;
  // Records raw frames to a .vrec from now on (the calibration, when made, goes with them).
  virtual Status startRecording(const std::string& path) = 0;
  virtual void stopRecording() = 0;
  // Called with every raw frame before it is solved.
  virtual void setFrameHook(std::function<void(const SensorFrame&)> hook) = 0;
  virtual const SensorFrame& lastFrame() const = 0;
  // What the source is, and the last notable event (calibrated, a glove unplugged, ...;
  // from the start: what the reader of a damaged recording skipped, where and why).
  virtual std::string describe() const = 0;
  virtual std::string status() const = 0;
};

// Opens a source for the avatar skeleton (see the file comment). The avatar's joints are
// found through the joint maps of options.config_dir (or canonical names). Errors name the
// spec, the file or device, and the reason.
Result<std::unique_ptr<PostureSource>> openPostureSource(const std::string& spec,
                                                         const Skeleton& avatar_skeleton,
                                                         const PostureSourceOptions& options = {});

// The devices a setup names, merged into one SensorSource (tracker frames carry the latest
// glove readings; a glove that fails is reported in status and left invalid).
Result<std::unique_ptr<SensorSource>> openSensorDevices(const SensorSetup& setup);

// Merges a tracker and gloves into one stream: poll() waits on the tracker, then takes what
// each glove has (without waiting).
class SensorRig final : public SensorSource {
 public:
  SensorRig(std::unique_ptr<SensorSource> tracker,
            std::vector<std::unique_ptr<SensorSource>> gloves);
  PollResult poll(double timeout_s, SensorFrame& frame) override;
  std::string describe() const override;
  // The latest glove problem ("left glove: ... unplugged"), empty while all are fine.
  const std::string& gloveStatus() const { return glove_status_; }

 private:
  std::unique_ptr<SensorSource> tracker_;
  std::vector<std::unique_ptr<SensorSource>> gloves_;
  std::vector<bool> glove_dead_;
  SensorFrame state_;
  std::string glove_status_;
};

}  // namespace vistel
