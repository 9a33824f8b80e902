// Request-head parsing, routing and response writing/reading (server/http/http_message).
#include "server/http/http_message.hpp"

#include <random>
#include <string>

#include <gtest/gtest.h>

namespace vistel::server {
namespace {

constexpr std::string_view kGet = "GET /metrics HTTP/1.1\r\nHost: x\r\nUser-Agent: t\r\n\r\n";

// The status parseRequestHead's error names, or 0 when it parses.
int statusOf(std::string_view head) {
  auto r = parseRequestHead(head);
  return r ? 0 : statusOfParseError(r.error());
}

TEST(HttpMessage, FindsTheEndOfTheHead) {
  EXPECT_FALSE(findHeadEnd("GET / HTTP/1.1\r\nHost: x\r\n"));
  EXPECT_EQ(findHeadEnd(kGet), kGet.size());
  std::string with_more = std::string(kGet) + "extra";
  EXPECT_EQ(findHeadEnd(with_more), kGet.size());
}

TEST(HttpMessage, ParsesAGoodRequest) {
  auto r = parseRequestHead(kGet);
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->method, "GET");
  EXPECT_EQ(r->path, "/metrics");
  EXPECT_EQ(r->query, "");
  EXPECT_EQ(r->version_minor, 1);
  ASSERT_EQ(r->headers.size(), 2u);
  EXPECT_EQ(r->headers[0].first, "host");
  EXPECT_EQ(r->headers[1].first, "user-agent");
  EXPECT_EQ(r->headers[1].second, "t");
}

TEST(HttpMessage, ParsesQueryAbsoluteFormHttp10AndLeadingBlankLine) {
  auto q = parseRequestHead("HEAD /readyz?verbose=1 HTTP/1.1\r\nHost: a:1\r\n\r\n");
  ASSERT_TRUE(q);
  EXPECT_EQ(q->method, "HEAD");
  EXPECT_EQ(q->path, "/readyz");
  EXPECT_EQ(q->query, "verbose=1");

  auto a = parseRequestHead("GET http://h:9/healthz HTTP/1.1\r\nHost: h:9\r\n\r\n");
  ASSERT_TRUE(a) << a.error().message;
  EXPECT_EQ(a->path, "/healthz");
  auto bare = parseRequestHead("GET http://h:9 HTTP/1.1\r\nHost: h:9\r\n\r\n");
  ASSERT_TRUE(bare);
  EXPECT_EQ(bare->path, "/");

  auto old = parseRequestHead("GET /healthz HTTP/1.0\r\n\r\n");  // no Host needed in 1.0
  ASSERT_TRUE(old);
  EXPECT_EQ(old->version_minor, 0);

  auto lead = parseRequestHead("\r\nGET / HTTP/1.1\r\nHost: x\r\n\r\n");
  ASSERT_TRUE(lead);
  EXPECT_EQ(lead->path, "/");
}

TEST(HttpMessage, TrimsHeaderValues) {
  auto r = parseRequestHead("GET / HTTP/1.1\r\nHost:   spaced \t\r\n\r\n");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->headers[0].second, "spaced");
}

