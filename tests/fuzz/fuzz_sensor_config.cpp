// libFuzzer target: the sensor configuration parsers (common/sensors/sensor_config.hpp),
// whose text also arrives inside .vrec recordings (replayed with their recorded config),
// and decodeHidReport (common/sensors/io/hid_source.hpp) under every layout they accept.
//
// Input layout: TOML text, then optionally a NUL byte and the bytes of one HID input report
// (cut or zero-padded to the layout's report_size). Properties: nothing crashes, leaks or
// reads out of bounds; a rejected setup names the source; an accepted setup's device
// formats validate (the device parsers assert on them), glove calibrations have one entry
// per sensor, and its HID layout fits the report, which decodes to unit orientations.
// Glove files named by a setup are read through readConfigText (disk or built in).
// Seeds: the built-in config/sensors/*.toml, and hid.toml with a report of its layout.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/base/embedded.hpp"
#include "common/sensors/cyberglove_protocol.hpp"
#include "common/sensors/fastrak_protocol.hpp"
#include "common/sensors/io/hid_source.hpp"
#include "common/sensors/sensor_config.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace vistel;
using fuzz::check;

// ---- seeds -------------------------------------------------------------------------------

// Writes v at offset as the layout's number type (scale: units per count).
void putValue(std::vector<std::uint8_t>& report, int offset, HidValueType type, float scale,
              float v) {
  std::uint8_t* p = report.data() + offset;
  if (type == HidValueType::kF32) {
    const float f = v / scale;
    std::memcpy(p, &f, 4);
  } else if (type == HidValueType::kI16) {
    const auto i = static_cast<std::int16_t>(std::lround(v / scale));
    std::memcpy(p, &i, 2);
  } else {
    *p = static_cast<std::uint8_t>(std::lround(v / scale));
  }
}

int sizeOf(HidValueType type) {
  return type == HidValueType::kF32 ? 4 : type == HidValueType::kI16 ? 2 : 1;
}

// A report in the setup's HID layout: every station tracked at a small offset from the
// origin with the identity orientation, the glove bytes mid-range.
std::vector<std::uint8_t> reportFor(const HidConfig& hid) {
  std::vector<std::uint8_t> report(static_cast<std::size_t>(hid.report_size), 0);
  if (hid.report_id >= 0) report[0] = static_cast<std::uint8_t>(hid.report_id);
  for (const HidStationLayout& l : hid.stations) {
    for (int k = 0; k < 3; ++k) {
      putValue(report, l.position_offset + k * sizeOf(l.position_type), l.position_type,
               l.position_scale, 0.1f * static_cast<float>(k + 1));
    }
    const float q[4] = {1.0f, 0.0f, 0.0f, 0.0f};
    for (int k = 0; k < 4; ++k) {
      putValue(report, l.orientation_offset + k * sizeOf(l.orientation_type), l.orientation_type,
               l.orientation_scale, q[k]);
    }
    if (l.valid_offset >= 0) report[static_cast<std::size_t>(l.valid_offset)] = 1;
  }
  for (const HidGloveLayout& g : hid.gloves) {
    std::fill_n(report.begin() + g.offset, g.sensor_count, std::uint8_t{128});
  }
  return report;
}

std::vector<fuzz::Seed> makeSeeds() {
  std::vector<fuzz::Seed> seeds;
  for (const EmbeddedFile& f : embeddedFiles()) {
    if (!f.path.starts_with("sensors/") || !f.path.ends_with(".toml")) continue;
    const std::string name(f.path.substr(8));
    seeds.push_back(fuzz::textSeed("builtin_" + name, f.data));
    if (name != "hid.toml") continue;
    Result<SensorSetup> setup = parseSensorSetup(f.data, f.path);
    check(setup.ok() && setup->tracker_kind == TrackerKind::kHid, "hid.toml parses as HID");
    std::vector<std::uint8_t> bytes(f.data.begin(), f.data.end());
    bytes.push_back(0);
    const std::vector<std::uint8_t> report = reportFor(setup->hid);
    SensorFrame frame;
    std::string why;
    check(decodeHidReport(report, setup->hid, 1.0, frame, why), "the seed report decodes");
    bytes.insert(bytes.end(), report.begin(), report.end());
    seeds.push_back({"builtin_hid_with_report.bin", bytes});
  }
  check(seeds.size() >= 2, "config/sensors has built-in files");
  return seeds;
}

// ---- properties --------------------------------------------------------------------------

void checkGlove(const GloveDeviceConfig& glove) {
  check(validateGloveFormat(glove.format).ok(), "an accepted glove format validates");
  check(glove.calibration.sensors.size() == static_cast<std::size_t>(glove.format.sensor_count),
        "a calibration entry per glove sensor");
  for (const GloveSensorCalibration& c : glove.calibration.sensors) {
    check(std::isfinite(c.gain) && std::isfinite(c.offset) && c.min <= c.max,
          "finite calibration with min <= max");
  }
}

void checkHid(const HidConfig& hid, std::span<const std::uint8_t> tail) {
  check(hid.report_size >= 1 && hid.report_size <= 4096, "report size 1..4096");
  for (const HidGloveLayout& g : hid.gloves) {
    check(g.calibration.sensors.size() == static_cast<std::size_t>(g.sensor_count),
          "a calibration entry per HID glove sensor");
  }
  // The report under the layout: exactly report_size bytes (ASan checks the offsets).
  std::vector<std::uint8_t> report(tail.begin(), tail.end());
  report.resize(static_cast<std::size_t>(hid.report_size), 0);
  SensorFrame frame;
  std::string why;
  if (!decodeHidReport(report, hid, 2.0, frame, why)) {
    check(!why.empty(), "a rejected report says why");
    return;
  }
  for (const StationReading& s : frame.stations) {
    if (!s.valid) continue;
    check(std::isfinite(s.position.x) && std::isfinite(s.position.y) && std::isfinite(s.position.z),
          "finite station positions");
    check(std::abs(glm::length(s.orientation) - 1.0f) < 1e-3f, "unit station orientations");
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto* end = std::find(data, data + size, std::uint8_t{0});
  const std::string_view text(reinterpret_cast<const char*>(data),
                              static_cast<std::size_t>(end - data));
  const std::span<const std::uint8_t> tail(end == data + size ? end : end + 1, data + size);

  Result<SensorSetup> setup = parseSensorSetup(text, "fuzz.toml");
  if (!setup.ok()) {
    check(setup.error().message.find("fuzz.toml") != std::string::npos,
          "a rejected setup names the source");
  } else {
    if (setup->tracker_kind == TrackerKind::kFastrak) {
      check(validateFastrakFormat(setup->tracker.format).ok(), "the tracker format validates");
      for (const StationMapping& m : setup->tracker.stations) {
        check(m.station >= 0 && m.station <= kFastrakMaxStations, "stations 0..4");
      }
    }
    if (setup->tracker_kind == TrackerKind::kHid) checkHid(setup->hid, tail);
    for (const GloveDeviceConfig& glove : setup->gloves) checkGlove(glove);
  }

  Result<GloveDeviceConfig> glove = parseGloveConfig(text, "fuzz_glove.toml");
  if (glove.ok()) checkGlove(*glove);
  return 0;
}
