#include "client/net/net_driver.hpp"

#include <charconv>
#include <functional>
#include <random>

#include <spdlog/spdlog.h>

namespace vistel::net {
namespace {

constexpr auto kTimerPeriod = std::chrono::milliseconds(5);

}  // namespace

Result<ServerAddress> parseServerAddress(const std::string& text) {
  ServerAddress a;
  std::string port_text;
  if (!text.empty() && text.front() == '[') {
    const auto close = text.find(']');
    if (close == std::string::npos || close + 1 >= text.size() || text[close + 1] != ':') {
      return fail("server address '{}': expected [IPv6]:PORT", text);
    }
    a.host = text.substr(1, close - 1);
    port_text = text.substr(close + 2);
  } else {
    const auto colon = text.rfind(':');
    if (colon == std::string::npos || colon == 0) {
      return fail("server address '{}': expected HOST:PORT", text);
    }
    a.host = text.substr(0, colon);
    port_text = text.substr(colon + 1);
  }
  unsigned port = 0;
  const auto [end, ec] =
      std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
  if (ec != std::errc() || end != port_text.data() + port_text.size() || port == 0 ||
      port > 65535) {
    return fail("server address '{}': port '{}' is not a number in 1..65535", text, port_text);
  }
  a.port = static_cast<std::uint16_t>(port);
  return a;
}

double monotonicSeconds() {
  static const auto kStart = std::chrono::steady_clock::now();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - kStart).count();
}

std::shared_ptr<NetDriver> NetDriver::create(asio::io_context& io, ServerAddress server,
                                             SessionSettings settings,
                                             std::shared_ptr<AvatarCache> cache,
                                             const BackoffSettings& backoff) {
  return std::shared_ptr<NetDriver>(
      new NetDriver(io, std::move(server), std::move(settings), std::move(cache), backoff));
}

NetDriver::NetDriver(asio::io_context& io, ServerAddress server, SessionSettings settings,
                     std::shared_ptr<AvatarCache> cache, const BackoffSettings& backoff)
    : io_(io),
      strand_(asio::make_strand(io)),
      server_(std::move(server)),
      resolver_(strand_),
      tcp_(strand_),
      udp_(strand_),
      timer_(strand_),
      settings_(std::move(settings)),
      cache_(std::move(cache)),
      session_(std::make_unique<ClientSession>(settings_, cache_)),
      backoff_(backoff, std::random_device{}() ^ std::hash<std::string>{}(settings_.name)),
      retry_timer_(strand_),
      read_buffer_(16u << 10),
      datagram_buffer_(65536) {
  (void)monotonicSeconds();
}

NetDriver::~NetDriver() = default;

int NetDriver::rejoins() const {
  std::lock_guard lock(mutex_);
  return rejoins_;
}

double NetDriver::secondsToLive() const {
  std::lock_guard lock(mutex_);
  return live_after_s_;
}

void NetDriver::start() {
  {
    std::lock_guard lock(mutex_);
    started_at_ = monotonicSeconds();
  }
  asio::post(strand_, [this, self = shared_from_this()] { connect(); });
}

void NetDriver::maybeRejoin() {
  double delay = -1.0;
  {
    std::lock_guard lock(mutex_);
    const double hint = session_->retryAfter();
    if (stopping_ || session_->state() != SessionState::kClosed || hint <= 0.0) return;
    delay = backoff_.nextDelay(hint);
    if (delay < 0.0) {
      spdlog::warn("'{}': the join was refused {} times in a row; giving up: {}", settings_.name,
                   backoff_.attempts(), session_->error());
      return;
    }
    if (backoff_.attempts() == 1) {
      spdlog::warn("'{}': {}; joining again in {:.2f} s (and backing off while refused)",
                   settings_.name, session_->error(), delay);
    } else {
      spdlog::debug("'{}': refused again ({}); attempt {} in {:.2f} s", settings_.name,
                    session_->error(), backoff_.attempts() + 1, delay);
    }
    session_ = std::make_unique<ClientSession>(settings_, cache_);
    ++rejoins_;
  }
  retry_timer_.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(delay)));
  retry_timer_.async_wait([this, self = shared_from_this()](const boost::system::error_code& ec) {
    if (ec || stopping_) return;
    connect();
  });
}

void NetDriver::connect() {
  // A fresh connection: the previous one's handlers have all run (they were aborted when
  // its sockets closed, before any retry delay ended).
  closed_ = false;
  connected_ = false;
  writing_ = false;
  close_after_write_ = false;
  write_queue_.clear();
  tcp_ = asio::ip::tcp::socket(strand_);
  udp_ = asio::ip::udp::socket(strand_);
  auto self = shared_from_this();
  resolver_.async_resolve(
      server_.host, std::to_string(server_.port),
      [this, self](const boost::system::error_code& ec,
                   asio::ip::tcp::resolver::results_type results) {
        if (ec) {
          fail("cannot resolve '" + server_.host + "': " + ec.message());
          return;
        }
        asio::async_connect(
            tcp_, results,
            [this, self](const boost::system::error_code& cec,
                         const asio::ip::tcp::endpoint& endpoint) {
              if (cec) {
                fail("cannot connect to " + server_.host + ":" + std::to_string(server_.port) +
                     ": " + cec.message());
                return;
              }
              boost::system::error_code e;
              tcp_.set_option(asio::ip::tcp::no_delay(true), e);
              // UDP to the same address and port, connected (only its datagrams arrive).
              const asio::ip::udp::endpoint udp_ep(endpoint.address(), endpoint.port());
              udp_.open(udp_ep.protocol(), e);
              if (!e) udp_.connect(udp_ep, e);
              if (e) {
                fail("cannot open UDP to " + udp_ep.address().to_string() + ": " + e.message());
                return;
              }
              connected_ = true;
              {
                std::lock_guard lock(mutex_);
                session_->start(monotonicSeconds());
              }
              flush();
              readStream();
              readDatagram();
              armTimer();
            });
      });
}

