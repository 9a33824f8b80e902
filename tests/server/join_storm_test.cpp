// Joins at once (issue 19): many members offering the same avatar the server lacks share
// one upload (the others wait for it and become ready with it), and an upload that fails
// is handed to a member that waited for it.
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include "server/core/server_core.hpp"
#include "tests/net/sim_network.hpp"
#include "tests/net/synthetic_avatar.hpp"
#include "tests/server/control_frames.hpp"

namespace vistel::server {
namespace {

using net::SessionState;
using test::SimNetwork;

// Room for exactly one upload of the avatar: a second concurrent reservation would be
// refused with SERVER_FULL.
ServerConfig oneUploadConfig(std::size_t avatar_bytes) {
  ServerConfig c;
  c.tick_rate_hz = 60.0;
  c.max_upload_bytes_total = avatar_bytes + avatar_bytes / 2;
  c.control_burst = 1000;
  return c;
}

// Every session live, and the server streaming its postures to the others.
void streamBriefly(SimNetwork& net, const std::vector<std::size_t>& clients) {
  double next = net.now();
  net.advance(0.5, 0.001, [&](double now) {
    if (now + 1e-9 < next) return;
    next += 1.0 / 30.0;
    for (std::size_t i : clients) net.session(i).sendPosture(test::syntheticPosture(now), now);
  });
}

TEST(JoinStorm, ConcurrentJoinsWithOneAvatarShareOneUpload) {
  spdlog::set_level(spdlog::level::err);
  const auto avatar = test::encodeSynthetic(test::makeCollidingAvatar());
  SimNetwork net(oneUploadConfig(avatar.bytes.size()), 41);
  constexpr int kMembers = 24;
  std::vector<std::size_t> clients;
  for (int i = 0; i < kMembers; ++i) {
    clients.push_back(net.addClient(test::sessionFor("hall", fmt::format("m{}", i), avatar, 5)));
  }
  // All connect at the same instant; the joins arrive (10 ms of TCP latency), and no
  // chunk can yet.
  for (std::size_t i : clients) net.connect(i);
  net.advance(0.015);
  EXPECT_EQ(net.server().lobby().uploadsInProgress(), 1);
  EXPECT_EQ(net.server().lobby().uploadBytesInFlight(), avatar.bytes.size());
  EXPECT_EQ(net.server().lobby().memberCount(), kMembers);

  streamBriefly(net, clients);
  EXPECT_EQ(net.server().lobby().uploadsInProgress(), 0);
  EXPECT_EQ(net.server().lobby().uploadBytesInFlight(), 0u);
  EXPECT_EQ(net.server().lobby().drops().count("upload capacity"), 0u);
  for (std::size_t i : clients) {
    ASSERT_EQ(net.session(i).state(), SessionState::kLive) << i << ": " << net.session(i).error();
    // Postures go out only once the server holds the avatar: everyone's did.
    EXPECT_GT(net.session(i).stats().postures_sent, 0u) << i;
  }
  // Everyone hears everyone else.
  const auto& heard = net.session(clients.back()).stats().members;
  EXPECT_EQ(heard.size(), static_cast<std::size_t>(kMembers - 1));
}

TEST(JoinStorm, AFailedUploadIsHandedToAMemberThatWaitedForIt) {
  spdlog::set_level(spdlog::level::err);
  const auto avatar = test::encodeSynthetic(test::makeCollidingAvatar());
  SimNetwork net(oneUploadConfig(avatar.bytes.size()), 43);
  // A raw peer offers the avatar first and never uploads it.
  constexpr ConnId kQuitter = 970;
  net.injectConnect(kQuitter);
  net.injectStream(
      kQuitter, test::frameOf(test::joinMessage("hall", "quitter", avatar.hash, avatar.bytes.size(),
                                                kProtocolVersion)));
  auto replies = test::messagesOf(net.rawReceived(kQuitter));
  ASSERT_FALSE(replies.empty());
  EXPECT_TRUE(replies[0].welcome().upload_avatar());

  // Two members with the same avatar join meanwhile: they wait for that upload.
  const auto ann = net.addClient(test::sessionFor("hall", "ann", avatar, 5));
  const auto ben = net.addClient(test::sessionFor("hall", "ben", avatar, 5));
  net.connect(ann);
  net.connect(ben);
  net.advance(0.2);
  EXPECT_EQ(net.server().lobby().uploadsInProgress(), 1);
  EXPECT_EQ(net.session(ann).stats().postures_sent, 0u);
  EXPECT_FALSE(net.session(ann).sendPosture(test::syntheticPosture(0.0), net.localTime(ann)));

  // The first uploader goes away: one of the waiting members takes the upload over, and
  // both become ready with it.
  net.server().onDisconnect(kQuitter, net.now());
  streamBriefly(net, {ann, ben});
  EXPECT_EQ(net.server().lobby().uploadsInProgress(), 0);
  EXPECT_EQ(net.server().lobby().uploadBytesInFlight(), 0u);
  for (std::size_t i : {ann, ben}) {
    ASSERT_EQ(net.session(i).state(), SessionState::kLive) << net.session(i).error();
    EXPECT_GT(net.session(i).stats().postures_sent, 0u);
  }
  EXPECT_EQ(net.server().findRoom("hall")->world().bodies().size(), 2u);
}

TEST(JoinStorm, ARefusalForCapacitySaysWhenToTryAgain) {
  spdlog::set_level(spdlog::level::err);
  const auto avatar = test::encodeSynthetic(test::makeCollidingAvatar());
  ServerConfig config = oneUploadConfig(avatar.bytes.size());
  SimNetwork net(config, 47);
  // Another avatar's upload holds the whole budget.
  net.injectConnect(980);
  net.injectStream(
      980, test::frameOf(test::joinMessage("hall", "big", std::string(64, 'b'),
                                           config.max_upload_bytes_total, kProtocolVersion)));
  const auto ann = net.addClient(test::sessionFor("hall", "ann", avatar, 5));
  net.connect(ann);
  net.advance(0.1);
  ASSERT_EQ(net.session(ann).state(), SessionState::kClosed);
  EXPECT_NE(net.session(ann).error().find("SERVER_FULL"), std::string::npos);
  EXPECT_GT(net.session(ann).retryAfter(), 0.0);
  // A refusal that is not transient says nothing of the kind.
  const auto twin = net.addClient(test::sessionFor("hall", "big", avatar, 5));
  net.connect(twin);
  net.advance(0.1);
  ASSERT_EQ(net.session(twin).state(), SessionState::kClosed);
  EXPECT_NE(net.session(twin).error().find("NAME_TAKEN"), std::string::npos);
  EXPECT_EQ(net.session(twin).retryAfter(), 0.0);
}

}  // namespace
}  // namespace vistel::server
