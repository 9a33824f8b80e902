// Resuming a session and NAT rebinding (issue 20, finding 7) over the simulated network:
// a client whose connection died without the server noticing joins again with the
// previous Welcome's member id and a proof from that session's resume secret
// (Join.resume_*) and replaces its stale member instead of being refused the name; a
// stranger with the name but not the secret cannot;
// a client whose UDP address changes says hello again when the server's datagrams stop,
// answers the challenge sent to its new address, and keeps its member.
#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include "tests/net/sim_network.hpp"
#include "tests/net/synthetic_avatar.hpp"

namespace vistel {
namespace {

using test::SimNetwork;

struct ResumeFixture : ::testing::Test {
  void SetUp() override { spdlog::set_level(spdlog::level::err); }

  // Every connected session sends its posture each 20 ms of simulated time.
  static void run(SimNetwork& net, double seconds) {
    double next = net.now();
    net.advance(seconds, 0.001, [&](double now) {
      if (now < next) return;
      next = now + 0.02;
      for (std::size_t i = 0; i < net.clientCount(); ++i) {
        if (net.client(i).connected) {
          net.session(i).sendPosture(test::syntheticPosture(now), net.localTime(i));
        }
      }
    });
  }

  // Names in the roster a session sees.
  static std::vector<std::string> rosterNames(const net::ClientSession& s) {
    std::vector<std::string> names;
    for (const auto& m : s.members()) names.push_back(m->name);
    return names;
  }

