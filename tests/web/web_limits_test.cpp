// Connections and request rates per address, and the [web] settings.
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "server/web/web_config.hpp"
#include "server/web/web_limits.hpp"

namespace vistel::server {
namespace {

WebConfig smallLimits() {
  WebConfig c;
  c.max_connections = 4;
  c.max_connections_per_address = 2;
  c.request_rate_hz = 2.0;
  c.request_burst = 3;
  return c;
}

TEST(WebLimits, ConnectionsPerAddressAndInAll) {
  WebLimits limits(smallLimits());
  EXPECT_EQ(limits.admit("127.0.0.1", 0.0), "");
  EXPECT_EQ(limits.admit("127.0.0.1", 0.0), "");
  EXPECT_EQ(limits.admit("127.0.0.1", 0.0), "connections per address");
  EXPECT_EQ(limits.openFrom("127.0.0.1"), 2);
  EXPECT_EQ(limits.admit("127.0.0.2", 0.0), "");
  EXPECT_EQ(limits.admit("127.0.0.3", 0.0), "");
  EXPECT_EQ(limits.admit("127.0.0.4", 0.0), "connection limit");
  EXPECT_EQ(limits.open(), 4);
  limits.release("127.0.0.1");
  EXPECT_EQ(limits.admit("127.0.0.4", 0.0), "");
  limits.release("127.0.0.9");  // never admitted: nothing changes
  limits.release("127.0.0.4");
  limits.release("127.0.0.4");  // twice: counted once
  EXPECT_EQ(limits.open(), 3);
  EXPECT_EQ(limits.refusals().at("connections per address"), 1u);
  EXPECT_EQ(limits.refusals().at("connection limit"), 1u);
}

TEST(WebLimits, RequestRatePerAddress) {
  WebLimits limits(smallLimits());
  // A burst of 3, then 2 per second.
  EXPECT_TRUE(limits.allowRequest("a", 0.0));
  EXPECT_TRUE(limits.allowRequest("a", 0.0));
  EXPECT_TRUE(limits.allowRequest("a", 0.0));
  EXPECT_FALSE(limits.allowRequest("a", 0.0));
  EXPECT_TRUE(limits.allowRequest("b", 0.0));  // another address has its own bucket
  EXPECT_FALSE(limits.allowRequest("a", 0.2));
  EXPECT_TRUE(limits.allowRequest("a", 0.5));
  EXPECT_FALSE(limits.allowRequest("a", 0.5));
  EXPECT_EQ(limits.refusals().at("request rate"), 3u);
}

TEST(WebLimits, TheAddressTableStaysBounded) {
  WebConfig c;
  c.request_rate_hz = 10.0;
  c.request_burst = 10;
  WebLimits limits(c);
  // A flood of one request each from many addresses: idle ones are forgotten.
  for (int i = 0; i < 20000; ++i) {
    limits.allowRequest(fmt::format("10.{}", i), static_cast<double>(i));
  }
  EXPECT_LE(limits.tracked(), WebLimits::kMaxTracked);
  // An address with an open connection is never forgotten.
  WebLimits held(c);
  EXPECT_EQ(held.admit("keep", 0.0), "");
  for (int i = 0; i < 10000; ++i) held.allowRequest(fmt::format("x{}", i), 100.0 + i);
  EXPECT_EQ(held.openFrom("keep"), 1);
}

TEST(WebConfig, DefaultsValuesAndErrors) {
  auto c = parseWebConfig("", "t.toml");
  ASSERT_TRUE(c);
  EXPECT_EQ(c->port, -1);
  EXPECT_FALSE(c->public_room_list);
  EXPECT_TRUE(c->allowed_hosts.empty());
  EXPECT_FALSE(c->members);
  c = parseWebConfig(
      "[network]\nport = 1\n[web]\nport = 8080\nmax_connections = 10\n"
      "max_connections_per_address = 3\nrequest_rate_hz = 5.5\nrequest_burst = 7\n"
      "max_header_bytes = 4096\nread_timeout_s = 2\nidle_timeout_s = 3\nwrite_timeout_s = 4\n"
      "max_spectators_per_room = 9\nmax_stream_rate_hz = 30\nmax_ws_queue_bytes = 100000\n"
      "public_room_list = true\nallowed_hosts = \"a.example, b.example:8080\"\n"
      "members = true\nmax_members = 3\nmember_pose_rate_hz = 5\n",
      "t.toml");
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->port, 8080);
  EXPECT_EQ(c->max_connections, 10);
  EXPECT_EQ(c->max_connections_per_address, 3);
  EXPECT_DOUBLE_EQ(c->request_rate_hz, 5.5);
  EXPECT_EQ(c->request_burst, 7);
  EXPECT_EQ(c->max_header_bytes, 4096u);
  EXPECT_DOUBLE_EQ(c->read_timeout_s, 2.0);
  EXPECT_DOUBLE_EQ(c->idle_timeout_s, 3.0);
  EXPECT_DOUBLE_EQ(c->write_timeout_s, 4.0);
  EXPECT_EQ(c->max_spectators_per_room, 9);
  EXPECT_DOUBLE_EQ(c->max_stream_rate_hz, 30.0);
  EXPECT_EQ(c->max_ws_queue_bytes, 100000u);
  EXPECT_TRUE(c->public_room_list);
  EXPECT_EQ(c->allowed_hosts, (std::vector<std::string>{"a.example", "b.example:8080"}));
  EXPECT_TRUE(c->members);
  EXPECT_EQ(c->max_members, 3);
  EXPECT_DOUBLE_EQ(c->member_pose_rate_hz, 5.0);

  auto bad = parseWebConfig("[web]\nport = 70000\n", "t.toml");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("port"), std::string::npos) << bad.error().message;
  bad = parseWebConfig("[web]\nprot = 1\n", "t.toml");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("prot"), std::string::npos) << bad.error().message;
  bad = parseWebConfig("[web]\nmax_header_bytes = 10\n", "t.toml");
  EXPECT_FALSE(bad);
  bad = parseWebConfig("[web]\nallowed_hosts = \"a b/c\"\n", "t.toml");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("b/c"), std::string::npos) << bad.error().message;
  bad = parseWebConfig("[web\n", "t.toml");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("t.toml"), std::string::npos);
}

}  // namespace
}  // namespace vistel::server
