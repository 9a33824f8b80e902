// vistel-server --web-port over real sockets, without a browser: join tokens on the
// spectator WebSocket, and the HTTP side's limits (request size, methods, rate,
// connections, slow heads, keep-alive).
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>
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
      port, "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Pad: " + std::string(2000, 'p') + "\r\n\r\n");
  EXPECT_EQ(statusOf(r), 431) << r;
  r = sendAndRead(port, "POST / HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 2\r\n\r\n{}");
  EXPECT_EQ(statusOf(r), 405) << r;
  EXPECT_NE(r.find("Allow: GET"), std::string::npos) << r;
  r = sendAndRead(port, "HEAD / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
  EXPECT_EQ(statusOf(r), 405) << r;
  // Keep-alive: two requests on one connection, both answered (the second closes).
  r = sendAndRead(port,
                  "GET /assets/style.css HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"
                  "GET /nope HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
  EXPECT_EQ(statusOf(r), 200) << r;
  EXPECT_NE(r.find("HTTP/1.1 404"), std::string::npos) << r;
  // The burst of five is spent (malformed heads count too): the next is 429.
  r = sendAndRead(port, "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
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
  EXPECT_EQ(statusOf(sendAndRead(port, "DELETE / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")), 405);

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

// A spectator WebSocket read message by message (blocking, 5 s per read at most).
class WsClient {
 public:
  WsClient(std::uint16_t port, const std::string& target) : ws_(io_) {
    ws_.next_layer().connect({asio::ip::make_address("127.0.0.1"), port});
    timeval timeout{5, 0};
    ::setsockopt(ws_.next_layer().native_handle(), SOL_SOCKET, SO_RCVTIMEO, &timeout,
                 sizeof timeout);
    ws_.handshake("127.0.0.1:" + std::to_string(port), target);
  }
  void sendText(const std::string& text) {
    ws_.text(true);
    ws_.write(asio::buffer(text));
  }
  // The next message (binary in *binary); false once closed or after a read timeout.
  bool next(std::string& out, bool* binary) {
    beast::flat_buffer buffer;
    beast::error_code ec;
    ws_.read(buffer, ec);
    if (ec) return false;
    out = beast::buffers_to_string(buffer.data());
    *binary = !ws_.got_text();
    return true;
  }
  // Reads until a text message for which pred(json) holds (true), or `seconds` pass.
  template <typename Pred>
  bool waitFor(Pred pred, double seconds, nlohmann::json* found = nullptr) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    std::string text;
    bool binary = false;
    while (std::chrono::steady_clock::now() < end && next(text, &binary)) {
      if (binary) continue;
      auto j = nlohmann::json::parse(text, nullptr, false);
      if (!j.is_discarded() && pred(j)) {
        if (found) *found = j;
        return true;
      }
    }
    return false;
  }
  void close() {
    beast::error_code ec;
    ws_.close(websocket::close_code::normal, ec);
  }

 private:
  asio::io_context io_;
  websocket::stream<asio::ip::tcp::socket> ws_;
};

// One member of a binary spectator frame (web/PROTOCOL.md): its root translation and
// joint rotations, or nullopt when the frame does not hold it with a posture.
struct FrameMember {
  glm::vec3 root{0.0f};
  std::vector<glm::quat> rotations;
};
std::optional<FrameMember> memberOfFrame(const std::string& frame, std::uint32_t id) {
  auto u16 = [&](std::size_t at) {
    return static_cast<std::uint16_t>(static_cast<std::uint8_t>(frame[at]) |
                                      (static_cast<std::uint8_t>(frame[at + 1]) << 8));
  };
  auto f32 = [&](std::size_t at) {
    float v;
    std::memcpy(&v, frame.data() + at, 4);
    return v;
  };
  if (frame.size() < 16 || frame[0] != 1) return std::nullopt;
  const int members = u16(2);
  std::size_t at = 16;
  for (int m = 0; m < members; ++m) {
    if (at + 28 > frame.size()) return std::nullopt;
    std::uint32_t member_id;
    std::memcpy(&member_id, frame.data() + at, 4);
    const int joints = static_cast<std::uint8_t>(frame[at + 14]);
    if (at + 28 + 8 * static_cast<std::size_t>(joints) > frame.size()) return std::nullopt;
    if (member_id == id && joints > 0) {
      FrameMember out;
      out.root = {f32(at + 16), f32(at + 20), f32(at + 24)};
      for (int j = 0; j < joints; ++j) {
        const std::size_t q = at + 28 + 8 * static_cast<std::size_t>(j);
        auto c = [&](int k) { return static_cast<std::int16_t>(u16(q + 2 * k)) / 32767.0f; };
        out.rotations.push_back(glm::quat(c(3), c(0), c(1), c(2)));
      }
      return out;
    }
    at += 28 + 8 * static_cast<std::size_t>(joints);
  }
  return std::nullopt;
}

TEST(WebServerNet, VisibleSpectatorJoinsAsAMemberAtItsCamera) {
  const std::string dir = test::scratchDir();
  WebServerProcess server(dir, {"--web-members", "--metrics-port", "0"});
  ASSERT_NE(server.web(), 0) << server.log();
  ASSERT_NE(server.metrics(), 0) << server.log();
  EXPECT_EQ(metricValue(test::httpGet(server.metrics(), "/metrics"), "vistel_members"), 0.0);

  // The page: a bad message is answered with an error and dropped; the socket stays.
  WsClient page(server.web(), "/ws/room/cams");
  page.sendText("{\"type\":\"dance\"}");
  nlohmann::json error;
  ASSERT_TRUE(page.waitFor([](const nlohmann::json& j) { return j.value("type", "") == "error"; },
                           5.0, &error))
      << server.log();
  EXPECT_NE(error.value("message", "").find("unknown type"), std::string::npos) << error;
  page.sendText(R"({"type":"join","name":"Ann"})");
  page.sendText(R"({"type":"pose","x":1.5,"y":1.7,"z":-2.0,"yaw":0.5,"pitch":0.25})");
  nlohmann::json live;
  ASSERT_TRUE(page.waitFor(
      [](const nlohmann::json& j) {
        return j.value("type", "") == "member" && j.value("state", "") != "joining";
      },
      15.0, &live))
      << server.log();
  ASSERT_EQ(live.value("state", ""), "live") << live << server.log();
  EXPECT_EQ(live.value("name", ""), "Ann (spectator)");
  const std::uint32_t id = live.value("id", 0u);
  ASSERT_NE(id, 0u);

  // A native observer: the server's /metrics counts one member more.
  EXPECT_EQ(metricValue(test::httpGet(server.metrics(), "/metrics"), "vistel_members"), 1.0);

  // Another spectator sees the member in the roster, its camera at the sent pose.
  WsClient watcher(server.web(), "/ws/room/cams");
  nlohmann::json roster;
  ASSERT_TRUE(watcher.waitFor(
      [](const nlohmann::json& j) {
        return j.value("type", "") == "roster" && j["members"].size() == 1;
      },
      5.0, &roster));
  const nlohmann::json& member = roster["members"][0];
  EXPECT_EQ(member.value("id", 0u), id);
  EXPECT_EQ(member.value("name", ""), "Ann (spectator)");
  EXPECT_TRUE(member["avatar"].is_string()) << roster;
  const float seat_x = member["seat"].value("x", 0.0f), seat_z = member["seat"].value("z", 0.0f),
              seat_yaw = member["seat"].value("yaw", 0.0f);
  std::optional<FrameMember> posed;
  std::string text;
  bool binary = false;
  for (int i = 0; i < 600 && !posed && watcher.next(text, &binary); ++i) {
    if (binary) posed = memberOfFrame(text, id);
  }
  ASSERT_TRUE(posed) << "no posture of the visible spectator in the frames";
  ASSERT_EQ(posed->rotations.size(), 2u);
  // Head = seat * (root + R_root * (0, 0.6, 0)); R_root turns about +Y only.
  const glm::vec3 model = posed->root + posed->rotations[0] * glm::vec3(0.0f, 0.6f, 0.0f);
  const glm::vec3 room =
      glm::angleAxis(seat_yaw, glm::vec3(0, 1, 0)) * model + glm::vec3(seat_x, 0.0f, seat_z);
  EXPECT_NEAR(room.x, 1.5f, 0.01f);
  EXPECT_NEAR(room.y, 1.7f, 0.01f);
  EXPECT_NEAR(room.z, -2.0f, 0.01f);

  // The page's avatar is served like any other.
  const std::string glb =
      test::httpGet(server.web(), "/avatar/" + member["avatar"].get<std::string>() + ".glb");
  EXPECT_EQ(statusOf(glb), 200);

  // The page goes: so does its member (the room, whose only member it was, closes).
  page.close();
  EXPECT_TRUE(watcher.waitFor(
      [](const nlohmann::json& j) {
        return j.value("type", "") == "status" && j.value("state", "") == "closed";
      },
      10.0))
      << server.log();
  EXPECT_EQ(metricValue(test::httpGet(server.metrics(), "/metrics"), "vistel_members"), 0.0);
  watcher.close();
}

TEST(WebServerNet, VisibleSpectatorsNeedTheFlag) {
  const std::string dir = test::scratchDir();
  WebServerProcess server(dir, {"--metrics-port", "0"});
  ASSERT_NE(server.web(), 0) << server.log();
  WsClient page(server.web(), "/ws/room/cams");
  page.sendText(R"({"type":"join"})");
  nlohmann::json refused;
  ASSERT_TRUE(page.waitFor([](const nlohmann::json& j) { return j.value("type", "") == "member"; },
                           5.0, &refused));
  EXPECT_EQ(refused.value("state", ""), "refused") << refused;
  EXPECT_NE(refused.value("message", "").find("--web-members"), std::string::npos) << refused;
  // Nobody joined; the refusal is counted.
  const std::string scrape = test::httpGet(server.metrics(), "/metrics");
  EXPECT_EQ(metricValue(scrape, "vistel_members"), 0.0) << scrape;
  EXPECT_EQ(metricValue(scrape, R"(vistel_web_refused_total{reason="members off"})"), 1.0)
      << scrape;
  page.close();
}

TEST(WebServerNet, VisibleSpectatorsKeepTokensAndRoomLimits) {
  const std::string dir = test::scratchDir();
  const std::string secret_path = dir + "/secret";
  ASSERT_TRUE(writeFileText(secret_path, std::string(64, 'b') + "\n"));
  ::chmod(secret_path.c_str(), 0600);
  auto secret = auth::readJoinSecret(secret_path);
  ASSERT_TRUE(secret) << secret.error().message;
  const std::string config = dir + "/server.toml";
  ASSERT_TRUE(writeFileText(config, "[limits]\nmax_members_per_room = 1\n"));
  WebServerProcess server(dir, {"--web-members", "--secret-file", secret_path, "--config", config});
  ASSERT_NE(server.web(), 0) << server.log();
  auto token = auth::createJoinToken(secret->bytes, {"cams", "watcher", auth::unixNow() + 600});
  ASSERT_TRUE(token);
  const auto memberState = [](WsClient& page) {
    nlohmann::json j;
    page.waitFor(
        [](const nlohmann::json& m) {
          return m.value("type", "") == "member" && m.value("state", "") != "joining";
        },
        15.0, &j);
    return j;
  };
  // Without a token the socket is refused before any join.
  {
    WsClient page(server.web(), "/ws/room/cams");
    page.sendText(R"({"type":"join"})");
    nlohmann::json status;
    ASSERT_TRUE(page.waitFor(
        [](const nlohmann::json& j) { return j.value("type", "") == "status"; }, 5.0, &status));
    EXPECT_EQ(status.value("state", ""), "unauthorized");
  }
  // With the page's token the member joins (the web side signs one for its name).
  WsClient first(server.web(), "/ws/room/cams?token=" + *token);
  first.sendText(R"({"type":"join","name":"one"})");
  const nlohmann::json live = memberState(first);
  EXPECT_EQ(live.value("state", ""), "live") << live << server.log();
  // The room holds one member: a second visible spectator is refused, saying why.
  WsClient second(server.web(), "/ws/room/cams?token=" + *token);
  second.sendText(R"({"type":"join","name":"two"})");
  const nlohmann::json full = memberState(second);
  EXPECT_EQ(full.value("state", ""), "refused") << full << server.log();
  EXPECT_FALSE(full.value("message", "").empty()) << full;
  first.close();
  second.close();
}

TEST(WebServerNet, AnswersOnlyItsOwnHostNames) {
  const std::string dir = test::scratchDir();
  const std::string config = dir + "/server.toml";
  ASSERT_TRUE(writeFileText(config, "[web]\nallowed_hosts = \"lab.example\"\n"));
  WebServerProcess server(dir, {"--config", config, "--metrics-port", "0"});
  ASSERT_NE(server.web(), 0) << server.log();
  const auto get = [&](const std::string& host, const std::string& path) {
    return statusOf(sendAndRead(server.web(), "GET " + path + " HTTP/1.1\r\nHost: " + host +
                                                  "\r\nConnection: close\r\n\r\n"));
  };
  const std::string port = std::to_string(server.web());
  EXPECT_EQ(get("127.0.0.1:" + port, "/"), 200);
  EXPECT_EQ(get("localhost:" + port, "/api/rooms"), 200);
  EXPECT_EQ(get("lab.example", "/"), 200);
  // A name whose DNS someone pointed at this server: nothing but a 421, WebSockets too.
  EXPECT_EQ(get("evil.example:" + port, "/"), 421);
  EXPECT_EQ(get("evil.example:" + port, "/assets/spectator.js"), 421);
  const std::string upgrade =
      "GET /ws/room/lab HTTP/1.1\r\nHost: evil.example:" + port +
      "\r\nOrigin: http://evil.example:" + port +
      "\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n"
      "Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\r\n";
  EXPECT_EQ(statusOf(sendAndRead(server.web(), upgrade)), 421);
  const std::string scrape = test::httpGet(server.metrics(), "/metrics");
  EXPECT_EQ(metricValue(scrape, R"(vistel_web_refused_total{reason="host"})"), 3.0) << scrape;
  EXPECT_EQ(metricValue(scrape, R"(vistel_web_refused_total{reason="bad request"})"), 0.0)
      << scrape;
}

}  // namespace
}  // namespace vistel
