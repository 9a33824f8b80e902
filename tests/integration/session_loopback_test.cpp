// The walking skeleton end to end on loopback, with the real programs: vistel-server on
// an ephemeral port (its printed address parsed), two vistel-bots replaying a clip, and
// a headless vistel-client whose --stats-json must show both bots at >= 90% of their
// send rate. Also the programs' failure paths and clean shutdown.

#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "common/avatar/avatar_io.hpp"
#include "common/base/file.hpp"
#include "tests/integration/program.hpp"
#include "tests/integration/session_scratch.hpp"
#include "tests/net/synthetic_avatar.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

using Child = test::Program;

using test::logOf;

class Loopback : public test::SessionScratch {};

TEST_F(Loopback, ServerTwoBotsAndAHeadlessClient) {
  Child server("vistel-server", {"--port", "0"}, dir_ + "/server.log", true);
  const std::string address = test::serverAddress(server);
  ASSERT_FALSE(address.empty());

  Child wave("vistel-bot",
             {"--server", address, "--room", "it", "--name", "wave", "--bvh", bvh_path_, "--avatar",
              avatar_path_, "--loop"},
             dir_ + "/wave.log", false);
  Child clap("vistel-bot",
             {"--server", address, "--room", "it", "--name", "clap", "--bvh", bvh_path_, "--avatar",
              avatar_path_, "--loop"},
             dir_ + "/clap.log", false);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const std::string stats_path = dir_ + "/stats.json";
  Child client("vistel-client",
               {"--server", address, "--room", "it", "--name", "viewer", "--avatar", avatar_path_,
                "--headless", "--duration", "4", "--stats-json", stats_path},
               dir_ + "/client.log", false);

  // The client finishes on its own and writes its stats.
  const auto client_status = client.wait(30.0);
  ASSERT_TRUE(client_status.has_value()) << logOf(dir_ + "/client.log");
  EXPECT_EQ(*client_status, 0) << logOf(dir_ + "/client.log");
  auto text = readFileText(stats_path);
  ASSERT_TRUE(text) << logOf(dir_ + "/client.log");
  const auto stats = nlohmann::json::parse(*text);
  std::printf("[ measure  ] client stats: %s\n", stats.dump().c_str());
  for (const char* bot : {"wave", "clap"}) {
    ASSERT_TRUE(stats["members"].contains(bot)) << *text;
    const double rate = stats["members"][bot]["rate_hz"].get<double>();
    EXPECT_GE(rate, 0.9 * 30.0) << bot << "\n" << *text;
    EXPECT_GE(stats["members"][bot]["postures_received"].get<int>(), 90) << bot;
  }
  EXPECT_TRUE(stats["latency_ms"]["mean"].is_number());
  EXPECT_TRUE(stats["latency_ms"]["p99"].is_number());
  EXPECT_LT(stats["latency_ms"]["mean"].get<double>(), 100.0);  // loopback
  EXPECT_EQ(stats["frames_rendered"].get<int>(), 0);

  // The bots leave cleanly on SIGINT; the server stops cleanly on SIGTERM.
  wave.signal(SIGINT);
  clap.signal(SIGINT);
  EXPECT_EQ(wave.wait(30.0).value_or(-999), 0) << logOf(dir_ + "/wave.log");
  EXPECT_EQ(clap.wait(30.0).value_or(-999), 0) << logOf(dir_ + "/clap.log");
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait(10.0).value_or(-999), 0) << logOf(dir_ + "/server.log");
  EXPECT_NE(logOf(dir_ + "/server.log").find("shut down cleanly"), std::string::npos);
}

TEST_F(Loopback, ServerStopsOnSigintWithClientsConnected) {
  Child server("vistel-server", {"--port", "0"}, dir_ + "/server.log", true);
  const std::string address = test::serverAddress(server);
  Child bot("vistel-bot",
            {"--server", address, "--room", "it", "--name", "b", "--bvh", bvh_path_, "--avatar",
             avatar_path_, "--loop", "--count", "3"},
            dir_ + "/bot.log", false);
  std::this_thread::sleep_for(std::chrono::seconds(1));
  server.signal(SIGINT);
  EXPECT_EQ(server.wait(10.0).value_or(-999), 0) << logOf(dir_ + "/server.log");
  EXPECT_NE(logOf(dir_ + "/server.log").find("'b-3' joined"), std::string::npos);
  // The bots are told the server is shutting down, say so, and wait to rejoin (a restart
  // brings them back: tests/net/loopback) until stopped themselves.
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  const std::string log = logOf(dir_ + "/bot.log");
  EXPECT_NE(log.find("SHUTTING_DOWN"), std::string::npos) << log;
  EXPECT_NE(log.find("reconnecting"), std::string::npos) << log;
  EXPECT_FALSE(bot.wait(0.1).has_value()) << "the bots gave up at once: " << log;
  bot.signal(SIGINT);
  EXPECT_TRUE(bot.wait(10.0).has_value()) << logOf(dir_ + "/bot.log");
}

