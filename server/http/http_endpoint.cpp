// The Asio side of the HTTP endpoint: accept loop with a connection cap and back-off,
// one Connection per socket with a deadline timer, graceful close. Parsing and routing
// are in http_message.cpp.
#include "server/http/http_endpoint.hpp"

#include <array>
#include <atomic>
#include <chrono>
#include <unordered_map>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "server/http/http_message.hpp"
#include "server/http/prometheus.hpp"

namespace vistel::server {
namespace {

using tcp = asio::ip::tcp;
using Strand = asio::strand<asio::io_context::executor_type>;
using Clock = std::chrono::steady_clock;

constexpr auto kAcceptBackoff = std::chrono::milliseconds(100);
constexpr auto kLingerTimeout = std::chrono::seconds(1);
constexpr auto kAcceptLogInterval = std::chrono::seconds(5);

std::chrono::steady_clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

MetricsProvider syncMetrics(std::function<std::string()> produce) {
  return [produce = std::move(produce)](MetricsReply reply) { reply(produce()); };
}

struct Connection;

struct HttpEndpoint::Impl : std::enable_shared_from_this<HttpEndpoint::Impl> {
  Impl(asio::io_context& io_context, HttpHandlers h, HttpEndpointOptions o)
      : io(io_context),
        strand(asio::make_strand(io_context)),
        acceptor(strand),
        backoff(strand),
        handlers(std::move(h)),
        options(o) {}

  void accept();
  void onAccepted(const boost::system::error_code& ec, tcp::socket socket);
  void closeAll();

  asio::io_context& io;
  Strand strand;
  tcp::acceptor acceptor;
  asio::steady_timer backoff;
  HttpHandlers handlers;
  HttpEndpointOptions options;
  bool stopped = false;                                             // strand only
  std::unordered_map<Connection*, std::weak_ptr<Connection>> open;  // strand only
  Clock::time_point last_accept_log{};                              // strand only
  std::uint64_t accept_errors_unlogged = 0;                         // strand only

  std::atomic<std::uint64_t> requests{0};
  std::atomic<std::uint64_t> bad_requests{0};
  std::atomic<std::uint64_t> refused_at_cap{0};
  std::atomic<std::uint64_t> timed_out{0};
  std::atomic<std::uint64_t> accept_errors{0};
};

// One accepted socket: read the head under a deadline, answer, close gracefully. Runs on
// the endpoint's strand (the socket and timer use it as their executor).
struct Connection : std::enable_shared_from_this<Connection> {
  Connection(std::shared_ptr<HttpEndpoint::Impl> owner, tcp::socket s)
      : endpoint(std::move(owner)), socket(std::move(s)), deadline(endpoint->strand) {
    head.reserve(1024);
  }

  void start() {
    armDeadline(seconds(endpoint->options.read_timeout_s));
    read();
  }

  // Closes the socket when the deadline passes (a re-arm cancels the previous wait).
  void armDeadline(Clock::duration after) {
    deadline.expires_after(after);
    deadline.async_wait([self = shared_from_this()](const boost::system::error_code& ec) {
      if (ec || self->closed) return;
      if (!self->lingering) self->endpoint->timed_out.fetch_add(1, std::memory_order_relaxed);
      self->close();
    });
  }

  void read() {
    // Never read more than one byte past the head limit: that byte proves it too long.
    std::size_t room = kMaxRequestHeadBytes + 1 - head.size();
    std::size_t want = std::min(chunk.size(), room);
    socket.async_read_some(asio::buffer(chunk.data(), want),
                           [self = shared_from_this()](const boost::system::error_code& ec,
                                                       std::size_t n) { self->onRead(ec, n); });
  }

