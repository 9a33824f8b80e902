// Request heads, targets and what a request gets (server/web/web_request.hpp).
#include <string>

#include <gtest/gtest.h>

#include "server/web/web_request.hpp"

namespace vistel::server {
namespace {

RequestHead headOf(std::string method, std::string target, bool has_body, bool is_upgrade) {
  RequestHead head;
  head.method = std::move(method);
  head.target = std::move(target);
  head.has_body = has_body;
  head.is_upgrade = is_upgrade;
  return head;
}

TEST(WebTarget, RoutesThePublicPaths) {
  auto t = parseTarget("/");
  ASSERT_TRUE(t);
  EXPECT_EQ(t->route, WebRoute::kRoomList);
  EXPECT_EQ(parseTarget("/api/rooms")->route, WebRoute::kRoomsJson);
  t = parseTarget("/room/lab-1.b_c");
  ASSERT_TRUE(t);
  EXPECT_EQ(t->route, WebRoute::kRoomPage);
  EXPECT_EQ(t->room, "lab-1.b_c");
  t = parseTarget("/ws/room/lab?token=vt1.abc-_&x=1");
  ASSERT_TRUE(t);
  EXPECT_EQ(t->route, WebRoute::kRoomSocket);
  EXPECT_EQ(t->room, "lab");
  EXPECT_EQ(t->token, "vt1.abc-_");
  const std::string hash(64, 'a');
  t = parseTarget("/avatar/" + hash + ".glb");
  ASSERT_TRUE(t);
  EXPECT_EQ(t->route, WebRoute::kAvatar);
  EXPECT_EQ(t->hash, hash);
  t = parseTarget("/assets/three.min.js");
  ASSERT_TRUE(t);
  EXPECT_EQ(t->route, WebRoute::kAsset);
  EXPECT_EQ(t->asset, "three.min.js");
  // Percent escapes in the path are decoded before routing.
  t = parseTarget("/room/l%61b");
  ASSERT_TRUE(t);
  EXPECT_EQ(t->room, "lab");
}

TEST(WebTarget, UnknownPathsAreNotFound) {
  for (const char* path : {"/x", "/room", "/room/", "/room/a/b", "/room/a%20b", "/room/.x/..z",
                           "/ws/room", "/avatar/abc.glb",
                           "/avatar/"
                           "AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA.glb",
                           "/assets/.hidden", "/assets/a/b", "/a/b/c/d/e/f", "/api"}) {
    auto t = parseTarget(path);
    if (t) {
      EXPECT_EQ(t->route, WebRoute::kNotFound) << path;
    }
  }
  EXPECT_EQ(parseTarget("/room/" + std::string(65, 'a'))->route, WebRoute::kNotFound);
}

TEST(WebTarget, RefusesMalformedTargets) {
  EXPECT_FALSE(parseTarget(""));
  EXPECT_FALSE(parseTarget("room/lab"));
  EXPECT_FALSE(parseTarget("http://host/room/lab"));
  EXPECT_FALSE(parseTarget("//room"));
  EXPECT_FALSE(parseTarget("/room/../etc"));
  EXPECT_FALSE(parseTarget("/room/%2e%2e/x"));  // decoded dot segment
  EXPECT_FALSE(parseTarget("/room/lab%"));
  EXPECT_FALSE(parseTarget("/room/lab%4"));
  EXPECT_FALSE(parseTarget("/room/lab%zz"));
  EXPECT_FALSE(parseTarget("/room/lab%00"));
  EXPECT_FALSE(parseTarget("/room/lab%0a"));
  EXPECT_FALSE(parseTarget("/" + std::string(kMaxTargetBytes, 'a')));
}

TEST(WebTarget, PercentDecodeAndQueryParameters) {
  EXPECT_EQ(*percentDecode("a%20b+c", false), "a b+c");
  EXPECT_EQ(*percentDecode("a%20b+c", true), "a b c");
  EXPECT_EQ(*percentDecode("%41%7a", false), "Az");
  EXPECT_FALSE(percentDecode("%", false));
  EXPECT_FALSE(percentDecode("%1", false));
  EXPECT_FALSE(percentDecode("%7f", false));
  EXPECT_FALSE(percentDecode("\x01", false));
  EXPECT_EQ(queryParam("a=1&token=x%2By&token=2", "token").value_or("-"), "x+y");
  EXPECT_EQ(queryParam("token", "token").value_or("-"), "");
  EXPECT_FALSE(queryParam("tokens=1&xtoken=2", "token"));
  EXPECT_FALSE(queryParam("token=%zz", "token"));
  EXPECT_FALSE(queryParam("", "token"));
}

TEST(WebRequest, OnlyGetOnPublicPaths) {
  for (const char* method : {"POST", "HEAD", "PUT", "DELETE", "OPTIONS", "PATCH", "get"}) {
    const RequestVerdict v = judgeRequest(headOf(method, "/", false, false));
    EXPECT_EQ(v.status, 405) << method;
  }
  EXPECT_EQ(judgeRequest(headOf("GET", "/", false, false)).status, 0);
  EXPECT_EQ(judgeRequest(headOf("GET", "/", true, false)).status, 413);
  EXPECT_EQ(judgeRequest(headOf("GET", "/nope", false, false)).status, 404);
  EXPECT_EQ(judgeRequest(headOf("GET", "/room/../x", false, false)).status, 400);
  EXPECT_EQ(judgeRequest(headOf("GET", "/" + std::string(3000, 'a'), false, false)).status, 414);
  EXPECT_EQ(judgeRequest(headOf("GET", "/ws/room/lab", false, false)).status, 426);
  EXPECT_EQ(judgeRequest(headOf("GET", "/ws/room/lab", false, true)).status, 0);
  EXPECT_EQ(judgeRequest(headOf("GET", "/room/lab", false, true)).status, 400);
}

TEST(WebRequest, RoomSocketsOnlyFromTheServersOwnPages) {
  const auto upgrade = [](std::string host, std::string origin) {
    return judgeRequest({"GET", "/ws/room/lab", false, true, std::move(host), std::move(origin)})
        .status;
  };
  EXPECT_EQ(upgrade("127.0.0.1:8080", "http://127.0.0.1:8080"), 0);
  EXPECT_EQ(upgrade("example.org", "https://example.org"), 0);
  EXPECT_EQ(upgrade("127.0.0.1:8080", ""), 0);  // not a browser's page (tools, tests)
  EXPECT_EQ(upgrade("127.0.0.1:8080", "http://evil.example"), 403);
  EXPECT_EQ(upgrade("127.0.0.1:8080", "http://127.0.0.1:9999"), 403);
  EXPECT_EQ(upgrade("127.0.0.1:8080", "null"), 403);
  EXPECT_EQ(upgrade("", "http://127.0.0.1:8080"), 403);
}

TEST(WebRequest, HostAllowListAgainstDnsRebinding) {
  const std::vector<std::string> none;
  // IP literals (any port), localhost, and no Host at all (not a browser) pass by default.
  for (const char* host : {"127.0.0.1:8080", "127.0.0.1", "10.1.2.3:80", "[::1]:8080", "[::1]",
                           "localhost:8080", "LOCALHOST", "localhost.", ""}) {
    EXPECT_TRUE(hostAllowed(host, none)) << host;
  }
  // Any other name (a rebound attacker's domain) and malformed values do not.
  for (const char* host :
       {"evil.example", "evil.example:8080", "127.0.0.1.evil.example", "lab.local", "[::1", "::1",
        "[::1]x", "127.0.0.1:", "127.0.0.1:0", "127.0.0.1:70000", "127.0.0.1:8o", "bad host",
        "bad_host", "a/b", "[127.0.0.1]", "localhost:123456"}) {
    EXPECT_FALSE(hostAllowed(host, none)) << host;
  }
  // Configured names: any port, or exactly the one given.
  auto allowed = parseAllowedHosts("lab.example.org, Vistel.Local:8080  other.test");
  ASSERT_TRUE(allowed) << allowed.error().message;
  ASSERT_EQ(allowed->size(), 3u);
  EXPECT_EQ((*allowed)[1], "vistel.local:8080");
  EXPECT_TRUE(hostAllowed("lab.example.org", *allowed));
  EXPECT_TRUE(hostAllowed("LAB.example.org:443", *allowed));
  EXPECT_TRUE(hostAllowed("vistel.local:8080", *allowed));
  EXPECT_FALSE(hostAllowed("vistel.local:8081", *allowed));
  EXPECT_FALSE(hostAllowed("vistel.local", *allowed));
  EXPECT_FALSE(hostAllowed("example.org", *allowed));
  EXPECT_TRUE(parseAllowedHosts("")->empty());
  auto bad = parseAllowedHosts("ok.example, not/a/host");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("not/a/host"), std::string::npos) << bad.error().message;
  EXPECT_FALSE(parseAllowedHosts("x.example:99999"));
}

TEST(WebRequest, ParsesHeadsWithinTheLimits) {
  HeadError error;
  auto head = parseRequestHead(
      "GET /room/lab?token=t HTTP/1.1\r\nHost: 127.0.0.1:8080\r\nUser-Agent: test\r\n\r\n", 8192,
      &error);
  ASSERT_TRUE(head) << error.message;
  EXPECT_EQ(head->head.method, "GET");
  EXPECT_EQ(head->head.target, "/room/lab?token=t");
  EXPECT_FALSE(head->head.has_body);
  EXPECT_FALSE(head->head.is_upgrade);
  EXPECT_TRUE(head->keep_alive);
  EXPECT_EQ(head->version, 11);

  head = parseRequestHead(
      "GET /ws/room/lab HTTP/1.1\r\nHost: h\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n"
      "Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n",
      8192, &error);
  ASSERT_TRUE(head) << error.message;
  EXPECT_TRUE(head->head.is_upgrade);

  head = parseRequestHead("GET / HTTP/1.0\r\n\r\n", 8192, &error);
  ASSERT_TRUE(head);
  EXPECT_FALSE(head->keep_alive);
  EXPECT_EQ(head->version, 10);
}

TEST(WebRequest, RefusesBadHeadsWithTheRightStatus) {
  HeadError error;
  // Too large: 431.
  const std::string big = "GET / HTTP/1.1\r\nX-Big: " + std::string(9000, 'a') + "\r\n\r\n";
  EXPECT_FALSE(parseRequestHead(big, 8192, &error));
  EXPECT_EQ(error.status, 431);
  // A body is the verdict's to refuse (after the method: a POST is 405).
  auto with_body =
      parseRequestHead("GET / HTTP/1.1\r\nContent-Length: 4\r\n\r\nabcd", 8192, &error);
  ASSERT_TRUE(with_body) << error.message;
  EXPECT_TRUE(with_body->head.has_body);
  EXPECT_EQ(judgeRequest(with_body->head).status, 413);
  with_body =
      parseRequestHead("GET / HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\n", 8192, &error);
  ASSERT_TRUE(with_body) << error.message;
  EXPECT_EQ(judgeRequest(with_body->head).status, 413);
  with_body = parseRequestHead("POST / HTTP/1.1\r\nContent-Length: 2\r\n\r\n{}", 8192, &error);
  ASSERT_TRUE(with_body) << error.message;
  EXPECT_EQ(judgeRequest(with_body->head).status, 405);
  // Malformed or incomplete: 400.
  for (const char* bad : {"GET / HTTP/1.1\r\n", "GET /\r\n\r\n", "GET / HTTP/2.0\r\n\r\n",
                          "G\x01T / HTTP/1.1\r\n\r\n", "GET / HTTP/1.1\r\nBad Header\r\n\r\n",
                          "GET / HTTP/1.1\r\nContent-Length: x\r\n\r\n", "", "\r\n\r\n"}) {
    EXPECT_FALSE(parseRequestHead(bad, 8192, &error)) << bad;
    EXPECT_EQ(error.status, 400) << bad;
  }
  // A zero-length body is no body.
  auto head = parseRequestHead("GET / HTTP/1.1\r\nContent-Length: 0\r\n\r\n", 8192, &error);
  ASSERT_TRUE(head) << error.message;
  EXPECT_FALSE(head->head.has_body);
}

TEST(WebRequest, StatusTexts) {
  EXPECT_EQ(statusText(404), "Not Found");
  EXPECT_EQ(statusText(431), "Request Header Fields Too Large");
  EXPECT_EQ(statusText(429), "Too Many Requests");
  EXPECT_EQ(statusText(999), "Error");
}

}  // namespace
}  // namespace vistel::server
