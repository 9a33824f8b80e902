// The server's protocol core over a simulated network: joining, the UDP handshake,
// avatars by hash, postures and snapshots, and every kind of bad input (which must
// only ever hurt its sender).
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/wire/framing.hpp"
#include "common/wire/packets.hpp"
#include "control.pb.h"
#include "server/core/server_core.hpp"
#include "tests/net/sim_network.hpp"
#include "tests/net/synthetic_avatar.hpp"
#include "tests/server/control_frames.hpp"
#include "tests/server/sealed_datagrams.hpp"

namespace vistel::server {
namespace {

using net::SessionState;
using test::SimNetwork;

ServerConfig testConfig() {
  ServerConfig c;
  c.tick_rate_hz = 60.0;
  c.member_timeout_s = 2.0;
  c.join_timeout_s = 1.0;
  c.max_members_per_room = 8;
  c.avatar_chunk_bytes = 300;  // small chunks: uploads take several
  return c;
}

using test::frameOf;
using test::messagesOf;

class ServerCoreTest : public ::testing::Test {
 protected:
  ServerCoreTest()
      : net_(testConfig(), 3),
        avatar_a_(test::encodeSynthetic(test::makeSyntheticAvatar("a", 0.10f))),
        avatar_b_(test::encodeSynthetic(test::makeSyntheticAvatar("b", 0.12f))) {}

  std::size_t join(const std::string& name, const test::EncodedAvatar& avatar,
                   const std::string& room = "lab") {
    const std::size_t i = net_.addClient(test::sessionFor(room, name, avatar, 5), {}, {}, 0.0,
                                         std::make_shared<net::AvatarCache>());
    net_.connect(i);
    return i;
  }

  // Sends synthetic postures from the given clients at 30 Hz while time advances.
  void stream(std::vector<std::size_t> senders, double duration) {
    double next = net_.now();
    net_.advance(duration, 0.001, [&](double now) {
      if (now + 1e-9 < next) return;
      next += 1.0 / 30.0;
      for (std::size_t i : senders) {
        net_.session(i).sendPosture(test::syntheticPosture(now), net_.localTime(i));
      }
    });
  }

  std::uint64_t received(std::size_t at, const std::string& from) {
    const auto& m = net_.session(at).stats().members;
    auto it = m.find(from);
    return it == m.end() ? 0 : it->second.postures_received;
  }