TEST_F(Loopback, ClientRendersTheRoomOffscreen) {
  Child server("vistel-server", {"--port", "0"}, dir_ + "/server.log", true);
  const std::string address = test::serverAddress(server);
  Child bot("vistel-bot",
            {"--server", address, "--room", "it", "--name", "wave", "--bvh", bvh_path_, "--avatar",
             avatar_path_, "--loop"},
            dir_ + "/bot.log", false);
  const std::string shot = dir_ + "/shot.png";
  const std::string stats_path = dir_ + "/stats.json";
  Child client("vistel-client",
               {"--server", address, "--room", "it", "--name", "viewer", "--avatar", avatar_path_,
                "--duration", "2", "--screenshot", shot, "--stats-json", stats_path, "--frames",
                dir_ + "/frames", "--frames-every", "20"},
               dir_ + "/client.log", false);
  ASSERT_EQ(client.wait(60.0).value_or(-999), 0) << logOf(dir_ + "/client.log");
  if (logOf(dir_ + "/client.log").find("no rendering") != std::string::npos) {
    GTEST_SKIP() << "no GL context on this machine: " << logOf(dir_ + "/client.log");
  }
  EXPECT_TRUE(std::filesystem::exists(shot)) << logOf(dir_ + "/client.log");
  EXPECT_FALSE(std::filesystem::is_empty(dir_ + "/frames"));
  auto text = readFileText(stats_path);
  ASSERT_TRUE(text);
  const auto stats = nlohmann::json::parse(*text);
  EXPECT_GT(stats["frames_rendered"].get<int>(), 0) << *text;
  EXPECT_TRUE(stats["members"].contains("wave")) << *text;
  bot.signal(SIGINT);
  EXPECT_EQ(bot.wait(10.0).value_or(-999), 0);
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait(10.0).value_or(-999), 0);
}

TEST_F(Loopback, ProgramsRefuseBadUsageWithAClearMessage) {
  // A recording that does not exist: the error names the option.
  Child rec("vistel-bot",
            {"--server", "127.0.0.1:1", "--room", "r", "--name", "n", "--recording", "x.vrec"},
            dir_ + "/rec.log", false);
  EXPECT_EQ(rec.wait(10.0).value_or(-999), 2);
  EXPECT_NE(logOf(dir_ + "/rec.log").find("--recording"), std::string::npos);
  // No source at all.
  Child none("vistel-bot", {"--server", "127.0.0.1:1", "--room", "r", "--name", "n"},
             dir_ + "/none.log", false);
  EXPECT_EQ(none.wait(10.0).value_or(-999), 2);
  // Nobody listening: the client says so and fails.
  Child client("vistel-client",
               {"--server", "127.0.0.1:1", "--room", "r", "--name", "n", "--avatar", avatar_path_,
                "--headless", "--duration", "3"},
               dir_ + "/client.log", false);
  EXPECT_EQ(client.wait(15.0).value_or(-999), 1);
  EXPECT_NE(logOf(dir_ + "/client.log").find("cannot connect"), std::string::npos)
      << logOf(dir_ + "/client.log");
  // A server port already taken by another server.
  Child first("vistel-server", {"--port", "0"}, dir_ + "/first.log", true);
  const std::string address = test::serverAddress(first);
  const std::string port = address.substr(address.rfind(':') + 1);
  Child second("vistel-server", {"--port", port}, dir_ + "/second.log", false);
  EXPECT_EQ(second.wait(10.0).value_or(-999), 1);
  EXPECT_NE(logOf(dir_ + "/second.log").find(port), std::string::npos);
  first.signal(SIGTERM);
  EXPECT_EQ(first.wait(10.0).value_or(-999), 0);
}

}  // namespace
}  // namespace vistel
