// The .vrec voice track (record type 4, common/sensors/recording.hpp): voice packets round
// trip through the writer between frames, a damaged or out-of-range voice record is skipped
// exactly (the frames and the other packets kept), the reader resynchronises on a voice
// record after garbage, a second writer appending to the same file (the client's voice
// beside its PostureSource's frames) keeps every record whole, and files without voice
// (version 1 and 2) read as before.
#include <cstring>
#include <filesystem>
#include <thread>

#include <gtest/gtest.h>

#include "common/base/bytes.hpp"
#include "common/base/file.hpp"
#include "common/sensors/recording.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

RecordingHeader voiceHeader() {
  RecordingHeader h;
  h.participant = "Grace";
  h.source = "sim:wave.bvh";
  h.stations = {{0, BodySite::kHead}, {0, BodySite::kChest}};
  return h;
}

SensorFrame simpleFrame(int k) {
  SensorFrame f;
  f.time = 10.0 + 0.01 * k;
  f.sequence = static_cast<std::uint64_t>(k);
  f.stations[0].valid = true;
  f.stations[0].time = f.time;
  f.stations[0].position = glm::vec3(0.0f, 1.6f, 0.001f * static_cast<float>(k));
  return f;
}

// A packet whose bytes say which it is (size 3 + k % 50).
std::vector<std::uint8_t> packetFor(int k) {
  std::vector<std::uint8_t> p(3 + static_cast<std::size_t>(k % 50));
  for (std::size_t i = 0; i < p.size(); ++i) p[i] = static_cast<std::uint8_t>(k + 7 * i);
  return p;
}

// Header, 30 frames 10 ms apart, a voice packet after every second frame (20 ms apart).
std::vector<std::uint8_t> voicedBytes(std::vector<std::size_t>* voice_starts = nullptr) {
  std::vector<std::uint8_t> bytes;
  encodeRecordingFileHeader(bytes);
  encodeHeaderRecord(voiceHeader(), bytes);
  for (int k = 0; k < 30; ++k) {
    encodeFrameRecord(simpleFrame(k), bytes);
    if (k % 2 == 1) {
      if (voice_starts) voice_starts->push_back(bytes.size());
      encodeVoiceRecord(10.0 + 0.01 * (k - 1), packetFor(k / 2), bytes);
    }
  }
  return bytes;
}

TEST(RecordingVoice, PacketsRoundTripThroughTheWriterBetweenFrames) {
  const std::string path = test::scratchDir() + "/voiced.vrec";
  {
    auto writer = RecordingWriter::create(path, voiceHeader());
    ASSERT_TRUE(writer) << writer.error().message;
    for (int k = 0; k < 30; ++k) {
      ASSERT_TRUE((*writer)->append(simpleFrame(k)));
      if (k % 2 == 1) {
        ASSERT_TRUE((*writer)->appendVoice(10.0 + 0.01 * (k - 1), packetFor(k / 2)));
      }
    }
    EXPECT_EQ((*writer)->voiceWritten(), 15u);
    // Not recordable: nothing written, an error naming the file.
    const std::vector<std::uint8_t> empty, huge(kRecordingMaxVoicePacket + 1, 1);
    EXPECT_FALSE((*writer)->appendVoice(11.0, empty));
    EXPECT_FALSE((*writer)->appendVoice(11.0, huge));
    auto nan = (*writer)->appendVoice(std::nan(""), packetFor(1));
    ASSERT_FALSE(nan);
    EXPECT_NE(nan.error().message.find(path), std::string::npos);
  }
  auto rec = loadRecording(path);
  ASSERT_TRUE(rec) << rec.error().message;
  EXPECT_TRUE(rec->complete) << rec->stop_reason;
  ASSERT_EQ(rec->frames.size(), 30u);
  ASSERT_EQ(rec->voice.size(), 15u);
  for (int i = 0; i < 15; ++i) {
    EXPECT_DOUBLE_EQ(rec->voice[i].time, 10.0 + 0.02 * i);
    EXPECT_EQ(rec->voice[i].packet, packetFor(i));
  }
  // The same bytes as the encoder's, and the largest packet fits.
  auto bytes = readFileBytes(path);
  ASSERT_TRUE(bytes);
  EXPECT_EQ(*bytes, voicedBytes());
  std::vector<std::uint8_t> big = voicedBytes();
  encodeVoiceRecord(12.0, std::vector<std::uint8_t>(kRecordingMaxVoicePacket, 0xab), big);
  auto decoded = decodeRecording(big, "big");
  ASSERT_TRUE(decoded);
  EXPECT_TRUE(decoded->complete) << decoded->stop_reason;
  ASSERT_EQ(decoded->voice.size(), 16u);
  EXPECT_EQ(decoded->voice.back().packet.size(), kRecordingMaxVoicePacket);
}

