// libFuzzer target: FastrakParser and decodeFastrakRecord (common/sensors) on arbitrary
// device output, ASCII or binary.
//
// Input layout: byte 0 chooses the format (bit 0: binary, bit 1: centimetres, bits 2-4:
// number of output items - 1), the next bytes are the item codes (code % 21, codes
// vistel does not decode are left out), and the rest is the byte stream from the device.
// Properties: nothing crashes or reads out of bounds; every record has a station 1..4, a
// valid status, finite positions and a unit orientation; the records do not depend on
// how the stream is split (pieces of 1..17 bytes against one piece); every byte fed is
// accounted for as a record, discarded or still buffered.
// Seeds: records written by encodeFastrakRecord for several formats, with garbage between.
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/sensors/fastrak_parser.hpp"
#include "common/sensors/fastrak_protocol.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace vistel;
using fuzz::check;

// The format header of an input (layout above); consumed bytes are removed from `bytes`.
bool readFormat(std::span<const std::uint8_t>& bytes, FastrakFormat& format) {
  if (bytes.empty()) return false;
  const std::uint8_t flags = bytes[0];
  const std::size_t count = 1 + ((flags >> 2) & 7);
  if (bytes.size() < 1 + count) return false;
  format.encoding = (flags & 1) ? FastrakEncoding::kBinary : FastrakEncoding::kAscii;
  format.units = (flags & 2) ? LengthUnit::kCentimetres : LengthUnit::kInches;
  format.items.clear();
  for (std::size_t i = 0; i < count; ++i) {
    if (auto item = fastrakItemFromCode(bytes[1 + i] % 21)) format.items.push_back(*item);
  }
  bytes = bytes.subspan(1 + count);
  return validateFastrakFormat(format).ok();
}

// ---- seeds -------------------------------------------------------------------------------

std::vector<std::uint8_t> formatHeader(bool binary, bool cm, const std::vector<int>& codes) {
  std::vector<std::uint8_t> out;
  out.push_back(
      static_cast<std::uint8_t>((binary ? 1 : 0) | (cm ? 2 : 0) | ((codes.size() - 1) << 2)));
  for (int c : codes) out.push_back(static_cast<std::uint8_t>(c));
  return out;
}

fuzz::Seed streamSeed(const char* name, bool binary, bool cm, const std::vector<int>& codes) {
  std::vector<std::uint8_t> bytes = formatHeader(binary, cm, codes);
  FastrakFormat format;
  std::span<const std::uint8_t> rest(bytes);
  fuzz::check(readFormat(rest, format), "the seed's format is valid");
  std::string stream = "garbage 0x\r\n";
  for (int station = 1; station <= 4; ++station) {
    FastrakRecord r;
    r.station = station;
    r.status = station == 3 ? 'w' : ' ';
    r.position = glm::vec3(0.1f * station, -0.2f, 0.3f);
    r.relative = glm::vec3(0.01f, 0.0f, -0.01f);
    r.orientation = glm::angleAxis(0.3f * station, glm::normalize(glm::vec3(1, 1, 0)));
    r.stylus = station % 2;
    encodeFastrakRecord(r, format, stream);
    if (station == 2) stream += "0";  // a stray record-start byte
  }
  bytes.insert(bytes.end(), stream.begin(), stream.end());
  FastrakParser parser(format);
  parser.feed(std::span<const std::uint8_t>(bytes).subspan(bytes.size() - stream.size()));
  FastrakRecord record;
  int records = 0;
  while (parser.next(record)) ++records;
  fuzz::check(records == 4, "the seed stream holds four records");
  return {name, bytes};
}

std::vector<fuzz::Seed> makeSeeds() {
  return {
      streamSeed("ascii_pos_euler.bin", false, false, {2, 4, 1}),
      streamSeed("ascii_pos_quat_cm.bin", false, true, {2, 11, 16, 1}),
      streamSeed("ascii_dircos.bin", false, false, {3, 5, 0, 1}),
      streamSeed("binary_pos_quat.bin", true, false, {2, 11, 0}),
      streamSeed("binary_16bit.bin", true, true, {18, 19, 20}),
      streamSeed("binary_euler_dircos.bin", true, false, {4, 5, 16}),
  };
}

// ---- properties --------------------------------------------------------------------------

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

void checkRecord(const FastrakRecord& r) {
  check(r.station >= 1 && r.station <= kFastrakMaxStations, "station 1..4");
  check(r.status == ' ' || (r.status >= 'A' && r.status <= 'Z') ||
            (r.status >= 'a' && r.status <= 'z'),
        "status is a space or a letter");
  check(finite(r.position) && finite(r.relative) && finite(r.euler_deg), "finite values");
  if (r.has_orientation) {
    const glm::quat& q = r.orientation;
    check(std::isfinite(q.w) && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z),
          "finite orientation");
    check(std::abs(glm::length(q) - 1.0f) < 1e-3f, "unit orientation");
  }
  check(r.stylus >= -1 && r.stylus <= 1, "stylus -1, 0 or 1");
}

bool same(const FastrakRecord& a, const FastrakRecord& b) {
  return a.station == b.station && a.status == b.status && a.has_position == b.has_position &&
         a.position == b.position && a.has_relative == b.has_relative && a.relative == b.relative &&
         a.has_orientation == b.has_orientation && a.orientation == b.orientation &&
         a.has_euler == b.has_euler && a.euler_deg == b.euler_deg && a.stylus == b.stylus;
}

// Feeds the stream in pieces (salt) or whole (salt < 0) and collects the records.
std::vector<FastrakRecord> parse(const FastrakFormat& format, std::span<const std::uint8_t> stream,
                                 int salt) {
  FastrakParser parser(format);
  std::vector<FastrakRecord> records;
  FastrakRecord r;
  const auto feed = [&](std::span<const std::uint8_t> piece) {
    parser.feed(piece);
    while (parser.next(r)) {
      checkRecord(r);
      records.push_back(r);
    }
  };
  if (salt < 0) {
    feed(stream);
  } else {
    fuzz::feedInChunks(stream, static_cast<unsigned>(salt), feed);
  }
  check(parser.recordCount() == records.size(), "recordCount counts the records");
  check(parser.discardedBytes() + records.size() * parser.recordSize() + parser.buffered() ==
            stream.size(),
        "every byte is a record, discarded or buffered");
  return records;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::span<const std::uint8_t> stream(data, size);
  FastrakFormat format;
  if (!readFormat(stream, format)) return 0;

  const std::vector<FastrakRecord> pieces = parse(format, stream, data[0]);
  if (stream.size() <= 4096) {  // within the parser's buffer: nothing is dropped
    const std::vector<FastrakRecord> whole = parse(format, stream, -1);
    check(whole.size() == pieces.size(), "the split does not change the record count");
    for (std::size_t i = 0; i < whole.size(); ++i) {
      check(same(whole[i], pieces[i]), "the split does not change the records");
    }
  }

  // The one-record decoder on the stream's first record-sized window.
  const std::size_t record = fastrakRecordSize(format);
  FastrakRecord r;
  if (stream.size() >= record && decodeFastrakRecord(stream.first(record), format, r)) {
    checkRecord(r);
  }
  return 0;
}
