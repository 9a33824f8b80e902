#include "common/sensors/io/hid_source.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <cwchar>

#include <hidapi.h>

#include "common/sensors/io/hid_text.hpp"

namespace vistel {
namespace {

int typeSize(HidValueType t) {
  return t == HidValueType::kF32 ? 4 : t == HidValueType::kI16 ? 2 : 1;
}

float readValue(std::span<const std::uint8_t> r, int offset, HidValueType type) {
  const std::uint8_t* p = r.data() + offset;
  switch (type) {
    case HidValueType::kF32: {
      float v;
      std::memcpy(&v, p, 4);
      return v;
    }
    case HidValueType::kI16: {
      std::int16_t v;
      std::memcpy(&v, p, 2);
      return static_cast<float>(v);
    }
    case HidValueType::kU8:
      return static_cast<float>(*p);
  }
  return 0.0f;
}

class HidapiDevice final : public HidDevice {
 public:
  HidapiDevice(hid_device* dev, std::string name) : dev_(dev), name_(std::move(name)) {}
  ~HidapiDevice() override {
    hid_close(dev_);
    hid_exit();
  }
  int read(std::uint8_t* data, std::size_t length, int timeout_ms) override {
    return hid_read_timeout(dev_, data, length, timeout_ms);
  }
  std::string lastError() const override { return hidText(hid_error(dev_)); }
  std::string describe() const override { return name_; }

 private:
  hid_device* dev_;
  std::string name_;
};

}  // namespace

Result<std::unique_ptr<HidDevice>> openHidapiDevice(const HidConfig& config) {
  const std::string name = fmt::format("hid {:04x}:{:04x}", config.vendor_id, config.product_id);
  if (hid_init() != 0) return fail("{}: hid_init failed", name);
  std::wstring serial(config.serial.begin(), config.serial.end());
  hid_device* dev = hid_open(config.vendor_id, config.product_id,
                             config.serial.empty() ? nullptr : serial.c_str());
  if (dev == nullptr) {
    const std::string why = hidText(hid_error(nullptr));
    hid_exit();
    return fail("{}: cannot open ({})", name,
                why.empty() ? "no such device, or no permission" : why);
  }
  return std::unique_ptr<HidDevice>(new HidapiDevice(dev, name));
}

bool decodeHidReport(std::span<const std::uint8_t> report, const HidConfig& config, double now,
                     SensorFrame& frame, std::string& why) {
  if (report.size() < static_cast<std::size_t>(config.report_size)) {
    why = fmt::format("report of {} bytes, expected {}", report.size(), config.report_size);
    return false;
  }
  if (config.report_id >= 0 && report[0] != config.report_id) {
    why = fmt::format("report id {} (expected {})", report[0], config.report_id);
    return false;
  }
  // Check everything first, then commit: a bad report changes nothing.
  std::array<StationReading, kBodySiteCount> stations = frame.stations;
  for (const HidStationLayout& l : config.stations) {
    StationReading& s = stations[static_cast<std::size_t>(l.site)];
    const bool tracked =
        l.valid_offset < 0 || report[static_cast<std::size_t>(l.valid_offset)] != 0;
    if (!tracked) {
      s.valid = false;
      continue;
    }
    glm::vec3 p;
    for (int k = 0; k < 3; ++k) {
      p[k] = readValue(report, l.position_offset + k * typeSize(l.position_type), l.position_type) *
             l.position_scale;
    }
    float q[4];
    for (int k = 0; k < 4; ++k) {
      q[k] = readValue(report, l.orientation_offset + k * typeSize(l.orientation_type),
                       l.orientation_type) *
             l.orientation_scale;
    }
    const glm::quat o(q[0], q[1], q[2], q[3]);
    const float n = glm::length(o);
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || !std::isfinite(n) ||
        std::abs(n - 1.0f) > 0.05f) {
      why = fmt::format("{} station: non-finite position or quaternion of length {}",
                        bodySiteName(l.site), n);
      return false;
    }
    s.position = config.transmitter.rotation * p + config.transmitter.position;
    s.orientation = glm::normalize(config.transmitter.rotation * (o / n));
    s.time = now;
    s.valid = true;
    s.status = ' ';
  }
  frame.stations = stations;
  for (const HidGloveLayout& g : config.gloves) {
    GloveRecord rec;
    rec.sensor_count = g.sensor_count;
    std::copy_n(report.begin() + g.offset, g.sensor_count, rec.raw.begin());
    GloveReading& out = frame.gloves[static_cast<std::size_t>(g.hand)];
    applyGloveCalibration(rec, g.calibration, out);
    out.time = now;
  }
  return true;
}

HidSource::HidSource(std::unique_ptr<HidDevice> device, HidConfig config, SourceClock clock)
    : device_(std::move(device)), config_(std::move(config)), clock_(std::move(clock)) {}

PollResult HidSource::poll(double timeout_s, SensorFrame& frame) {
  const double deadline = clock_() + std::max(0.0, timeout_s);
  const std::size_t want =
      std::min<std::size_t>(report_.size(), static_cast<std::size_t>(config_.report_size));
  for (;;) {
    const double left = std::max(0.0, deadline - clock_());
    const int n = device_->read(report_.data(), want, static_cast<int>(std::ceil(left * 1000.0)));
    if (n < 0) {
      const std::string why = device_->lastError();
      return PollResult::unplugged(fmt::format("{}: device unplugged or failed ({})", describe(),
                                               why.empty() ? "read error" : why));
    }
    if (n == 0) {
      return PollResult::timeout(
          fmt::format("{}: no report within {:.3f} s", describe(), timeout_s));
    }
    std::string why;
    if (decodeHidReport(std::span<const std::uint8_t>(report_.data(), static_cast<std::size_t>(n)),
                        config_, clock_(), state_, why)) {
      break;
    }
    ++rejected_;  // skip it; a later report may be good
    if (clock_() >= deadline)
      return PollResult::timeout(fmt::format("{}: only bad reports ({})", describe(), why));
  }
  state_.time = clock_();
  state_.sequence = ++sequence_;
  frame.time = state_.time;
  frame.sequence = state_.sequence;
  frame.stations = state_.stations;
  for (const HidGloveLayout& g : config_.gloves) {
    frame.gloves[static_cast<std::size_t>(g.hand)] =
        state_.gloves[static_cast<std::size_t>(g.hand)];
  }
  return PollResult::frame();
}

}  // namespace vistel