TEST(HttpMessage, RefusesMalformedRequestLines) {
  EXPECT_EQ(statusOf("GET  / HTTP/1.1\r\nHost: x\r\n\r\n"), 400);                // double space
  EXPECT_EQ(statusOf("GET / HTTP/1.1 x\r\nHost: x\r\n\r\n"), 400);               // extra part
  EXPECT_EQ(statusOf("GET /\r\nHost: x\r\n\r\n"), 400);                          // no version
  EXPECT_EQ(statusOf("G(T / HTTP/1.1\r\nHost: x\r\n\r\n"), 400);                 // not a token
  EXPECT_EQ(statusOf("GETGETGETGETGETGET / HTTP/1.1\r\nHost: x\r\n\r\n"), 400);  // too long
  EXPECT_EQ(statusOf("GET metrics HTTP/1.1\r\nHost: x\r\n\r\n"), 400);           // not a path
  EXPECT_EQ(statusOf("GET ?x HTTP/1.1\r\nHost: x\r\n\r\n"), 400);                // query only
  EXPECT_EQ(statusOf("GET http:///x HTTP/1.1\r\nHost: x\r\n\r\n"), 400);         // no authority
  EXPECT_EQ(statusOf("GET /\x80 HTTP/1.1\r\nHost: x\r\n\r\n"), 400);             // non-ASCII target
  EXPECT_EQ(statusOf("GET / HTTP/1.1\r\nHost: x\r\n\r\n"), 0);
  EXPECT_EQ(statusOf("GET / http/1.1\r\nHost: x\r\n\r\n"), 400);
  EXPECT_EQ(statusOf("GET / HTTP/2.0\r\nHost: x\r\n\r\n"), 505);
  EXPECT_EQ(statusOf("GET / HTTP/1.2\r\nHost: x\r\n\r\n"), 505);
  EXPECT_EQ(statusOf("GET / HTTP/1.10\r\nHost: x\r\n\r\n"), 400);
  EXPECT_EQ(statusOf("\r\n\r\n"), 400);
  std::string long_target = "GET /" + std::string(3000, 'a') + " HTTP/1.1\r\nHost: x\r\n\r\n";
  EXPECT_EQ(statusOf(long_target), 400);
}

TEST(HttpMessage, RefusesBadHeaders) {
  EXPECT_EQ(statusOf("GET / HTTP/1.1\r\n\r\n"), 400);                        // 1.1 without Host
  EXPECT_EQ(statusOf("GET / HTTP/1.1\r\nHost: a\r\nHost: b\r\n\r\n"), 400);  // two Hosts
  EXPECT_EQ(statusOf("GET / HTTP/1.1\r\nHost: a\r\n folded\r\n\r\n"), 400);  // obs-fold
  EXPECT_EQ(statusOf("GET / HTTP/1.1\r\nHost : a\r\n\r\n"), 400);            // space before colon
  EXPECT_EQ(statusOf("GET / HTTP/1.1\r\nHost: a\r\nNoColon\r\n\r\n"), 400);
  EXPECT_EQ(statusOf("GET / HTTP/1.1\r\nHost: a\x01\r\n\r\n"), 400);  // control character
  EXPECT_EQ(statusOf(std::string("GET / HTTP/1.1\r\nHost: a\0b\r\n\r\n", 30)), 400);  // NUL
  EXPECT_EQ(statusOf("GET / HTTP/1.1\nHost: a\r\n\r\n"), 400);                        // bare LF
  EXPECT_EQ(statusOf("GET / HTTP/1.1\r\nHost: a\rb\r\n\r\n"), 400);                   // bare CR
  EXPECT_EQ(statusOf("GET / HTTP/1.1\r\nHost: a\r\nContent-Length: 5\r\n\r\n"), 400);
  EXPECT_EQ(statusOf("GET / HTTP/1.1\r\nHost: a\r\nContent-Length: 0\r\n\r\n"), 0);
  EXPECT_EQ(statusOf("GET / HTTP/1.1\r\nHost: a\r\nTransfer-Encoding: chunked\r\n\r\n"), 400);
  EXPECT_EQ(statusOf("GET / HTTP/1.1\r\nHost: a\r\n\r\nGET / HTTP/1.1\r\n\r\n"), 400);
}

TEST(HttpMessage, BoundsHeadSizeAndFieldCount) {
  std::string many = "GET / HTTP/1.1\r\nHost: a\r\n";
  for (int i = 0; i < 70; ++i) many += "X-" + std::to_string(i) + ": v\r\n";
  many += "\r\n";
  EXPECT_EQ(statusOf(many), 431);
  std::string big =
      "GET / HTTP/1.1\r\nHost: a\r\nX: " + std::string(kMaxRequestHeadBytes, 'v') + "\r\n\r\n";
  EXPECT_EQ(statusOf(big), 431);
}

// Every prefix of a good head is incomplete: it must fail (or not be a head), never crash.
TEST(HttpMessage, EveryPrefixOfAHeadFailsCleanly) {
  for (std::size_t n = 0; n < kGet.size(); ++n) {
    std::string_view prefix = kGet.substr(0, n);
    EXPECT_FALSE(findHeadEnd(prefix)) << n;
    EXPECT_FALSE(parseRequestHead(prefix)) << n;
  }
}

