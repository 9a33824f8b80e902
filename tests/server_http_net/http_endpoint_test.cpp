// The HTTP endpoint on 127.0.0.1 port 0, fetched with a plain blocking Asio client (and
// with the project's own async client), including the hardening: slowloris deadline,
// oversized heads, the connection cap, a metrics provider that never answers.
#include "server/http/http_endpoint.hpp"

#include <sys/socket.h>
#include <sys/time.h>

#include <atomic>
#include <chrono>
#include <future>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "server/http/http_client.hpp"
#include "server/http/http_message.hpp"
#include "server/http/prometheus.hpp"

namespace vistel::server {
namespace {

using tcp = asio::ip::tcp;

// Runs an io_context on a background thread for the life of the fixture.
class EndpointTest : public ::testing::Test {
 protected:
  void startEndpoint(HttpHandlers handlers, HttpEndpointOptions options = {}) {
    auto started = HttpEndpoint::start(io_, "127.0.0.1", 0, std::move(handlers), options);
    ASSERT_TRUE(started) << started.error().message;
    endpoint_ = std::move(*started);
    ASSERT_NE(endpoint_->port(), 0);
    thread_ = std::thread([this] { io_.run(); });
  }

  void TearDown() override {
    if (endpoint_) endpoint_->stop();
    work_.reset();
    if (thread_.joinable()) thread_.join();  // returns only if stop() released everything
    endpoint_.reset();
  }

