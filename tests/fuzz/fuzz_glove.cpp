// libFuzzer target: CyberGloveParser and applyGloveCalibration (common/sensors) on
// arbitrary glove output.
//
// Input layout: byte 0 chooses the format (bit 0: 18 sensors instead of 22, bit 1:
// timestamp, bit 2: status byte); the rest is the byte stream from the glove.
// Properties: nothing crashes or reads out of bounds; a sample has the format's sensor
// count and only non-zero sensor bytes, an error record the code 's' or 'g'; the records
// do not depend on how the stream is split (pieces of 1..17 bytes against one piece);
// every byte fed is a record, discarded or still buffered; calibrated angles are finite
// and within each sensor's [min, max].
// Seeds: records written by encodeGloveRecord for every format, with errors and garbage.
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/sensors/cyberglove_protocol.hpp"
#include "common/sensors/sensor_frame.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace vistel;
using fuzz::check;

GloveFormat formatOf(std::uint8_t flags) {
  GloveFormat f;
  f.sensor_count = (flags & 1) ? 18 : 22;
  f.timestamp = (flags & 2) != 0;
  f.status_byte = (flags & 4) != 0;
  return f;
}

std::vector<fuzz::Seed> makeSeeds() {
  std::vector<fuzz::Seed> seeds;
  for (std::uint8_t flags = 0; flags < 8; ++flags) {
    const GloveFormat format = formatOf(flags);
    std::string stream(1, static_cast<char>(flags));
    stream += "?";  // garbage before the first record
    for (int k = 0; k < 3; ++k) {
      GloveRecord r;
      r.sensor_count = format.sensor_count;
      for (int i = 0; i < format.sensor_count; ++i) {
        r.raw[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(1 + (40 * k + 11 * i) % 255);
      }
      r.timestamp = 0x0102030405ull + static_cast<std::uint64_t>(k);
      r.status = static_cast<std::uint8_t>(k);
      encodeGloveRecord(r, format, stream);
      if (k == 1) stream += std::string("es\0eg", 5);  // two error records
    }
    CyberGloveParser parser(format);
    parser.feed(std::span<const std::uint8_t>(
        reinterpret_cast<const std::uint8_t*>(stream.data()) + 1, stream.size() - 1));
    GloveRecord record;
    int records = 0;
    while (parser.next(record)) ++records;
    check(records == 5, "the seed stream holds three samples and two errors");
    seeds.push_back(fuzz::textSeed("glove_" + std::to_string(flags) + ".bin", stream));
  }
  return seeds;
}

bool same(const GloveRecord& a, const GloveRecord& b) {
  return a.kind == b.kind && a.sensor_count == b.sensor_count && a.raw == b.raw &&
         a.timestamp == b.timestamp && a.status == b.status && a.error_code == b.error_code;
}

void checkRecord(const GloveRecord& r, const GloveFormat& format,
                 const GloveCalibration& calibration) {
  if (r.kind == GloveRecord::Kind::kError) {
    check(r.error_code == 's' || r.error_code == 'g', "error code 's' or 'g'");
    return;
  }
  check(r.sensor_count == format.sensor_count, "the format's sensor count");
  for (int i = 0; i < r.sensor_count; ++i) {
    check(r.raw[static_cast<std::size_t>(i)] != 0, "sensor bytes are non-zero");
  }
  check(format.timestamp || r.timestamp == 0, "no timestamp without the format's");
  check(r.timestamp < (std::uint64_t{1} << 40), "a timestamp has 5 bytes");

  // Calibration: every slot the record fills is finite and within its sensor's range.
  GloveReading reading;
  applyGloveCalibration(r, calibration, reading);
  check(reading.valid, "a calibrated sample is valid");
  const std::span<const int> slots = gloveSlots(r.sensor_count);
  for (std::size_t i = 0; i < slots.size(); ++i) {
    const float a = reading.angles[static_cast<std::size_t>(slots[i])];
    const GloveSensorCalibration& c = calibration.sensors[i];
    check(std::isfinite(a) && a >= c.min && a <= c.max, "calibrated angles within range");
  }
  for (float a : reading.angles) check(std::isfinite(a), "every angle is finite");
}

// Feeds the stream in pieces (salt) or whole (salt < 0) and collects the records.
std::vector<GloveRecord> parse(const GloveFormat& format, std::span<const std::uint8_t> stream,
                               int salt) {
  const GloveCalibration calibration = defaultGloveCalibration(format.sensor_count);
  CyberGloveParser parser(format);
  std::vector<GloveRecord> records;
  std::size_t record_bytes = 0;
  GloveRecord r;
  const auto feed = [&](std::span<const std::uint8_t> piece) {
    parser.feed(piece);
    while (parser.next(r)) {
      checkRecord(r, format, calibration);
      record_bytes += r.kind == GloveRecord::Kind::kError ? 2 : gloveRecordSize(format);
      records.push_back(r);
    }
  };
  if (salt < 0) {
    feed(stream);
  } else {
    fuzz::feedInChunks(stream, static_cast<unsigned>(salt), feed);
  }
  check(parser.recordCount() == records.size(), "recordCount counts the records");
  // Every byte fed is a record, discarded, or part of the one partial record left.
  check(record_bytes + parser.discardedBytes() <= stream.size(),
        "records and discards never exceed the bytes fed");
  const std::size_t rest = stream.size() - record_bytes - parser.discardedBytes();
  check(rest < gloveRecordSize(format), "at most a partial record stays buffered");
  return records;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const GloveFormat format = formatOf(data[0]);
  const std::span<const std::uint8_t> stream(data + 1, size - 1);

  const std::vector<GloveRecord> pieces = parse(format, stream, data[0]);
  if (stream.size() <= 4096) {  // within the parser's buffer: nothing is dropped
    const std::vector<GloveRecord> whole = parse(format, stream, -1);
    check(whole.size() == pieces.size(), "the split does not change the record count");
    for (std::size_t i = 0; i < whole.size(); ++i) {
      check(same(whole[i], pieces[i]), "the split does not change the records");
    }
  }
  return 0;
}
