// AgonesSdk against a fake SDK sidecar: a blocking Asio listener on 127.0.0.1 that
// records every request (method, target, headers, JSON body) and answers with scripted
// statuses, the way the real REST gateway does.
#include "server/http/agones_sdk.hpp"

#include <sys/socket.h>
#include <sys/time.h>

#include <atomic>
#include <chrono>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "server/http/http_message.hpp"

namespace vistel::server {
namespace {

using tcp = asio::ip::tcp;

struct Recorded {
  std::string method;
  std::string target;
  std::string content_type;
  std::string body;
};

class FakeSdk {
 public:
  FakeSdk() : acceptor_(io_, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0)) {
    thread_ = std::thread([this] { serve(); });
  }
  ~FakeSdk() {
    stopping_ = true;
    boost::system::error_code ignored;
    // Wake the blocking accept with a connection of our own.
    tcp::socket poke(io_);
    poke.connect(acceptor_.local_endpoint(), ignored);
    thread_.join();
  }

  std::uint16_t port() const { return acceptor_.local_endpoint().port(); }

  // Statuses for the next requests, in order; 200 once they run out.
  void script(std::vector<int> statuses) {
    std::lock_guard lock(mutex_);
    statuses_.assign(statuses.begin(), statuses.end());
  }

  std::vector<Recorded> requests() const {
    std::lock_guard lock(mutex_);
    return requests_;
  }
  std::size_t count(std::string_view target) const {
    std::lock_guard lock(mutex_);
    std::size_t n = 0;
    for (const auto& r : requests_) n += r.target == target;
    return n;
  }

 private:
  void serve() {
    while (!stopping_) {
      boost::system::error_code ec;
      tcp::socket socket(io_);
      acceptor_.accept(socket, ec);
      if (ec || stopping_) continue;
      timeval tv{2, 0};
      ::setsockopt(socket.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
      handle(socket);
    }
  }

  // Reads the head and a Content-Length body, records them, answers.
  void handle(tcp::socket& socket) {
    std::string in;
    char buf[2048];
    std::optional<std::size_t> head_end;
    std::size_t body_length = 0;
    while (true) {
      ssize_t n = ::recv(socket.native_handle(), buf, sizeof buf, 0);
      if (n <= 0) return;
      in.append(buf, static_cast<std::size_t>(n));
      if (!head_end) head_end = findHeadEnd(in);
      if (head_end) {
        // The SDK client's requests are HTTP/1.1 with Host, so parseRequestHead (which
        // refuses bodies) parses a copy of the head without Content-Length.
        std::string head = in.substr(0, *head_end);
        std::size_t at = head.find("Content-Length: ");
        if (at != std::string::npos) {
          body_length = std::stoul(head.substr(at + 16));
        }
        if (in.size() >= *head_end + body_length) break;
      }
    }
    Recorded r;
    std::string head = in.substr(0, *head_end);
    std::size_t sp1 = head.find(' ');
    std::size_t sp2 = head.find(' ', sp1 + 1);
    r.method = head.substr(0, sp1);
    r.target = head.substr(sp1 + 1, sp2 - sp1 - 1);
    std::size_t ct = head.find("Content-Type: ");
    if (ct != std::string::npos)
      r.content_type = head.substr(ct + 14, head.find("\r\n", ct) - ct - 14);
    r.body = in.substr(*head_end, body_length);
    EXPECT_NE(head.find("\r\nHost: 127.0.0.1:"), std::string::npos) << head;
    EXPECT_NE(head.find("\r\nConnection: close\r\n"), std::string::npos) << head;

    int status = 200;
    {
      std::lock_guard lock(mutex_);
      requests_.push_back(r);
      if (!statuses_.empty()) {
        status = statuses_.front();
        statuses_.pop_front();
      }
    }
    // The real gateway answers "{}" for Empty; errors carry a JSON message.
    HttpResponse response;
    response.status = status;
    response.content_type = "application/json";
    response.body = status == 200 ? "{}" : R"({"code":14,"message":"not ready yet"})";
    std::string out = serializeResponse(response, false);
    boost::system::error_code ec;
    asio::write(socket, asio::buffer(out), ec);
    socket.shutdown(tcp::socket::shutdown_send, ec);
  }

  asio::io_context io_;
  tcp::acceptor acceptor_;
  std::thread thread_;
  std::atomic<bool> stopping_{false};
  mutable std::mutex mutex_;
  std::deque<int> statuses_;
  std::vector<Recorded> requests_;
};

class AgonesSdkTest : public ::testing::Test {
 protected:
  AgonesSdkOptions options() {
    AgonesSdkOptions o;
    o.port = fake_.port();
    o.health_interval_s = 0.05;
    o.request_timeout_s = 2.0;
    o.ready_attempts = 5;
    return o;
  }

