// CyberGlove-class 'G' records: 18 and 22 sensors, with and without timestamp and status
// byte, split at every byte, error codes, garbage, bad reads; calibration to radians.
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/sensors/cyberglove_protocol.hpp"
#include "common/sensors/io/byte_transport.hpp"
#include "common/sensors/random.hpp"

namespace vistel {
namespace {

GloveRecord sample(int n, std::uint64_t seed) {
  SimRandom rng(seed);
  GloveRecord r;
  r.sensor_count = n;
  for (int i = 0; i < n; ++i)
    r.raw[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(1 + rng.next() % 255);
  r.timestamp = rng.next() & 0xFFFFFFFFFFull;
  r.status = static_cast<std::uint8_t>(rng.next() & 0xFF);
  return r;
}

std::vector<GloveFormat> formats() {
  std::vector<GloveFormat> out;
  for (int n : {18, 22}) {
    for (bool ts : {false, true}) {
      for (bool st : {false, true}) out.push_back({n, ts, st});
    }
  }
  return out;
}

void expectSame(const GloveRecord& a, const GloveRecord& b, const GloveFormat& f) {
  ASSERT_EQ(b.kind, GloveRecord::Kind::kSample);
  EXPECT_EQ(a.sensor_count, b.sensor_count);
  for (int i = 0; i < f.sensor_count; ++i)
    EXPECT_EQ(a.raw[static_cast<std::size_t>(i)], b.raw[static_cast<std::size_t>(i)]);
  if (f.timestamp) {
    EXPECT_EQ(a.timestamp, b.timestamp);
  }
  if (f.status_byte) {
    EXPECT_EQ(a.status, b.status);
  }
}

TEST(CyberGloveParser, EveryFormatSplitAtEveryByte) {
  for (const GloveFormat& f : formats()) {
    SCOPED_TRACE(::testing::Message()
                 << f.sensor_count << " ts " << f.timestamp << " st " << f.status_byte);
    ASSERT_TRUE(validateGloveFormat(f).ok());
    std::vector<GloveRecord> records;
    std::string bytes;
    for (int i = 0; i < 3; ++i) {
      records.push_back(sample(f.sensor_count, 100 + static_cast<std::uint64_t>(i)));
      encodeGloveRecord(records.back(), f, bytes);
    }
    EXPECT_EQ(bytes.size(), 3 * gloveRecordSize(f));
    for (std::size_t cut = 0; cut <= bytes.size(); ++cut) {
      CyberGloveParser parser(f);
      std::vector<GloveRecord> got;
      GloveRecord r;
      parser.feed(bytesOf(std::string_view(bytes).substr(0, cut)));
      while (parser.next(r)) got.push_back(r);
      parser.feed(bytesOf(std::string_view(bytes).substr(cut)));
      while (parser.next(r)) got.push_back(r);
      ASSERT_EQ(got.size(), records.size()) << "cut " << cut;
      for (std::size_t i = 0; i < got.size(); ++i) expectSame(records[i], got[i], f);
    }
  }
}

TEST(CyberGloveParser, RecordSizes) {
  EXPECT_EQ(gloveRecordSize({22, false, false}), 24u);
  EXPECT_EQ(gloveRecordSize({18, false, false}), 20u);
  EXPECT_EQ(gloveRecordSize({22, true, true}), 30u);
  EXPECT_FALSE(validateGloveFormat({20, false, false}).ok());
}

TEST(CyberGloveParser, ErrorsGarbageAndBadReads) {
  const GloveFormat f{22, false, false};
  // Raw values that are neither 'G' nor 'e', so the test knows exactly what to expect.
  auto fixed = [](int base) {
    GloveRecord r;
    r.sensor_count = 22;
    for (int i = 0; i < 22; ++i)
      r.raw[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(base + i);
    return r;
  };
  const GloveRecord a = fixed(2), b = fixed(30), c = fixed(130);
  std::string s;
  s += "\x13junk";  // line noise
  encodeGloveRecord(a, f, s);
  s += std::string("es\0", 3);  // sampling error with its NUL
  s += "eg";                    // glove unplugged, no NUL
  s += "G";                     // a record cut short by an error
  s += "es";
  std::string bad;
  encodeGloveRecord(b, f, bad);
  bad[5] = '\0';  // a zero sensor byte: a bad read
  s += bad;
  encodeGloveRecord(b, f, s);
  s += "ex";  // not an error code
  encodeGloveRecord(c, f, s);

  CyberGloveParser parser(f);
  std::vector<GloveRecord> got;
  GloveRecord r;
  for (char ch : s) {  // one byte at a time
    parser.feed(bytesOf(std::string_view(&ch, 1)));
    while (parser.next(r)) got.push_back(r);
  }
  ASSERT_EQ(got.size(), 6u);
  expectSame(a, got[0], f);
  EXPECT_EQ(got[1].kind, GloveRecord::Kind::kError);
  EXPECT_EQ(got[1].error_code, 's');
  EXPECT_EQ(got[2].error_code, 'g');
  EXPECT_EQ(got[3].error_code, 's');
  expectSame(b, got[4], f);
  expectSame(c, got[5], f);
  EXPECT_EQ(gloveErrorText('g'), "glove not plugged in");
  EXPECT_GT(parser.discardedBytes(), 0u);
}

TEST(CyberGloveParser, RandomGarbageNeverCrashes) {
  const GloveFormat f{18, true, true};
  CyberGloveParser parser(f);
  SimRandom rng(9);
  GloveRecord r;
  std::string chunk;
  for (int round = 0; round < 2000; ++round) {
    chunk.clear();
    const int n = static_cast<int>(rng.next() % 64);
    for (int i = 0; i < n; ++i) chunk.push_back(static_cast<char>(rng.next() & 0xFF));
    parser.feed(bytesOf(chunk));
    while (parser.next(r)) {
      if (r.kind == GloveRecord::Kind::kSample) {
        for (int i = 0; i < r.sensor_count; ++i) EXPECT_NE(r.raw[static_cast<std::size_t>(i)], 0);
      }
    }
  }
}

TEST(GloveCalibration, DefaultAndEighteenSensorFill) {
  const GloveCalibration c22 = defaultGloveCalibration(22);
  ASSERT_EQ(c22.sensors.size(), 22u);
  GloveRecord r;
  r.sensor_count = 22;
  r.raw.fill(1);
  GloveReading out;
  applyGloveCalibration(r, c22, out);
  EXPECT_TRUE(out.valid);
  EXPECT_NEAR(out.angles[kIndexMpj], 0.0f, 1e-5f);
  EXPECT_NEAR(out.angles[kWristPitch], glm::radians(-60.0f), 1e-5f);
  r.raw.fill(255);
  applyGloveCalibration(r, c22, out);
  EXPECT_NEAR(out.angles[kIndexMpj], glm::radians(90.0f), 1e-5f);
  EXPECT_NEAR(out.angles[kMiddleIndexAbduction], glm::radians(30.0f), 1e-5f);

  const GloveCalibration c18 = defaultGloveCalibration(18);
  ASSERT_EQ(c18.sensors.size(), 18u);
  ASSERT_EQ(gloveSlots(18).size(), 18u);
  r.sensor_count = 18;
  r.raw.fill(128);
  GloveReading out18;
  applyGloveCalibration(r, c18, out18);
  EXPECT_NEAR(out18.angles[kIndexDij], out18.angles[kIndexPij] * 2.0f / 3.0f, 1e-6f);
  EXPECT_NEAR(out18.angles[kPinkyDij], out18.angles[kPinkyPij] * 2.0f / 3.0f, 1e-6f);
  EXPECT_GT(out18.angles[kPinkyPij], 0.5f);
  // Gain/offset/clamp: angle = gain * (raw - offset), clamped.
  GloveCalibration custom = c18;
  custom.sensors[0] = {0.01f, 100.0f, -0.1f, 0.2f};
  r.raw[0] = 120;
  applyGloveCalibration(r, custom, out18);
  EXPECT_NEAR(out18.angles[kThumbRotation], 0.2f, 1e-6f);
  r.raw[0] = 105;
  applyGloveCalibration(r, custom, out18);
  EXPECT_NEAR(out18.angles[kThumbRotation], 0.05f, 1e-6f);
}

TEST(GloveCommands, Bytes) {
  EXPECT_EQ(gloveSetSensorCountCommand(18), std::string("N\x12", 2));
  EXPECT_EQ(gloveSetTimestampCommand(true), std::string("D\x01", 2));
  EXPECT_EQ(gloveSetStatusByteCommand(false), std::string("U\0", 2));
}

}  // namespace
}  // namespace vistel
