// ForceFeedbackWriter: the own avatar's contact force per body part, sent to a force-feedback
// device as HID output reports (hidapi hid_write) laid out by the sensors config's
// [force_feedback] section (ForceFeedbackConfig: per channel a part, a byte offset, a number
// type, newtons per count, and an axis or the magnitude). The HID call sits behind
// HidOutputDevice (hidapi in openHidapiOutput; a fake in tests: there is no /dev/hidraw on
// the build machines).
//
// Rate: a report goes out when its bytes differ from the last one sent, at most max_rate_hz
// times a second; a change that comes too soon goes out with the first update() after the
// interval (so the device always ends on the newest forces, a release to zero included).
// close() (and the destructor) sends an all-zero report, so that no actuator stays on.
//
// Not thread-safe: one thread (the client's render thread) calls update(). update() allocates
// nothing; a write blocks for as long as hid_write does (a hidraw write: microseconds).
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/base/result.hpp"
#include "common/sensors/sensor_config.hpp"

namespace vistel {

class HidOutputDevice {
 public:
  virtual ~HidOutputDevice() = default;
  // Writes one output report (byte 0: the report id). Returns the bytes written, or -1 when
  // the device failed or went away (then lastError() says why).
  virtual int write(std::span<const std::uint8_t> report) = 0;
  virtual std::string lastError() const = 0;
  virtual std::string describe() const = 0;
};

// Opens the device by vendor/product id (and serial number when configured). Errors name the
// device ("force feedback hid 1234:5678") and why.
Result<std::unique_ptr<HidOutputDevice>> openHidapiOutput(const ForceFeedbackConfig& config);

// Which part each channel carries: its index in `part_names`, or -1 when no part has that
// name (`unknown` then gets the channel's part name, once per name).
std::vector<int> bindForceChannels(const ForceFeedbackConfig& config,
                                   std::span<const std::string> part_names,
                                   std::vector<std::string>* unknown = nullptr);

// Encodes one report: byte 0 the report id, each channel's value (see ForceFeedbackChannel)
// from forces[channel_part[c]] (N, model space; a channel bound to -1, or to a part beyond
// forces, sends 0), every other byte 0. report: config.report_size bytes; channel_part: one
// entry per channel. Non-finite forces send 0.
void encodeForceReport(const ForceFeedbackConfig& config, std::span<const int> channel_part,
                       std::span<const glm::vec3> forces, std::span<std::uint8_t> report);

class ForceFeedbackWriter {
 public:
  // part_names: the parts whose forces update() will get, in that order (the own avatar's
  // primitives). Channels naming other parts send 0 and are listed by unknownParts().
  // max_rate_hz: reports per second at most (<= 0: the config's).
  ForceFeedbackWriter(std::unique_ptr<HidOutputDevice> device, ForceFeedbackConfig config,
                      std::span<const std::string> part_names, double max_rate_hz = 0.0);
  ~ForceFeedbackWriter();
  ForceFeedbackWriter(const ForceFeedbackWriter&) = delete;
  ForceFeedbackWriter& operator=(const ForceFeedbackWriter&) = delete;

  // The channels' part names that part_names lacks (for a warning at start).
  const std::vector<std::string>& unknownParts() const { return unknown_; }

  // This frame's forces (N, model space, one per part name) at time `now` (seconds, any
  // monotonic clock). Sends a report when due (see the top of the file). Returns the
  // device's error the first time a write fails; after that the writer sends nothing.
  Status update(double now, std::span<const glm::vec3> forces);
  // Sends an all-zero report (once; no rate limit) and stops. Idempotent.
  void close();

  std::string describe() const { return device_ ? device_->describe() : "force feedback"; }
  std::uint64_t reportsSent() const { return sent_; }
  bool failed() const { return failed_; }

 private:
  bool send(std::span<const std::uint8_t> report);

  std::unique_ptr<HidOutputDevice> device_;
  ForceFeedbackConfig config_;
  std::vector<int> channel_part_;  // (nchannel) index into the part names, or -1
  std::vector<std::string> unknown_;
  double min_interval_s_ = 0.0;
  std::vector<std::uint8_t> report_;  // (report_size) this update's report
  std::vector<std::uint8_t> last_;    // (report_size) the last one sent
  bool have_last_ = false;
  double last_time_ = 0.0;
  bool failed_ = false;
  bool closed_ = false;
  std::string error_;
  std::uint64_t sent_ = 0;
};

}  // namespace vistel
