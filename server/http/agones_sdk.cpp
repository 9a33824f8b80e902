// Agones SDK over its REST gateway: JSON bodies written with nlohmann::json, requests
// with httpRequest, retries and the health timer on the server's io_context.
#include "server/http/agones_sdk.hpp"

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cstdlib>

#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "server/http/http_client.hpp"

namespace vistel::server {
namespace {

constexpr std::string_view kLabelPrefixName = "sdk-";  // Agones: "agones.dev/sdk-<key>"
constexpr std::size_t kMaxLabelName = 63;

bool isAlnum(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9');
}

// A Kubernetes label name or value: [A-Za-z0-9]([-A-Za-z0-9_.]*[A-Za-z0-9])?
bool isLabelText(std::string_view s) {
  if (s.empty() || !isAlnum(s.front()) || !isAlnum(s.back())) return false;
  return std::all_of(s.begin(), s.end(),
                     [](char c) { return isAlnum(c) || c == '-' || c == '_' || c == '.'; });
}

std::chrono::steady_clock::duration toDuration(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(s));
}

}  // namespace

Result<std::uint16_t> parsePort(std::string_view text) {
  unsigned value = 0;
  auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || value == 0 ||
      value > 65535) {
    return fail("'{}' is not a port number (1..65535)", text.substr(0, 32));
  }
  return static_cast<std::uint16_t>(value);
}

Result<AgonesSdkOptions> agonesOptionsFromEnvironment() {
  AgonesSdkOptions options;
  if (const char* env = std::getenv("AGONES_SDK_HTTP_PORT"); env && *env) {
    auto port = parsePort(env);
    if (!port) return withContext("AGONES_SDK_HTTP_PORT", port.error());
    options.port = *port;
  }
  return options;
}

Status validateAgonesLabel(std::string_view key, std::string_view value) {
  std::string name = std::string(kLabelPrefixName) + std::string(key);
  if (key.empty() || name.size() > kMaxLabelName || !isLabelText(name)) {
    return fail(
        "Agones label key '{}': 'agones.dev/sdk-{}' is not a valid label name (at most "
        "63 characters of A-Z a-z 0-9 - _ ., alphanumeric at both ends)",
        key.substr(0, 80), key.substr(0, 80));
  }
  if (!value.empty() && (value.size() > kMaxLabelName || !isLabelText(value))) {
    return fail(
        "Agones label '{}': value '{}' is not a valid label value (at most 63 "
        "characters of A-Z a-z 0-9 - _ ., alphanumeric at both ends)",
        key, value.substr(0, 80));
  }
  return {};
}

struct AgonesSdk::Impl : std::enable_shared_from_this<AgonesSdk::Impl> {
  Impl(asio::io_context& io_context, AgonesSdkOptions o)
      : io(io_context),
        strand(asio::make_strand(io_context)),
        health_timer(strand),
        ready_timer(strand),
        options(o) {}

  // One request; done gets OK for a 2xx answer, an Error naming the call otherwise.
  void call(std::string method, std::string target, std::string body, Done done) {
    HttpClientRequest request;
    request.host = options.host;
    request.port = options.port;
    request.method = std::move(method);
    request.target = std::move(target);
    request.body = std::move(body);
    request.timeout_s = options.request_timeout_s;
    request.max_response_bytes = 64u << 10;
    std::string what = fmt::format("Agones SDK {} {}", request.method, request.target);
    httpRequest(io, std::move(request),
                [what = std::move(what), done = std::move(done)](Result<HttpClientResponse> r) {
                  if (!done) return;
                  if (!r) return done(withContext("Agones SDK", r.error()));
                  if (r->status < 200 || r->status > 299) {
                    return done(fail("{}: answered {} {}", what, r->status,
                                     std::string_view(r->body).substr(0, 200)));
                  }
                  done(Status{});
                });
  }

  void readyAttempt(int attempt, double delay_s, Done done) {
    auto self = shared_from_this();
    call("POST", "/ready", "{}", [self, attempt, delay_s, done](Status st) {
      if (st || attempt + 1 >= self->options.ready_attempts) {
        if (st) spdlog::info("Agones: GameServer marked Ready");
        if (done) done(st);
        return;
      }
      if (attempt == 0) {
        spdlog::info("Agones: ready not yet accepted ({}); retrying", st.error().message);
      }
      // The retry waits on the strand, where stop() cancels it.
      asio::post(self->strand, [self, attempt, delay_s, done, st] {
        if (self->stopped) {
          if (done) done(st);
          return;
        }
        self->ready_timer.expires_after(toDuration(delay_s));
        self->ready_timer.async_wait(
            [self, attempt, delay_s, done, st](const boost::system::error_code& ec) {
              if (ec || self->stopped) {
                if (done) done(st);
                return;
              }
              self->readyAttempt(attempt + 1, std::min(delay_s * 2.0, 2.0), done);
            });
      });
    });
  }

