// A room's tick once warm: postures in, the collision world stepped (posing, balls, Step 1),
// snapshots out, with no heap allocation (STYLE.md: "a test can count").
#include <vector>

#include <gtest/gtest.h>

#include "common/avatar/avatar_io.hpp"
#include "common/scene/seat_layout.hpp"
#include "common/wire/packets.hpp"
#include "server/core/collision_model.hpp"
#include "server/core/room.hpp"
#include "tests/net/synthetic_avatar.hpp"
#include "tests/server/seated_room.hpp"
#include "tests/support/alloc_counter.hpp"

namespace vistel::server {
namespace {

TEST(RoomTick, AllocatesNothingOnceWarm) {
  constexpr int kMembers = 4;
  constexpr int kWarm = 120;
  constexpr int kCounted = 240;
  RoomSettings settings;
  settings.tick_rate_hz = 60.0;
  const RoomId room_id{1};
  Room room(room_id, "alloc", settings, 0.0);
  auto decoded = decodeAvatar(encodeAvatar(test::makeCollidingAvatar()), "test");
  ASSERT_TRUE(decoded);
  auto model = makeCollisionModel(std::move(*decoded), {}, "test");
  ASSERT_TRUE(model);

  // Members close together (their arms touch), bound; a ball above the first, one beside.
  std::vector<wire::Endpoint> endpoints;
  for (int i = 0; i < kMembers; ++i) {
    RoomCommand c;
    c.kind = RoomCommand::Kind::kAddMember;
    c.room = room_id;
    c.member = MemberId{test::seatedMemberId(i)};
    test::setTestKeys(c);
    c.seat = seatPlacement(i, SeatLayout{0.3f, 0.3f, 1.0f});
    c.joint_count = 5;
    c.collision = *model;
    room.apply(c, 0.0);
    c.kind = RoomCommand::Kind::kBindEndpoint;
    c.endpoint = wire::Endpoint::ipv4(0x0A000001u + static_cast<std::uint32_t>(i), 4000);
    endpoints.push_back(c.endpoint);
    room.apply(c, 0.0);
  }
  for (std::uint32_t k = 0; k < 2; ++k) {
    RoomCommand c;
    c.kind = RoomCommand::Kind::kSpawnProp;
    c.room = room_id;
    c.prop = PropId{0x00010000u + k};
    c.member = k == 0 ? MemberId{0x00010000u} : MemberId{};
    c.position = {0.8f, 1.5f, 0.0f};
    room.apply(c, 0.0);
  }

  // Every member's posture datagram for every tick, made before counting.
  const int ticks = kWarm + kCounted;
  std::vector<std::vector<std::vector<std::uint8_t>>> datagrams(kMembers);
  for (int i = 0; i < kMembers; ++i) {
    for (int t = 0; t < ticks; ++t) {
      wire::PosturePacket p;
      p.header = {test::seatedMemberId(i), 0};
      const double now = (t + 0.5) / 60.0;
      ASSERT_TRUE(wire::encodePostureRecord(test::syntheticPosture(now + i),
                                            static_cast<std::uint16_t>(t + 1), now, p.record));
      std::vector<std::uint8_t> plain;
      wire::write(p, plain);
      datagrams[i].push_back(test::sealAs(p.header.member_id, std::move(plain)));
    }
  }

  Effects fx;
  std::size_t sent = 0;
  const auto run = [&](int from, int to) {
    for (int t = from; t < to; ++t) {
      const double now = (t + 0.5) / 60.0;
      for (int i = 0; i < kMembers; ++i) {
        room.onDatagram(datagrams[i][t], endpoints[i], now, fx);
      }
      room.update(now + 0.5 / 60.0, fx);
      sent += fx.datagrams.size();
      fx.clear();
    }
  };
  run(0, kWarm);
  long allocations = 0;
  sent = 0;
  {
    test::AllocationCounter counter;
    run(kWarm, ticks);
    allocations = counter.count();
  }
  EXPECT_EQ(allocations, 0);
  EXPECT_GE(sent, static_cast<std::size_t>(kMembers * kCounted));
  EXPECT_EQ(room.posturesAccepted(), static_cast<std::uint64_t>(kMembers * ticks));
  EXPECT_FALSE(room.world().interactions().pairs.empty());
  EXPECT_EQ(room.world().propCount(), 2);
  EXPECT_EQ(room.world().bodies().size(), static_cast<std::size_t>(kMembers + 2));
}

}  // namespace
}  // namespace vistel::server
