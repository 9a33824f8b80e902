// Client settings, server addresses, the data folder, statistics JSON.
#include <cstdlib>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "client/net/client_config.hpp"
#include "client/net/data_dir.hpp"
#include "client/net/net_driver.hpp"
#include "client/net/session_stats.hpp"

namespace vistel::net {
namespace {

TEST(ClientConfig, EmbeddedDefaultsParse) {
  auto c = loadClientConfig("config/client.toml");
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_DOUBLE_EQ(c->interpolation_delay_s, 0.1);
  EXPECT_EQ(c->session.jitter_capacity, 32);
  auto bad = parseClientConfig("[playback]\njitter_capacity = 1\n", "c.toml");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("jitter_capacity"), std::string::npos);
  auto unknown = parseClientConfig("[nope]\n", "c.toml");
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().message.find("nope"), std::string::npos);
}

TEST(ClientConfig, ReconnectSettings) {
  auto defaults = parseClientConfig("", "c.toml");
  ASSERT_TRUE(defaults) << defaults.error().message;
  EXPECT_GT(defaults->session.reconnect_give_up_s, 60.0);
  EXPECT_GT(defaults->session.rehello_after_s, 0.0);
  auto c =
      parseClientConfig("[network]\nreconnect_give_up_s = 0\nrehello_after_s = 1.5\n", "c.toml");
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_DOUBLE_EQ(c->session.reconnect_give_up_s, 0.0);
  EXPECT_DOUBLE_EQ(c->session.rehello_after_s, 1.5);
  auto bad = parseClientConfig("[network]\nreconnect_give_up_s = -1\n", "c.toml");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("reconnect_give_up_s"), std::string::npos);
}

TEST(ServerAddress, ParsesHostPortAndRefusesTheRest) {
  auto a = parseServerAddress("127.0.0.1:7400");
  ASSERT_TRUE(a);
  EXPECT_EQ(a->host, "127.0.0.1");
  EXPECT_EQ(a->port, 7400);
  auto v6 = parseServerAddress("[::1]:9");
  ASSERT_TRUE(v6);
  EXPECT_EQ(v6->host, "::1");
  for (const char* bad : {"localhost", "host:", ":80", "h:0", "h:65536", "h:12x", "[::1]9"}) {
    EXPECT_FALSE(parseServerAddress(bad)) << bad;
  }
}

TEST(DataDir, EnvironmentWins) {
  setenv("VISTEL_DATA_DIR", "/some/where", 1);
  EXPECT_EQ(findDataDir(), "/some/where");
  EXPECT_EQ(defaultAvatarPath(), "/some/where/default.vavatar");
  unsetenv("VISTEL_DATA_DIR");
  EXPECT_FALSE(findDataDir().empty());
}

TEST(SessionStats, JsonHasTheAgreedShape) {
  SessionStats s;
  s.members["bot"].postures_received = 31;
  s.members["bot"].first_arrival = 1.0;
  s.members["bot"].last_arrival = 2.0;
  for (int i = 1; i <= 100; ++i) s.latency.add(i);
  const auto doc = nlohmann::json::parse(statsJson(s, 7, 0.5, 0.001));
  EXPECT_EQ(doc["members"]["bot"]["postures_received"], 31);
  EXPECT_DOUBLE_EQ(doc["members"]["bot"]["rate_hz"].get<double>(), 30.0);
  EXPECT_DOUBLE_EQ(doc["latency_ms"]["mean"].get<double>(), 50.5);
  EXPECT_NEAR(doc["latency_ms"]["p99"].get<double>(), 99.0, 0.05);
  EXPECT_EQ(doc["frames_rendered"], 7);
  EXPECT_EQ(doc["reconnects"], 0);
  EXPECT_EQ(doc["udp_rebinds"], 0);
}

}  // namespace
}  // namespace vistel::net