  SimNetwork net_;
  test::EncodedAvatar avatar_a_;
  test::EncodedAvatar avatar_b_;
};

TEST_F(ServerCoreTest, TwoMembersJoinHandshakeAndSeeEachOther) {
  const auto a = join("alice", avatar_a_);
  const auto b = join("bob", avatar_b_);
  net_.advance(0.5);
  ASSERT_EQ(net_.session(a).state(), SessionState::kLive) << net_.session(a).error();
  ASSERT_EQ(net_.session(b).state(), SessionState::kLive) << net_.session(b).error();
  EXPECT_EQ(net_.server().lobby().memberCount(), 2);
  EXPECT_EQ(net_.server().lobby().roomCount(), 1);
  ASSERT_NE(net_.server().findRoom("lab"), nullptr);

  // Both rosters list both, with distinct seats facing each other across the circle.
  const auto& roster = net_.session(a).members();
  ASSERT_EQ(roster.size(), 2u);
  EXPECT_EQ(roster[0]->name, "alice");
  EXPECT_TRUE(roster[0]->is_self);
  EXPECT_EQ(roster[1]->name, "bob");
  EXPECT_EQ(roster[1]->joint_count, 5);
  EXPECT_NEAR(roster[0]->seat.x, -roster[1]->seat.x, 1e-4f);
  EXPECT_NEAR(roster[0]->seat.z, -roster[1]->seat.z, 1e-4f);
  EXPECT_NE(roster[0]->seat.z, roster[1]->seat.z);

  // Postures flow both ways.
  stream({a, b}, 1.0);
  EXPECT_GE(received(a, "bob"), 25u);
  EXPECT_GE(received(b, "alice"), 25u);
  net::RemoteMember const* bob = net_.session(a).findMember(net_.session(b).memberId());
  ASSERT_NE(bob, nullptr);
  Posture p;
  ASSERT_TRUE(bob->buffer.sample(bob->buffer.newestTime(), p));
  const Posture expected = test::syntheticPosture(p.time);
  for (std::size_t j = 0; j < 5; ++j) {
    EXPECT_LT(angleBetween(p.rotations[j], expected.rotations[j]), wire::kQuatAngleBoundRad);
  }
}

TEST_F(ServerCoreTest, AvatarsAreUploadedOnceAndFetchedByOthers) {
  const auto a = join("alice", avatar_a_);
  net_.advance(0.3);
  EXPECT_EQ(net_.server().lobby().avatars().size(), 1u);
  const auto b = join("bob", avatar_b_);
  const auto c = join("carol", avatar_a_);  // same avatar as alice: no second upload
  net_.advance(0.5);
  EXPECT_EQ(net_.server().lobby().avatars().size(), 2u);
  ASSERT_EQ(net_.session(c).state(), SessionState::kLive);

  // Everyone has fetched the others' avatars into their caches, checked by hash.
  for (std::size_t i : {a, b, c}) {
    for (const auto& m : net_.session(i).members()) {
      if (m->is_self) continue;
      EXPECT_TRUE(m->avatar_ready);
    }
  }
  // The server drops what nobody uses any more.
  net_.session(b).leave("done");
  net_.advance(0.2);
  EXPECT_EQ(net_.server().lobby().avatars().size(), 1u);
}

TEST_F(ServerCoreTest, FetchedAvatarsLandInTheCache) {
  auto cache = std::make_shared<net::AvatarCache>();
  const auto a = join("alice", avatar_a_);
  const auto b = net_.addClient(test::sessionFor("lab", "bob", avatar_b_, 5), {}, {}, 0.0, cache);
  net_.connect(b);
  net_.advance(0.5);
  (void)a;
  const auto model = cache->find(avatar_a_.hash);
  ASSERT_NE(model, nullptr);
  EXPECT_EQ(model->skeleton.jointCount(), 5);
}

TEST_F(ServerCoreTest, BadJoinsAreRefusedWithAReason) {
  join("alice", avatar_a_);
  const auto dup = join("alice", avatar_b_);
  const auto bad_room = join("carol", avatar_b_, "no spaces allowed");
  net_.advance(0.3);
  EXPECT_EQ(net_.session(dup).state(), SessionState::kClosed);
  EXPECT_NE(net_.session(dup).error().find("NAME_TAKEN"), std::string::npos)
      << net_.session(dup).error();
  EXPECT_EQ(net_.session(bad_room).state(), SessionState::kClosed);
  EXPECT_NE(net_.session(bad_room).error().find("BAD_JOIN"), std::string::npos);
  EXPECT_EQ(net_.server().lobby().memberCount(), 1);

  // A wrong protocol version, straight on the wire.
  control::ClientMessage msg;
  msg.mutable_join()->set_protocol_version(99);
  msg.mutable_join()->set_room("lab");
  msg.mutable_join()->set_name("dave");
  msg.mutable_join()->set_avatar_hash(avatar_a_.hash);
  net_.injectConnect(900);
  net_.injectStream(900, frameOf(msg));
  const auto replies = messagesOf(net_.rawReceived(900));
  ASSERT_EQ(replies.size(), 1u);
  EXPECT_EQ(replies[0].error().code(), control::ErrorReply::VERSION_MISMATCH);
  EXPECT_TRUE(net_.rawClosed(900));
}

TEST_F(ServerCoreTest, InvalidUploadsAreRejected) {
  // Offer a hash, then upload bytes that hash to something else.
  control::ClientMessage join;
  join.mutable_join()->set_protocol_version(kProtocolVersion);
  join.mutable_join()->set_room("lab");
  join.mutable_join()->set_name("mallory");
  join.mutable_join()->set_avatar_hash(std::string(64, 'a'));
  join.mutable_join()->set_avatar_size(100);
  join.mutable_join()->set_udp_public_key(test::kTestUdpPublicKey);
  net_.injectConnect(901);
  net_.injectStream(901, frameOf(join));
  control::ClientMessage chunk;
  chunk.mutable_avatar_chunk()->set_hash(std::string(64, 'a'));
  chunk.mutable_avatar_chunk()->set_total_size(100);
  chunk.mutable_avatar_chunk()->set_offset(0);
  chunk.mutable_avatar_chunk()->set_data(std::string(100, 'x'));
  net_.injectStream(901, frameOf(chunk));
  auto replies = messagesOf(net_.rawReceived(901));
  ASSERT_FALSE(replies.empty());
  EXPECT_TRUE(replies.back().has_error());
  EXPECT_EQ(replies.back().error().code(), control::ErrorReply::AVATAR_REJECTED);
  EXPECT_NE(replies.back().error().message().find("does not match"), std::string::npos);
  EXPECT_TRUE(net_.rawClosed(901));
  EXPECT_EQ(net_.server().lobby().memberCount(), 0);

  // Bytes with the right hash that are not an avatar.
  const std::vector<std::uint8_t> junk(100, 'x');
  const std::string junk_hash = avatarContentHash(junk);
  join.mutable_join()->set_avatar_hash(junk_hash);
  chunk.mutable_avatar_chunk()->set_hash(junk_hash);
  net_.injectConnect(902);
  net_.injectStream(902, frameOf(join));
  net_.injectStream(902, frameOf(chunk));
  replies = messagesOf(net_.rawReceived(902));
  ASSERT_FALSE(replies.empty());
  EXPECT_EQ(replies.back().error().code(), control::ErrorReply::AVATAR_REJECTED);

  // An offered size over the cap is refused at join.
  join.mutable_join()->set_avatar_size(1ull << 40);
  net_.injectConnect(903);
  net_.injectStream(903, frameOf(join));
  replies = messagesOf(net_.rawReceived(903));
  ASSERT_EQ(replies.size(), 1u);
  EXPECT_EQ(replies[0].error().code(), control::ErrorReply::AVATAR_REJECTED);
}

// Issue 20, finding 4: datagrams are sealed with per-member keys from the handshake. A
// sniffer sees member ids and counters, never a key: its forged hellos and postures (a
// guessed key, the observed counters, sequence +32767 and a far root) are dropped, its
// replays of what it captured too, and the member's real stream goes on.
TEST_F(ServerCoreTest, ForgedAndReplayedDatagramsAreDroppedAndTheMemberKeepsMoving) {
  const auto a = join("alice", avatar_a_);
  const auto b = join("bob", avatar_b_);
  net_.sniff(true);
  stream({a, b}, 0.5);
  net_.sniff(false);
  ASSERT_EQ(net_.session(a).state(), SessionState::kLive);
  const std::uint32_t alice = net_.session(a).memberId();
  const wire::Endpoint attacker = wire::Endpoint::ipv4(0xC0A80001u, 6666);
  std::vector<std::vector<std::uint8_t>> captured;
  std::uint64_t newest_counter = 0;
  for (const auto& d : net_.sniffed()) {
    if (d.client != a) continue;
    captured.push_back(d.bytes);
    newest_counter = std::max(newest_counter, wire::peekCounter(d.bytes, wire::kClientHeaderBytes));
  }
  ASSERT_GE(captured.size(), 10u);
  // What travels in clear: the id and the counter, nothing that opens or forges.
  EXPECT_EQ(wire::peekMemberId(captured[0]), alice);

  wire::AeadKey guessed{};
  guessed.fill(0x5A);
  // A hello with alice's id, sealed with a guessed key, from elsewhere: no answer at all.
  wire::HelloPacket hello;
  hello.header = {alice, 0};
  std::vector<std::uint8_t> bytes;
  wire::write(hello, bytes);
  net_.injectDatagram(test::sealWith(guessed, bytes, newest_counter + 1), attacker);
  // Postures claiming to be alice, from her endpoint and elsewhere: the next counters she
  // will use, sequence 32767 (ahead of hers by ~32750), a root far away.
  wire::PosturePacket forged;
  forged.header = {alice, 0};
  Posture p = test::syntheticPosture(0.0);
  p.root_translation = {9.0f, 9.0f, 9.0f};
  ASSERT_TRUE(wire::encodePostureRecord(p, 32767, net_.now(), forged.record));
  std::vector<std::uint8_t> forged_plain;
  wire::write(forged, forged_plain);
  for (int k = 0; k < 20; ++k) {
    const auto forged_bytes = test::sealWith(guessed, forged_plain, newest_counter + 1 + k);
    net_.injectDatagram(forged_bytes, net_.client(a).endpoint, 0.01 * k);
    net_.injectDatagram(forged_bytes, attacker, 0.01 * k);
  }
  // Every datagram alice sent, replayed from her own endpoint.
  for (const auto& d : captured) net_.injectDatagram(d, net_.client(a).endpoint, 0.005);
  const auto before = received(b, "alice");
  stream({a, b}, 1.0);

  EXPECT_TRUE(net_.rawDatagrams(attacker).empty());
  EXPECT_GE(net_.server().lobby().drops().count("hello with bad tag"), 1u);
  const Room* room = net_.server().findRoom("lab");
  ASSERT_NE(room, nullptr);
  EXPECT_GE(room->drops().count("bad datagram tag"), 20u);  // from alice's endpoint
  EXPECT_GE(room->drops().count("wrong endpoint"), 20u);    // from elsewhere
  // The replays: the room's window drops the postures and pings it has seen (the oldest
  // as too old), the lobby's the hellos.
  const std::uint64_t replays_dropped = room->drops().count("replayed datagram") +
                                        room->drops().count("datagram too old") +
                                        net_.server().lobby().drops().count("replayed datagram") +
                                        net_.server().lobby().drops().count("datagram too old");
  EXPECT_EQ(replays_dropped, captured.size());
  // Bob goes on seeing alice's real stream, never the forged root.
  EXPECT_GE(received(b, "alice"), before + 25u);
  const auto* seen = net_.session(b).findMember(alice);
  Posture latest;
  ASSERT_TRUE(seen->buffer.sample(1e9, latest));
  EXPECT_LT(latest.root_translation.x, 1.0f);
  EXPECT_EQ(net_.session(a).state(), SessionState::kLive);
}

TEST_F(ServerCoreTest, UnauthenticatedDatagramsNeverGetMoreBytesBack) {
  const auto a = join("alice", avatar_a_);
  net_.advance(0.3);
  const wire::Endpoint stranger = wire::Endpoint::ipv4(0xC0A80002u, 7777);
  // Garbage of every size, pings and postures for members that do not exist.
  for (std::size_t n = 0; n < 1300; n += 7) {
    std::vector<std::uint8_t> garbage(n, static_cast<std::uint8_t>(n));
    if (n >= 2) {
      garbage[0] = wire::kWireVersion;
      garbage[1] = static_cast<std::uint8_t>(n % 3 + 1);
    }
    net_.injectDatagram(garbage, stranger);
  }
  wire::PingPacket ping;
  ping.header = {net_.session(a).memberId() + 1, 1};
  std::vector<std::uint8_t> ping_bytes;
  wire::write(ping, ping_bytes);
  net_.injectDatagram(test::sealWith(wire::AeadKey{}, ping_bytes), stranger);
  net_.advance(0.2);
  EXPECT_TRUE(net_.rawDatagrams(stranger).empty());
  EXPECT_EQ(net_.session(a).state(), SessionState::kLive);
}

TEST_F(ServerCoreTest, GarbageAndOversizedTcpFramesDropOnlyTheirSender) {
  const auto a = join("alice", avatar_a_);
  const auto b = join("bob", avatar_b_);
  stream({a, b}, 0.5);
  const auto before = received(b, "alice");

  // Garbage inside a valid frame, before joining and after joining.
  net_.injectConnect(910);
  net_.injectStream(910, {5, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0xFF, 0xFF});
  EXPECT_TRUE(net_.rawClosed(910));
  ASSERT_FALSE(messagesOf(net_.rawReceived(910)).empty());
  EXPECT_EQ(messagesOf(net_.rawReceived(910)).back().error().code(),
            control::ErrorReply::BAD_MESSAGE);
  // A frame header announcing 4 GB.
  net_.injectConnect(911);
  net_.injectStream(911, {0xFF, 0xFF, 0xFF, 0xFF});
  EXPECT_TRUE(net_.rawClosed(911));
  EXPECT_NE(messagesOf(net_.rawReceived(911)).back().error().message().find("exceeds"),
            std::string::npos);
  // A joined member that then sends garbage is dropped (and its room mirror with it).
  control::ClientMessage join_msg;
  join_msg.mutable_join()->set_protocol_version(kProtocolVersion);
  join_msg.mutable_join()->set_room("lab");
  join_msg.mutable_join()->set_name("eve");
  join_msg.mutable_join()->set_avatar_hash(avatar_a_.hash);
  join_msg.mutable_join()->set_avatar_size(avatar_a_.bytes.size());
  join_msg.mutable_join()->set_udp_public_key(test::kTestUdpPublicKey);
  net_.injectConnect(912);
  net_.injectStream(912, frameOf(join_msg));
  EXPECT_EQ(net_.server().lobby().memberCount(), 3);
  net_.injectStream(912, {3, 0, 0, 0, 1, 2, 3});
  EXPECT_TRUE(net_.rawClosed(912));
  EXPECT_EQ(net_.server().lobby().memberCount(), 2);

  // Alice and Bob carried on throughout.
  stream({a, b}, 0.5);
  EXPECT_EQ(net_.session(a).state(), SessionState::kLive);
  EXPECT_EQ(net_.session(b).state(), SessionState::kLive);
  EXPECT_GE(received(b, "alice"), before + 12);
}

TEST_F(ServerCoreTest, ConnectionsThatNeverJoinAreClosed) {
  net_.injectConnect(920);
  net_.advance(1.5);
  EXPECT_TRUE(net_.rawClosed(920));
  EXPECT_EQ(messagesOf(net_.rawReceived(920)).back().error().code(), control::ErrorReply::TIMEOUT);
}

TEST_F(ServerCoreTest, SilentMembersTimeOutAndOthersAreTold) {
  const auto a = join("alice", avatar_a_);
  const auto b = join("bob", avatar_b_);
  stream({a, b}, 0.3);
  // Alice's UDP goes dark (her pings and postures stop arriving).
  net_.client(a).up.loss = 1.0;
  stream({b}, 3.0);
  EXPECT_EQ(net_.session(a).state(), SessionState::kClosed);
  EXPECT_NE(net_.session(a).error().find("TIMEOUT"), std::string::npos) << net_.session(a).error();
  EXPECT_EQ(net_.session(b).members().size(), 1u);
  EXPECT_EQ(net_.server().lobby().memberCount(), 1);
}

TEST_F(ServerCoreTest, LeavingEmptiesAndClosesTheRoomAndStaleIdsAreRefused) {
  const auto a = join("alice", avatar_a_);
  net_.advance(0.3);
  const std::uint32_t old_id = net_.session(a).memberId();
  net_.session(a).leave("bye");
  net_.advance(0.1);
  EXPECT_EQ(net_.server().lobby().memberCount(), 0);
  EXPECT_EQ(net_.server().lobby().roomCount(), 0);
  EXPECT_EQ(net_.server().findRoom("lab"), nullptr);

  // A newcomer reuses the slot under a new generation; the old id stays dead.
  const auto b = join("bob", avatar_b_);
  net_.advance(0.3);
  EXPECT_NE(net_.session(b).memberId(), old_id);
  EXPECT_EQ(net_.session(b).memberId() & 0xFFFFu, old_id & 0xFFFFu);
  wire::HelloPacket hello;
  hello.header = {old_id, 0};
  std::vector<std::uint8_t> bytes;
  wire::write(hello, bytes);
  bytes = test::sealWith(wire::AeadKey{}, bytes);  // the key does not matter: the id is stale
  net_.injectDatagram(bytes, wire::Endpoint::ipv4(0xC0A80003u, 1));
  net_.advance(0.01);
  EXPECT_GE(net_.server().lobby().drops().count("hello for unknown member"), 1u);
}

TEST(ServerCoreSnapshots, LargeRoomsSplitSnapshotsAcrossDatagrams) {
  ServerConfig config = testConfig();
  SimNetwork net(config, 4);
  const AvatarModel model = test::makeChainAvatar(52);
  const auto avatar = test::encodeSynthetic(model);
  constexpr int kMembers = 8;
  for (int i = 0; i < kMembers; ++i) {
    net.connect(net.addClient(test::sessionFor("big", fmt::format("m{}", i), avatar, 52)));
  }
  net.advance(0.5);
  double next = net.now();
  net.advance(1.0, 0.001, [&](double now) {
    if (now + 1e-9 < next) return;
    next += 1.0 / 30.0;
    for (std::size_t i = 0; i < kMembers; ++i) {
      ASSERT_TRUE(net.session(i).sendPosture(test::wavingPosture(52, now), net.localTime(i)));
    }
  });
  // 7 others x 225 bytes do not fit one 1200-byte datagram: every member still hears
  // from every other, from more snapshot datagrams than ticks.
  for (std::size_t i = 0; i < kMembers; ++i) {
    const auto& stats = net.session(i).stats();
    EXPECT_EQ(stats.members.size(), static_cast<std::size_t>(kMembers - 1));
    for (const auto& [name, m] : stats.members) EXPECT_GE(m.postures_received, 25u) << name;
    EXPECT_GE(stats.snapshots_received, 2u * 55u);
  }
}

TEST(ServerConfig, DefaultsParseAndErrorsNameTheKey) {
  auto embedded = loadServerConfig("config/server.toml");
  ASSERT_TRUE(embedded) << embedded.error().message;
  EXPECT_EQ(embedded->port, 7400);
  EXPECT_EQ(embedded->tick_rate_hz, 60.0);
  auto bad = parseServerConfig("[session]\ntick_rate_hz = 0\n", "x.toml");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("tick_rate_hz"), std::string::npos);
  auto unknown = parseServerConfig("[session]\ntick_rate = 5\n", "x.toml");
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().message.find("tick_rate"), std::string::npos);
  auto syntax = parseServerConfig("[session\n", "x.toml");
  ASSERT_FALSE(syntax);
  EXPECT_NE(syntax.error().message.find("x.toml"), std::string::npos);
}

}  // namespace
}  // namespace vistel::server

