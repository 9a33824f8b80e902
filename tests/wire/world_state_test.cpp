// The collision world in snapshots (proto/WIRE.md §3.6-3.8): prop states and interaction
// sections, the byte example of WIRE.md, round trips through the one serialize function,
// the incremental server path, every prefix rejected, malformed sections rejected, and the
// bytes they take.
#include <cstdio>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "common/wire/packets.hpp"

namespace vistel::wire {
namespace {

InteractionSection sampleSection() {
  InteractionSection x;
  x.member_ids = {0x00010001u, 0x00020002u};
  x.prop_ids = {0x00010000u};
  x.pairs = {{0, 3, 1, 4}, {1, 0, 2, 0}};
  return x;
}

Snapshot sampleSnapshot() {
  Snapshot s;
  s.header.counter = 9;
  s.header.tick = 5;
  s.header.server_time = 2.0;
  s.header.part = 0;
  s.header.part_count = 1;
  s.header.posture_ack = 0x1234;
  s.header.ack_flags = kAckValid;
  s.props.push_back(encodePropState(0x00010000u, {0.0f, 1.5f, 0.0f}, {0.0f, -1.0f, 0.0f}));
  s.interactions = sampleSection();
  return s;
}

std::vector<std::uint8_t> bytesOf(const Snapshot& s) {
  std::vector<std::uint8_t> out;
  write(s, out);
  return out;
}

// The example of proto/WIRE.md §3.8, byte for byte.
TEST(WorldState, SnapshotLayoutMatchesWireMd) {
  const std::vector<std::uint8_t> expected = {
      0x04, 0x82,                                      // version 4, snapshot
      0x09, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,  // counter 9 (set by sealing)
      0x05, 0x00, 0x00, 0x00,                          // tick 5
      0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x40,  // 2.0 s
      0x00, 0x01, 0x00, 0x01,                          // 0 entries, 1 prop, part 0 of 1
      0x34, 0x12, 0x01,                                // posture 0x1234 acknowledged
      0x00, 0x00, 0x01, 0x00,                          // prop 0x00010000
      0x00, 0x00, 0xDC, 0x05, 0x00, 0x00,              // at (0, 1500, 0) mm
      0x00, 0x00, 0x18, 0xFC, 0x00, 0x00,              // moving (0, -1000, 0) mm/s
      0x00, 0x02, 0x01,                                // flags 0, 2 members, 1 prop
      0x01, 0x00, 0x01, 0x00, 0x02, 0x00, 0x02, 0x00,  // member ids
      0x00, 0x00, 0x01, 0x00,                          // prop id
      0x02, 0x00,                                      // 2 pairs of 2 + 12 + 2 + 12 bits
      0x0C, 0x40, 0x04, 0x10, 0x00, 0x08, 0x00,        // (0,3)-(1,4), (1,0)-(2,0)
  };
  const auto bytes = bytesOf(sampleSnapshot());
  EXPECT_EQ(bytes, expected);
  EXPECT_EQ(measure(sampleSnapshot()), expected.size());
  Snapshot back;
  ASSERT_TRUE(readSnapshot(bytes, back));
  EXPECT_EQ(back.interactions.pairs, sampleSection().pairs);
  EXPECT_EQ(back.interactions.member_ids, sampleSection().member_ids);
  EXPECT_EQ(back.props[0].prop_id, 0x00010000u);
  EXPECT_FLOAT_EQ(propPosition(back.props[0]).y, 1.5f);
  EXPECT_FLOAT_EQ(propVelocity(back.props[0]).y, -1.0f);
}

// The server's path (a header, raw record bytes, world bytes serialized once, the count
// patched) writes exactly what serializing the whole Snapshot writes.
TEST(WorldState, IncrementalPathEqualsSerializedSnapshot) {
  Posture p;
  p.root_translation = {0.1f, 1.0f, -0.2f};
  p.rotations.assign(52, glm::angleAxis(0.3f, glm::vec3(0.0f, 1.0f, 0.0f)));
  Snapshot s = sampleSnapshot();
  s.entries.resize(2);
  for (std::size_t i = 0; i < 2; ++i) {
    s.entries[i].member_id = 0x00030000u + static_cast<std::uint32_t>(i);
    ASSERT_TRUE(
        encodePostureRecord(p, static_cast<std::uint16_t>(i + 1), 1.5, s.entries[i].record));
  }
  s.header.entry_count = 2;
  s.header.prop_count = 1;
  std::vector<std::uint8_t> packet;
  beginSnapshot(s.header, packet);
  for (const SnapshotEntry& e : s.entries) {
    std::vector<std::uint8_t> record;
    writeRecord(e.record, record);
    appendSnapshotEntry(e.member_id, record, packet);
  }
  std::vector<std::uint8_t> world;
  writeSnapshotWorld(s.props, &s.interactions, world);
  appendSnapshotWorld(world, packet);
  finishSnapshot(2, packet);
  EXPECT_EQ(packet, bytesOf(s));
  EXPECT_EQ(packet.size(), measure(s));
  Snapshot back;
  ASSERT_TRUE(readSnapshot(packet, back));
  EXPECT_EQ(back.entries.size(), 2u);
  EXPECT_EQ(back.entries[1].record.rotations, s.entries[1].record.rotations);
  EXPECT_EQ(back.interactions.pairs, s.interactions.pairs);
}

TEST(WorldState, EveryPrefixAndATrailingByteAreRejected) {
  for (const Snapshot& s : {sampleSnapshot(), [] {
                              Snapshot empty;  // an empty section: no bodies, no pairs
                              empty.header.part_count = 1;
                              return empty;
                            }()}) {
    const auto bytes = bytesOf(s);
    Snapshot out;
    ASSERT_TRUE(readSnapshot(bytes, out));
    for (std::size_t n = 0; n < bytes.size(); ++n) {
      EXPECT_FALSE(readSnapshot(std::span(bytes.data(), n), out)) << "prefix of " << n;
    }
    auto longer = bytes;
    longer.push_back(0);
    EXPECT_FALSE(readSnapshot(longer, out));
  }
}

TEST(WorldState, MalformedSectionsAreRejected) {
  const auto good = bytesOf(sampleSnapshot());
  Snapshot out;
  const std::size_t section = kSnapshotHeaderBytes + kPropStateBytes;  // flags byte
  // Unknown flag bits (bit 0 truncated and bit 1 self-contact omitted are defined).
  auto bad = good;
  bad[section] = 0x04;
  EXPECT_FALSE(readSnapshot(bad, out));
  bad[section] = 0x03;
  EXPECT_TRUE(readSnapshot(bad, out));
  // Unknown acknowledgement flags (the header's last byte).
  bad = good;
  bad[kSnapshotHeaderBytes - 1] = 0x04;
  EXPECT_FALSE(readSnapshot(bad, out));
  // A body index past the table (3 bodies: index 3 fits the 2-bit field).
  bad = good;
  bad[section + 17] |= 0x03;  // body_a of the first pair = 3
  EXPECT_FALSE(readSnapshot(bad, out));
  // Non-zero padding (one pair of 28 bits: the last 4 bits of its 4 bytes are padding).
  Snapshot one = sampleSnapshot();
  one.interactions.pairs.resize(1);
  bad = bytesOf(one);
  ASSERT_TRUE(readSnapshot(bad, out));
  bad.back() |= 0x80;
  EXPECT_FALSE(readSnapshot(bad, out));
  // A pair count the bytes cannot hold.
  bad = good;
  bad[section + 15] = 0xFF;
  EXPECT_FALSE(readSnapshot(bad, out));
  // Part index past the part count; more parts than allowed; a part index without parts.
  bad = good;
  bad[24] = 1;
  EXPECT_FALSE(readSnapshot(bad, out));
  bad = good;
  bad[25] = kMaxInteractionParts + 1;
  EXPECT_FALSE(readSnapshot(bad, out));
  // Pairs without bodies.
  InteractionSection x;
  x.pairs.push_back({});
  Snapshot s;
  s.header.part_count = 1;
  s.interactions = x;
  EXPECT_FALSE(readSnapshot(bytesOf(s), out));
  // A prop count the bytes cannot hold.
  bad = good;
  bad[23] = 200;
  EXPECT_FALSE(readSnapshot(bad, out));
}

TEST(WorldState, PropStatesQuantizeToAMillimetre) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> pos(-30.0f, 30.0f);
  for (int i = 0; i < 1000; ++i) {
    const glm::vec3 p(pos(rng), pos(rng), pos(rng));
    const glm::vec3 v(pos(rng), pos(rng), pos(rng));
    const PropStateRecord r = encodePropState(7, p, v);
    EXPECT_LE(glm::length(propPosition(r) - p), 0.5e-3f * 1.8f);
    EXPECT_LE(glm::length(propVelocity(r) - v), 0.5e-3f * 1.8f);
  }
  // Beyond the range: clamped; not finite: zero.
  const PropStateRecord far = encodePropState(7, {100.0f, -100.0f, NAN}, {INFINITY, 0.0f, 0.0f});
  EXPECT_EQ(far.position_mm[0], 32767);
  EXPECT_EQ(far.position_mm[1], -32767);
  EXPECT_EQ(far.position_mm[2], 0);
  EXPECT_EQ(far.velocity_mm_s[0], 0);
}

// Random sections round-trip exactly; garbage never crashes the reader and what it
// accepts re-serializes to the same bytes.
TEST(WorldState, RandomSectionsRoundTripAndGarbageIsSafe) {
  std::mt19937 rng(11);
  for (int i = 0; i < 500; ++i) {
    Snapshot s;
    s.header.tick = rng();
    s.header.server_time = 1.0 + i;
    s.header.part_count = static_cast<std::uint8_t>(1 + rng() % 4);
    s.header.part = static_cast<std::uint8_t>(rng() % s.header.part_count);
    const int m = static_cast<int>(rng() % 20), q = static_cast<int>(rng() % 6);
    for (int k = 0; k < m; ++k) s.interactions.member_ids.push_back(rng());
    for (int k = 0; k < q; ++k) s.interactions.prop_ids.push_back(rng());
    for (int k = 0; k < q; ++k) s.props.push_back(encodePropState(rng(), {0, 1, 0}, {}));
    const int pairs = m + q == 0 ? 0 : static_cast<int>(rng() % 100);
    for (int k = 0; k < pairs; ++k) {
      s.interactions.pairs.push_back(
          {static_cast<std::uint8_t>(rng() % (m + q)), static_cast<std::uint16_t>(rng() % 4096),
           static_cast<std::uint8_t>(rng() % (m + q)), static_cast<std::uint16_t>(rng() % 4096)});
    }
    auto bytes = bytesOf(s);
    if (bytes.size() > kMaxDatagramBytes) continue;
    Snapshot back;
    ASSERT_TRUE(readSnapshot(bytes, back)) << i;
    EXPECT_EQ(bytesOf(back), bytes);
    EXPECT_EQ(bytes.size(), kSnapshotHeaderBytes + q * kPropStateBytes +
                                interactionSectionBytes(m + q, static_cast<std::size_t>(pairs)));
    // Mutations: rejected or read exactly.
    for (int k = 0; k < 8; ++k) {
      auto mutated = bytes;
      mutated[rng() % mutated.size()] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
      if (readSnapshot(mutated, back)) {
        EXPECT_EQ(bytesOf(back), mutated);
      }
    }
  }
}

// The bytes report (proto/WIRE.md §3.8): what the collision world adds to a tick.
TEST(WorldState, BytesPerTickReport) {
  EXPECT_EQ(kSnapshotHeaderBytes, 29u);
  EXPECT_EQ(kPropStateBytes, 16);
  std::printf(
      "[ measure  ] snapshot header 29 B (+16 B tag sealed); prop state 16 B; section 5 B + "
      "4 B/body + pairs\n");
  struct Case {
    int bodies;
    std::size_t pairs;
  };
  for (const Case c :
       {Case{1, 0}, Case{2, 40}, Case{3, 60}, Case{9, 200}, Case{17, 300}, Case{24, 600}}) {
    const std::size_t bytes = interactionSectionBytes(c.bodies, c.pairs);
    const int bits = 2 * bodyIndexBits(c.bodies) + 2 * kPrimIndexBits;
    std::printf(
        "[ measure  ] %2d bodies, %3zu pairs: %2d bits/pair, section %4zu B, %zu datagram(s)\n",
        c.bodies, c.pairs, bits, bytes,
        (bytes + kMaxPlainDatagramBytes - kSnapshotHeaderBytes - 1) /
            (kMaxPlainDatagramBytes - kSnapshotHeaderBytes));
    Snapshot s;
    s.header.part_count = 1;
    for (int b = 0; b < c.bodies; ++b) s.interactions.member_ids.push_back(b);
    s.interactions.pairs.resize(c.pairs);
    EXPECT_EQ(measure(s), kSnapshotHeaderBytes + bytes);
  }
  EXPECT_EQ(interactionSectionBytes(2, 40), 5u + 8u + 130u);      // 26 bits a pair
  EXPECT_EQ(interactionSectionBytes(17, 300), 5u + 68u + 1275u);  // 34 bits a pair
}

}  // namespace
}  // namespace vistel::wire
