// HidSource: a tracker (and/or glove) that sends its readings as USB HID input reports,
// read through hidapi (the hidraw backend), decoded by the layout in the config (HidConfig:
// per station the byte offsets and number types of position and quaternion, a tracked
// flag; per glove the raw sensor bytes). The HID calls sit behind HidDevice (hidapi in
// openHidapiDevice; a fake in tests — there is no /dev/hidraw on the build machines).
#pragma once

#include <array>
#include <memory>
#include <span>
#include <string>

#include "common/base/result.hpp"
#include "common/sensors/io/fastrak_source.hpp"
#include "common/sensors/sensor_config.hpp"
#include "common/sensors/sensor_source.hpp"

namespace vistel {

class HidDevice {
 public:
  virtual ~HidDevice() = default;
  // One input report into `data`: its size, 0 on timeout, -1 when the device failed or
  // went away (then lastError() says why).
  virtual int read(std::uint8_t* data, std::size_t length, int timeout_ms) = 0;
  virtual std::string lastError() const = 0;
  virtual std::string describe() const = 0;
};

// Opens the device by vendor/product id (and serial number when configured).
Result<std::unique_ptr<HidDevice>> openHidapiDevice(const HidConfig& config);

// Decodes one report into the frame's stations and gloves (tracker space, metres, radians)
// at time `now`. Returns false, with `why`, when the report is too short, has the wrong
// report id, or holds a non-finite or far-from-unit quaternion (nothing is changed then).
bool decodeHidReport(std::span<const std::uint8_t> report, const HidConfig& config, double now,
                     SensorFrame& frame, std::string& why);

class HidSource final : public SensorSource {
 public:
  HidSource(std::unique_ptr<HidDevice> device, HidConfig config,
            SourceClock clock = steadySeconds());
  PollResult poll(double timeout_s, SensorFrame& frame) override;
  std::string describe() const override { return device_->describe(); }
  std::uint64_t rejectedReports() const { return rejected_; }

 private:
  std::unique_ptr<HidDevice> device_;
  HidConfig config_;
  SourceClock clock_;
  std::array<std::uint8_t, 4096> report_{};
  SensorFrame state_;
  std::uint64_t sequence_ = 0;
  std::uint64_t rejected_ = 0;
};

}  // namespace vistel