TEST(RecordingVoice, DamagedVoiceRecordIsSkippedAndEverythingElseKept) {
  std::vector<std::size_t> starts;
  const std::vector<std::uint8_t> good = voicedBytes(&starts);
  // A flipped byte in the 5th packet: its CRC fails; the reader resynchronises on the
  // frame after it.
  {
    std::vector<std::uint8_t> bytes = good;
    bytes[starts[4] + 20] ^= 0x40;
    auto rec = decodeRecording(bytes, "flipped.vrec");
    ASSERT_TRUE(rec) << rec.error().message;
    EXPECT_FALSE(rec->complete);
    ASSERT_EQ(rec->damage.size(), 1u) << rec->stop_reason;
    EXPECT_EQ(rec->damage[0].offset, starts[4]);
    EXPECT_EQ(rec->damage[0].why, "checksum mismatch");
    EXPECT_EQ(rec->frames.size(), 30u);
    ASSERT_EQ(rec->voice.size(), 14u);
    EXPECT_EQ(rec->voice[4].packet, packetFor(5));
    EXPECT_NE(rec->stop_reason.find("flipped.vrec"), std::string::npos);
  }
  // Well framed (CRC right) but out of range: a packet size beyond the record, a zero-length
  // packet, a non-finite time. Each is skipped exactly, naming why.
  struct Bad {
    const char* what;
    std::vector<std::uint8_t> payload;
    const char* why;
  };
  std::vector<Bad> bads;
  {
    std::vector<std::uint8_t> p;
    ByteWriter w(p);
    w.f64(10.5);
    w.u16(40);  // 40 claimed, 3 present
    w.u8(1), w.u8(2), w.u8(3);
    bads.push_back({"size beyond the record", p, "voice packet of 40 bytes in 3"});
  }
  {
    std::vector<std::uint8_t> p;
    ByteWriter w(p);
    w.f64(10.5);
    w.u16(0);
    bads.push_back({"empty packet", p, "voice packet of 0 bytes"});
  }
  {
    std::vector<std::uint8_t> p;
    ByteWriter w(p);
    w.f64(std::numeric_limits<double>::infinity());
    w.u16(1);
    w.u8(9);
    bads.push_back({"infinite time", p, "not finite"});
  }
  {
    std::vector<std::uint8_t> p;
    ByteWriter w(p);
    w.f64(10.5);
    w.u16(static_cast<std::uint16_t>(kRecordingMaxVoicePacket + 1));
    for (std::size_t i = 0; i <= kRecordingMaxVoicePacket; ++i) w.u8(0);
    bads.push_back({"packet over 1275 bytes", p, "voice packet of 1276 bytes"});
  }
  for (const Bad& bad : bads) {
    SCOPED_TRACE(bad.what);
    std::vector<std::uint8_t> record;
    ByteWriter w(record);
    w.u32(static_cast<std::uint32_t>(bad.payload.size()));
    w.u8(4);
    record.insert(record.end(), bad.payload.begin(), bad.payload.end());
    ByteWriter(record).u32(
        crc32(std::span<const std::uint8_t>(record).subspan(4, bad.payload.size() + 1)));
    std::vector<std::uint8_t> bytes(good.begin(), good.begin() + starts[2]);
    bytes.insert(bytes.end(), record.begin(), record.end());
    bytes.insert(bytes.end(), good.begin() + starts[2], good.end());
    auto rec = decodeRecording(bytes, "bad.vrec");
    ASSERT_TRUE(rec) << rec.error().message;
    ASSERT_EQ(rec->damage.size(), 1u) << rec->stop_reason;
    EXPECT_EQ(rec->damage[0].offset, starts[2]);
    EXPECT_EQ(rec->damage[0].bytes, record.size());
    EXPECT_NE(rec->damage[0].why.find(bad.why), std::string::npos) << rec->damage[0].why;
    EXPECT_EQ(rec->frames.size(), 30u);
    EXPECT_EQ(rec->voice.size(), 15u);
  }
}