  void onRead(const boost::system::error_code& ec, std::size_t n) {
    if (closed || responding) return;
    if (ec) {  // peer closed or reset before a complete head: nothing to answer
      close();
      return;
    }
    head.append(chunk.data(), n);
    if (auto end = findHeadEnd(head)) {
      handleHead(std::string_view(head).substr(0, *end));
    } else if (head.size() > kMaxRequestHeadBytes) {
      endpoint->bad_requests.fetch_add(1, std::memory_order_relaxed);
      respond(plainResponse(431, "request head too large"), false);
    } else {
      read();
    }
  }

  void handleHead(std::string_view bytes) {
    auto request = parseRequestHead(bytes);
    if (!request) {
      endpoint->bad_requests.fetch_add(1, std::memory_order_relaxed);
      int status = statusOfParseError(request.error());
      respond(plainResponse(status, std::string_view(request.error().message).substr(4)), false);
      return;
    }
    endpoint->requests.fetch_add(1, std::memory_order_relaxed);
    const bool head_only = request->method == "HEAD";
    armDeadline(seconds(endpoint->options.write_timeout_s));
    HttpRoutes routes{endpoint->handlers.ready};
    if (auto response = routeRequest(*request, routes)) {
      respond(std::move(*response), head_only);
      return;
    }
    // /metrics: ask the provider; its reply comes back to this strand.
    if (!endpoint->handlers.metrics) {
      respond(plainResponse(503, "metrics unavailable"), head_only);
      return;
    }
    responding = true;  // no more reads; the reply or the deadline ends the connection
    auto self = shared_from_this();
    auto replied = std::make_shared<std::atomic<bool>>(false);
    endpoint->handlers.metrics([self, replied, head_only](std::string text) {
      if (replied->exchange(true)) return;  // a second reply is ignored
      asio::post(self->endpoint->strand, [self, head_only, text = std::move(text)]() mutable {
        if (self->closed) return;
        HttpResponse response;
        response.content_type = std::string(kPrometheusContentType);
        response.body = std::move(text);
        self->respond(std::move(response), head_only);
      });
    });
  }

  void respond(HttpResponse response, bool head_only) {
    responding = true;
    out = serializeResponse(response, head_only);
    asio::async_write(socket, asio::buffer(out),
                      [self = shared_from_this()](const boost::system::error_code& ec,
                                                  std::size_t) { self->onWritten(ec); });
  }

  // After the response: half-close, then drain what the peer still sends until it closes
  // (or a short deadline), so that unread request bytes do not turn the close into a
  // reset that could destroy the response in flight.
  void onWritten(const boost::system::error_code& ec) {
    if (closed) return;
    if (ec) {
      close();
      return;
    }
    boost::system::error_code ignored;
    socket.shutdown(tcp::socket::shutdown_send, ignored);
    lingering = true;
    armDeadline(kLingerTimeout);
    drain();
  }

  void drain() {
    socket.async_read_some(
        asio::buffer(chunk),
        [self = shared_from_this()](const boost::system::error_code& ec, std::size_t) {
          if (self->closed) return;
          if (ec) {
            self->close();
          } else {
            self->drain();
          }
        });
  }

  void close() {
    if (closed) return;
    closed = true;
    boost::system::error_code ignored;
    socket.close(ignored);
    deadline.cancel();
    endpoint->open.erase(this);
  }

