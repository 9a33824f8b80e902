#include "common/sensors/cyberglove_protocol.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include <fmt/format.h>
#include <glm/glm.hpp>

namespace vistel {
namespace {

constexpr std::array<int, 22> kSlots22 = {0,  1,  2,  3,  4,  5,  6,  7,  8,  9,  10,
                                          11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21};
constexpr std::array<int, 18> kSlots18 = {kThumbRotation,  kThumbMpj,   kThumbIj,
                                          kThumbAbduction, kIndexMpj,   kIndexPij,
                                          kMiddleMpj,      kMiddlePij,  kMiddleIndexAbduction,
                                          kRingMpj,        kRingPij,    kRingMiddleAbduction,
                                          kPinkyMpj,       kPinkyPij,   kPinkyRingAbduction,
                                          kPalmArch,       kWristPitch, kWristYaw};

bool isErrorCode(std::uint8_t c) { return c == 's' || c == 'g'; }

}  // namespace

Status validateGloveFormat(const GloveFormat& format) {
  if (format.sensor_count != 18 && format.sensor_count != 22) {
    return fail("glove sensor count {} (expected 18 or 22)", format.sensor_count);
  }
  return {};
}

std::size_t gloveRecordSize(const GloveFormat& format) {
  return 1 + static_cast<std::size_t>(format.sensor_count) + (format.timestamp ? 5 : 0) +
         (format.status_byte ? 1 : 0) + 1;
}

std::string_view gloveErrorText(char code) {
  switch (code) {
    case 's':
      return "sampling problem (sample too early or overrun)";
    case 'g':
      return "glove not plugged in";
    default:
      return "unknown glove error";
  }
}

CyberGloveParser::CyberGloveParser(GloveFormat format)
    : format_(format), record_size_(gloveRecordSize(format)), stream_(4096) {
  assert(validateGloveFormat(format_).ok());
}

bool CyberGloveParser::next(GloveRecord& out) {
  for (;;) {
    const std::span<const std::uint8_t> b = stream_.front();
    std::size_t skip = 0;
    while (skip < b.size() && b[skip] != 'G' && b[skip] != 'e') ++skip;
    if (skip > 0) {
      discarded_ += skip;
      stream_.consume(skip);
      continue;
    }
    if (b.empty()) return false;
    if (b[0] == 'e') {
      if (b.size() < 2) return false;
      if (isErrorCode(b[1])) {
        out = GloveRecord{};
        out.kind = GloveRecord::Kind::kError;
        out.error_code = static_cast<char>(b[1]);
        // A NUL terminator may follow; it is skipped as garbage if it does.
        stream_.consume(2);
        ++records_;
        return true;
      }
      ++discarded_;
      stream_.consume(1);
      continue;
    }
    if (b.size() < record_size_) {
      // An 'e' error can arrive in place of a sample: if one follows the 'G' before the
      // record could be complete, the 'G' was not a record start.
      bool zero = false;
      for (std::size_t i = 1; i < b.size() && i <= static_cast<std::size_t>(format_.sensor_count);
           ++i) {
        zero = zero || b[i] == 0;
      }
      if (!zero) return false;
      ++discarded_;
      stream_.consume(1);
      continue;
    }
    // Check: sensors non-zero, NUL at the end.
    const int n = format_.sensor_count;
    bool ok = b[record_size_ - 1] == 0;
    for (int i = 0; ok && i < n; ++i) ok = b[1 + i] != 0;
    if (!ok) {
      ++discarded_;
      stream_.consume(1);
      continue;
    }
    out = GloveRecord{};
    out.kind = GloveRecord::Kind::kSample;
    out.sensor_count = n;
    std::copy_n(b.begin() + 1, n, out.raw.begin());
    std::size_t pos = 1 + static_cast<std::size_t>(n);
    if (format_.timestamp) {
      for (int i = 0; i < 5; ++i)
        out.timestamp |= static_cast<std::uint64_t>(b[pos + i]) << (8 * i);
      pos += 5;
    }
    if (format_.status_byte) out.status = b[pos];
    stream_.consume(record_size_);
    ++records_;
    return true;
  }
}

void encodeGloveRecord(const GloveRecord& r, const GloveFormat& format, std::string& out) {
  out.push_back('G');
  for (int i = 0; i < format.sensor_count; ++i) {
    out.push_back(static_cast<char>(r.raw[i] == 0 ? 1 : r.raw[i]));
  }
  if (format.timestamp) {
    for (int i = 0; i < 5; ++i) out.push_back(static_cast<char>((r.timestamp >> (8 * i)) & 0xFF));
  }
  if (format.status_byte) out.push_back(static_cast<char>(r.status));
  out.push_back('\0');
}

std::string gloveSetSensorCountCommand(int n) {
  std::string cmd = "N";
  cmd.push_back(static_cast<char>(n));
  return cmd;
}

std::string gloveSetTimestampCommand(bool on) {
  std::string cmd = "D";
  cmd.push_back(static_cast<char>(on ? 1 : 0));
  return cmd;
}

std::string gloveSetStatusByteCommand(bool on) {
  std::string cmd = "U";
  cmd.push_back(static_cast<char>(on ? 1 : 0));
  return cmd;
}

std::span<const int> gloveSlots(int sensor_count) {
  if (sensor_count == 18) return kSlots18;
  return kSlots22;
}

GloveCalibration defaultGloveCalibration(int sensor_count) {
  GloveCalibration cal;
  const std::span<const int> slots = gloveSlots(sensor_count);
  for (int slot : slots) {
    GloveSensorCalibration s;
    float lo = 0.0f;
    float hi = glm::radians(90.0f);
    if (slot == kThumbAbduction || slot == kMiddleIndexAbduction || slot == kRingMiddleAbduction ||
        slot == kPinkyRingAbduction) {
      hi = glm::radians(30.0f);
    } else if (slot == kWristPitch || slot == kWristYaw) {
      lo = glm::radians(-60.0f);
      hi = glm::radians(60.0f);
    } else if (slot == kThumbRotation || slot == kPalmArch) {
      lo = glm::radians(-30.0f);
      hi = glm::radians(30.0f);
    }
    // raw 1 -> lo, raw 255 -> hi.
    s.gain = (hi - lo) / 254.0f;
    s.offset = 1.0f - lo / s.gain;
    s.min = lo;
    s.max = hi;
    cal.sensors.push_back(s);
  }
  return cal;
}

void applyGloveCalibration(const GloveRecord& record, const GloveCalibration& calibration,
                           GloveReading& out) {
  const std::span<const int> slots = gloveSlots(record.sensor_count);
  const std::size_t n = std::min(slots.size(), calibration.sensors.size());
  for (std::size_t i = 0; i < n; ++i) {
    const GloveSensorCalibration& c = calibration.sensors[i];
    const float angle = c.gain * (static_cast<float>(record.raw[i]) - c.offset);
    out.angles[slots[i]] = std::clamp(angle, c.min, c.max);
  }
  if (record.sensor_count == 18) {
    out.angles[kIndexDij] = out.angles[kIndexPij] * (2.0f / 3.0f);
    out.angles[kMiddleDij] = out.angles[kMiddlePij] * (2.0f / 3.0f);
    out.angles[kRingDij] = out.angles[kRingPij] * (2.0f / 3.0f);
    out.angles[kPinkyDij] = out.angles[kPinkyPij] * (2.0f / 3.0f);
  }
  out.valid = true;
}

}  // namespace vistel
