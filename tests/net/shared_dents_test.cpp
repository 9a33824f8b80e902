// Shared dents over the session (proto/SESSION.md §2.5): a member's Dents for its own avatar
// or a prop of its room reach the rest of the room and, kept by the server, a member who
// joins later; dents for another member's avatar, malformed ones and ones faster than
// dents_interval_s are ignored without dropping their sender; a body's dents go with it.
#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include "control.pb.h"
#include "tests/net/sim_network.hpp"
#include "tests/net/synthetic_avatar.hpp"

namespace vistel::test {
namespace {

using net::BodyDents;
using net::SessionState;

struct QuietDentLogs {
  QuietDentLogs() { spdlog::set_level(spdlog::level::err); }
} quiet_dent_logs;

BodyDents dentsFor(bool prop, std::uint32_t body, std::uint32_t first_vertex, double time) {
  BodyDents d;
  d.prop = prop;
  d.body_id = body;
  d.server_time = time;
  d.record.vertex_count = 500;
  d.record.gaps = {first_vertex, 0, 7};
  d.record.depths = {12, 30, 4};
  return d;
}

class SharedDents : public ::testing::Test {
 protected:
  SharedDents() : net_(config(), 7), avatar_(encodeSynthetic(makeSyntheticAvatar())) {
    a_ = join("a");
    b_ = join("b");
  }

  static server::ServerConfig config() {
    server::ServerConfig c;
    c.room_props.push_back(server::RoomPropConfig{});  // one ball
    return c;
  }
  std::size_t join(const std::string& name) {
    const std::size_t i = net_.addClient(sessionFor("r", name, avatar_, 5));
    net_.connect(i);
    net_.advance(0.5);
    EXPECT_EQ(net_.session(i).state(), SessionState::kLive) << net_.session(i).error();
    return i;
  }
  std::uint32_t id(std::size_t i) { return net_.session(i).memberId(); }
  std::uint32_t propId() {
    EXPECT_EQ(net_.session(a_).props().size(), 1u);
    return net_.session(a_).props().empty() ? 0 : net_.session(a_).props()[0]->id;
  }
  std::vector<BodyDents> take(std::size_t i) {
    std::vector<BodyDents> out;
    std::swap(out, net_.session(i).receivedDents());
    return out;
  }
  // Dents written by hand, as a broken client would send them.
  void sendRaw(std::size_t i, const control::Dents& dents) {
    control::ClientMessage msg;
    *msg.mutable_dents() = dents;
    const std::string payload = msg.SerializeAsString();
    wire::appendFrame(
        std::span(reinterpret_cast<const std::uint8_t*>(payload.data()), payload.size()),
        net_.session(i).outbox().stream);
  }
  std::uint64_t dropped(std::string_view reason) {
    return net_.server().lobby().drops().count(reason);
  }

