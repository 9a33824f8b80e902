// vistel-server --web-port over real sockets, without a browser: join tokens on the
// spectator WebSocket, and the HTTP side's limits (request size, methods, rate,
// connections, slow heads, keep-alive).
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <memory>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include "common/auth/join_token.hpp"
#include "common/auth/secret_file.hpp"
#include "common/auth/token_command.hpp"
#include "common/base/file.hpp"
#include "tests/integration/http_get.hpp"
#include "tests/integration/program.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace websocket = boost::beast::websocket;

using test::logOf;

// A server with the web side on a free port; web() is its port (metrics() that of
// --metrics-port, when `extra` asks for one).
class WebServerProcess {
 public:
  WebServerProcess(const std::string& dir, std::vector<std::string> extra)
      : log_(dir + "/server.log") {
    std::vector<std::string> args = {"--port", "0", "--web-port", "0"};
    args.insert(args.end(), extra.begin(), extra.end());
    program_ = std::make_unique<test::Program>("vistel-server", args, log_, true);
    address_ = test::serverAddress(*program_);
    for (int i = 0; i < 5 && web_ == 0; ++i) {
      auto line = program_->readLine(20.0);
      if (!line) break;
      const std::string prefix = "vistel-server web on http://";
      const std::string metrics = "vistel-server metrics on ";
      if (line->rfind(prefix, 0) == 0) web_ = test::portOf(line->substr(0, line->size() - 1));
      if (line->rfind(metrics, 0) == 0) metrics_ = test::portOf(*line);
    }
  }
  ~WebServerProcess() {
    program_->signal(SIGTERM);
    EXPECT_EQ(program_->wait(10.0).value_or(-999), 0) << log();
  }
  std::uint16_t web() const { return web_; }
  std::uint16_t metrics() const { return metrics_; }
  std::string log() const { return logOf(log_); }

 private:
  std::string log_;
  std::unique_ptr<test::Program> program_;
  std::string address_;
  std::uint16_t web_ = 0;
  std::uint16_t metrics_ = 0;
};

std::string sendAndRead(std::uint16_t port, const std::string& bytes, double wait_s = 3.0) {
  return test::sendAndRead(port, bytes, wait_s);
}

int statusOf(const std::string& response) {
  if (response.rfind("HTTP/1.1 ", 0) != 0 || response.size() < 12) return 0;
  return std::stoi(response.substr(9, 3));
}

// Opens the spectator WebSocket of `target` and reads its text messages until it closes
// or `count` arrived; the close code (0: still open) in close_code.
std::vector<nlohmann::json> watch(std::uint16_t port, const std::string& target, int count,
                                  int* close_code) {
  std::vector<nlohmann::json> messages;
  *close_code = 0;
  asio::io_context io;
  websocket::stream<asio::ip::tcp::socket> ws(io);
  try {
    ws.next_layer().connect({asio::ip::make_address("127.0.0.1"), port});
    timeval timeout{5, 0};
    ::setsockopt(ws.next_layer().native_handle(), SOL_SOCKET, SO_RCVTIMEO, &timeout,
                 sizeof timeout);
    ws.handshake("127.0.0.1:" + std::to_string(port), target);
    while (static_cast<int>(messages.size()) < count) {
      beast::flat_buffer buffer;
      beast::error_code ec;
      ws.read(buffer, ec);
      if (ec == websocket::error::closed) {
        *close_code = ws.reason().code;
        break;
      }
      if (ec) break;
      if (ws.got_text())
        messages.push_back(nlohmann::json::parse(beast::buffers_to_string(buffer.data())));
    }
  } catch (const std::exception& e) {
    ADD_FAILURE() << target << ": " << e.what();
  }
  return messages;
}

std::string stateOf(const std::vector<nlohmann::json>& messages) {
  for (const auto& m : messages) {
    if (m.value("type", "") == "status") return m.value("state", "");
  }
  return "(none)";
}

// The value of one sample line of a Prometheus scrape ("name{labels} value"), or -1.
double metricValue(const std::string& scrape, const std::string& series) {
  const std::string needle = "\n" + series + " ";
  const auto at = scrape.find(needle);
  if (at == std::string::npos) return -1.0;
  return std::stod(scrape.substr(at + needle.size()));
}