  // Runs io until done is set (with a 10 s guard against hangs).
  void runUntil(const std::function<bool()>& done) {
    auto guard = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (!done() && std::chrono::steady_clock::now() < guard) {
      io_.restart();
      io_.run_for(std::chrono::milliseconds(10));
    }
    ASSERT_TRUE(done()) << "timed out";
  }

  // Calls one SDK method and waits for its completion.
  Status complete(const std::function<void(AgonesSdk::Done)>& call) {
    std::optional<Status> result;
    call([&](Status st) { result = std::move(st); });
    runUntil([&] { return result.has_value(); });
    return result ? *result : Status(Error{"no result"});
  }

  FakeSdk fake_;
  asio::io_context io_;
};

TEST_F(AgonesSdkTest, ReadyPostsAnEmptyJsonObject) {
  AgonesSdk sdk(io_, options());
  Status st = complete([&](AgonesSdk::Done d) { sdk.ready(d); });
  ASSERT_TRUE(st) << st.error().message;
  auto requests = fake_.requests();
  ASSERT_EQ(requests.size(), 1u);
  EXPECT_EQ(requests[0].method, "POST");
  EXPECT_EQ(requests[0].target, "/ready");
  EXPECT_EQ(requests[0].content_type, "application/json");
  EXPECT_EQ(requests[0].body, "{}");
}

TEST_F(AgonesSdkTest, ReadyRetriesUntilTheSidecarAccepts) {
  fake_.script({503, 503});
  AgonesSdk sdk(io_, options());
  Status st = complete([&](AgonesSdk::Done d) { sdk.ready(d); });
  ASSERT_TRUE(st) << st.error().message;
  EXPECT_EQ(fake_.count("/ready"), 3u);
}

TEST_F(AgonesSdkTest, ReadyGivesUpAfterItsAttempts) {
  fake_.script({503, 503, 503});
  AgonesSdkOptions o = options();
  o.ready_attempts = 2;
  AgonesSdk sdk(io_, o);
  Status st = complete([&](AgonesSdk::Done d) { sdk.ready(d); });
  ASSERT_FALSE(st);
  EXPECT_NE(st.error().message.find("503"), std::string::npos) << st.error().message;
  EXPECT_NE(st.error().message.find("/ready"), std::string::npos);
  EXPECT_EQ(fake_.count("/ready"), 2u);
}

TEST_F(AgonesSdkTest, StopEndsReadyRetriesAndHealth) {
  fake_.script({503, 503, 503, 503, 503});
  AgonesSdkOptions o = options();
  o.ready_attempts = 100;
  AgonesSdk sdk(io_, o);
  std::optional<Status> result;
  sdk.ready([&](Status st) { result = std::move(st); });
  runUntil([&] { return fake_.count("/ready") >= 1; });
  sdk.stop();
  sdk.startHealth();  // after stop(): no pings
  runUntil([&] { return result.has_value(); });
  ASSERT_FALSE(*result);
  EXPECT_NE(result->error().message.find("503"), std::string::npos);
  EXPECT_LE(fake_.count("/ready"), 2u);
  // With nothing pending, the loop runs dry: run() returns by itself.
  io_.restart();
  io_.run();
  EXPECT_EQ(fake_.count("/health"), 0u);
}

TEST_F(AgonesSdkTest, HealthPingsRepeatUntilStopped) {
  AgonesSdk sdk(io_, options());
  sdk.startHealth();
  sdk.startHealth();  // a second start does not double the pings
  runUntil([&] { return sdk.healthPingsSent() >= 3; });
  sdk.stopHealth();
  io_.restart();
  io_.run_for(std::chrono::milliseconds(50));  // let the stop and any reply land
  std::size_t after_stop = fake_.count("/health");
  io_.restart();
  io_.run_for(std::chrono::milliseconds(200));        // four intervals: no new ping
  EXPECT_LE(fake_.count("/health"), after_stop + 1);  // at most one already in flight
  for (const auto& r : fake_.requests()) {
    EXPECT_EQ(r.method, "POST");
    EXPECT_EQ(r.body, "{}");
  }
  EXPECT_EQ(sdk.healthPingsFailed(), 0u);
}

TEST_F(AgonesSdkTest, SetsLabelsAndAnnotations) {
  AgonesSdk sdk(io_, options());
  ASSERT_TRUE(complete([&](AgonesSdk::Done d) { sdk.setLabel("vistel-version", "0.1.0", d); }));
  ASSERT_TRUE(complete(
      [&](AgonesSdk::Done d) { sdk.setAnnotation("vistel-rooms", "lobby, \"a\" room", d); }));
  auto requests = fake_.requests();
  ASSERT_EQ(requests.size(), 2u);
  EXPECT_EQ(requests[0].method, "PUT");
  EXPECT_EQ(requests[0].target, "/metadata/label");
  auto label = nlohmann::json::parse(requests[0].body);
  EXPECT_EQ(label, (nlohmann::json{{"key", "vistel-version"}, {"value", "0.1.0"}}));
  EXPECT_EQ(requests[1].target, "/metadata/annotation");
  EXPECT_EQ(nlohmann::json::parse(requests[1].body)["value"], "lobby, \"a\" room");

  // An invalid label fails here, without a request.
  Status bad = complete([&](AgonesSdk::Done d) { sdk.setLabel("room name", "x", d); });
  EXPECT_FALSE(bad);
  EXPECT_EQ(fake_.requests().size(), 2u);
}

TEST_F(AgonesSdkTest, AddsAndRemovesListValues) {
  AgonesSdk sdk(io_, options());
  ASSERT_TRUE(complete([&](AgonesSdk::Done d) { sdk.addListValue("rooms", "lobby", d); }));
  ASSERT_TRUE(complete([&](AgonesSdk::Done d) { sdk.removeListValue("rooms", "lobby", d); }));
  EXPECT_FALSE(complete([&](AgonesSdk::Done d) { sdk.addListValue("../x", "v", d); }));
  auto requests = fake_.requests();
  ASSERT_EQ(requests.size(), 2u);
  EXPECT_EQ(requests[0].method, "POST");
  EXPECT_EQ(requests[0].target, "/v1beta1/lists/rooms:addValue");
  EXPECT_EQ(nlohmann::json::parse(requests[0].body), (nlohmann::json{{"value", "lobby"}}));
  EXPECT_EQ(requests[1].target, "/v1beta1/lists/rooms:removeValue");
}

TEST_F(AgonesSdkTest, AllocatePostsAnEmptyJsonObject) {
  AgonesSdk sdk(io_, options());
  ASSERT_TRUE(complete([&](AgonesSdk::Done d) { sdk.allocate(d); }));
  auto requests = fake_.requests();
  ASSERT_EQ(requests.size(), 1u);
  EXPECT_EQ(requests[0].method, "POST");
  EXPECT_EQ(requests[0].target, "/allocate");
  EXPECT_EQ(requests[0].body, "{}");
}

TEST_F(AgonesSdkTest, ShutdownPostsAndStopsHealth) {
  AgonesSdk sdk(io_, options());
  sdk.startHealth();
  runUntil([&] { return sdk.healthPingsSent() >= 1; });
  ASSERT_TRUE(complete([&](AgonesSdk::Done d) { sdk.shutdown(d); }));
  EXPECT_EQ(fake_.count("/shutdown"), 1u);
  std::size_t pings = fake_.count("/health");
  io_.restart();
  io_.run_for(std::chrono::milliseconds(200));
  EXPECT_LE(fake_.count("/health"), pings + 1);  // at most one already in flight
}

TEST_F(AgonesSdkTest, ReportsAnAbsentSidecar) {
  AgonesSdkOptions o = options();
  {
    // A port that was free a moment ago: nothing listens there.
    tcp::acceptor probe(io_, tcp::endpoint(asio::ip::make_address("127.0.0.1"), 0));
    o.port = probe.local_endpoint().port();
  }
  o.ready_attempts = 1;
  AgonesSdk sdk(io_, o);
  Status st = complete([&](AgonesSdk::Done d) { sdk.ready(d); });
  ASSERT_FALSE(st);
  EXPECT_NE(st.error().message.find("connect"), std::string::npos) << st.error().message;
}

}  // namespace
}  // namespace vistel::server
