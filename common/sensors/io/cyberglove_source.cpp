#include "common/sensors/io/cyberglove_source.hpp"

#include <algorithm>

namespace vistel {

CyberGloveSource::CyberGloveSource(std::unique_ptr<ByteTransport> transport,
                                   const GloveDeviceConfig& config, SourceClock clock)
    : transport_(std::move(transport)),
      config_(config),
      clock_(std::move(clock)),
      parser_(config.format) {}

Result<std::unique_ptr<CyberGloveSource>> CyberGloveSource::open(
    std::unique_ptr<ByteTransport> transport, const GloveDeviceConfig& config, SourceClock clock) {
  if (Status s = validateGloveFormat(config.format); !s)
    return withContext(transport->describe(), s.error());
  if (config.calibration.sensors.size() != static_cast<std::size_t>(config.format.sensor_count)) {
    return fail("{}: glove calibration has {} sensors for a {}-sensor glove", transport->describe(),
                config.calibration.sensors.size(), config.format.sensor_count);
  }
  std::unique_ptr<CyberGloveSource> src(
      new CyberGloveSource(std::move(transport), config, std::move(clock)));
  if (Status s = src->initialise(); !s) return s.error();
  return src;
}

IoResult CyberGloveSource::send(std::string_view bytes) {
  IoResult r = transport_->write(bytesOf(bytes), config_.reply_timeout_s);
  if (r.status != IoStatus::kOk) r.message = fmt::format("glove: {}", r.message);
  return r;
}

Result<std::string> CyberGloveSource::queryReply(char letter, std::size_t count) {
  std::string got;
  const double deadline = clock_() + config_.reply_timeout_s;
  for (;;) {
    // Look for '?', letter, count bytes, NUL anywhere in what arrived.
    for (std::size_t i = 0; i + count + 3 <= got.size(); ++i) {
      if (got[i] == '?' && got[i + 1] == letter && got[i + 2 + count] == '\0')
        return got.substr(i + 2, count);
    }
    const double left = deadline - clock_();
    if (left <= 0.0) break;
    const IoResult r = transport_->read(buffer_, left);
    if (r.status == IoStatus::kUnplugged || r.status == IoStatus::kFailed)
      return fail("glove: {}", r.message);
    if (r.status == IoStatus::kTimeout) break;
    got.append(reinterpret_cast<const char*>(buffer_.data()), r.bytes);
  }
  return fail(
      "glove on {}: no reply to '?{}' within {} s (is the box on, on this port, at {} baud?)",
      transport_->describe(), letter, config_.reply_timeout_s, config_.baud);
}

Status CyberGloveSource::initialise() {
  // Stop streaming in both spellings, then drain.
  if (IoResult r = send(kGloveStreamOff); r.status != IoStatus::kOk) return Error{r.message};
  if (IoResult r = send(std::string_view("\x03", 1)); r.status != IoStatus::kOk)
    return Error{r.message};
  const double drain_until = clock_() + 0.2;
  while (clock_() < drain_until) {
    const IoResult r = transport_->read(buffer_, 0.05);
    if (r.status == IoStatus::kUnplugged || r.status == IoStatus::kFailed)
      return fail("glove: {}", r.message);
    if (r.status == IoStatus::kTimeout) break;
  }
  transport_->discardInput();

  // The enabled sensor count must be the configured one.
  if (IoResult r = send(kGloveQueryEnabled); r.status != IoStatus::kOk) return Error{r.message};
  Result<std::string> n = queryReply('N', 1);
  if (!n) return n.error();
  const int enabled = static_cast<std::uint8_t>((*n)[0]);
  if (enabled != config_.format.sensor_count) {
    if (IoResult r = send(gloveSetSensorCountCommand(config_.format.sensor_count));
        r.status != IoStatus::kOk) {
      return Error{r.message};
    }
    if (IoResult r = send(kGloveQueryEnabled); r.status != IoStatus::kOk) return Error{r.message};
    Result<std::string> again = queryReply('N', 1);
    if (!again) return again.error();
    if (static_cast<std::uint8_t>((*again)[0]) != config_.format.sensor_count) {
      return fail("glove on {}: {} sensors enabled and it refuses {}", transport_->describe(),
                  enabled, config_.format.sensor_count);
    }
  }
  // Timestamp and status byte as configured (the box echoes; the echo is drained below).
  if (IoResult r = send(gloveSetTimestampCommand(config_.format.timestamp));
      r.status != IoStatus::kOk)
    return Error{r.message};
  if (IoResult r = send(gloveSetStatusByteCommand(config_.format.status_byte));
      r.status != IoStatus::kOk)
    return Error{r.message};
  const double settle = clock_() + 0.05;
  while (clock_() < settle && transport_->read(buffer_, 0.02).status == IoStatus::kOk) {
  }
  parser_.reset();
  if (config_.stream) {
    if (IoResult r = send(kGloveStreamOn); r.status != IoStatus::kOk) return Error{r.message};
  }
  return {};
}

PollResult CyberGloveSource::poll(double timeout_s, SensorFrame& frame) {
  const double deadline = clock_() + std::max(0.0, timeout_s);
  if (!config_.stream) {
    if (IoResult r = send(kGlovePoll); r.status != IoStatus::kOk) {
      return r.status == IoStatus::kUnplugged ? PollResult::unplugged(r.message)
                                              : PollResult::failed(r.message);
    }
  }
  int samples = 0;
  GloveRecord rec;
  for (;;) {
    const double left = deadline - clock_();
    const IoResult r = transport_->read(buffer_, samples > 0 ? 0.0 : std::max(0.0, left));
    if (r.status == IoStatus::kUnplugged) {
      reading_.valid = false;
      frame.gloves[static_cast<std::size_t>(config_.hand)].valid = false;
      return PollResult::unplugged(fmt::format("glove: {}", r.message));
    }
    if (r.status == IoStatus::kFailed)
      return PollResult::failed(fmt::format("glove: {}", r.message));
    if (r.status == IoStatus::kOk)
      parser_.feed(std::span<const std::uint8_t>(buffer_.data(), r.bytes));
    while (parser_.next(rec)) {
      if (rec.kind == GloveRecord::Kind::kError) {
        if (rec.error_code == 'g') {
          reading_.valid = false;
          frame.gloves[static_cast<std::size_t>(config_.hand)].valid = false;
          return PollResult::unplugged(fmt::format("glove on {}: {} (the box reports 'e g')",
                                                   transport_->describe(), gloveErrorText('g')));
        }
        ++sampling_errors_;
        continue;
      }
      applyGloveCalibration(rec, config_.calibration, reading_);
      reading_.time = clock_();
      ++samples;
    }
    if (samples > 0 && r.status != IoStatus::kOk) break;  // drained what was waiting
    if (samples == 0 && (r.status == IoStatus::kTimeout || clock_() >= deadline)) {
      return PollResult::timeout(
          fmt::format("glove on {}: no record within {:.3f} s", transport_->describe(), timeout_s));
    }
  }
  frame.gloves[static_cast<std::size_t>(config_.hand)] = reading_;
  frame.time = reading_.time;
  frame.sequence = ++sequence_;
  return PollResult::frame();
}

std::string CyberGloveSource::describe() const {
  return fmt::format("{} glove on {} ({} sensors, {})", handName(config_.hand),
                     transport_->describe(), config_.format.sensor_count,
                     config_.stream ? "streaming" : "polled");
}

}  // namespace vistel
