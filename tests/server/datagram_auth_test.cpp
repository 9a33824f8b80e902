// A room's checks on sealed datagrams (issue 20, finding 4; proto/WIRE.md §3.9, §3.4): a
// forged or replayed datagram is dropped and counted; capture times are bounded on both
// sides of the server clock; an authentic sender's wild sequence number cannot freeze it.
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include "common/scene/seat_layout.hpp"
#include "common/wire/packets.hpp"
#include "server/core/room.hpp"
#include "tests/net/synthetic_avatar.hpp"
#include "tests/server/seated_room.hpp"

namespace vistel::server {
namespace {

using test::seatedEndpoint;
using test::seatedMemberId;

class DatagramAuth : public ::testing::Test {
 protected:
  DatagramAuth() : room_(RoomId{1}, "auth", settings(), 0.0) {
    spdlog::set_level(spdlog::level::err);
    test::seatMembers(room_, 2);
  }

  static RoomSettings settings() {
    RoomSettings s;
    s.forward_interval_s = 0.0;  // forward every posture at once
    s.max_capture_age_s = 5.0;
    return s;
  }

  // Member 0's keyframe posture, plain (not sealed), with its root at x = root_x.
  static std::vector<std::uint8_t> posture(int sequence, double capture, float root_x = 0.0f) {
    wire::PosturePacket p;
    p.header = {seatedMemberId(0), 0};
    Posture pose = test::syntheticPosture(capture);
    pose.root_translation.x = root_x;
    EXPECT_TRUE(
        wire::encodePostureRecord(pose, static_cast<std::uint16_t>(sequence), capture, p.record));
    std::vector<std::uint8_t> out;
    wire::write(p, out);
    return out;
  }

  // Delivers a sealed datagram from member 0's endpoint; returns the postures member 1
  // received from it (root x of each).
  std::vector<float> deliver(const std::vector<std::uint8_t>& sealed, double now) {
    fx_.clear();
    room_.onDatagram(sealed, seatedEndpoint(0), now, fx_);
    room_.update(now, fx_);
    std::vector<float> roots;
    for (const OutDatagram& out : fx_.datagrams) {
      if (!(out.to == seatedEndpoint(1))) continue;
      const auto plain = test::openFor(seatedMemberId(1), out.bytes);
      EXPECT_FALSE(plain.empty()) << "every datagram the room sends is sealed for its recipient";
      wire::Snapshot snapshot;
      if (!wire::readSnapshot(plain, snapshot)) continue;
      for (const auto& e : snapshot.entries) {
        if (e.member_id == seatedMemberId(0)) roots.push_back(e.record.root_mm[0] * 0.001f);
      }
    }
    return roots;
  }

  Room room_;
  Effects fx_;
};

TEST_F(DatagramAuth, AForgedPostureWithAGuessedKeyIsDroppedAndTheMemberKeepsMoving) {
  double now = 1.0;
  int sequence = 1;
  ASSERT_EQ(deliver(test::sealAs(seatedMemberId(0), posture(sequence++, now)), now).size(), 1u);
  // The attacker saw the member id and counters; it guesses a key, jumps the sequence by
  // 32767 and moves the root far away.
  wire::AeadKey guessed = test::uplinkKeyOf(seatedMemberId(0));
  guessed[31] ^= 1;  // even one bit off
  now += 0.01;
  EXPECT_TRUE(deliver(test::sealWith(guessed, posture(sequence + 32767, now, 9.0f)), now).empty());
  EXPECT_EQ(room_.drops().count("bad datagram tag"), 1u);
  // The member's own next postures go on being forwarded.
  for (int k = 0; k < 5; ++k) {
    now += 0.01;
    const auto roots = deliver(test::sealAs(seatedMemberId(0), posture(sequence++, now)), now);
    ASSERT_EQ(roots.size(), 1u) << k;
    EXPECT_LT(roots[0], 1.0f);
  }
}

TEST_F(DatagramAuth, AReplayedDatagramIsDroppedAndCounted) {
  const auto sealed = test::sealAs(seatedMemberId(0), posture(1, 1.0));
  ASSERT_EQ(deliver(sealed, 1.0).size(), 1u);
  EXPECT_TRUE(deliver(sealed, 1.01).empty());
  EXPECT_EQ(room_.drops().count("replayed datagram"), 1u);
  // Even after the member moved on, and once it is older than the window.
  const std::uint64_t first = wire::peekCounter(sealed, wire::kClientHeaderBytes);
  ASSERT_EQ(
      deliver(test::sealWith(test::uplinkKeyOf(seatedMemberId(0)), posture(2, 1.02), first + 100),
              1.02)
          .size(),
      1u);
  EXPECT_TRUE(deliver(sealed, 1.03).empty());
  EXPECT_EQ(room_.drops().count("datagram too old"), 1u);
  EXPECT_EQ(room_.posturesAccepted(), 2u);
}

TEST_F(DatagramAuth, CaptureTimesAreBoundedOnBothSides) {
  const double now = 4000.0;
  // An hour old: dropped, counted.
  EXPECT_TRUE(deliver(test::sealAs(seatedMemberId(0), posture(1, now - 3600.0)), now).empty());
  EXPECT_EQ(room_.drops().count("capture time too old"), 1u);
  // Older than the bound (5 s), and too far ahead (1 s): dropped.
  EXPECT_TRUE(deliver(test::sealAs(seatedMemberId(0), posture(2, now - 5.5)), now).empty());
  EXPECT_EQ(room_.drops().count("capture time too old"), 2u);
  EXPECT_TRUE(deliver(test::sealAs(seatedMemberId(0), posture(3, now + 1.5)), now).empty());
  EXPECT_EQ(room_.drops().count("capture time in the future"), 1u);
  // Within the bounds: accepted.
  EXPECT_EQ(deliver(test::sealAs(seatedMemberId(0), posture(4, now - 4.0)), now).size(), 1u);
  EXPECT_EQ(deliver(test::sealAs(seatedMemberId(0), posture(5, now - 0.01)), now).size(), 1u);
}

TEST_F(DatagramAuth, AnAuthenticSequenceJumpDoesNotFreezeTheMember) {
  // A buggy (but authentic) client jumps its sequence by 32767, then goes on from where it
  // was. The jump resynchronises (a keyframe), and so does its real stream after it: the
  // member never looks stale for minutes.
  double now = 1.0;
  int sequence = 10;
  ASSERT_EQ(deliver(test::sealAs(seatedMemberId(0), posture(sequence, now)), now).size(), 1u);
  now += 0.01;
  EXPECT_EQ(
      deliver(test::sealAs(seatedMemberId(0), posture(sequence + 32767, now, 0.5f)), now).size(),
      1u);
  for (int k = 1; k <= 5; ++k) {
    now += 0.01;
    const auto roots = deliver(test::sealAs(seatedMemberId(0), posture(sequence + k, now)), now);
    ASSERT_EQ(roots.size(), 1u) << k;
    EXPECT_LT(roots[0], 0.1f);
  }
}

}  // namespace
}  // namespace vistel::server
