// The CyberGlove-class serial protocol (facts from ../shared/data/devices/PROTOCOLS.md §3;
// all code here is vistel's own): 'G' sample records, 'e' error codes, the commands a
// driver needs, and per-sensor calibration from raw bytes to radians.
//
// A sample record is 'G', n sensor bytes (n = 18 or 22, each 1..255: 0 would end the
// record), an optional 5-byte timestamp, an optional status byte, then NUL. An error shows
// as 'e' and a code ('s' sampling problem, 'g' glove not plugged in).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/base/result.hpp"
#include "common/sensors/byte_stream.hpp"
#include "common/sensors/sensor_frame.hpp"

namespace vistel {

inline constexpr int kGloveMaxSensors = 22;

struct GloveFormat {
  int sensor_count = 22;     // 18 or 22
  bool timestamp = false;    // 5 timestamp bytes after the sensors (the `D` setting)
  bool status_byte = false;  // 1 glove-status byte (the `U` setting)
};

Status validateGloveFormat(const GloveFormat& format);
std::size_t gloveRecordSize(const GloveFormat& format);  // 'G' ... NUL

struct GloveRecord {
  enum class Kind : std::uint8_t { kSample, kError };
  Kind kind = Kind::kSample;
  int sensor_count = 0;
  std::array<std::uint8_t, kGloveMaxSensors> raw{};  // record order, 1..255
  std::uint64_t timestamp = 0;  // the 5 timestamp bytes, little-endian, when present
  std::uint8_t status = 0;      // the status byte, when present
  char error_code = 0;          // kError: 's' (sampling) or 'g' (glove unplugged)
};

// Glove error code -> words ("sampling problem", "glove not plugged in").
std::string_view gloveErrorText(char code);

// Pure byte-stream decoder, resynchronising after garbage like FastrakParser: a record
// candidate starts at 'G' and must have only non-zero sensor bytes and the NUL exactly
// where the format puts it; 'e' followed by 's' or 'g' is an error record. Allocates
// nothing after construction.
class CyberGloveParser {
 public:
  explicit CyberGloveParser(GloveFormat format);  // format must validate (asserted)

  void feed(std::span<const std::uint8_t> bytes) { stream_.feed(bytes); }
  bool next(GloveRecord& out);
  void reset() { stream_.clear(); }

  const GloveFormat& format() const { return format_; }
  std::uint64_t recordCount() const { return records_; }
  std::uint64_t discardedBytes() const { return discarded_ + stream_.dropped(); }

 private:
  GloveFormat format_;
  std::size_t record_size_;
  ByteStream stream_;
  std::uint64_t records_ = 0;
  std::uint64_t discarded_ = 0;
};

// Encodes a sample record (the emulators' half); raw bytes of 0 are written as 1.
void encodeGloveRecord(const GloveRecord& record, const GloveFormat& format, std::string& out);

// ---- Commands ---------------------------------------------------------------------------

inline constexpr std::string_view kGlovePoll = "G";
inline constexpr std::string_view kGloveStreamOn = "S";
inline constexpr std::string_view kGloveStreamOff = "^c";  // ASR's form; Ctrl-C also sent
inline constexpr std::string_view kGloveQuerySensors = "?S";
inline constexpr std::string_view kGloveQueryEnabled = "?N";

// `N` n: enable n sensors. `D`/`U` 0|1: timestamp / status byte off or on.
std::string gloveSetSensorCountCommand(int n);
std::string gloveSetTimestampCommand(bool on);
std::string gloveSetStatusByteCommand(bool on);

// ---- Calibration ------------------------------------------------------------------------

// Per sensor (record order): angle = gain * (raw - offset), clamped to [min, max], radians.
struct GloveSensorCalibration {
  float gain = 0.0f;    // radians per count
  float offset = 0.0f;  // counts
  float min = -3.2f;    // radians
  float max = 3.2f;
};

struct GloveCalibration {
  std::vector<GloveSensorCalibration> sensors;  // sensor_count entries, record order
};

// Record index -> GloveSensor slot for a glove of 18 or 22 sensors (the 18-sensor glove
// lacks the four DIJ sensors, PROTOCOLS.md §3).
std::span<const int> gloveSlots(int sensor_count);

// A default calibration: raw 1..255 maps linearly onto 0..90 degrees of flexion, 0..30
// degrees for abductions, -60..60 degrees for the wrist, -30..30 for thumb rotation and
// palm arch.
GloveCalibration defaultGloveCalibration(int sensor_count);

// Fills all 22 angles of `out` from a sample record: calibrated sensors into their slots;
// for an 18-sensor glove each missing DIJ is estimated as 2/3 of its PIJ. Sets valid.
void applyGloveCalibration(const GloveRecord& record, const GloveCalibration& calibration,
                           GloveReading& out);

}  // namespace vistel
