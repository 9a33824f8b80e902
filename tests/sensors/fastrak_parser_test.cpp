// FASTRAK-class records: every output item in ASCII and binary, inches and centimetres, fed
// whole, split at every byte, one byte at a time, and with garbage between records.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/sensors/fastrak_parser.hpp"
#include "common/sensors/io/byte_transport.hpp"
#include "common/sensors/random.hpp"

namespace vistel {
namespace {

using Items = std::vector<FastrakItem>;

std::vector<FastrakRecord> sampleRecords(const FastrakFormat& format, int count) {
  std::vector<FastrakRecord> out;
  SimRandom rng(11);
  for (int i = 0; i < count; ++i) {
    FastrakRecord r;
    r.station = 1 + i % 4;
    r.status = i % 5 == 3 ? 'W' : ' ';
    r.position = glm::vec3(static_cast<float>(rng.uniform() * 1.6 - 0.8),
                           static_cast<float>(rng.uniform() * 1.6 - 0.8),
                           static_cast<float>(rng.uniform() * 1.6 - 0.8));
    r.relative = r.position * 0.1f;
    r.orientation = glm::normalize(
        glm::quat(static_cast<float>(rng.gaussian()), static_cast<float>(rng.gaussian()),
                  static_cast<float>(rng.gaussian()), static_cast<float>(rng.gaussian())));
    if (r.orientation.w < 0.0f) r.orientation = -r.orientation;
    r.stylus = i % 2;
    for (FastrakItem item : format.items) {
      if (item == FastrakItem::kPosition || item == FastrakItem::kPosition16) r.has_position = true;
      if (item == FastrakItem::kRelativePosition) r.has_relative = true;
      if (item == FastrakItem::kEuler || item == FastrakItem::kEuler16 ||
          item == FastrakItem::kQuaternion || item == FastrakItem::kQuaternion16 ||
          item == FastrakItem::kDirectionCosines) {
        r.has_orientation = true;
      }
    }
    out.push_back(r);
  }
  return out;
}

std::string encodeAll(const std::vector<FastrakRecord>& records, const FastrakFormat& format) {
  std::string bytes;
  for (const FastrakRecord& r : records) encodeFastrakRecord(r, format, bytes);
  return bytes;
}

// Tolerances: ASCII has 2 decimals of the unit for positions, 4 for quaternions and
// cosines, 2 for degrees; the 16-bit items have 14 bits.
void expectSame(const FastrakRecord& want, const FastrakRecord& got, const FastrakFormat& format) {
  const bool ascii = format.encoding == FastrakEncoding::kAscii;
  const float unit = format.units == LengthUnit::kInches ? 0.0254f : 0.01f;
  bool p16 = false, a16 = false;
  for (FastrakItem i : format.items) {
    p16 = p16 || i == FastrakItem::kPosition16;
    a16 = a16 || i == FastrakItem::kEuler16 || i == FastrakItem::kQuaternion16;
  }
  EXPECT_EQ(want.station, got.station);
  EXPECT_EQ(want.status, got.status);
  EXPECT_EQ(want.has_position, got.has_position);
  EXPECT_EQ(want.has_orientation, got.has_orientation);
  const float pos_tol = p16 ? 3.0f / 8192.0f : ascii ? 0.0051f * unit : 1e-6f;
  if (want.has_position) {
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(want.position[k], got.position[k], pos_tol);
  }
  if (want.has_relative) {
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(want.relative[k], got.relative[k], ascii ? 0.0051f * unit : 1e-6f);
  }
  if (want.has_orientation) {
    const glm::quat d = glm::inverse(want.orientation) * got.orientation;
    const float angle = 2.0f * std::atan2(glm::length(glm::vec3(d.x, d.y, d.z)), std::abs(d.w));
    EXPECT_LT(glm::degrees(angle), ascii || a16 ? 0.1f : 1e-3f);
  }
  for (FastrakItem i : format.items) {
    if (i == FastrakItem::kStylus) {
      EXPECT_EQ(want.stylus, got.stylus);
    }
  }
}

struct FormatCase {
  FastrakEncoding encoding;
  LengthUnit units;
  Items items;
};

std::vector<FormatCase> allFormats() {
  std::vector<FormatCase> cases;
  const std::vector<Items> lists = {
      {FastrakItem::kPosition, FastrakItem::kQuaternion, FastrakItem::kSpace},  // VRPN
      {FastrakItem::kPosition, FastrakItem::kEuler, FastrakItem::kStylus,
       FastrakItem::kCrLf},  // Vrui
      {FastrakItem::kPosition, FastrakItem::kSpace, FastrakItem::kEuler,
       FastrakItem::kCrLf},  // Java
      {FastrakItem::kRelativePosition, FastrakItem::kPosition, FastrakItem::kDirectionCosines,
       FastrakItem::kCrLf},
      {FastrakItem::kQuaternion, FastrakItem::kCrLf}};
  for (FastrakEncoding e : {FastrakEncoding::kAscii, FastrakEncoding::kBinary}) {
    for (LengthUnit u : {LengthUnit::kInches, LengthUnit::kCentimetres}) {
      for (const Items& l : lists) cases.push_back({e, u, l});
    }
  }
  cases.push_back({FastrakEncoding::kBinary,
                   LengthUnit::kInches,
                   {FastrakItem::kPosition16, FastrakItem::kQuaternion16, FastrakItem::kSpace}});
  cases.push_back({FastrakEncoding::kBinary,
                   LengthUnit::kCentimetres,
                   {FastrakItem::kPosition16, FastrakItem::kEuler16, FastrakItem::kCrLf}});
  return cases;
}

std::string describe(const FastrakFormat& f) {
  std::string s = f.encoding == FastrakEncoding::kAscii ? "ascii" : "binary";
  s += f.units == LengthUnit::kInches ? " in [" : " cm [";
  for (FastrakItem i : f.items) s += std::to_string(static_cast<int>(i)) + " ";
  return s + "]";
}

TEST(FastrakParser, DecodesEveryFormatWhole) {
  for (const FormatCase& c : allFormats()) {
    const FastrakFormat format{c.encoding, c.units, c.items};
    SCOPED_TRACE(describe(format));
    ASSERT_TRUE(validateFastrakFormat(format).ok());
    const auto records = sampleRecords(format, 12);
    const std::string bytes = encodeAll(records, format);
    ASSERT_EQ(bytes.size(), records.size() * fastrakRecordSize(format));
    FastrakParser parser(format);
    parser.feed(bytesOf(bytes));
    FastrakRecord got;
    for (const FastrakRecord& want : records) {
      ASSERT_TRUE(parser.next(got));
      expectSame(want, got, format);
    }
    EXPECT_FALSE(parser.next(got));
    EXPECT_EQ(parser.discardedBytes(), 0u);
  }
}

TEST(FastrakParser, SplitAtEveryByteAndOneByteAtATime) {
  for (const FormatCase& c : allFormats()) {
    const FastrakFormat format{c.encoding, c.units, c.items};
    SCOPED_TRACE(describe(format));
    const auto records = sampleRecords(format, 3);
    const std::string bytes = encodeAll(records, format);
    for (std::size_t cut = 0; cut <= bytes.size(); ++cut) {
      FastrakParser parser(format);
      std::vector<FastrakRecord> got;
      FastrakRecord r;
      parser.feed(bytesOf(std::string_view(bytes).substr(0, cut)));
      while (parser.next(r)) got.push_back(r);
      EXPECT_EQ(got.size(), cut / fastrakRecordSize(format));  // every complete prefix record
      parser.feed(bytesOf(std::string_view(bytes).substr(cut)));
      while (parser.next(r)) got.push_back(r);
      ASSERT_EQ(got.size(), records.size()) << "cut at " << cut;
      for (std::size_t i = 0; i < got.size(); ++i) expectSame(records[i], got[i], format);
    }
    FastrakParser parser(format);
    std::size_t n = 0;
    FastrakRecord r;
    for (char ch : bytes) {
      parser.feed(bytesOf(std::string_view(&ch, 1)));
      while (parser.next(r)) ++n;
    }
    EXPECT_EQ(n, records.size());
  }
}

TEST(FastrakParser, ResynchronisesAfterGarbage) {
  SimRandom rng(5);
  for (const FormatCase& c : allFormats()) {
    const FastrakFormat format{c.encoding, c.units, c.items};
    SCOPED_TRACE(describe(format));
    const auto records = sampleRecords(format, 20);
    std::string stream;
    std::vector<std::string> encoded;
    for (std::size_t i = 0; i < records.size(); ++i) {
      // Garbage before every other record: random bytes, fake headers, a status reply, and
      // the head of a record cut short (a lost tail).
      if (i % 2 == 1) {
        const int kind = static_cast<int>(i / 2) % 4;
        if (kind == 0) {
          for (int k = 0; k < 13; ++k) stream.push_back(static_cast<char>(rng.next() & 0xFF));
        } else if (kind == 1) {
          stream += "01 0";
          stream += "03X";
        } else if (kind == 2) {
          stream += "21S   status reply with 0123 digits\r\n";
        } else {
          std::string part;
          encodeFastrakRecord(records[i - 1], format, part);
          stream += part.substr(0, part.size() / 2);
        }
      }
      encodeFastrakRecord(records[i], format, stream);
    }
    FastrakParser parser(format);
    std::vector<FastrakRecord> got;
    FastrakRecord r;
    // Feed in uneven chunks.
    for (std::size_t pos = 0; pos < stream.size();) {
      const std::size_t n = std::min<std::size_t>(stream.size() - pos, 1 + rng.next() % 40);
      parser.feed(bytesOf(std::string_view(stream).substr(pos, n)));
      pos += n;
      while (parser.next(r)) got.push_back(r);
    }
    ASSERT_EQ(got.size(), records.size());
    for (std::size_t i = 0; i < got.size(); ++i) expectSame(records[i], got[i], format);
    EXPECT_GT(parser.discardedBytes(), 0u);
  }
}

TEST(FastrakParser, RejectsImplausibleRecords) {
  const FastrakFormat format;  // binary, 2 11 0
  FastrakRecord r;
  r.station = 2;
  r.has_position = r.has_orientation = true;
  r.position = glm::vec3(0.1f, 0.2f, 0.3f);
  std::string good;
  encodeFastrakRecord(r, format, good);
  const auto decode = [&](const std::string& s) {
    FastrakRecord out;
    return decodeFastrakRecord(bytesOf(s), format, out);
  };
  EXPECT_TRUE(decode(good));
  std::string bad = good;
  bad[0] = '2';  // a status record, not data
  EXPECT_FALSE(decode(bad));
  bad = good;
  bad[1] = '5';  // no station 5
  EXPECT_FALSE(decode(bad));
  bad = good;
  bad[2] = '#';  // status must be a space or a letter
  EXPECT_FALSE(decode(bad));
  bad = good;
  bad.back() = 'x';  // the space item
  EXPECT_FALSE(decode(bad));
  bad = good;
  const float nan = std::nanf("");
  std::memcpy(&bad[3], &nan, 4);
  EXPECT_FALSE(decode(bad));
  bad = good;
  const float two = 2.0f;
  std::memcpy(&bad[15], &two, 4);  // quaternion w = 2
  EXPECT_FALSE(decode(bad));
  EXPECT_FALSE(decode(good.substr(1)));
}

TEST(FastrakParser, AsciiSampleLineFromTheJavaDriver) {
  // PROTOCOLS.md: list 2,0,4,1 gives 48-byte records; the driver's sample line.
  const FastrakFormat format{
      FastrakEncoding::kAscii,
      LengthUnit::kInches,
      {FastrakItem::kPosition, FastrakItem::kSpace, FastrakItem::kEuler, FastrakItem::kCrLf}};
  EXPECT_EQ(fastrakRecordSize(format), 48u);
  const std::string line = "01F   0.89   0.04   1.82  -70.55  41.83 -23.48\r\n";
  ASSERT_EQ(line.size(), 48u);
  FastrakRecord r;
  ASSERT_TRUE(decodeFastrakRecord(bytesOf(line), format, r));
  EXPECT_EQ(r.station, 1);
  EXPECT_EQ(r.status, 'F');
  EXPECT_NEAR(r.position.x, 0.89f * 0.0254f, 1e-6f);
  EXPECT_NEAR(r.position.z, 1.82f * 0.0254f, 1e-6f);
  EXPECT_NEAR(r.euler_deg.x, -70.55f, 1e-4f);
  EXPECT_NEAR(r.euler_deg.y, 41.83f, 1e-4f);
  EXPECT_NEAR(r.euler_deg.z, -23.48f, 1e-4f);
  const glm::vec3 back = fastrakQuatToEuler(r.orientation);
  EXPECT_NEAR(back.x, -70.55f, 1e-3f);
  EXPECT_NEAR(back.y, 41.83f, 1e-3f);
  EXPECT_NEAR(back.z, -23.48f, 1e-3f);
}

TEST(FastrakParser, EulerConvention) {
  // Azimuth 90 turns +X to +Y about Z; elevation 90 turns +X to -Z about Y.
  const glm::vec3 x(1, 0, 0);
  glm::vec3 v = fastrakEulerToQuat({90, 0, 0}) * x;
  EXPECT_NEAR(v.y, 1.0f, 1e-6f);
  v = fastrakEulerToQuat({0, 90, 0}) * x;
  EXPECT_NEAR(v.z, -1.0f, 1e-6f);
  v = fastrakEulerToQuat({0, 0, 90}) * glm::vec3(0, 1, 0);
  EXPECT_NEAR(v.z, 1.0f, 1e-6f);
}

TEST(FastrakParser, RejectsBadFormats) {
  EXPECT_FALSE(validateFastrakFormat({FastrakEncoding::kBinary, LengthUnit::kInches, {}}).ok());
  EXPECT_FALSE(
      validateFastrakFormat({FastrakEncoding::kBinary, LengthUnit::kInches, {FastrakItem::kSpace}})
          .ok());
  EXPECT_FALSE(validateFastrakFormat(
                   {FastrakEncoding::kAscii, LengthUnit::kInches, {FastrakItem::kPosition16}})
                   .ok());
  EXPECT_FALSE(fastrakItemFromCode(7).has_value());
  EXPECT_EQ(fastrakItemFromCode(11), FastrakItem::kQuaternion);
}

TEST(FastrakCommands, InitSequence) {
  const FastrakFormat format;
  const int stations[] = {1, 2, 4};
  const auto cmds = fastrakInitCommands(format, stations, true);
  const std::vector<std::string> want = {"c",      "l1,1\r", "O1,2,11,0\r", "l2,1\r", "O2,2,11,0\r",
                                         "l3,0\r", "l4,1\r", "O4,2,11,0\r", "U",      "f",
                                         "C"};
  EXPECT_EQ(cmds, want);
  const FastrakFormat ascii{FastrakEncoding::kAscii,
                            LengthUnit::kCentimetres,
                            {FastrakItem::kPosition, FastrakItem::kCrLf}};
  const auto polled = fastrakInitCommands(ascii, stations, false);
  EXPECT_EQ(polled.back(), "F");
  EXPECT_EQ(polled[polled.size() - 2], "u");
}

}  // namespace
}  // namespace vistel