  // A blocking connection with a 5 s receive timeout (a guard against hangs, not a
  // measurement).
  tcp::socket connect() {
    tcp::socket socket(client_io_);
    socket.connect(tcp::endpoint(asio::ip::make_address("127.0.0.1"), endpoint_->port()));
    timeval tv{5, 0};
    ::setsockopt(socket.native_handle(), SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    return socket;
  }

  // Everything the server sends until it closes (or the guard timeout).
  static std::string readAll(tcp::socket& socket) {
    std::string in;
    char buf[4096];
    while (true) {
      ssize_t n = ::recv(socket.native_handle(), buf, sizeof buf, 0);
      if (n <= 0) break;
      in.append(buf, static_cast<std::size_t>(n));
    }
    return in;
  }

  std::string exchange(std::string_view raw) {
    tcp::socket socket = connect();
    boost::system::error_code ec;  // a peer that closes at once may reset the write
    asio::write(socket, asio::buffer(raw.data(), raw.size()), ec);
    return readAll(socket);
  }

  HttpClientResponse get(std::string_view path, std::string_view method = "GET") {
    std::string raw = fmt::format("{} {} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n", method, path);
    auto parsed = parseResponse(exchange(raw), method == "HEAD");
    EXPECT_TRUE(parsed) << parsed.error().message;
    return parsed ? *parsed : HttpClientResponse{};
  }

  static std::string header(const HttpClientResponse& r, std::string_view name) {
    for (const auto& [n, v] : r.headers) {
      if (n == name) return v;
    }
    return {};
  }

  asio::io_context io_;
  asio::executor_work_guard<asio::io_context::executor_type> work_ = asio::make_work_guard(io_);
  asio::io_context client_io_;
  std::unique_ptr<HttpEndpoint> endpoint_;
  std::thread thread_;
};

TEST_F(EndpointTest, ServesHealthReadinessAndMetrics) {
  std::atomic<bool> ready{false};
  MetricsSnapshot snapshot;
  snapshot.members = 3;
  snapshot.joins_refused["SERVER_FULL"] = 2;
  HttpHandlers handlers;
  handlers.ready = [&] { return ready.load(); };
  handlers.metrics = syncMetrics([&] { return formatMetrics(snapshot); });
  startEndpoint(handlers);
  EXPECT_EQ(endpoint_->localAddress(), fmt::format("127.0.0.1:{}", endpoint_->port()));

  HttpClientResponse health = get("/healthz");
  EXPECT_EQ(health.status, 200);
  EXPECT_EQ(health.body, "ok\n");
  EXPECT_EQ(header(health, "connection"), "close");

  EXPECT_EQ(get("/readyz").status, 503);
  ready = true;
  EXPECT_EQ(get("/readyz").status, 200);

  HttpClientResponse metrics = get("/metrics");
  EXPECT_EQ(metrics.status, 200);
  EXPECT_EQ(header(metrics, "content-type"), kPrometheusContentType);
  EXPECT_NE(metrics.body.find("# TYPE vistel_members gauge\nvistel_members 3\n"),
            std::string::npos);
  EXPECT_NE(metrics.body.find("vistel_joins_refused_total{reason=\"SERVER_FULL\"} 2\n"),
            std::string::npos);

  HttpClientResponse head = get("/metrics", "HEAD");
  EXPECT_EQ(head.status, 200);
  EXPECT_TRUE(head.body.empty());
  EXPECT_EQ(header(head, "content-length"), std::to_string(metrics.body.size()));

  EXPECT_EQ(get("/nothing").status, 404);
  HttpClientResponse post = get("/metrics", "POST");
  EXPECT_EQ(post.status, 405);
  EXPECT_EQ(header(post, "allow"), "GET, HEAD");
  EXPECT_EQ(get("/healthz", "DELETE").status, 405);
  EXPECT_EQ(endpoint_->stats().requests, 8u);
}

TEST_F(EndpointTest, AnswersMalformedRequestsWithTheirStatus) {
  startEndpoint({});
  auto status = [&](std::string_view raw) {
    auto r = parseResponse(exchange(raw));
    return r ? r->status : -1;
  };
  EXPECT_EQ(status("GET / HTTP/1.1\r\n\r\n"), 400);  // no Host
  EXPECT_EQ(status("GET /healthz HTTP/2.0\r\nHost: x\r\n\r\n"), 505);
  EXPECT_EQ(status("GET /healthz HTTP/1.1\r\nHost: x\r\nContent-Length: 4\r\n\r\nbody"), 400);
  const char tls_hello[] = "\x16\x03\x01\x02\x00\x01\x00\x01\xfc\x03\x03\r\n\r\n";
  EXPECT_EQ(status(std::string_view(tls_hello, sizeof tls_hello - 1)), 400);  // TLS, NULs
  EXPECT_EQ(status("GET /readyz HTTP/1.0\r\n\r\n"), 503);                     // no ready handler
  EXPECT_EQ(status("GET /metrics HTTP/1.0\r\n\r\n"), 503);                    // no metrics provider
  EXPECT_GE(endpoint_->stats().bad_requests, 4u);
}

TEST_F(EndpointTest, RefusesOversizedHeads) {
  startEndpoint({});
  std::string raw = "GET /healthz HTTP/1.1\r\nHost: x\r\nX-Pad: " + std::string(9000, 'a');
  // The server answers as soon as the limit is passed, without waiting for the rest.
  tcp::socket socket = connect();
  asio::write(socket, asio::buffer(raw));
  auto r = parseResponse(readAll(socket));
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->status, 431);
}

TEST_F(EndpointTest, ClosesSlowRequestsAtTheReadDeadline) {
  HttpEndpointOptions options;
  options.read_timeout_s = 0.2;
  startEndpoint({}, options);
  tcp::socket socket = connect();
  asio::write(socket, asio::buffer(std::string_view("GET /healthz HTTP/1.1\r\nHo")));
  std::string got = readAll(socket);  // the server closes without an answer
  EXPECT_EQ(got, "");
  EXPECT_EQ(endpoint_->stats().timed_out, 1u);
  EXPECT_EQ(get("/healthz").status, 200);  // still serving
}

TEST_F(EndpointTest, CapsConcurrentConnections) {
  HttpEndpointOptions options;
  options.max_connections = 2;
  startEndpoint({}, options);
  tcp::socket first = connect();
  tcp::socket second = connect();
  // Make sure both are accepted (and counted) before the third arrives.
  for (int i = 0; i < 500 && endpoint_->stats().refused_at_cap == 0; ++i) {
    tcp::socket third = connect();
    boost::system::error_code ec;
    asio::write(third, asio::buffer(std::string_view("GET /healthz HTTP/1.0\r\n\r\n")), ec);
    if (readAll(third).empty()) break;  // closed at accept
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_GE(endpoint_->stats().refused_at_cap, 1u);

  // Once the two idle connections go away, requests are served again.
  first.close();
  second.close();
  int status = 0;
  for (int i = 0; i < 500 && status != 200; ++i) {
    auto r = parseResponse(exchange("GET /healthz HTTP/1.0\r\n\r\n"));
    status = r ? r->status : 0;
    if (status != 200) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_EQ(status, 200);
}

TEST_F(EndpointTest, MetricsProviderMayAnswerFromAnotherThread) {
  std::vector<std::thread> helpers;
  std::mutex helpers_mutex;
  HttpHandlers handlers;
  handlers.metrics = [&](MetricsReply reply) {
    std::lock_guard lock(helpers_mutex);
    helpers.emplace_back([reply] {
      reply("# HELP x y\n# TYPE x gauge\nx 1\n");
      reply("ignored second reply");
    });
  };
  startEndpoint(handlers);
  HttpClientResponse r = get("/metrics");
  EXPECT_EQ(r.status, 200);
  EXPECT_EQ(r.body, "# HELP x y\n# TYPE x gauge\nx 1\n");
  std::lock_guard lock(helpers_mutex);
  for (auto& t : helpers) t.join();
}

TEST_F(EndpointTest, MetricsProviderThatNeverAnswersTimesOut) {
  HttpEndpointOptions options;
  options.write_timeout_s = 0.2;
  MetricsReply kept;  // held, never called (until the test ends)
  HttpHandlers handlers;
  handlers.metrics = [&](MetricsReply reply) { kept = reply; };
  startEndpoint(handlers, options);
  EXPECT_EQ(exchange("GET /metrics HTTP/1.0\r\n\r\n"), "");
  EXPECT_EQ(endpoint_->stats().timed_out, 1u);
  // A late reply after the close is harmless.
  std::promise<void> done;
  asio::post(io_, [&] {
    kept("late");
    done.set_value();
  });
  done.get_future().wait();
  EXPECT_EQ(get("/healthz").status, 200);
}

TEST_F(EndpointTest, OwnAsyncClientFetchesEveryPath) {
  HttpHandlers handlers;
  handlers.ready = [] { return true; };
  handlers.metrics = syncMetrics([] { return std::string("m 1\n"); });
  startEndpoint(handlers);
  for (const char* path : {"/healthz", "/readyz", "/metrics"}) {
    std::promise<Result<HttpClientResponse>> promise;
    HttpClientRequest request;
    request.port = endpoint_->port();
    request.target = path;
    httpRequest(io_, request,
                [&](Result<HttpClientResponse> r) { promise.set_value(std::move(r)); });
    auto r = promise.get_future().get();
    ASSERT_TRUE(r) << r.error().message;
    EXPECT_EQ(r->status, 200) << path;
  }
}

// /healthz is answered by the event loop itself: while the loop is blocked there is no
// answer, and it comes once the loop turns again.
TEST_F(EndpointTest, HealthzNeedsTheEventLoop) {
  startEndpoint({});
  std::promise<void> release;
  std::promise<void> blocked;
  asio::post(io_, [&] {
    blocked.set_value();
    release.get_future().wait();  // the only I/O thread is stuck here
  });
  blocked.get_future().wait();
  tcp::socket socket = connect();
  boost::system::error_code ec;  // no throw here: the loop must be released below
  asio::write(socket, asio::buffer(std::string_view("GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n")),
              ec);
  EXPECT_FALSE(ec);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  char byte = 0;
  EXPECT_EQ(::recv(socket.native_handle(), &byte, 1, MSG_DONTWAIT), -1);  // nothing yet
  release.set_value();
  auto r = parseResponse(readAll(socket));
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->status, 200);
}

TEST_F(EndpointTest, StopLetsTheLoopFinish) {
  startEndpoint({});
  tcp::socket idle = connect();  // an open connection must not keep the loop alive
  EXPECT_EQ(get("/healthz").status, 200);
  endpoint_->stop();
  work_.reset();
  thread_.join();  // returns: acceptor, timers and connections are all closed
  EXPECT_EQ(readAll(idle), "");
}

TEST(EndpointStart, ReportsBindErrors) {
  asio::io_context io;
  auto bad = HttpEndpoint::start(io, "not-an-address", 0, {});
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("not-an-address"), std::string::npos);

  auto first = HttpEndpoint::start(io, "127.0.0.1", 0, {});
  ASSERT_TRUE(first);
  auto clash = HttpEndpoint::start(io, "127.0.0.1", (*first)->port(), {});
  ASSERT_FALSE(clash);
  EXPECT_NE(clash.error().message.find(std::to_string((*first)->port())), std::string::npos);

  HttpEndpointOptions zero;
  zero.max_connections = 0;
  EXPECT_FALSE(HttpEndpoint::start(io, "127.0.0.1", 0, {}, zero));
}

}  // namespace
}  // namespace vistel::server
