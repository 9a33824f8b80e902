#include "common/sensors/io/force_feedback.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <hidapi.h>

#include "common/sensors/io/hid_text.hpp"

namespace vistel {
namespace {

class HidapiOutput final : public HidOutputDevice {
 public:
  HidapiOutput(hid_device* dev, std::string name) : dev_(dev), name_(std::move(name)) {}
  ~HidapiOutput() override {
    hid_close(dev_);
    hid_exit();
  }
  int write(std::span<const std::uint8_t> report) override {
    return hid_write(dev_, report.data(), report.size());
  }
  std::string lastError() const override { return hidText(hid_error(dev_)); }
  std::string describe() const override { return name_; }

 private:
  hid_device* dev_;
  std::string name_;
};

// The channel's value in newtons: a model-space axis of the force, or its length.
float component(const glm::vec3& f, ForceComponent c) {
  switch (c) {
    case ForceComponent::kX:
      return f.x;
    case ForceComponent::kY:
      return f.y;
    case ForceComponent::kZ:
      return f.z;
    case ForceComponent::kMagnitude:
      return glm::length(f);
  }
  return 0.0f;
}

// Writes `counts` as the channel's type at its offset (little-endian), rounded and clamped
// to the type's range.
void put(std::span<std::uint8_t> report, const ForceFeedbackChannel& c, float counts) {
  std::uint8_t* p = report.data() + c.offset;
  switch (c.type) {
    case HidValueType::kF32:
      std::memcpy(p, &counts, 4);
      return;
    case HidValueType::kI16: {
      const auto v =
          static_cast<std::int16_t>(std::lround(std::clamp(counts, -32768.0f, 32767.0f)));
      p[0] = static_cast<std::uint8_t>(static_cast<std::uint16_t>(v) & 0xFF);
      p[1] = static_cast<std::uint8_t>(static_cast<std::uint16_t>(v) >> 8);
      return;
    }
    case HidValueType::kU8:
      *p = static_cast<std::uint8_t>(std::lround(std::clamp(counts, 0.0f, 255.0f)));
      return;
  }
}

}  // namespace

Result<std::unique_ptr<HidOutputDevice>> openHidapiOutput(const ForceFeedbackConfig& config) {
  const std::string name =
      fmt::format("force feedback hid {:04x}:{:04x}", config.vendor_id, config.product_id);
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
  return std::unique_ptr<HidOutputDevice>(new HidapiOutput(dev, name));
}

std::vector<int> bindForceChannels(const ForceFeedbackConfig& config,
                                   std::span<const std::string> part_names,
                                   std::vector<std::string>* unknown) {
  std::vector<int> out;
  out.reserve(config.channels.size());
  for (const ForceFeedbackChannel& c : config.channels) {
    const auto found = std::find(part_names.begin(), part_names.end(), c.part);
    out.push_back(found == part_names.end() ? -1 : static_cast<int>(found - part_names.begin()));
    if (found == part_names.end() && unknown != nullptr &&
        std::find(unknown->begin(), unknown->end(), c.part) == unknown->end()) {
      unknown->push_back(c.part);
    }
  }
  return out;
}

void encodeForceReport(const ForceFeedbackConfig& config, std::span<const int> channel_part,
                       std::span<const glm::vec3> forces, std::span<std::uint8_t> report) {
  std::fill(report.begin(), report.end(), std::uint8_t{0});
  if (report.empty()) return;
  report[0] = static_cast<std::uint8_t>(config.report_id);
  const std::size_t n = std::min(config.channels.size(), channel_part.size());
  for (std::size_t i = 0; i < n; ++i) {
    const ForceFeedbackChannel& c = config.channels[i];
    const int part = channel_part[i];
    const int size = c.type == HidValueType::kF32 ? 4 : c.type == HidValueType::kI16 ? 2 : 1;
    if (c.offset < 1 || static_cast<std::size_t>(c.offset + size) > report.size()) continue;
    float newtons = 0.0f;
    if (part >= 0 && static_cast<std::size_t>(part) < forces.size()) {
      newtons = component(forces[static_cast<std::size_t>(part)], c.component);
    }
    if (!std::isfinite(newtons)) newtons = 0.0f;
    put(report, c, newtons / c.scale);
  }
}

ForceFeedbackWriter::ForceFeedbackWriter(std::unique_ptr<HidOutputDevice> device,
                                         ForceFeedbackConfig config,
                                         std::span<const std::string> part_names,
                                         double max_rate_hz)
    : device_(std::move(device)), config_(std::move(config)) {
  channel_part_ = bindForceChannels(config_, part_names, &unknown_);
  const double rate = max_rate_hz > 0.0 ? max_rate_hz : config_.max_rate_hz;
  min_interval_s_ = rate > 0.0 ? 1.0 / rate : 0.0;
  const auto size = static_cast<std::size_t>(std::max(config_.report_size, 1));
  report_.assign(size, 0);
  last_.assign(size, 0);
}

ForceFeedbackWriter::~ForceFeedbackWriter() { close(); }

bool ForceFeedbackWriter::send(std::span<const std::uint8_t> report) {
  if (!device_ || failed_) return false;
  if (device_->write(report) < 0) {
    failed_ = true;
    error_ = device_->lastError();
    return false;
  }
  ++sent_;
  return true;
}

Status ForceFeedbackWriter::update(double now, std::span<const glm::vec3> forces) {
  if (failed_ || closed_) return {};
  encodeForceReport(config_, channel_part_, forces, report_);
  // Only a change is sent, and not sooner than the rate allows (a pending change goes out
  // with a later update).
  if (have_last_ && report_ == last_) return {};
  if (have_last_ && now - last_time_ < min_interval_s_) return {};
  if (!send(report_)) {
    return fail("{}: write failed ({}); force feedback stopped", describe(),
                error_.empty() ? "device gone" : error_);
  }
  std::copy(report_.begin(), report_.end(), last_.begin());
  have_last_ = true;
  last_time_ = now;
  return {};
}

void ForceFeedbackWriter::close() {
  if (closed_) return;
  closed_ = true;
  encodeForceReport(config_, channel_part_, {}, report_);
  if (!have_last_ || report_ != last_) send(report_);
}

}  // namespace vistel
