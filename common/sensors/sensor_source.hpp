// SensorSource: anything that delivers SensorFrames — a tracker or glove driver, a
// recording, the simulator, or several of them merged.
//
// poll() waits at most timeout_s for new readings. On kFrame it has updated `frame` in
// place: stations and gloves that produced nothing new keep their last readings (their
// own `time` says how old they are), `sequence` increments. Every other status leaves the
// frame untouched and says why in `message`: kTimeout (nothing arrived in time; call again),
// kEnd (a recording or clip is exhausted), kUnplugged (the device went away: the port
// closed or hung up, USB/HID reported no device; reopen to continue), kFailed (the device
// answered nonsense or the OS refused; the message names the device and the reason).
// Sources never throw and never abort on device data.
#pragma once

#include <cstdint>
#include <string>
#include <utility>

#include "common/sensors/sensor_frame.hpp"

namespace vistel {

enum class PollStatus : std::uint8_t { kFrame, kTimeout, kEnd, kUnplugged, kFailed };

struct PollResult {
  PollStatus status = PollStatus::kTimeout;
  std::string message;  // empty for kFrame

  bool isFrame() const { return status == PollStatus::kFrame; }
  static PollResult frame() { return {PollStatus::kFrame, {}}; }
  static PollResult timeout(std::string why = "timed out waiting for data") {
    return {PollStatus::kTimeout, std::move(why)};
  }
  static PollResult end(std::string why) { return {PollStatus::kEnd, std::move(why)}; }
  static PollResult unplugged(std::string why) { return {PollStatus::kUnplugged, std::move(why)}; }
  static PollResult failed(std::string why) { return {PollStatus::kFailed, std::move(why)}; }
};

// "frame", "timeout", "end", "unplugged", "failed".
const char* pollStatusName(PollStatus status);

class SensorSource {
 public:
  virtual ~SensorSource() = default;
  // See the file comment. Not thread-safe: one thread polls.
  virtual PollResult poll(double timeout_s, SensorFrame& frame) = 0;
  // A short description for messages ("fastrak on /dev/ttyUSB0").
  virtual std::string describe() const = 0;
};

}  // namespace vistel
