// The client's side of the collision world: prop tracks (out of order, duplicates,
// interpolation) and the assembly of a tick's interaction list from its parts (missing,
// duplicated, late and newer parts).
#include <vector>

#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include "client/net/prop_track.hpp"
#include "common/wire/datagram_crypto.hpp"
#include "common/wire/packets.hpp"
#include "tests/net/sim_network.hpp"
#include "tests/net/synthetic_avatar.hpp"

namespace vistel::net {
namespace {

using test::SimNetwork;

PropSample sampleAt(double t, float y, float vy = 0.0f) {
  return PropSample{t, glm::vec3(0.0f, y, 0.0f), glm::vec3(0.0f, vy, 0.0f)};
}

TEST(PropTrack, InterpolatesHoldsAndRefusesDuplicates) {
  PropTrack track(4);
  PropSample s;
  EXPECT_FALSE(track.sample(0.0, s));
  EXPECT_EQ(track.push(2, sampleAt(0.2, 2.0f, -1.0f)), PropTrack::Push::kAccepted);
  EXPECT_EQ(track.push(1, sampleAt(0.1, 1.0f, 1.0f)), PropTrack::Push::kAccepted);  // reordered
  EXPECT_EQ(track.push(2, sampleAt(0.2, 2.0f)), PropTrack::Push::kDuplicate);
  ASSERT_TRUE(track.sample(0.15, s));
  EXPECT_FLOAT_EQ(s.position.y, 1.5f);
  EXPECT_FLOAT_EQ(s.velocity.y, 0.0f);
  EXPECT_DOUBLE_EQ(s.time, 0.15);
  ASSERT_TRUE(track.sample(0.0, s));  // held, not extrapolated
  EXPECT_FLOAT_EQ(s.position.y, 1.0f);
  ASSERT_TRUE(track.sample(9.0, s));
  EXPECT_FLOAT_EQ(s.position.y, 2.0f);
  // Full: the oldest goes; something older than everything is stale.
  for (std::uint32_t t = 3; t <= 5; ++t) track.push(t, sampleAt(0.1 * t, static_cast<float>(t)));
  EXPECT_EQ(track.size(), 4);
  EXPECT_EQ(track.push(0, sampleAt(0.0, 0.0f)), PropTrack::Push::kStale);
  EXPECT_FLOAT_EQ(track.newest().position.y, 5.0f);
}

// A session in kLive, fed hand-made snapshot parts.
class InteractionAssembly : public ::testing::Test {
 protected:
  InteractionAssembly() : net_(server::ServerConfig{}, 41) {
    spdlog::set_level(spdlog::level::warn);
    const auto avatar = test::encodeSynthetic(test::makeSyntheticAvatar());
    c_ = net_.addClient(test::sessionFor("r", "c", avatar, 5));
    net_.connect(c_);
    net_.advance(0.3);
  }

  // Part `part` of `count` of tick `tick`: pairs (member 7 prim k) - (member 8 prim k) for
  // k in [first, first + n).
  void deliver(std::uint32_t tick, int part, int count, int first, int n, bool truncated = false) {
    wire::Snapshot s;
    s.header.tick = tick;
    s.header.server_time = 100.0 + tick;
    s.header.part = static_cast<std::uint8_t>(part);
    s.header.part_count = static_cast<std::uint8_t>(count);
    s.interactions.flags = truncated ? wire::kInteractionsTruncated : 0;
    s.interactions.member_ids = {7, 8};
    for (int k = first; k < first + n; ++k) {
      s.interactions.pairs.push_back(
          {0, static_cast<std::uint16_t>(k), 1, static_cast<std::uint16_t>(k)});
    }
    std::vector<std::uint8_t> bytes;
    wire::write(s, bytes);
    // Sealed as the room would (WIRE.md §3.9), with counters past the room's own.
    const wire::SessionKeys* keys = net_.server().lobby().keysOf(net_.session(c_).memberId());
    EXPECT_NE(keys, nullptr);
    if (keys == nullptr) return;
    wire::sealDatagram(keys->server_to_client, counter_++, wire::kServerHeaderBytes, bytes);
    net_.session(c_).onDatagram(bytes, net_.localTime(c_));
  }

  SimNetwork net_;
  std::size_t c_ = 0;
  std::uint64_t counter_ = std::uint64_t{1} << 32;
};

TEST_F(InteractionAssembly, AListIsPublishedOnlyWhenAllItsPartsArrive) {
  ClientSession& s = net_.session(c_);
  const std::uint64_t v0 = s.interactionsVersion();  // the server's own (empty) lists
  const std::uint32_t base = 1u << 20;               // ticks far ahead of the server's
  deliver(base, 2, 3, 20, 5);
  deliver(base, 0, 3, 0, 10);
  deliver(base, 0, 3, 0, 10);  // duplicate
  EXPECT_EQ(s.interactionsVersion(), v0);
  deliver(base, 1, 3, 10, 10, /*truncated=*/true);
  ASSERT_EQ(s.interactionsVersion(), v0 + 1);
  const ReceivedInteractions& got = s.latestInteractions();
  EXPECT_EQ(got.tick, base);
  EXPECT_DOUBLE_EQ(got.server_time, 100.0 + base);
  EXPECT_TRUE(got.truncated);
  ASSERT_EQ(got.pairs.size(), 25u);
  EXPECT_EQ(got.pairs[0].a.id, 7u);
  EXPECT_EQ(got.pairs[0].b.id, 8u);
  EXPECT_FALSE(got.pairs[0].b.is_prop);

  // Late parts of older ticks change nothing; a newer tick replaces the one being
  // assembled when it has not completed.
  deliver(base - 1, 0, 1, 0, 3);
  EXPECT_EQ(s.interactionsVersion(), v0 + 1);
  deliver(base + 1, 0, 2, 0, 4);  // never completed
  deliver(base + 2, 1, 2, 4, 1);
  deliver(base + 1, 1, 2, 4, 4);  // older than the pending tick: ignored
  EXPECT_EQ(s.interactionsVersion(), v0 + 1);
  deliver(base + 2, 0, 2, 0, 2);
  ASSERT_EQ(s.interactionsVersion(), v0 + 2);
  EXPECT_EQ(s.latestInteractions().tick, base + 2);
  EXPECT_EQ(s.latestInteractions().pairs.size(), 3u);
  EXPECT_FALSE(s.latestInteractions().truncated);
  // An inconsistent part count for the tick being assembled is ignored.
  deliver(base + 3, 0, 2, 0, 1);
  deliver(base + 3, 1, 3, 1, 1);
  EXPECT_EQ(s.interactionsVersion(), v0 + 2);
  EXPECT_EQ(s.state(), SessionState::kLive);
}

}  // namespace
}  // namespace vistel::net
