// RoomWorld's snapshot parts: a crowded room's interaction list split over datagrams, each
// a self-contained part within the datagram budget; past max_parts the list is truncated,
// self-contact pairs first, and every part says so.
#include <set>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "common/avatar/avatar_io.hpp"
#include "common/wire/packets.hpp"
#include "server/core/collision_model.hpp"
#include "server/core/room_world.hpp"
#include "tests/net/synthetic_avatar.hpp"
#include "tests/server/seated_room.hpp"

namespace vistel::server {
namespace {

using End = test::PairEnd;
using test::IdPair;

// 16 members on one spot (every primitive touches every other) and a ball among them.
void crowd(RoomWorld& world) {
  auto decoded = decodeAvatar(encodeAvatar(test::makeCollidingAvatar()), "test");
  ASSERT_TRUE(decoded);
  auto model = makeCollisionModel(std::move(*decoded), {}, "test");
  ASSERT_TRUE(model);
  for (std::uint32_t i = 0; i < 16; ++i) {
    world.addMember(MemberId{0x00010000u + i},
                    SeatPlacement{0.01f * static_cast<float>(i), 0.0f, 0.0f}, *model);
  }
  PropSpec spec;
  ASSERT_TRUE(world.addProp(PropId{0x00010000u}, spec, {0.0f, 1.5f, 0.0f}, {}));
  world.step(1.0 / 60.0);
}

// The pairs of each part, decoded from a datagram built around it.
std::vector<std::set<IdPair>> decodeParts(const RoomWorld& world, bool& truncated) {
  std::vector<std::set<IdPair>> out;
  truncated = false;
  const auto parts = world.parts();
  for (std::size_t k = 0; k < parts.size(); ++k) {
    std::vector<std::uint8_t> datagram;
    wire::SnapshotHeader h;
    h.tick = 1;
    h.server_time = 1.0;
    h.prop_count = parts[k].prop_count;
    h.part = static_cast<std::uint8_t>(k);
    h.part_count = static_cast<std::uint8_t>(parts.size());
    wire::beginSnapshot(h, datagram);
    wire::appendSnapshotWorld(parts[k].bytes, datagram);
    wire::finishSnapshot(0, datagram);
    EXPECT_LE(datagram.size(), wire::kMaxDatagramBytes);
    wire::Snapshot s;
    EXPECT_TRUE(wire::readSnapshot(datagram, s)) << "part " << k;
    EXPECT_EQ(s.props.size(), k == 0 ? 1u : 0u);
    const auto& x = s.interactions;
    truncated = truncated || (x.flags & wire::kInteractionsTruncated) != 0;
    const auto end = [&](std::uint8_t body, std::uint16_t prim) {
      const bool prop = body >= x.member_ids.size();
      return End{prop, prop ? x.prop_ids[body - x.member_ids.size()] : x.member_ids[body], prim};
    };
    std::set<IdPair>& pairs = out.emplace_back();
    for (const wire::WirePair& p : x.pairs)
      pairs.insert(test::orderedPair(end(p.body_a, p.prim_a), end(p.body_b, p.prim_b)));
  }
  return out;
}

std::set<IdPair> allPairs(const RoomWorld& world, bool self) {
  std::set<IdPair> out;
  for (const Interaction& p : world.interactions().pairs) {
    if ((p.body_a == p.body_b) != self) continue;
    const WorldBody& a = world.bodies()[p.body_a];
    const WorldBody& b = world.bodies()[p.body_b];
    out.insert(test::orderedPair({a.is_prop, a.id, p.prim_a}, {b.is_prop, b.id, p.prim_b}));
  }
  return out;
}

TEST(RoomWorldParts, ACrowdedListIsSplitIntoSelfContainedParts) {
  WorldSettings settings;
  settings.max_parts = 32;
  settings.send_self_contact = true;
  RoomWorld world(settings);
  crowd(world);
  const std::set<IdPair> cross = allPairs(world, false);
  const std::set<IdPair> self = allPairs(world, true);
  bool truncated = true;
  const auto parts = decodeParts(world, truncated);
  std::printf("[ measure  ] 16 members + 1 ball: %zu pairs (%zu self-contact) in %zu datagrams\n",
              cross.size() + self.size(), self.size(), parts.size());
  EXPECT_GT(parts.size(), 3u);
  EXPECT_FALSE(truncated);
  EXPECT_FALSE(world.truncated());
  std::set<IdPair> got;
  std::size_t total = 0;
  for (const auto& p : parts) {
    got.insert(p.begin(), p.end());
    total += p.size();
  }
  EXPECT_EQ(total, got.size());  // each pair in exactly one part
  std::set<IdPair> expected = cross;
  expected.insert(self.begin(), self.end());
  EXPECT_EQ(got, expected);
}

// By default only the pairs between bodies are computed and travel, flagged so; every
// client adds its bodies' self-contact from its own poses.
TEST(RoomWorldParts, ByDefaultOnlyPairsBetweenBodiesAreSent) {
  WorldSettings settings;
  settings.max_parts = 32;
  RoomWorld world(settings);
  crowd(world);
  bool truncated = true;
  const auto parts = decodeParts(world, truncated);
  EXPECT_FALSE(truncated);
  std::set<IdPair> got;
  for (const auto& p : parts) got.insert(p.begin(), p.end());
  EXPECT_EQ(got, allPairs(world, false));
  EXPECT_TRUE(allPairs(world, true).empty());  // not even computed
  for (const WorldPart& part : world.parts()) {
    std::vector<std::uint8_t> datagram;
    wire::SnapshotHeader h;
    h.part_count = static_cast<std::uint8_t>(world.parts().size());
    h.prop_count = part.prop_count;
    wire::beginSnapshot(h, datagram);
    wire::appendSnapshotWorld(part.bytes, datagram);
    wire::finishSnapshot(0, datagram);
    wire::Snapshot snapshot;
    ASSERT_TRUE(wire::readSnapshot(datagram, snapshot));
    EXPECT_NE(snapshot.interactions.flags & wire::kInteractionsSelfOmitted, 0);
  }
}

TEST(RoomWorldParts, PastTheLimitSelfContactIsDroppedFirst) {
  WorldSettings settings;
  settings.max_parts = 2;
  settings.send_self_contact = true;
  RoomWorld world(settings);
  crowd(world);
  bool truncated = false;
  const auto parts = decodeParts(world, truncated);
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_TRUE(truncated);
  EXPECT_TRUE(world.truncated());
  const std::set<IdPair> cross = allPairs(world, false);
  const std::set<IdPair> self = allPairs(world, true);
  std::size_t sent = 0;
  for (const auto& p : parts) {
    for (const IdPair& pair : p) {
      EXPECT_TRUE(cross.count(pair)) << "a self-contact pair was sent before all cross pairs";
      ++sent;
    }
  }
  EXPECT_LT(sent, cross.size());
  EXPECT_FALSE(self.empty());
}

}  // namespace
}  // namespace vistel::server