  server::ServerConfig config;
  test::EncodedAvatar avatar = test::encodeSynthetic(test::makeSyntheticAvatar());
};

TEST_F(ResumeFixture, ResumingReplacesTheStaleMemberAndKeepsItsSeat) {
  SimNetwork net(config, 7);
  const auto other = net.addClient(test::sessionFor("r", "other", avatar, 5));
  const auto old = net.addClient(test::sessionFor("r", "ada", avatar, 5));
  net.connect(other);
  net.connect(old);
  run(net, 1.0);
  ASSERT_EQ(net.session(old).state(), net::SessionState::kLive) << net.session(old).error();
  const std::uint32_t old_id = net.session(old).memberId();
  const float old_seat_x = net.session(old).findMember(old_id)->seat.x;

  // The old connection dies on the client's side only: the server still holds "ada".
  net.client(old).connected = false;
  auto settings = test::sessionFor("r", "ada", avatar, 5);
  settings.resume_member_id = old_id;
  settings.resume_secret = net.session(old).resumeSecret();
  const auto resumed = net.addClient(settings);
  net.connect(resumed);
  run(net, 1.0);

  ASSERT_EQ(net.session(resumed).state(), net::SessionState::kLive) << net.session(resumed).error();
  EXPECT_NE(net.session(resumed).memberId(), old_id);
  EXPECT_EQ(net.server().lobby().memberCount(), 2);
  // One "ada" in everyone's roster, in the old seat.
  const auto names = rosterNames(net.session(other));
  EXPECT_EQ(std::count(names.begin(), names.end(), "ada"), 1);
  EXPECT_EQ(names.size(), 2u);
  const net::RemoteMember* me = net.session(resumed).findMember(net.session(resumed).memberId());
  ASSERT_NE(me, nullptr);
  EXPECT_FLOAT_EQ(me->seat.x, old_seat_x);
  // The resumed member's postures reach the other member.
  EXPECT_GT(net.session(other).stats().members.at("ada").postures_received, 0u);
}

TEST_F(ResumeFixture, ResumingAloneKeepsTheRoomsAvatarFile) {
  SimNetwork net(config, 13);
  const auto old = net.addClient(test::sessionFor("r", "ada", avatar, 5));
  net.connect(old);
  run(net, 1.0);
  ASSERT_EQ(net.session(old).state(), net::SessionState::kLive);
  ASSERT_NE(net.server().lobby().avatars().find(avatar.hash), nullptr);

  // The only member's stale copy goes: its avatar must not go with it.
  net.client(old).connected = false;
  auto settings = test::sessionFor("r", "ada", avatar, 5);
  settings.resume_member_id = net.session(old).memberId();
  settings.resume_secret = net.session(old).resumeSecret();
  const auto resumed = net.addClient(settings);
  net.connect(resumed);
  run(net, 1.0);
  ASSERT_EQ(net.session(resumed).state(), net::SessionState::kLive) << net.session(resumed).error();
  EXPECT_EQ(net.server().lobby().memberCount(), 1);
  EXPECT_NE(net.server().lobby().avatars().find(avatar.hash), nullptr);
  EXPECT_EQ(net.server().lobby().uploadsInProgress(), 0);
  EXPECT_GT(net.session(resumed).stats().postures_sent, 0u);
}

TEST_F(ResumeFixture, ANameWithoutTheKeyEvictsNobody) {
  SimNetwork net(config, 8);
  const auto owner = net.addClient(test::sessionFor("r", "ada", avatar, 5));
  net.connect(owner);
  run(net, 1.0);
  ASSERT_EQ(net.session(owner).state(), net::SessionState::kLive);

  // A stranger knows the name and the member id (both in every roster), not the resume
  // secret (derived from the key exchange; it never travels).
  auto settings = test::sessionFor("r", "ada", avatar, 5);
  settings.resume_member_id = net.session(owner).memberId();
  settings.resume_secret = net.session(owner).resumeSecret();
  settings.resume_secret[0] ^= 1u;
  const auto stranger = net.addClient(settings);
  net.connect(stranger);
  run(net, 1.0);

  EXPECT_EQ(net.session(stranger).state(), net::SessionState::kClosed);
  EXPECT_EQ(net.session(stranger).closeCause(), net::CloseCause::kTaken)
      << net.session(stranger).error();
  EXPECT_EQ(net.session(owner).state(), net::SessionState::kLive);
  EXPECT_EQ(net.server().lobby().memberCount(), 1);
}

TEST_F(ResumeFixture, ARefusalForGoodSaysSo) {
  SimNetwork net(config, 9);
  auto settings = test::sessionFor("bad room name!", "ada", avatar, 5);
  const auto c = net.addClient(settings);
  net.connect(c);
  run(net, 0.5);
  EXPECT_EQ(net.session(c).state(), net::SessionState::kClosed);
  EXPECT_EQ(net.session(c).closeCause(), net::CloseCause::kRefused) << net.session(c).error();
}

TEST_F(ResumeFixture, AShutdownIsALostSessionNotARefusal) {
  SimNetwork net(config, 10);
  const auto c = net.addClient(test::sessionFor("r", "ada", avatar, 5));
  net.connect(c);
  run(net, 1.0);
  ASSERT_EQ(net.session(c).state(), net::SessionState::kLive);
  net.server().shutdown(net.now());
  run(net, 0.5);
  EXPECT_EQ(net.session(c).state(), net::SessionState::kClosed);
  EXPECT_EQ(net.session(c).closeCause(), net::CloseCause::kLost) << net.session(c).error();
}

TEST_F(ResumeFixture, ANatRebindingKeepsTheSession) {
  SimNetwork net(config, 11);
  const auto peer = net.addClient(test::sessionFor("r", "peer", avatar, 5));
  const auto moving = net.addClient(test::sessionFor("r", "ada", avatar, 5));
  net.connect(peer);
  net.connect(moving);
  run(net, 1.0);
  ASSERT_EQ(net.session(moving).state(), net::SessionState::kLive);
  const std::uint32_t id = net.session(moving).memberId();

  // The NAT gives the client a new public port: the server keeps sending to the old one
  // (lost) and drops what comes from the new one until the challenge is answered.
  net.client(moving).endpoint.port =
      static_cast<std::uint16_t>(net.client(moving).endpoint.port + 1000);
  const auto before = net.session(moving).stats().members.at("peer").postures_received;
  // Longer than both timeouts (the server's member timeout, the client's server timeout).
  run(net, std::max(config.member_timeout_s, 10.0) + 3.0);

  EXPECT_EQ(net.session(moving).state(), net::SessionState::kLive) << net.session(moving).error();
  EXPECT_EQ(net.session(moving).memberId(), id);
  EXPECT_EQ(net.server().lobby().memberCount(), 2);
  EXPECT_EQ(net.session(moving).stats().udp_rebinds, 1u);
  EXPECT_FALSE(net.session(moving).rehelloing());
  // Postures flow again both ways.
  EXPECT_GT(net.session(moving).stats().members.at("peer").postures_received, before);
  EXPECT_EQ(net.session(peer).state(), net::SessionState::kLive);
}

TEST_F(ResumeFixture, AQuietServerGetsHellosThatChangeNothing) {
  SimNetwork net(config, 12);
  const auto c = net.addClient(test::sessionFor("r", "ada", avatar, 5));
  net.connect(c);
  run(net, 1.0);
  ASSERT_EQ(net.session(c).state(), net::SessionState::kLive);
  // Every datagram from the server is lost for a while (the address did not change).
  net.client(c).down.loss = 1.0;
  run(net, 3.0);
  EXPECT_TRUE(net.session(c).rehelloing());
  net.client(c).down.loss = 0.0;
  run(net, 1.0);
  EXPECT_EQ(net.session(c).state(), net::SessionState::kLive);
  EXPECT_FALSE(net.session(c).rehelloing());
  EXPECT_EQ(net.session(c).stats().udp_rehellos, 1u);
  EXPECT_EQ(net.session(c).stats().udp_rebinds, 0u);
}

}  // namespace
}  // namespace vistel