  SimNetwork net_;
  EncodedAvatar avatar_;
  std::size_t a_ = 0, b_ = 0;
};

TEST_F(SharedDents, RelayedToTheRoomAndKeptForALateJoiner) {
  ASSERT_TRUE(net_.session(a_).sendDents(dentsFor(false, id(a_), 40, 1.5)));
  ASSERT_TRUE(net_.session(b_).sendDents(dentsFor(true, propId(), 3, 2.5)));
  net_.advance(0.1);
  const std::vector<BodyDents> at_b = take(b_);
  ASSERT_EQ(at_b.size(), 1u) << "b gets a's avatar's dents, not its own prop's back";
  EXPECT_FALSE(at_b[0].prop);
  EXPECT_EQ(at_b[0].body_id, id(a_));
  EXPECT_EQ(at_b[0].member, id(a_));
  EXPECT_DOUBLE_EQ(at_b[0].server_time, 1.5);
  EXPECT_EQ(at_b[0].record, dentsFor(false, id(a_), 40, 1.5).record);
  const std::vector<BodyDents> at_a = take(a_);
  ASSERT_EQ(at_a.size(), 1u);
  EXPECT_TRUE(at_a[0].prop);
  EXPECT_EQ(at_a[0].member, id(b_));

  // Newer dents of the same body replace the kept ones; a late joiner gets the newest of
  // each body, after its roster (so it knows the bodies).
  net_.advance(0.3);
  ASSERT_TRUE(net_.session(a_).sendDents(dentsFor(false, id(a_), 41, 1.9)));
  net_.advance(0.1);
  const std::size_t c = join("c");
  const std::vector<BodyDents> at_c = take(c);
  ASSERT_EQ(at_c.size(), 2u);
  for (const BodyDents& d : at_c) {
    if (d.prop) {
      EXPECT_EQ(d.body_id, propId());
      EXPECT_EQ(d.record.gaps[0], 3u);
    } else {
      EXPECT_EQ(d.body_id, id(a_));
      EXPECT_EQ(d.record.gaps[0], 41u);
      EXPECT_DOUBLE_EQ(d.server_time, 1.9);
    }
  }
  EXPECT_EQ(net_.session(c).stats().dents_received, 2u);

  // A member's dents leave with it; the prop's stay.
  net_.cut(a_);
  net_.advance(0.2);
  const std::size_t d = join("d");
  const std::vector<BodyDents> at_d = take(d);
  ASSERT_EQ(at_d.size(), 1u);
  EXPECT_TRUE(at_d[0].prop);
}

TEST_F(SharedDents, WhatTheServerIgnoresLeavesTheSenderInTheRoom) {
  // Another member's avatar, an unknown prop; a malformed record (a vertex outside the skin)
  // and a non-finite time, which the session refuses to send, so they are written by hand.
  ASSERT_TRUE(net_.session(a_).sendDents(dentsFor(false, id(b_), 1, 1.0)));
  ASSERT_TRUE(net_.session(a_).sendDents(dentsFor(true, propId() + 1, 1, 1.0)));
  BodyDents bad = dentsFor(false, id(a_), 1, 1.0);
  bad.record.vertex_count = 5;
  EXPECT_FALSE(net_.session(a_).sendDents(bad)) << "the session checks what it sends";
  EXPECT_FALSE(net_.session(a_).sendDents(dentsFor(false, id(a_), 1, NAN)));
  control::Dents raw;
  raw.set_body_id(id(a_));
  raw.set_vertex_count(5);
  raw.add_gaps(9);
  raw.add_depths(1);
  sendRaw(a_, raw);
  raw.set_vertex_count(500);
  raw.set_server_time(INFINITY);
  sendRaw(a_, raw);
  net_.advance(0.1);
  EXPECT_EQ(dropped("dents for another body"), 2u);
  EXPECT_EQ(dropped("malformed dents"), 2u);
  EXPECT_TRUE(take(b_).empty());

  // Faster than dents_interval_s (0.2 s) per body: the second is ignored, the prop's (another
  // body) is not, and one after the interval goes through.
  ASSERT_TRUE(net_.session(a_).sendDents(dentsFor(false, id(a_), 1, 2.0)));
  ASSERT_TRUE(net_.session(a_).sendDents(dentsFor(false, id(a_), 2, 2.1)));
  ASSERT_TRUE(net_.session(a_).sendDents(dentsFor(true, propId(), 2, 2.1)));
  net_.advance(0.25);
  ASSERT_TRUE(net_.session(a_).sendDents(dentsFor(false, id(a_), 3, 2.3)));
  net_.advance(0.1);
  EXPECT_EQ(dropped("dents too often"), 1u);
  const std::vector<BodyDents> at_b = take(b_);
  ASSERT_EQ(at_b.size(), 2u) << "the newest per body waits";
  for (const BodyDents& d : at_b) {
    EXPECT_EQ(d.record.gaps[0], d.prop ? 2u : 3u);
  }
  EXPECT_EQ(net_.session(b_).stats().dents_received, 3u);
  // Everyone is still there.
  EXPECT_EQ(net_.session(a_).state(), SessionState::kLive) << net_.session(a_).error();
  EXPECT_EQ(net_.server().lobby().memberCount(), 2);
}

// Each Dents goes to the whole room, so a member's relayed bytes are budgeted: a token bucket
// of dents_bytes_per_s, bursts of 4 s worth.
TEST_F(SharedDents, BytesPastTheBudgetAreIgnored) {
  server::ServerConfig c;
  c.dents_bytes_per_s = 256.0;  // bursts of 1024 bytes
  SimNetwork net(c, 5);
  std::vector<std::size_t> members;
  for (const char* name : {"a", "b"}) {
    members.push_back(net.addClient(sessionFor("r", name, avatar_, 5)));
    net.connect(members.back());
    net.advance(0.5);
  }
  const std::size_t a = members[0], b = members[1];
  BodyDents big;
  big.body_id = net.session(a).memberId();
  big.server_time = 1.0;
  big.record.vertex_count = 1000;
  big.record.gaps.assign(400, 0);    // 400 vertices in a row: a byte each
  big.record.depths.assign(400, 5);  // ... and a byte each
  ASSERT_TRUE(net.session(a).sendDents(big));
  net.advance(0.3);
  ASSERT_TRUE(net.session(a).sendDents(big));  // ~820 bytes again, 0.3 s later: over
  net.advance(0.1);
  EXPECT_EQ(net.server().lobby().drops().count("dents over the byte rate"), 1u);
  EXPECT_EQ(net.session(b).stats().dents_received, 1u);
  net.advance(3.0);  // refilled
  ASSERT_TRUE(net.session(a).sendDents(big));
  net.advance(0.1);
  EXPECT_EQ(net.session(b).stats().dents_received, 2u);
  EXPECT_EQ(net.session(a).state(), SessionState::kLive) << net.session(a).error();
}

TEST_F(SharedDents, ASpawnedPropsDentsGoWithIt) {
  // max 1 prop per room and no config props: a second spawn replaces the first.
  server::ServerConfig c;
  c.max_props_per_room = 1;
  c.spawn_interval_s = 0.0;
  SimNetwork net(c, 3);
  const std::size_t a = net.addClient(sessionFor("r", "a", avatar_, 5));
  net.connect(a);
  net.advance(0.5);
  ASSERT_TRUE(net.session(a).requestBall());
  net.advance(0.2);
  ASSERT_EQ(net.session(a).props().size(), 1u);
  const std::uint32_t first = net.session(a).props()[0]->id;
  ASSERT_TRUE(net.session(a).sendDents(dentsFor(true, first, 1, 1.0)));
  net.advance(0.1);
  ASSERT_TRUE(net.session(a).requestBall());
  net.advance(0.2);
  ASSERT_EQ(net.session(a).props().size(), 1u);
  EXPECT_NE(net.session(a).props()[0]->id, first);
  const std::size_t b = net.addClient(sessionFor("r", "b", avatar_, 5));
  net.connect(b);
  net.advance(0.5);
  EXPECT_TRUE(net.session(b).receivedDents().empty()) << "the removed prop's dents are gone";
}

}  // namespace
}  // namespace vistel::test