  std::shared_ptr<HttpEndpoint::Impl> endpoint;
  tcp::socket socket;
  asio::steady_timer deadline;
  std::array<char, 2048> chunk{};
  std::string head;  // bytes read so far (at most kMaxRequestHeadBytes + 1)
  std::string out;   // the response being written
  bool responding = false;
  bool lingering = false;
  bool closed = false;
};

void HttpEndpoint::Impl::accept() {
  if (stopped) return;
  acceptor.async_accept(
      strand, [self = shared_from_this()](const boost::system::error_code& ec, tcp::socket socket) {
        self->onAccepted(ec, std::move(socket));
      });
}

void HttpEndpoint::Impl::onAccepted(const boost::system::error_code& ec, tcp::socket socket) {
  if (stopped) return;
  if (ec) {
    if (ec == asio::error::operation_aborted) return;
    // Out of descriptors and the like: wait before the next try, log at a bounded rate.
    accept_errors.fetch_add(1, std::memory_order_relaxed);
    ++accept_errors_unlogged;
    Clock::time_point now = Clock::now();
    if (now - last_accept_log >= kAcceptLogInterval) {
      spdlog::warn("metrics endpoint: accept failed: {} ({} failure(s) since the last report)",
                   ec.message(), accept_errors_unlogged);
      last_accept_log = now;
      accept_errors_unlogged = 0;
    }
    backoff.expires_after(kAcceptBackoff);
    backoff.async_wait([self = shared_from_this()](const boost::system::error_code& wait_ec) {
      if (!wait_ec) self->accept();
    });
    return;
  }
  if (static_cast<int>(open.size()) >= options.max_connections) {
    refused_at_cap.fetch_add(1, std::memory_order_relaxed);
    boost::system::error_code ignored;
    socket.close(ignored);
  } else {
    auto connection = std::make_shared<Connection>(shared_from_this(), std::move(socket));
    open.emplace(connection.get(), connection);
    connection->start();
  }
  accept();
}

void HttpEndpoint::Impl::closeAll() {
  stopped = true;
  boost::system::error_code ignored;
  acceptor.close(ignored);
  backoff.cancel();
  // close() erases from open: collect first.
  std::vector<std::shared_ptr<Connection>> live;
  for (auto& [raw, weak] : open) {
    if (auto c = weak.lock()) live.push_back(std::move(c));
  }
  for (auto& c : live) c->close();
  open.clear();
}

Result<std::unique_ptr<HttpEndpoint>> HttpEndpoint::start(asio::io_context& io,
                                                          const std::string& bind_address,
                                                          std::uint16_t port, HttpHandlers handlers,
                                                          HttpEndpointOptions options) {
  boost::system::error_code ec;
  asio::ip::address address = asio::ip::make_address(bind_address, ec);
  if (ec) return fail("metrics endpoint: bad bind address '{}': {}", bind_address, ec.message());
  if (options.max_connections < 1 || !(options.read_timeout_s > 0.0) ||
      !(options.write_timeout_s > 0.0)) {
    return fail("metrics endpoint: max_connections and timeouts must be positive");
  }

  auto impl = std::make_shared<Impl>(io, std::move(handlers), options);
  tcp::endpoint where(address, port);
  impl->acceptor.open(where.protocol(), ec);
  if (!ec) impl->acceptor.set_option(tcp::acceptor::reuse_address(true), ec);
  if (!ec) impl->acceptor.bind(where, ec);
  if (!ec) impl->acceptor.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    return fail("metrics endpoint: cannot listen on {}:{}: {}", bind_address, port, ec.message());
  }
  tcp::endpoint local = impl->acceptor.local_endpoint(ec);
  if (ec) return fail("metrics endpoint: no local address: {}", ec.message());
  std::string text = fmt::format("{}:{}", local.address().to_string(), local.port());

  asio::post(impl->strand, [impl] { impl->accept(); });
  return std::unique_ptr<HttpEndpoint>(new HttpEndpoint(std::move(impl), local.port(), text));
}

HttpEndpoint::HttpEndpoint(std::shared_ptr<Impl> impl, std::uint16_t port, std::string local)
    : impl_(std::move(impl)), port_(port), local_(std::move(local)) {}

HttpEndpoint::~HttpEndpoint() { stop(); }

void HttpEndpoint::stop() {
  asio::post(impl_->strand, [impl = impl_] { impl->closeAll(); });
}

HttpEndpoint::Stats HttpEndpoint::stats() const {
  Stats s;
  s.requests = impl_->requests.load();
  s.bad_requests = impl_->bad_requests.load();
  s.refused_at_cap = impl_->refused_at_cap.load();
  s.timed_out = impl_->timed_out.load();
  s.accept_errors = impl_->accept_errors.load();
  return s;
}

}  // namespace vistel::server
