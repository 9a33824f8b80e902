// UDP datagrams: exact layout, round trips, and rejection of every malformed input.
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "common/wire/packets.hpp"

namespace vistel::wire {
namespace {

PostureRecord sampleRecord(int joints) {
  Posture p;
  p.root_translation = {0.001f, -0.001f, 1.0f};
  p.rotations.assign(static_cast<std::size_t>(joints), glm::quat(1, 0, 0, 0));
  PostureRecord r;
  EXPECT_TRUE(encodePostureRecord(p, 0x0102, 1.0, r));
  return r;
}

template <typename Packet>
std::vector<std::uint8_t> bytesOf(const Packet& p) {
  std::vector<std::uint8_t> out;
  write(p, out);
  return out;
}

// Every proper prefix and the packet with one extra byte must be refused.
template <typename Packet>
void expectPrefixesRejected(const std::vector<std::uint8_t>& bytes) {
  Packet out;
  ASSERT_TRUE(read(bytes, out));
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    EXPECT_FALSE(read(std::span(bytes.data(), n), out)) << "prefix of " << n << " bytes";
  }
  std::vector<std::uint8_t> longer = bytes;
  longer.push_back(0);
  EXPECT_FALSE(read(longer, out)) << "trailing byte";
}

// The byte-for-byte examples of proto/WIRE.md.
TEST(Packets, HelloLayoutMatchesWireMd) {
  HelloPacket h;
  h.header.member_id = 0x00010002u;
  h.header.counter = 0x1122334455667788ull;
  h.attempt = 3;
  h.cookie = 0x0102030405060708ull;
  const std::vector<std::uint8_t> expected = {0x04, 0x01, 0x02, 0x00, 0x01, 0x00, 0x88, 0x77, 0x66,
                                              0x55, 0x44, 0x33, 0x22, 0x11, 0x03, 0x00, 0x00, 0x00,
                                              0x08, 0x07, 0x06, 0x05, 0x04, 0x03, 0x02, 0x01};
  EXPECT_EQ(bytesOf(h), expected);
  EXPECT_EQ(measure(h), expected.size());
}

TEST(Packets, PostureRecordLayoutMatchesWireMd) {
  std::vector<std::uint8_t> bytes;
  writeRecord(sampleRecord(1), bytes);
  // sequence 0x0102, time 1.0 s = 10000 ticks, 1 joint, root (1, -1, 1000) mm, identity
  // = index 3 (w) with three codes 511.
  const std::vector<std::uint8_t> expected = {0x02, 0x01, 0x10, 0x27, 0x00, 0x00, 0x01, 0x01, 0x00,
                                              0xFF, 0xFF, 0xE8, 0x03, 0xFF, 0xF7, 0xDF, 0x7F};
  EXPECT_EQ(bytes, expected);
}

TEST(Packets, RoundTripsAndPrefixes) {
  HelloPacket hello;
  hello.header = {0x00020003u, 42};
  hello.attempt = 9;
  expectPrefixesRejected<HelloPacket>(bytesOf(hello));

  PosturePacket posture;
  posture.header = {0x00020003u, 42};
  posture.record = sampleRecord(52);
  const auto posture_bytes = bytesOf(posture);
  EXPECT_EQ(posture_bytes.size(), measure(posture));
  expectPrefixesRejected<PosturePacket>(posture_bytes);
  PosturePacket back;
  ASSERT_TRUE(read(posture_bytes, back));
  EXPECT_EQ(back.record.rotations, posture.record.rotations);
  EXPECT_EQ(back.record.root_mm, posture.record.root_mm);
  EXPECT_EQ(back.header.counter, 42u);

  PingPacket ping;
  ping.header = {7, 8};
  ping.ping_id = 5;
  ping.client_time = 12.5;
  expectPrefixesRejected<PingPacket>(bytesOf(ping));

  HelloAckPacket ack{7, 9, 11};
  expectPrefixesRejected<HelloAckPacket>(bytesOf(ack));

  PongPacket pong{5, 99.25};
  expectPrefixesRejected<PongPacket>(bytesOf(pong));
  PongPacket pong_back;
  ASSERT_TRUE(read(bytesOf(pong), pong_back));
  EXPECT_EQ(pong_back.server_time, 99.25);

  // A server must answer a hello with no more bytes than it carried, a ping with fewer
  // (sealing adds the same 16 bytes to both).
  EXPECT_LE(measure(ack), measure(hello));
  EXPECT_LT(measure(pong), measure(ping));
  // The server -> client clear header carries the counter after version and type.
  EXPECT_EQ(bytesOf(ack).size(), kServerHeaderBytes + 16);
  EXPECT_EQ(clearHeaderBytes(PacketType::kHelloAck), kServerHeaderBytes);
  EXPECT_EQ(clearHeaderBytes(PacketType::kSnapshot), kServerHeaderBytes);
  EXPECT_EQ(clearHeaderBytes(PacketType::kPosture), kClientHeaderBytes);
}

TEST(Packets, WrongVersionOrTypeIsRejected) {
  HelloPacket hello;
  auto bytes = bytesOf(hello);
  bytes[0] = 1;  // version 1 (before the collision world) is no longer spoken
  HelloPacket out;
  EXPECT_FALSE(read(bytes, out));
  EXPECT_FALSE(peekPacketType(bytes).has_value());
  bytes[0] = kWireVersion;
  bytes[1] = static_cast<std::uint8_t>(PacketType::kPing);
  EXPECT_FALSE(read(bytes, out));
  bytes[1] = 0x7F;
  EXPECT_FALSE(peekPacketType(bytes).has_value());
}

TEST(Packets, NonFiniteTimesAreRejected) {
  PongPacket pong{1, std::numeric_limits<double>::quiet_NaN()};
  PongPacket out;
  EXPECT_FALSE(read(bytesOf(pong), out));
  PingPacket ping;
  ping.client_time = std::numeric_limits<double>::infinity();
  PingPacket ping_out;
  EXPECT_FALSE(read(bytesOf(ping), ping_out));
}

std::vector<std::uint8_t> makeSnapshot(int members, int joints) {
  std::vector<std::uint8_t> packet;
  SnapshotHeader h;
  h.tick = 77;
  h.server_time = 3.5;
  beginSnapshot(h, packet);
  std::vector<std::uint8_t> record;
  writeRecord(sampleRecord(joints), record);
  for (int m = 0; m < members; ++m) {
    appendSnapshotEntry(0x00010000u + static_cast<std::uint32_t>(m), record, packet);
  }
  finishSnapshot(static_cast<std::uint8_t>(members), packet);
  return packet;
}

TEST(Packets, SnapshotRoundTripEqualsSerializedEntries) {
  const auto packet = makeSnapshot(3, 25);
  Snapshot snap;
  ASSERT_TRUE(readSnapshot(packet, snap));
  const SnapshotHeader& h = snap.header;
  const std::vector<SnapshotEntry>& entries = snap.entries;
  EXPECT_EQ(h.tick, 77u);
  EXPECT_EQ(h.server_time, 3.5);
  ASSERT_EQ(entries.size(), 3u);
  EXPECT_EQ(entries[2].member_id, 0x00010002u);
  EXPECT_EQ(entries[1].record.joint_count, 25);
  // The raw-append path writes exactly what serializing the entry writes.
  std::size_t size = kSnapshotHeaderBytes;
  for (const auto& e : entries) size += measure(e);
  EXPECT_EQ(size, packet.size());
}

TEST(Packets, EverySnapshotPrefixIsRejected) {
  const auto packet = makeSnapshot(2, 10);
  Snapshot snap;
  for (std::size_t n = 0; n < packet.size(); ++n) {
    EXPECT_FALSE(readSnapshot(std::span(packet.data(), n), snap)) << n;
  }
  auto longer = packet;
  longer.push_back(0);
  EXPECT_FALSE(readSnapshot(longer, snap));
  // A count larger than the entries present, and one the datagram cannot possibly hold.
  auto lying = packet;
  lying[22] = 3;
  EXPECT_FALSE(readSnapshot(lying, snap));
  lying[22] = 255;
  EXPECT_FALSE(readSnapshot(lying, snap));
}

TEST(Packets, OversizedDatagramsAreRejected) {
  std::vector<std::uint8_t> big(kMaxDatagramBytes + 1, 0);
  big[0] = kWireVersion;
  big[1] = static_cast<std::uint8_t>(PacketType::kPosture);
  PosturePacket out;
  EXPECT_FALSE(read(big, out));
  EXPECT_FALSE(peekPacketType(big).has_value());
}

// Random bytes (and random mutations of valid packets) never crash a reader; whatever
// a reader accepts re-serializes to the same bytes.
TEST(Packets, GarbageIsRejectedOrReadExactly) {
  std::mt19937 rng(5);
  PosturePacket valid;
  valid.header = {1, 2};
  valid.record = sampleRecord(20);
  const auto base = bytesOf(valid);
  int accepted = 0;
  for (int i = 0; i < 20000; ++i) {
    std::vector<std::uint8_t> bytes;
    if (i % 2 == 0) {
      bytes.resize(rng() % 128);
      for (auto& b : bytes) b = static_cast<std::uint8_t>(rng());
      if (bytes.size() >= 2 && i % 4 == 0) {
        bytes[0] = kWireVersion;
        bytes[1] =
            static_cast<std::uint8_t>(std::vector<int>{1, 2, 3, 0x81, 0x82, 0x83}[rng() % 6]);
      }
    } else {
      bytes = base;
      for (int k = 0; k < 3; ++k) bytes[rng() % bytes.size()] ^= static_cast<std::uint8_t>(rng());
      if (rng() % 3 == 0) bytes.resize(rng() % bytes.size());
    }
    PosturePacket p;
    if (read(bytes, p)) {
      ++accepted;
      EXPECT_EQ(bytesOf(p), bytes);
    }
    HelloPacket h;
    (void)read(bytes, h);
    PingPacket ping;
    (void)read(bytes, ping);
    PongPacket pong;
    (void)read(bytes, pong);
    Snapshot snap;
    (void)readSnapshot(bytes, snap);
  }
  EXPECT_GT(accepted, 0);  // mutated rotations are still valid records
}

}  // namespace
}  // namespace vistel::wire