void NetDriver::stop(const std::string& reason) {
  auto self = shared_from_this();
  asio::post(strand_, [this, self, reason] {
    stopping_ = true;
    retry_timer_.cancel();
    {
      std::lock_guard lock(mutex_);
      session_->leave(reason);
    }
    if (!connected_) {
      resolver_.cancel();
      closeSockets();
      return;
    }
    flush();
  });
}

bool NetDriver::sendPosture(const Posture& posture) {
  bool sent = false;
  {
    std::lock_guard lock(mutex_);
    sent = session_->sendPosture(posture, monotonicSeconds());
  }
  if (sent) asio::post(strand_, [self = shared_from_this()] { self->flush(); });
  return sent;
}

bool NetDriver::requestBall() {
  bool sent = false;
  {
    std::lock_guard lock(mutex_);
    sent = session_->requestBall();
  }
  if (sent) asio::post(strand_, [self = shared_from_this()] { self->flush(); });
  return sent;
}

SessionState NetDriver::state() const {
  std::lock_guard lock(mutex_);
  return session_->state();
}

std::string NetDriver::error() const {
  std::lock_guard lock(mutex_);
  return session_->error();
}

void NetDriver::fail(const std::string& reason) {
  {
    std::lock_guard lock(mutex_);
    session_->onDisconnected(reason, monotonicSeconds());
  }
  closeSockets();
}

void NetDriver::closeSockets() {
  if (closed_) return;
  closed_ = true;
  boost::system::error_code ignored;
  timer_.cancel();
  tcp_.shutdown(asio::ip::tcp::socket::shutdown_both, ignored);
  tcp_.close(ignored);
  udp_.close(ignored);
  maybeRejoin();
}

void NetDriver::flush() {
  if (closed_) return;
  // Take what the session wants sent.
  std::vector<std::uint8_t> stream;
  std::vector<std::vector<std::uint8_t>> datagrams;
  bool close = false;
  {
    std::lock_guard lock(mutex_);
    SessionOutbox& out = session_->outbox();
    stream.swap(out.stream);
    datagrams.swap(out.datagrams);
    close = out.close;
    out.clear();
  }
  // Datagrams now (a full socket buffer drops them, as the network would).
  for (const auto& d : datagrams) {
    boost::system::error_code ec;
    udp_.send(asio::buffer(d), 0, ec);
  }
  if (!stream.empty()) write_queue_.push_back(std::move(stream));
  if (close) close_after_write_ = true;
  writeStream();
}

void NetDriver::writeStream() {
  if (writing_ || closed_) return;
  if (write_queue_.empty()) {
    if (close_after_write_) closeSockets();
    return;
  }
  writing_ = true;
  asio::async_write(
      tcp_, asio::buffer(write_queue_.front()),
      [this, self = shared_from_this()](const boost::system::error_code& ec, std::size_t) {
        writing_ = false;
        if (closed_) return;
        write_queue_.pop_front();
        if (ec) {
          fail("write failed: " + ec.message());
          return;
        }
        writeStream();
      });
}

void NetDriver::readStream() {
  tcp_.async_read_some(
      asio::buffer(read_buffer_),
      [this, self = shared_from_this()](const boost::system::error_code& ec, std::size_t n) {
        if (closed_) return;
        if (ec) {
          fail(ec == asio::error::eof ? "the server closed the connection" : ec.message());
          return;
        }
        {
          std::lock_guard lock(mutex_);
          session_->onStreamBytes(std::span(read_buffer_.data(), n), monotonicSeconds());
        }
        flush();
        readStream();
      });
}

void NetDriver::readDatagram() {
  udp_.async_receive(
      asio::buffer(datagram_buffer_),
      [this, self = shared_from_this()](const boost::system::error_code& ec, std::size_t n) {
        if (closed_) return;
        if (!ec) {
          std::lock_guard lock(mutex_);
          session_->onDatagram(std::span(datagram_buffer_.data(), n), monotonicSeconds());
        }
        // Errors such as ICMP port unreachable are transient on UDP: keep receiving.
        readDatagram();
      });
}

void NetDriver::armTimer() {
  timer_.expires_after(kTimerPeriod);
  timer_.async_wait([this, self = shared_from_this()](const boost::system::error_code& ec) {
    if (ec || closed_) return;
    {
      std::lock_guard lock(mutex_);
      const double now = monotonicSeconds();
      session_->update(now);
      if (live_after_s_ < 0.0 && session_->state() == SessionState::kLive) {
        live_after_s_ = now - started_at_;
        backoff_.reset();
      }
    }
    flush();
    armTimer();
  });
}

}  // namespace vistel::net