TEST(WebServerNet, JoinTokensGuardTheRoomSockets) {
  const std::string dir = test::scratchDir();
  const std::string secret_path = dir + "/secret";
  ASSERT_TRUE(writeFileText(secret_path, std::string(64, 'a') + "\n"));
  ::chmod(secret_path.c_str(), 0600);
  auto secret = auth::readJoinSecret(secret_path);
  ASSERT_TRUE(secret) << secret.error().message;
  WebServerProcess server(dir, {"--secret-file", secret_path});
  ASSERT_NE(server.web(), 0) << server.log();

  const auto token = [&](const std::string& room, const std::vector<std::uint8_t>& key) {
    auto t = auth::createJoinToken(key, {room, "watcher", auth::unixNow() + 600});
    EXPECT_TRUE(t);
    return t ? *t : std::string();
  };
  int code = 0;
  auto messages = watch(server.web(), "/ws/room/it", 3, &code);
  EXPECT_EQ(stateOf(messages), "unauthorized");
  EXPECT_EQ(code, static_cast<int>(websocket::close_code::policy_error));
  messages = watch(server.web(), "/ws/room/it?token=vt1.garbage", 3, &code);
  EXPECT_EQ(stateOf(messages), "unauthorized");
  messages = watch(server.web(), "/ws/room/it?token=" + token("other", secret->bytes), 3, &code);
  EXPECT_EQ(stateOf(messages), "unauthorized");
  const std::vector<std::uint8_t> other_secret(32, 7);
  messages = watch(server.web(), "/ws/room/it?token=" + token("it", other_secret), 3, &code);
  EXPECT_EQ(stateOf(messages), "unauthorized");

  // A valid token for the room (any name): the stream begins; the room is not open.
  messages = watch(server.web(), "/ws/room/it?token=" + token("it", secret->bytes), 2, &code);
  ASSERT_EQ(messages.size(), 2u) << server.log();
  EXPECT_EQ(messages[0]["type"], "hello");
  EXPECT_EQ(messages[0]["room"], "it");
  EXPECT_EQ(stateOf(messages), "absent");
  EXPECT_EQ(code, 0);

  // The room list is not public with tokens.
  const std::string list = test::httpGet(server.web(), "/");
  EXPECT_EQ(statusOf(list), 200);
  EXPECT_NE(list.find("not public"), std::string::npos) << list;
  const std::string json = test::httpGet(server.web(), "/api/rooms");
  EXPECT_NE(json.find("\"hidden\":true"), std::string::npos) << json;
}

TEST(WebServerNet, OpenRoomsStreamWithoutATokenAndSayWhenAbsent) {
  const std::string dir = test::scratchDir();
  WebServerProcess server(dir, {});
  ASSERT_NE(server.web(), 0) << server.log();
  int code = 0;
  auto messages = watch(server.web(), "/ws/room/nobody", 2, &code);
  ASSERT_EQ(messages.size(), 2u);
  EXPECT_EQ(messages[0]["type"], "hello");
  EXPECT_EQ(stateOf(messages), "absent");
  EXPECT_NE(test::httpGet(server.web(), "/").find("No rooms are open"), std::string::npos);
  // Another site's page may not open a spectator socket in its visitor's browser.
  const std::string upgrade =
      "GET /ws/room/nobody HTTP/1.1\r\nHost: 127.0.0.1:" + std::to_string(server.web()) +
      "\r\nOrigin: http://evil.example\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n"
      "Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n";
  EXPECT_EQ(statusOf(sendAndRead(server.web(), upgrade)), 403);
}

