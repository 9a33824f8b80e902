// The client's network side (NetDriver, as vistel-client and vistel-bot run it) on
// loopback against the server core (issue 20, finding 7): a session survives a server
// restart on the same port and a network cut the server did not notice, rejoining with the
// same name and no duplicate member; a NAT rebinding (a new local UDP port) keeps the
// session after a re-hello; a refusal for good still ends it, and so does the give-up time.
//
// The waits poll the driver with a generous cap so that a broken build fails instead of
// hanging; nothing asserts how long anything took.
#include <gtest/gtest.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <functional>
#include <memory>
#include <thread>

#include "client/net/net_driver.hpp"
#include "tests/net/loopback/loopback_server.hpp"
#include "tests/net/synthetic_avatar.hpp"

namespace vistel {
namespace {

namespace asio = boost::asio;
using net::NetDriver;
using net::SessionState;

class Reconnect : public ::testing::Test {
 protected:
  void SetUp() override { spdlog::set_level(spdlog::level::err); }
  void TearDown() override {
    if (driver_) {
      driver_->stop("test over");
      waitFor([&] { return driver_->state() == SessionState::kClosed; }, 2.0);
    }
    io_.stop();
    if (network_.joinable()) network_.join();
  }

  net::SessionSettings settings(const std::string& room = "lab", const std::string& name = "ada") {
    auto s = test::sessionFor(room, name, avatar_, 5);
    s.rehello_after_s = 0.3;
    return s;
  }

  // Starts a driver (backoff windows from 0.2 s) toward the loopback server's port.
  void startDriver(std::uint16_t port, const net::SessionSettings& s) {
    net::BackoffSettings backoff;
    backoff.base_s = 0.2;
    backoff.max_s = 1.0;
    driver_ = NetDriver::create(io_, net::ServerAddress{"127.0.0.1", port}, s, nullptr, backoff);
    driver_->start();
    network_ = std::thread([this] { io_.run(); });
  }

  // Polls `done` (sending postures meanwhile) until true or `cap_s` passed.
  bool waitFor(const std::function<bool()>& done, double cap_s = 8.0) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(cap_s);
    while (std::chrono::steady_clock::now() < end) {
      if (done()) return true;
      if (driver_) driver_->sendPosture(test::syntheticPosture(net::monotonicSeconds()));
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return done();
  }
  bool waitLive() {
    return waitFor([&] { return driver_->state() == SessionState::kLive; });
  }

  // Names in the server's roster of `room`, and the members it holds in all.
  static int serverMembers(test::LoopbackServer& server) {
    return server.inspect(
        [](const server::ServerCore& core) { return core.lobby().memberCount(); });
  }
  std::size_t rosterSize() {
    return driver_->withSession(
        [](const net::ClientSession& s, double) { return s.members().size(); });
  }
  net::SessionStats stats() {
    return driver_->withSession([](const net::ClientSession& s, double) { return s.stats(); });
  }

