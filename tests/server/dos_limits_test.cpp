// Limits against floods (server/core/lobby.hpp): a control-message flood, too many
// half-finished avatar uploads and stalled uploads drop the abuser with a logged reason
// and never anyone else.
#include <string>
#include <vector>

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

ServerConfig limitsConfig() {
  ServerConfig c;
  c.tick_rate_hz = 60.0;
  c.member_timeout_s = 3.0;
  c.control_rate_hz = 10.0;
  c.control_burst = 30;
  c.max_upload_bytes_total = 250000;
  c.upload_stall_timeout_s = 0.5;
  return c;
}

class DosLimitsTest : public ::testing::Test {
 protected:
  DosLimitsTest()
      : net_(limitsConfig(), 31), avatar_(test::encodeSynthetic(test::makeCollidingAvatar())) {
    spdlog::set_level(spdlog::level::err);
    for (const char* name : {"alice", "bob"}) {
      good_.push_back(net_.addClient(test::sessionFor("lab", name, avatar_, 5)));
      net_.connect(good_.back());
    }
    net_.advance(0.5);
  }

  // The good members stream for a while; true when both stay live and hear each other.
  bool goodMembersCarryOn(double duration) {
    const auto heard = [&](std::size_t at, const char* from) {
      const auto& m = net_.session(at).stats().members;
      auto it = m.find(from);
      return it == m.end() ? std::uint64_t{0} : it->second.postures_received;
    };
    const std::uint64_t before = heard(good_[1], "alice");
    double next = net_.now();
    net_.advance(duration, 0.001, [&](double now) {
      if (now + 1e-9 < next) return;
      next += 1.0 / 30.0;
      for (std::size_t i : good_) {
        net_.session(i).sendPosture(test::syntheticPosture(now), net_.localTime(i));
      }
    });
    const bool live = net_.session(good_[0]).state() == SessionState::kLive &&
                      net_.session(good_[1]).state() == SessionState::kLive;
    return live && heard(good_[1], "alice") >= before + static_cast<std::uint64_t>(duration * 25);
  }

  SimNetwork net_;
  test::EncodedAvatar avatar_;
  std::vector<std::size_t> good_;
};

TEST_F(DosLimitsTest, AControlMessageFloodDropsTheSenderOnly) {
  // A member that asks for the same avatar 200 times at once.
  net_.injectConnect(930);
  net_.injectStream(930, test::frameOf(test::joinMessage("lab", "flood", avatar_.hash,
                                                         avatar_.bytes.size(), kProtocolVersion)));
  EXPECT_EQ(net_.server().lobby().memberCount(), 3);
  control::ClientMessage request;
  request.mutable_avatar_request()->set_hash(avatar_.hash);
  std::vector<std::uint8_t> flood;
  for (int k = 0; k < 200; ++k) {
    const auto f = test::frameOf(request);
    flood.insert(flood.end(), f.begin(), f.end());
  }
  net_.injectStream(930, flood);
  const auto replies = test::messagesOf(net_.rawReceived(930));
  ASSERT_FALSE(replies.empty());
  EXPECT_EQ(replies.back().error().code(), control::ErrorReply::RATE_LIMITED);
  EXPECT_NE(replies.back().error().message().find("faster than"), std::string::npos);
  EXPECT_TRUE(net_.rawClosed(930));
  EXPECT_EQ(net_.server().lobby().drops().count("control message rate"), 1u);
  // It was served at most its burst of requests before being cut (each answer is the file
  // in chunks, from offset 0).
  int served = 0;
  for (const auto& m : replies) served += m.has_avatar_chunk() && m.avatar_chunk().offset() == 0;
  EXPECT_LE(served, 30);
  EXPECT_EQ(net_.server().lobby().memberCount(), 2);
  EXPECT_TRUE(goodMembersCarryOn(1.0));

  // A member sending at the sustained rate is not dropped (spawns are rate-limited apart,
  // so ignored ones cost nothing more).
  const auto steady = net_.addClient(test::sessionFor("lab", "steady", avatar_, 5));
  net_.connect(steady);
  net_.advance(0.5);
  for (int k = 0; k < 40; ++k) {
    ASSERT_TRUE(net_.session(steady).requestBall());
    net_.advance(0.15);
  }
  EXPECT_EQ(net_.session(steady).state(), SessionState::kLive) << net_.session(steady).error();
}

TEST_F(DosLimitsTest, HalfFinishedUploadsAreCappedAndStalledOnesDropped) {
  // Joins offering unknown avatars of 100 kB each, never finishing: two fit the 250 kB
  // budget, the third is refused.
  for (int k = 0; k < 3; ++k) {
    const auto conn = static_cast<ConnId>(940 + k);
    net_.injectConnect(conn);
    net_.injectStream(conn, test::frameOf(test::joinMessage("lab", "up" + std::to_string(k),
                                                            std::string(63, 'a') + char('0' + k),
                                                            100000, kProtocolVersion)));
  }
  EXPECT_EQ(net_.server().lobby().uploadBytesInFlight(), 200000u);
  auto replies = test::messagesOf(net_.rawReceived(942));
  ASSERT_EQ(replies.size(), 1u);
  EXPECT_EQ(replies[0].error().code(), control::ErrorReply::SERVER_FULL);
  EXPECT_NE(replies[0].error().message().find("uploads in progress"), std::string::npos);
  EXPECT_EQ(net_.server().lobby().drops().count("upload capacity"), 1u);
  // One of them trickles a chunk, then stalls too.
  control::ClientMessage chunk;
  chunk.mutable_avatar_chunk()->set_hash(std::string(63, 'a') + '1');
  chunk.mutable_avatar_chunk()->set_total_size(100000);
  chunk.mutable_avatar_chunk()->set_offset(0);
  chunk.mutable_avatar_chunk()->set_data(std::string(300, 'x'));
  net_.advance(0.3);
  net_.injectStream(941, test::frameOf(chunk));
  // A newcomer whose avatar the server has joins meanwhile.
  const auto carol = net_.addClient(test::sessionFor("lab", "carol", avatar_, 5));
  net_.connect(carol);
  EXPECT_TRUE(goodMembersCarryOn(1.0));
  EXPECT_EQ(net_.session(carol).state(), SessionState::kLive);

  // Both stalled uploads were dropped, their reservations given back.
  for (ConnId conn : {ConnId{940}, ConnId{941}}) {
    EXPECT_TRUE(net_.rawClosed(conn));
    replies = test::messagesOf(net_.rawReceived(conn));
    ASSERT_FALSE(replies.empty());
    EXPECT_EQ(replies.back().error().code(), control::ErrorReply::TIMEOUT);
    EXPECT_NE(replies.back().error().message().find("stalled"), std::string::npos);
  }
  EXPECT_EQ(net_.server().lobby().drops().count("upload stalled"), 2u);
  EXPECT_EQ(net_.server().lobby().uploadBytesInFlight(), 0u);
  EXPECT_EQ(net_.server().lobby().memberCount(), 3);

  // With the budget free again, a real upload goes through.
  const auto other = test::encodeSynthetic(test::makeCollidingAvatar("other"));
  const auto dave = net_.addClient(test::sessionFor("lab", "dave", other, 5));
  net_.connect(dave);
  net_.advance(0.3);
  EXPECT_EQ(net_.session(dave).state(), SessionState::kLive) << net_.session(dave).error();
  EXPECT_EQ(net_.server().lobby().uploadBytesInFlight(), 0u);
  EXPECT_EQ(net_.server().findRoom("lab")->world().bodies().size(), 4u);
}

}  // namespace
}  // namespace vistel::server
