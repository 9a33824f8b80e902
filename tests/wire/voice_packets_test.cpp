// Voice datagrams (common/wire/voice_packets.hpp, proto/WIRE.md §3.10): the byte layout of
// the examples in WIRE.md, round trips, and a clear refusal of every malformed input.
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/wire/voice_packets.hpp"

namespace vistel::wire {
namespace {

const std::vector<std::uint8_t> kOpus = {0x48, 0x0B, 0xE4};  // any bytes: never decoded here

VoicePacket sampleVoice() {
  VoicePacket p;
  p.header.member_id = 0x00010002u;
  p.header.counter = 0x1122334455667788ull;
  p.frame.sequence = 0x0102;
  p.frame.capture_time = 0x0A0B0C0Du;
  p.frame.level = 23;
  p.payload = kOpus;
  return p;
}

TEST(VoicePackets, VoiceLayoutMatchesWireMd) {
  std::vector<std::uint8_t> bytes;
  ASSERT_TRUE(writeVoice(sampleVoice(), bytes));
  const std::vector<std::uint8_t> expected = {0x04, 0x04, 0x02, 0x00, 0x01, 0x00, 0x88, 0x77,
                                              0x66, 0x55, 0x44, 0x33, 0x22, 0x11, 0x02, 0x01,
                                              0x0D, 0x0C, 0x0B, 0x0A, 0x17, 0x48, 0x0B, 0xE4};
  EXPECT_EQ(bytes, expected);
  EXPECT_EQ(peekPacketType(bytes), PacketType::kVoice);
  EXPECT_EQ(peekMemberId(bytes), 0x00010002u);
  EXPECT_EQ(clearHeaderBytes(PacketType::kVoice), kClientHeaderBytes);

  VoicePacket read;
  ASSERT_TRUE(readVoice(bytes, read));
  EXPECT_EQ(read.header.member_id, 0x00010002u);
  EXPECT_EQ(read.header.counter, 0x1122334455667788ull);
  EXPECT_EQ(read.frame.sequence, 0x0102);
  EXPECT_EQ(read.frame.capture_time, 0x0A0B0C0Du);
  EXPECT_EQ(read.frame.level, 23);
  EXPECT_EQ(std::vector<std::uint8_t>(read.payload.begin(), read.payload.end()), kOpus);
}

TEST(VoicePackets, VoiceForwardLayoutMatchesWireMd) {
  VoiceForwardPacket p;
  p.counter = 5;
  p.speaker_id = 0x00030004u;
  p.frame = sampleVoice().frame;
  p.payload = kOpus;
  std::vector<std::uint8_t> bytes;
  ASSERT_TRUE(writeVoiceForward(p, bytes));
  const std::vector<std::uint8_t> expected = {0x04, 0x84, 0x05, 0x00, 0x00, 0x00, 0x00, 0x00,
                                              0x00, 0x00, 0x04, 0x00, 0x03, 0x00, 0x02, 0x01,
                                              0x0D, 0x0C, 0x0B, 0x0A, 0x17, 0x48, 0x0B, 0xE4};
  EXPECT_EQ(bytes, expected);
  EXPECT_EQ(peekPacketType(bytes), PacketType::kVoiceForward);
  EXPECT_EQ(clearHeaderBytes(PacketType::kVoiceForward), kServerHeaderBytes);
  VoiceForwardPacket read;
  ASSERT_TRUE(readVoiceForward(bytes, read));
  EXPECT_EQ(read.counter, 5u);
  EXPECT_EQ(read.speaker_id, 0x00030004u);
  EXPECT_EQ(read.frame.capture_time, 0x0A0B0C0Du);
  EXPECT_EQ(read.payload.size(), kOpus.size());
}

TEST(VoicePackets, LargestPayloadFitsAndOneMoreIsRefused) {
  std::vector<std::uint8_t> opus(kMaxVoicePayloadBytes, 0x5A);
  VoicePacket p = sampleVoice();
  p.payload = opus;
  std::vector<std::uint8_t> bytes;
  ASSERT_TRUE(writeVoice(p, bytes));
  EXPECT_EQ(bytes.size(), kMaxVoiceDatagramBytes);
  EXPECT_LE(bytes.size() + kSealOverheadBytes, kMaxDatagramBytes);
  VoicePacket read;
  EXPECT_TRUE(readVoice(bytes, read));

  opus.push_back(0);
  p.payload = opus;
  std::vector<std::uint8_t> more;
  const Status refused = writeVoice(p, more);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("401 bytes"), std::string::npos)
      << refused.error().message;
  EXPECT_TRUE(more.empty());  // nothing appended
  bytes.push_back(0x5A);      // the same on reading
  const Status too_long = readVoice(bytes, read);
  ASSERT_FALSE(too_long);
  EXPECT_NE(too_long.error().message.find("at most 400"), std::string::npos);
}

TEST(VoicePackets, MalformedDatagramsAreRefusedSayingWhy) {
  std::vector<std::uint8_t> good;
  ASSERT_TRUE(writeVoice(sampleVoice(), good));
  VoicePacket read;
  auto why = [&](const std::vector<std::uint8_t>& bytes) {
    const Status st = readVoice(bytes, read);
    return st ? std::string("accepted") : st.error().message;
  };
  // Every prefix: a header cut short, or no payload.
  for (std::size_t n = 0; n < good.size() - kOpus.size() + 1; ++n) {
    const std::string reason = why(std::vector<std::uint8_t>(good.begin(), good.begin() + n));
    EXPECT_NE(reason, "accepted") << n;
  }
  EXPECT_NE(why(std::vector<std::uint8_t>(good.begin(), good.begin() + kVoiceHeaderBytes))
                .find("empty Opus payload"),
            std::string::npos);
  EXPECT_NE(why(std::vector<std::uint8_t>(good.begin(), good.begin() + 10)).find("shorter"),
            std::string::npos);
  std::vector<std::uint8_t> bad = good;
  bad[0] = 3;
  EXPECT_NE(why(bad).find("version 3"), std::string::npos) << why(bad);
  bad = good;
  bad[1] = 0x02;
  EXPECT_NE(why(bad).find("type 0x02"), std::string::npos) << why(bad);
  bad = good;
  bad[20] = 128;  // level
  EXPECT_NE(why(bad).find("level 128"), std::string::npos) << why(bad);
  std::vector<std::uint8_t> huge(kMaxPlainDatagramBytes + 1, 0);
  EXPECT_NE(why(huge).find("1185 bytes"), std::string::npos) << why(huge);
  // A voice forward is not a voice datagram, nor the other way round.
  VoiceForwardPacket forward;
  EXPECT_FALSE(readVoiceForward(good, forward));
}

TEST(VoicePackets, LevelFieldIsMinusDbfsClamped) {
  EXPECT_EQ(voiceLevelField(-23.4f), 23);
  EXPECT_EQ(voiceLevelField(0.0f), 0);
  EXPECT_EQ(voiceLevelField(3.0f), 0);
  EXPECT_EQ(voiceLevelField(-200.0f), kVoiceLevelSilent);
  EXPECT_EQ(voiceLevelField(std::numeric_limits<float>::quiet_NaN()), kVoiceLevelSilent);
}

}  // namespace
}  // namespace vistel::wire