TEST(RecordingVoice, ResynchronisesOnAVoiceRecordAfterGarbage) {
  std::vector<std::size_t> starts;
  const std::vector<std::uint8_t> good = voicedBytes(&starts);
  // Garbage right before the 8th packet: the next record that frames is that packet.
  std::vector<std::uint8_t> bytes(good.begin(), good.begin() + starts[7]);
  for (int i = 0; i < 37; ++i) bytes.push_back(static_cast<std::uint8_t>(0xa5 ^ i));
  bytes.insert(bytes.end(), good.begin() + starts[7], good.end());
  auto rec = decodeRecording(bytes, "slipped.vrec");
  ASSERT_TRUE(rec);
  ASSERT_EQ(rec->damage.size(), 1u) << rec->stop_reason;
  EXPECT_EQ(rec->damage[0].bytes, 37u);
  EXPECT_EQ(rec->voice.size(), 15u);
  EXPECT_EQ(rec->frames.size(), 30u);
  // A cut in the last packet: every earlier record kept.
  std::vector<std::uint8_t> cut(good.begin(), good.end() - 4);
  auto tail = decodeRecording(cut, "cut.vrec");
  ASSERT_TRUE(tail);
  EXPECT_EQ(tail->voice.size(), 14u);
  EXPECT_EQ(tail->frames.size(), 30u);
  EXPECT_FALSE(tail->complete);
}

TEST(RecordingVoice, SecondWriterAppendsWholeRecordsBesideTheFirst) {
  const std::string path = test::scratchDir() + "/two_writers.vrec";
  auto frames = RecordingWriter::create(path, voiceHeader());
  ASSERT_TRUE(frames) << frames.error().message;
  auto voice = RecordingWriter::appendTo(path);
  ASSERT_TRUE(voice) << voice.error().message;
  std::thread voice_thread([&] {
    for (int i = 0; i < 400; ++i) ASSERT_TRUE((*voice)->appendVoice(0.02 * i, packetFor(i)));
  });
  for (int k = 0; k < 800; ++k) ASSERT_TRUE((*frames)->append(simpleFrame(k)));
  voice_thread.join();
  auto rec = loadRecording(path);
  ASSERT_TRUE(rec);
  EXPECT_TRUE(rec->complete) << rec->stop_reason;
  EXPECT_EQ(rec->frames.size(), 800u);
  ASSERT_EQ(rec->voice.size(), 400u);
  for (int i = 0; i < 400; ++i) EXPECT_EQ(rec->voice[i].packet, packetFor(i));
  // Not a recording: refused, naming the file.
  const std::string text = test::scratchDir() + "/text.vrec";
  ASSERT_TRUE(writeFileText(text, "hello, not a recording"));
  auto refused = RecordingWriter::appendTo(text);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find(text), std::string::npos);
  EXPECT_FALSE(RecordingWriter::appendTo(test::scratchDir() + "/missing.vrec"));
}

TEST(RecordingVoice, FilesWithoutVoiceReadAsBefore) {
  for (std::uint32_t version : {1u, 2u}) {
    SCOPED_TRACE(version);
    std::vector<std::uint8_t> bytes;
    encodeRecordingFileHeader(bytes, version);
    encodeHeaderRecord(voiceHeader(), bytes, version);
    for (int k = 0; k < 5; ++k) encodeFrameRecord(simpleFrame(k), bytes, version);
    auto rec = decodeRecording(bytes, "old.vrec");
    ASSERT_TRUE(rec);
    EXPECT_TRUE(rec->complete);
    EXPECT_EQ(rec->frames.size(), 5u);
    EXPECT_TRUE(rec->voice.empty());
    // A voice record fits either version.
    encodeVoiceRecord(10.0, packetFor(3), bytes);
    auto voiced = decodeRecording(bytes, "old.vrec");
    ASSERT_TRUE(voiced);
    EXPECT_TRUE(voiced->complete);
    EXPECT_EQ(voiced->voice.size(), 1u);
  }
}

}  // namespace
}  // namespace vistel