  // Runs on the strand: a ping, then the next one after the interval.
  void healthTick() {
    if (!health_on) return;
    auto self = shared_from_this();
    call("POST", "/health", "{}", [self](Status st) {
      if (st) {
        self->pings_sent.fetch_add(1, std::memory_order_relaxed);
      } else if (self->pings_failed.fetch_add(1, std::memory_order_relaxed) % 30 == 0) {
        spdlog::warn("Agones: health ping failed: {}", st.error().message);
      }
    });
    health_timer.expires_after(toDuration(options.health_interval_s));
    health_timer.async_wait([self](const boost::system::error_code& ec) {
      if (!ec) self->healthTick();
    });
  }

  asio::io_context& io;
  asio::strand<asio::io_context::executor_type> strand;
  asio::steady_timer health_timer;
  asio::steady_timer ready_timer;  // between POST /ready attempts
  AgonesSdkOptions options;
  bool health_on = false;  // strand only
  bool stopped = false;    // strand only: no more ready retries or health pings
  std::atomic<std::uint64_t> pings_sent{0};
  std::atomic<std::uint64_t> pings_failed{0};
};

AgonesSdk::AgonesSdk(asio::io_context& io, AgonesSdkOptions options)
    : impl_(std::make_shared<Impl>(io, std::move(options))) {}

AgonesSdk::~AgonesSdk() { stop(); }

void AgonesSdk::stop() {
  asio::post(impl_->strand, [impl = impl_] {
    impl->stopped = true;
    impl->health_on = false;
    impl->health_timer.cancel();
    impl->ready_timer.cancel();
  });
}

void AgonesSdk::ready(Done done) {
  auto impl = impl_;
  asio::post(impl->strand, [impl, done = std::move(done)] { impl->readyAttempt(0, 0.25, done); });
}

void AgonesSdk::startHealth() {
  asio::post(impl_->strand, [impl = impl_] {
    if (impl->health_on || impl->stopped) return;
    impl->health_on = true;
    impl->healthTick();
  });
}

void AgonesSdk::stopHealth() {
  asio::post(impl_->strand, [impl = impl_] {
    impl->health_on = false;
    impl->health_timer.cancel();
  });
}

void AgonesSdk::shutdown(Done done) {
  stopHealth();
  impl_->call("POST", "/shutdown", "{}", std::move(done));
}

void AgonesSdk::allocate(Done done) { impl_->call("POST", "/allocate", "{}", std::move(done)); }

void AgonesSdk::failLater(std::string message, const Done& done) {
  if (done) asio::post(impl_->strand, [done, message] { done(Error{message}); });
}

void AgonesSdk::setLabel(std::string key, std::string value, Done done) {
  if (Status st = validateAgonesLabel(key, value); !st) return failLater(st.error().message, done);
  nlohmann::json body = {{"key", key}, {"value", value}};
  impl_->call("PUT", "/metadata/label", body.dump(), std::move(done));
}

void AgonesSdk::setAnnotation(std::string key, std::string value, Done done) {
  if (Status st = validateAgonesLabel(key, ""); !st) return failLater(st.error().message, done);
  nlohmann::json body = {{"key", key}, {"value", value}};
  impl_->call("PUT", "/metadata/annotation",
              body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), std::move(done));
}

void AgonesSdk::addListValue(std::string list, std::string value, Done done) {
  if (!isLabelText(list))
    return failLater(fmt::format("Agones list name '{}' is not valid", list), done);
  nlohmann::json body = {{"value", value}};
  impl_->call("POST", fmt::format("/v1beta1/lists/{}:addValue", list),
              body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), std::move(done));
}

void AgonesSdk::removeListValue(std::string list, std::string value, Done done) {
  if (!isLabelText(list))
    return failLater(fmt::format("Agones list name '{}' is not valid", list), done);
  nlohmann::json body = {{"value", value}};
  impl_->call("POST", fmt::format("/v1beta1/lists/{}:removeValue", list),
              body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), std::move(done));
}

std::uint64_t AgonesSdk::healthPingsSent() const { return impl_->pings_sent.load(); }
std::uint64_t AgonesSdk::healthPingsFailed() const { return impl_->pings_failed.load(); }

}  // namespace vistel::server
