// A small, hardened HTTP/1.1 endpoint on its own TCP port for operators and orchestrators:
//   GET /healthz  200 "ok" whenever the io_context runs its handlers (the reply is made
//                 by the event loop itself, so a stalled loop gives no answer)
//   GET /readyz   200 while handlers.ready() is true, 503 otherwise
//   GET /metrics  Prometheus text (prometheus.hpp) from handlers.metrics
// HEAD is answered like GET without a body; other methods get 405, other paths 404.
//
// Hardening: the request head is at most kMaxRequestHeadBytes (431 beyond), must arrive
// within options.read_timeout_s of the accept (slowloris), and no body is accepted; at
// most options.max_connections are open at once (more are closed at accept); the accept
// loop backs off on errors (e.g. out of file descriptors) and logs them at a bounded rate;
// every response carries Connection: close and the connection is closed after it.
//
// Threads: all of the endpoint's work runs on one strand of the io_context, which may be
// run by several threads. ready() and metrics() are called on that strand; they must be
// safe to call from any I/O thread. The endpoint keeps io.run() busy until stop(); destroy
// it before the io_context.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "common/base/result.hpp"
#include "server/shell/asio.hpp"

namespace vistel::server {

// Hands the Prometheus text of one scrape back; may be called from any thread, once.
using MetricsReply = std::function<void(std::string text)>;
// Produces one scrape: calls reply (now or later, e.g. after gathering figures on other
// strands). If reply is not called within options.write_timeout_s the scrape fails.
using MetricsProvider = std::function<void(MetricsReply reply)>;

// A provider that calls produce() on the endpoint's strand and replies at once.
MetricsProvider syncMetrics(std::function<std::string()> produce);

struct HttpHandlers {
  std::function<bool()> ready;  // absent: /readyz is always 503
  MetricsProvider metrics;      // absent: /metrics is 503
};

struct HttpEndpointOptions {
  int max_connections = 32;       // open at once; more are closed right after accept
  double read_timeout_s = 5.0;    // from accept to a complete request head
  double write_timeout_s = 10.0;  // from the complete head to the response sent
};

class HttpEndpoint {
 public:
  struct Stats {
    std::uint64_t requests = 0;        // heads parsed and answered
    std::uint64_t bad_requests = 0;    // answered 4xx/5xx for a malformed head
    std::uint64_t refused_at_cap = 0;  // closed at accept: too many connections
    std::uint64_t timed_out = 0;       // closed by the read or write deadline
    std::uint64_t accept_errors = 0;   // failed accepts (each followed by a back-off)
  };

  // Binds bind_address:port (port 0: a free port) and starts accepting on io. The error
  // names the address and the OS reason. Nothing runs until io runs.
  static Result<std::unique_ptr<HttpEndpoint>> start(asio::io_context& io,
                                                     const std::string& bind_address,
                                                     std::uint16_t port, HttpHandlers handlers,
                                                     HttpEndpointOptions options = {});
  ~HttpEndpoint();  // stop()
  HttpEndpoint(const HttpEndpoint&) = delete;
  HttpEndpoint& operator=(const HttpEndpoint&) = delete;

  std::uint16_t port() const { return port_; }                // the port actually bound
  const std::string& localAddress() const { return local_; }  // "ADDRESS:PORT"

  // Closes the acceptor and every open connection (posted to the strand; safe from any
  // thread, idempotent). io.run() can then return once nothing else is pending.
  void stop();

  Stats stats() const;  // from any thread

  struct Impl;

 private:
  HttpEndpoint(std::shared_ptr<Impl> impl, std::uint16_t port, std::string local);
  std::shared_ptr<Impl> impl_;
  std::uint16_t port_ = 0;
  std::string local_;
};

}  // namespace vistel::server