// Random byte changes to a good head never crash the parser (run under ASan in CI).
TEST(HttpMessage, SurvivesMutatedHeads) {
  std::mt19937 rng(7);
  std::string base = "GET /metrics?x=1 HTTP/1.1\r\nHost: h\r\nAccept: */*\r\n\r\n";
  int parsed = 0;
  for (int i = 0; i < 5000; ++i) {
    std::string head = base;
    int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits; ++e) {
      std::size_t at = rng() % head.size();
      switch (rng() % 3) {
        case 0:
          head[at] = static_cast<char>(rng() & 0xff);
          break;
        case 1:
          head.erase(at, 1);
          break;
        default:
          head.insert(at, 1, static_cast<char>(rng() & 0xff));
          break;
      }
    }
    auto r = parseRequestHead(head);
    if (r) {
      ++parsed;
      EXPECT_FALSE(r->path.empty());
      EXPECT_EQ(r->path.front(), '/');
    } else {
      int status = statusOfParseError(r.error());
      EXPECT_TRUE(status == 400 || status == 431 || status == 505) << r.error().message;
    }
  }
  EXPECT_GT(parsed, 0);
}

TEST(HttpMessage, StatusOfParseErrorDefaultsTo400) {
  EXPECT_EQ(statusOfParseError(Error{"505 x"}), 505);
  EXPECT_EQ(statusOfParseError(Error{"431 x"}), 431);
  EXPECT_EQ(statusOfParseError(Error{"oops"}), 400);
  EXPECT_EQ(statusOfParseError(Error{"99"}), 400);
  EXPECT_EQ(statusOfParseError(Error{"200 fine"}), 400);
}

HttpRequestHead request(std::string method, std::string path) {
  HttpRequestHead r;
  r.method = std::move(method);
  r.path = std::move(path);
  return r;
}

TEST(HttpMessage, RoutesHealthReadinessAndErrors) {
  bool ready = false;
  HttpRoutes routes{[&] { return ready; }};

  auto health = routeRequest(request("GET", "/healthz"), routes);
  ASSERT_TRUE(health);
  EXPECT_EQ(health->status, 200);
  EXPECT_EQ(health->body, "ok\n");

  EXPECT_EQ(routeRequest(request("GET", "/readyz"), routes)->status, 503);
  ready = true;
  EXPECT_EQ(routeRequest(request("HEAD", "/readyz"), routes)->status, 200);
  EXPECT_EQ(routeRequest(request("GET", "/readyz"), HttpRoutes{})->status, 503);

  EXPECT_FALSE(routeRequest(request("GET", "/metrics"), routes));
  EXPECT_FALSE(routeRequest(request("HEAD", "/metrics"), routes));

  EXPECT_EQ(routeRequest(request("GET", "/"), routes)->status, 404);
  EXPECT_EQ(routeRequest(request("GET", "/metrics/"), routes)->status, 404);
  auto post = routeRequest(request("POST", "/metrics"), routes);
  ASSERT_TRUE(post);
  EXPECT_EQ(post->status, 405);
  ASSERT_EQ(post->extra_headers.size(), 1u);
  EXPECT_EQ(post->extra_headers[0].first, "Allow");
  EXPECT_EQ(post->extra_headers[0].second, "GET, HEAD");
  EXPECT_EQ(routeRequest(request("get", "/healthz"), routes)->status, 405);  // case-sensitive
}

