// Postures forwarded as they arrive, not at the next tick, and interest management
// (server/core/room.hpp): the nearest members at every posture, farther ones at a
// fraction of it, so that a member's downlink grows far slower than the room.
#include <cstdint>
#include <map>
#include <vector>

#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include "common/scene/seat_layout.hpp"
#include "common/wire/packets.hpp"
#include "common/wire/posture_delta.hpp"
#include "server/core/room.hpp"
#include "tests/net/synthetic_avatar.hpp"
#include "tests/server/seated_room.hpp"

namespace vistel::server {
namespace {

using test::seatedEndpoint;
using test::seatedMemberId;

std::vector<std::uint8_t> postureFrom(int i, int sequence, double time) {
  wire::PosturePacket p;
  p.header = {seatedMemberId(i), 0};
  EXPECT_TRUE(wire::encodePostureRecord(test::syntheticPosture(time + i),
                                        static_cast<std::uint16_t>(sequence), time, p.record));
  std::vector<std::uint8_t> out;
  wire::write(p, out);
  return test::sealAs(seatedMemberId(i), out);
}

// (recipient index, sender member id) -> entries, over the datagrams in fx; world
// datagrams (with an interaction part) counted apart.
struct Delivered {
  std::map<std::pair<int, std::uint32_t>, int> entries;
  int world_datagrams = 0;
  int world_entries = 0;
};
void tally(const Effects& fx, Delivered& d) {
  wire::Snapshot snapshot;
  for (const OutDatagram& out : fx.datagrams) {
    const int to = out.to.port - test::kSeatedPortBase;
    ASSERT_TRUE(wire::readSnapshot(test::openFor(seatedMemberId(to), out.bytes), snapshot));
    if (snapshot.header.part_count > 0) {
      ++d.world_datagrams;
      d.world_entries += static_cast<int>(snapshot.entries.size());
    }
    for (const wire::SnapshotEntry& e : snapshot.entries) ++d.entries[{to, e.member_id}];
  }
}

TEST(PostureForwarding, APostureReachesTheOthersWithinTheIntervalNotAtTheTick) {
  spdlog::set_level(spdlog::level::err);
  RoomSettings settings;
  settings.tick_rate_hz = 60.0;
  settings.forward_interval_s = 0.002;
  Room room(RoomId{1}, "fwd", settings, 0.0);
  test::seatMembers(room, 4);
  Effects fx;

  // The first posture goes on at once, to the three others.
  room.onDatagram(postureFrom(0, 1, 0.004), seatedEndpoint(0), 0.004, fx);
  Delivered d;
  tally(fx, d);
  EXPECT_EQ(fx.datagrams.size(), 3u);
  for (int to = 1; to < 4; ++to) EXPECT_EQ((d.entries[{to, seatedMemberId(0)}]), 1) << to;
  EXPECT_EQ(d.entries.count({0, seatedMemberId(0)}), 0u);  // not back to its sender
  fx.clear();

  // One 1 ms later waits for the batch, due 2 ms after the first: well before the tick.
  room.onDatagram(postureFrom(1, 1, 0.005), seatedEndpoint(1), 0.005, fx);
  EXPECT_TRUE(fx.datagrams.empty());
  EXPECT_NEAR(room.nextWakeTime(), 0.006, 1e-9);
  EXPECT_LT(room.nextWakeTime(), room.nextTickTime());
  room.update(0.006, fx);
  d = {};
  tally(fx, d);
  for (int to : {0, 2, 3}) EXPECT_EQ((d.entries[{to, seatedMemberId(1)}]), 1) << to;
  EXPECT_EQ(d.world_datagrams, 0);
  fx.clear();

  // The tick sends the world (props, interaction list) and no posture again.
  room.update(room.nextTickTime(), fx);
  d = {};
  tally(fx, d);
  EXPECT_EQ(d.world_datagrams, 4);
  EXPECT_EQ(d.world_entries, 0);
  EXPECT_TRUE(d.entries.empty());
}

// The uplink's acknowledgement: every snapshot a member gets carries the newest of its
// postures the room decoded, and asks for a keyframe when a delta came without its reference.
TEST(PostureForwarding, SnapshotsAcknowledgeTheUplinkAndAskForAKeyframeAfterALoss) {
  spdlog::set_level(spdlog::level::err);
  RoomSettings settings;
  Room room(RoomId{1}, "ack", settings, 0.0);
  test::seatMembers(room, 2);
  Effects fx;
  wire::PostureDeltaOptions options;
  options.joint_count = test::kSeatedJoints;
  options.reference = wire::DeltaReference::kPrevious;  // each delta needs the frame before
  wire::PostureDeltaEncoder encoder(options);
  const auto datagramOf = [&](int sequence, double t) {
    std::vector<std::uint8_t> record, out;
    EXPECT_TRUE(encoder.encode(test::syntheticPosture(t), static_cast<std::uint16_t>(sequence), t,
                               false, record));
    wire::writePostureDatagram({seatedMemberId(0), 0}, record, out);
    return test::sealAs(seatedMemberId(0), out);
  };
  const auto headerTo = [&](int member) {
    wire::Snapshot snapshot;
    for (const OutDatagram& out : fx.datagrams) {
      if (out.to == seatedEndpoint(member) &&
          wire::readSnapshot(test::openFor(seatedMemberId(member), out.bytes), snapshot)) {
        return snapshot.header;
      }
    }
    ADD_FAILURE() << "no snapshot to member " << member;
    return wire::SnapshotHeader{};
  };
  room.onDatagram(datagramOf(1, 0.001), seatedEndpoint(0), 0.001, fx);  // a keyframe
  room.onDatagram(datagramOf(2, 0.002), seatedEndpoint(0), 0.002, fx);
  fx.clear();
  room.update(room.nextTickTime(), fx);
  EXPECT_EQ(headerTo(0).ack_flags, wire::kAckValid);
  EXPECT_EQ(headerTo(0).posture_ack, 2);
  EXPECT_EQ(headerTo(1).ack_flags, 0);  // member 1 sent nothing
  // Frame 3 is lost; frame 4 refers to it.
  (void)datagramOf(3, 0.003);
  fx.clear();
  room.onDatagram(datagramOf(4, 0.004), seatedEndpoint(0), 0.03, fx);
  EXPECT_EQ(room.posturesWithoutReference(), 1u);
  fx.clear();
  room.update(room.nextTickTime(), fx);
  EXPECT_EQ(headerTo(0).ack_flags, wire::kAckValid | wire::kAckWantKeyframe);
  EXPECT_EQ(headerTo(0).posture_ack, 2);
  // The keyframe asked for clears the request.
  encoder.requestKeyframe();
  room.onDatagram(datagramOf(5, 0.005), seatedEndpoint(0), 0.04, fx);
  fx.clear();
  room.update(room.nextTickTime(), fx);
  EXPECT_EQ(headerTo(0).ack_flags, wire::kAckValid);
  EXPECT_EQ(headerTo(0).posture_ack, 5);
}

// Every member sends `frames` postures at 60 Hz; entries each member receives per frame.
double entriesPerMemberFrame(int members, int frames, Delivered* out = nullptr) {
  RoomSettings settings;
  settings.forward_interval_s = 0.002;
  Room room(RoomId{1}, "crowd", settings, 0.0);
  test::seatMembers(room, members);
  Effects fx;
  Delivered d;
  for (int f = 0; f < frames; ++f) {
    const double t = (f + 1) / 60.0;
    for (int i = 0; i < members; ++i) {
      // Arrivals spread over the frame, as from unsynchronised senders.
      const double now = t + 0.015 * i / members;
      room.onDatagram(postureFrom(i, f + 1, now), seatedEndpoint(i), now, fx);
      room.update(now, fx);
      tally(fx, d);
      fx.clear();
    }
  }
  room.update(frames / 60.0 + 0.1, fx);
  tally(fx, d);
  EXPECT_EQ(room.entriesForwarded(), [&] {
    std::uint64_t sum = 0;
    for (const auto& [key, n] : d.entries) sum += static_cast<std::uint64_t>(n);
    return sum;
  }());
  if (out != nullptr) *out = d;
  return static_cast<double>(room.entriesForwarded()) / (members * frames);
}

TEST(PostureForwarding, NearMembersAtFullRateFarOnesAtAFractionDownlinkSublinear) {
  spdlog::set_level(spdlog::level::err);
  constexpr int kFrames = 48;
  // Up to near_members + 1 members, everyone hears everyone at every posture.
  EXPECT_DOUBLE_EQ(entriesPerMemberFrame(16, kFrames), 15.0);
  Delivered d;
  const double at50 = entriesPerMemberFrame(50, kFrames);
  const double at100 = entriesPerMemberFrame(100, kFrames, &d);
  // Recipient 0 hears its nearest neighbour at every posture, the farthest at a quarter.
  const glm::vec2 self(seatPlacement(0, SeatLayout{}).x, seatPlacement(0, SeatLayout{}).z);
  int nearest = 1, farthest = 1;
  for (int i = 1; i < 100; ++i) {
    const auto at = [&](int k) {
      const SeatPlacement s = seatPlacement(k, SeatLayout{});
      return glm::distance(self, glm::vec2(s.x, s.z));
    };
    if (at(i) < at(nearest)) nearest = i;
    if (at(i) > at(farthest)) farthest = i;
  }
  EXPECT_EQ((d.entries[{0, seatedMemberId(nearest)}]), kFrames);
  EXPECT_EQ((d.entries[{0, seatedMemberId(farthest)}]), kFrames / 4);
  // Six times the members, well under three times the downlink.
  std::printf(
      "[ measure  ] entries per member-frame: 16 members 15.0, 50 members %.1f, 100 "
      "members %.1f\n",
      at50, at100);
  EXPECT_LT(at50, 0.7 * 49);
  EXPECT_LT(at100, 0.5 * 99);
  EXPECT_LT(at100 / 15.0, 3.0);
}

}  // namespace
}  // namespace vistel::server