namespace vistel::server {
namespace {

// A member that forges its hello's source address (issue 20, finding 3) cannot point the
// room's stream at a third party: the forged address gets one challenge, smaller than the
// hello, and nothing after it; only an address that echoes its challenge is bound.
TEST(HelloChallenge, AForgedSourceAddressGetsOneSmallChallengeAndNoStream) {
  SimNetwork net(testConfig(), 61);
  const auto avatar = test::encodeSynthetic(test::makeCollidingAvatar());
  const auto alice = net.addClient(test::sessionFor("lab", "alice", avatar, 5));
  const auto bob = net.addClient(test::sessionFor("lab", "bob", avatar, 5));
  net.connect(alice);
  net.connect(bob);
  net.advance(0.3);
  ASSERT_EQ(net.session(alice).state(), SessionState::kLive);
  // Alice knows her own id and keys; she seals a hello as if from the victim.
  const wire::Endpoint victim = wire::Endpoint::ipv4(0x7F000042u, 5555);
  const wire::SessionKeys* keys = net.server().lobby().keysOf(net.session(alice).memberId());
  ASSERT_NE(keys, nullptr);
  wire::HelloPacket hello;
  hello.header = {net.session(alice).memberId(), 0};
  hello.attempt = 1;
  std::vector<std::uint8_t> bytes;
  wire::write(hello, bytes);
  bytes = test::sealWith(keys->client_to_server, bytes, std::uint64_t{1} << 40);
  net.injectDatagram(bytes, victim);
  double next = net.now();
  net.advance(1.0, 0.001, [&](double now) {
    if (now + 1e-9 < next) return;
    next += 1.0 / 30.0;
    for (std::size_t i : {alice, bob}) {
      net.session(i).sendPosture(test::syntheticPosture(now), net.localTime(i));
    }
  });
  const auto& to_victim = net.rawDatagrams(victim);
  ASSERT_EQ(to_victim.size(), 1u);
  EXPECT_LE(to_victim[0].size(), bytes.size());
  wire::HelloAckPacket challenge;
  ASSERT_TRUE(wire::read(test::openWith(keys->server_hello, to_victim[0]), challenge));
  EXPECT_NE(challenge.cookie, 0u);
  // Alice's own stream goes on where she really is.
  EXPECT_EQ(net.session(alice).state(), SessionState::kLive);
  EXPECT_GT(net.session(bob).stats().members.at("alice").postures_received, 20u);
}

}  // namespace
}  // namespace vistel::server