TEST(HttpMessage, SerializesResponses) {
  HttpResponse r = plainResponse(200, "ok");
  EXPECT_EQ(serializeResponse(r, false),
            "HTTP/1.1 200 OK\r\nContent-Type: text/plain; charset=utf-8\r\nContent-Length: 3\r\n"
            "Connection: close\r\nCache-Control: no-store\r\n\r\nok\n");
  // HEAD: the same head (with the GET body's length), no body.
  EXPECT_EQ(serializeResponse(r, true),
            "HTTP/1.1 200 OK\r\nContent-Type: text/plain; charset=utf-8\r\nContent-Length: 3\r\n"
            "Connection: close\r\nCache-Control: no-store\r\n\r\n");
  HttpResponse not_allowed = plainResponse(405, "no");
  not_allowed.extra_headers.emplace_back("Allow", "GET, HEAD");
  std::string bytes = serializeResponse(not_allowed, false);
  EXPECT_EQ(bytes.rfind("HTTP/1.1 405 Method Not Allowed\r\n", 0), 0u);
  EXPECT_NE(bytes.find("\r\nAllow: GET, HEAD\r\n"), std::string::npos);
  EXPECT_EQ(reasonPhrase(431), "Request Header Fields Too Large");
  EXPECT_EQ(reasonPhrase(299), "Unknown");
}

TEST(HttpMessage, ReadsResponsesBack) {
  // Our own writer round-trips.
  auto r = parseResponse(serializeResponse(plainResponse(503, "not ready"), false));
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->status, 503);
  EXPECT_EQ(r->body, "not ready\n");

  // Content-Length cuts the body; without it the body runs to the end.
  auto cut = parseResponse("HTTP/1.1 200 OK\r\nContent-Length: 2\r\n\r\n{}garbage");
  ASSERT_TRUE(cut);
  EXPECT_EQ(cut->body, "{}");
  auto open_ended = parseResponse("HTTP/1.0 204 No Content\r\nX: y\r\n\r\nabc");
  ASSERT_TRUE(open_ended);
  EXPECT_EQ(open_ended->status, 204);
  EXPECT_EQ(open_ended->body, "abc");

  // Chunked bodies (what a Go server sends without a length).
  auto chunked = parseResponse(
      "HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\n2\r\n{}\r\n3;x=y\r\nabc\r\n0\r\n\r\n");
  ASSERT_TRUE(chunked) << chunked.error().message;
  EXPECT_EQ(chunked->body, "{}abc");

  EXPECT_FALSE(parseResponse("HTTP/1.1 200 OK\r\nContent-Length: 9\r\n\r\nshort"));
  auto head = parseResponse("HTTP/1.1 200 OK\r\nContent-Length: 9\r\n\r\n", true);
  ASSERT_TRUE(head);  // a HEAD answer: the length is the GET body's, no body follows
  EXPECT_EQ(head->body, "");
  EXPECT_FALSE(parseResponse("HTTP/1.1 200 OK\r\nContent-Length: x\r\n\r\n"));
  EXPECT_FALSE(parseResponse("HTTP/1.1 200 OK\r\n"));
  EXPECT_FALSE(parseResponse("SMTP 220 hello\r\n\r\n"));
  EXPECT_FALSE(parseResponse("HTTP/1.1 2x0 OK\r\n\r\n"));
  EXPECT_FALSE(parseResponse("HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\nzz\r\n"));
  EXPECT_FALSE(parseResponse("HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\n9\r\nab\r\n"));
}

TEST(HttpMessage, EveryPrefixOfAResponseFailsOrParses) {
  std::string full = "HTTP/1.1 200 OK\r\nTransfer-Encoding: chunked\r\n\r\n2\r\n{}\r\n0\r\n\r\n";
  for (std::size_t n = 0; n < full.size(); ++n) {
    auto r = parseResponse(std::string_view(full).substr(0, n));
    if (r) {
      EXPECT_LE(r->body.size(), 2u);
    }
  }
  EXPECT_TRUE(parseResponse(full));
}

TEST(HttpMessage, SerializesClientRequests) {
  EXPECT_EQ(serializeRequest("POST", "/ready", "127.0.0.1:9358", "{}"),
            "POST /ready HTTP/1.1\r\nHost: 127.0.0.1:9358\r\nConnection: close\r\n"
            "Content-Type: application/json\r\nContent-Length: 2\r\n\r\n{}");
  EXPECT_EQ(serializeRequest("GET", "/gameserver", "h:1", ""),
            "GET /gameserver HTTP/1.1\r\nHost: h:1\r\nConnection: close\r\n\r\n");
}

}  // namespace
}  // namespace vistel::server