  server::ServerConfig config_;
  test::EncodedAvatar avatar_ = test::encodeSynthetic(test::makeSyntheticAvatar());
  asio::io_context io_;
  asio::executor_work_guard<asio::io_context::executor_type> work_ = asio::make_work_guard(io_);
  std::shared_ptr<NetDriver> driver_;
  std::thread network_;
};

TEST_F(Reconnect, SurvivesAServerKilledAndStartedAgainOnTheSamePort) {
  auto first = std::make_unique<test::LoopbackServer>(config_);
  const std::uint16_t port = first->port();
  startDriver(port, settings());
  ASSERT_TRUE(waitLive()) << driver_->error();

  first->stop();  // no goodbye
  first.reset();
  test::LoopbackServer second(config_, port);
  ASSERT_TRUE(waitFor([&] { return driver_->reconnects() == 1; })) << driver_->error();
  ASSERT_TRUE(waitLive()) << driver_->error();

  EXPECT_EQ(serverMembers(second), 1);
  EXPECT_TRUE(waitFor([&] { return rosterSize() == 1; }));
  EXPECT_EQ(stats().reconnects, 1u);
  EXPECT_TRUE(driver_->error().empty()) << driver_->error();
}

TEST_F(Reconnect, SurvivesAGracefulRestart) {
  auto first = std::make_unique<test::LoopbackServer>(config_);
  const std::uint16_t port = first->port();
  startDriver(port, settings());
  ASSERT_TRUE(waitLive()) << driver_->error();

  first->stop(/*graceful=*/true);  // SHUTTING_DOWN to everyone
  first.reset();
  test::LoopbackServer second(config_, port);
  ASSERT_TRUE(waitFor([&] { return driver_->reconnects() == 1; })) << driver_->error();
  ASSERT_TRUE(waitLive());
  EXPECT_EQ(serverMembers(second), 1);
}

TEST_F(Reconnect, ACutTheServerMissedResumesWithoutADuplicate) {
  test::LoopbackServer server(config_);
  startDriver(server.port(), settings());
  ASSERT_TRUE(waitLive()) << driver_->error();

  // The server still holds our member when we come back: the resume replaces it (the name
  // is not refused, no second member appears).
  server.sever();
  ASSERT_TRUE(waitFor([&] { return driver_->reconnects() == 1; })) << driver_->error();
  ASSERT_TRUE(waitLive());
  EXPECT_EQ(serverMembers(server), 1);
  EXPECT_TRUE(waitFor([&] { return rosterSize() == 1; }));
  EXPECT_EQ(driver_->rejoins(), 1);  // one join was enough: no NAME_TAKEN in between
}

TEST_F(Reconnect, ANatRebindingKeepsTheSession) {
  test::LoopbackServer server(config_);
  startDriver(server.port(), settings());
  ASSERT_TRUE(waitLive()) << driver_->error();
  const auto id =
      driver_->withSession([](const net::ClientSession& s, double) { return s.memberId(); });

  driver_->reopenDatagramSocket();  // the server now sees us at a new port
  ASSERT_TRUE(waitFor([&] { return stats().udp_rebinds == 1; })) << driver_->error();

  EXPECT_EQ(driver_->state(), SessionState::kLive);
  EXPECT_EQ(driver_->reconnects(), 0);
  EXPECT_EQ(driver_->withSession([](const net::ClientSession& s, double) { return s.memberId(); }),
            id);
  EXPECT_EQ(serverMembers(server), 1);
  // Datagrams flow again: pongs keep the clock going, no re-hello pending.
  EXPECT_TRUE(waitFor([&] {
    return !driver_->withSession(
        [](const net::ClientSession& s, double) { return s.rehelloing(); });
  }));
}

TEST_F(Reconnect, ARefusedFirstJoinEnds) {
  test::LoopbackServer server(config_);
  startDriver(server.port(), settings("no spaces allowed"));
  ASSERT_TRUE(waitFor([&] { return driver_->state() == SessionState::kClosed; }));
  EXPECT_NE(driver_->error().find("BAD_JOIN"), std::string::npos) << driver_->error();
  EXPECT_EQ(driver_->rejoins(), 0);
}

TEST_F(Reconnect, ARefusalForGoodWhileReconnectingEnds) {
  auto first = std::make_unique<test::LoopbackServer>(config_);
  const std::uint16_t port = first->port();
  startDriver(port, settings());
  ASSERT_TRUE(waitLive()) << driver_->error();

  // The new server will not take our avatar (it lacks it and allows less).
  first->stop();
  first.reset();
  server::ServerConfig strict = config_;
  strict.max_avatar_bytes = 64;
  test::LoopbackServer second(strict, port);
  ASSERT_TRUE(waitFor([&] { return driver_->state() == SessionState::kClosed; }));
  EXPECT_NE(driver_->error().find("AVATAR_REJECTED"), std::string::npos) << driver_->error();
  EXPECT_EQ(driver_->reconnects(), 0);
}

TEST_F(Reconnect, GivesUpAfterTheConfiguredTime) {
  auto server = std::make_unique<test::LoopbackServer>(config_);
  auto s = settings();
  s.reconnect_give_up_s = 0.5;
  startDriver(server->port(), s);
  ASSERT_TRUE(waitLive()) << driver_->error();

  server->stop();  // and it never comes back
  server.reset();
  ASSERT_TRUE(waitFor([&] { return driver_->state() == SessionState::kClosed; }));
  EXPECT_FALSE(driver_->error().empty());
  EXPECT_GE(driver_->rejoins(), 1);
  EXPECT_EQ(driver_->reconnects(), 0);
}

}  // namespace
}  // namespace vistel