TEST(WebServerNet, HttpLimits) {
  const std::string dir = test::scratchDir();
  const std::string config = dir + "/server.toml";
  ASSERT_TRUE(writeFileText(config,
                            "[web]\nmax_connections_per_address = 3\nrequest_rate_hz = 1\n"
                            "request_burst = 5\nread_timeout_s = 0.5\nmax_header_bytes = 1024\n"));
  WebServerProcess server(dir, {"--config", config, "--metrics-port", "0"});
  ASSERT_NE(server.web(), 0) << server.log();
  const std::uint16_t port = server.web();

  // Too large a head: 431. Other methods: 405 with Allow: GET. A body: 413.
  std::string r = sendAndRead(
      port, "GET / HTTP/1.1\r\nHost: x\r\nX-Pad: " + std::string(2000, 'p') + "\r\n\r\n");
  EXPECT_EQ(statusOf(r), 431) << r;
  r = sendAndRead(port, "POST / HTTP/1.1\r\nHost: x\r\nContent-Length: 2\r\n\r\n{}");
  EXPECT_EQ(statusOf(r), 405) << r;
  EXPECT_NE(r.find("Allow: GET"), std::string::npos) << r;
  r = sendAndRead(port, "HEAD / HTTP/1.1\r\nHost: x\r\n\r\n");
  EXPECT_EQ(statusOf(r), 405) << r;
  // Keep-alive: two requests on one connection, both answered (the second closes).
  r = sendAndRead(port,
                  "GET /assets/style.css HTTP/1.1\r\nHost: x\r\n\r\n"
                  "GET /nope HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(statusOf(r), 200) << r;
  EXPECT_NE(r.find("HTTP/1.1 404"), std::string::npos) << r;
  // The burst of five is spent (malformed heads count too): the next is 429.
  r = sendAndRead(port, "GET / HTTP/1.1\r\nHost: x\r\n\r\n");
  EXPECT_EQ(statusOf(r), 429) << r;

  // A head that never completes is dropped after read_timeout_s.
  const auto start = std::chrono::steady_clock::now();
  r = sendAndRead(port, "GET / HT", 5.0);
  const double took =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_TRUE(r.empty()) << r;
  EXPECT_LT(took, 4.0) << "the slow head was not dropped";

  // Three connections from one address at most: a fourth is closed at once.
  std::vector<int> held;
  for (int i = 0; i < 3; ++i) held.push_back(test::connectLoopback(port));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  const int fourth = test::connectLoopback(port);
  ASSERT_GE(fourth, 0);
  // Closed (a refusal, not the read timeout of an admitted connection: /metrics below tells
  // them apart; a busy machine may take a while to get to it).
  timeval timeout{3, 0};
  ::setsockopt(fourth, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof timeout);
  char byte = 0;
  EXPECT_EQ(::recv(fourth, &byte, 1, 0), 0) << "the fourth connection was not closed";
  ::close(fourth);
  for (int fd : held) ::close(fd);

  // /metrics names each refusal (the fourth connection's too): 431 and 405 (twice) are bad
  // requests.
  const std::string scrape = test::httpGet(server.metrics(), "/metrics");
  EXPECT_GE(metricValue(scrape, R"(vistel_web_refused_total{reason="request rate"})"), 1.0)
      << scrape;
  EXPECT_GE(metricValue(scrape, R"(vistel_web_refused_total{reason="connections per address"})"),
            1.0)
      << scrape;
  EXPECT_GE(metricValue(scrape, R"(vistel_web_refused_total{reason="bad request"})"), 3.0)
      << scrape;
  EXPECT_GE(metricValue(scrape, "vistel_web_timeouts_total"), 1.0) << scrape;
}

TEST(WebServerNet, MetricsCountTheWebSide) {
  const std::string dir = test::scratchDir();
  WebServerProcess server(dir, {"--metrics-port", "0"});
  ASSERT_NE(server.web(), 0) << server.log();
  ASSERT_NE(server.metrics(), 0) << server.log();
  const std::uint16_t port = server.web();

  std::string before = test::httpGet(server.metrics(), "/metrics");
  EXPECT_NE(before.find("# TYPE vistel_web_requests_total counter"), std::string::npos) << before;
  EXPECT_EQ(metricValue(before, "vistel_web_spectators"), 0.0) << before;

  // Three pages, one unknown path, one refused method, one spectator socket.
  EXPECT_EQ(statusOf(test::httpGet(port, "/")), 200);
  EXPECT_EQ(statusOf(test::httpGet(port, "/api/rooms")), 200);
  EXPECT_EQ(statusOf(test::httpGet(port, "/assets/style.css")), 200);
  EXPECT_EQ(statusOf(test::httpGet(port, "/nope")), 404);
  EXPECT_EQ(statusOf(sendAndRead(port, "DELETE / HTTP/1.1\r\nHost: x\r\n\r\n")), 405);

  // While a spectator watches, the gauge shows it.
  asio::io_context io;
  websocket::stream<asio::ip::tcp::socket> ws(io);
  ws.next_layer().connect({asio::ip::make_address("127.0.0.1"), port});
  ws.handshake("127.0.0.1:" + std::to_string(port), "/ws/room/quiet");
  beast::flat_buffer buffer;
  ws.read(buffer);  // hello: the server has taken the spectator in
  std::string during;
  for (int i = 0; i < 50; ++i) {  // the feed joins on the socket's strand: look a few times
    during = test::httpGet(server.metrics(), "/metrics");
    if (metricValue(during, "vistel_web_spectators") == 1.0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_EQ(metricValue(during, "vistel_web_spectators"), 1.0) << during;
  ws.close(websocket::close_code::normal);

  const std::string after = test::httpGet(server.metrics(), "/metrics");
  EXPECT_EQ(metricValue(after, R"(vistel_web_requests_total{route="room_list",status="2xx"})"), 2.0)
      << after;
  EXPECT_EQ(metricValue(after, R"(vistel_web_requests_total{route="asset",status="2xx"})"), 1.0)
      << after;
  EXPECT_EQ(metricValue(after, R"(vistel_web_requests_total{route="other",status="4xx"})"), 2.0)
      << after;
  EXPECT_EQ(metricValue(after, R"(vistel_web_requests_total{route="websocket",status="1xx"})"), 1.0)
      << after;
  EXPECT_EQ(metricValue(after, R"(vistel_web_refused_total{reason="bad request"})"), 1.0) << after;
  EXPECT_GT(metricValue(after, R"(vistel_web_sent_bytes_total{transport="http"})"), 1000.0)
      << after;
  EXPECT_GT(metricValue(after, R"(vistel_web_sent_bytes_total{transport="websocket"})"), 10.0)
      << after;
  // The session server's own families are still there, first.
  EXPECT_LT(after.find("vistel_members"), after.find("vistel_web_requests_total")) << after;
}

}  // namespace
}  // namespace vistel
