#include "client/net/net_driver.hpp"

#include <charconv>
#include <functional>
#include <limits>
#include <random>

#include <spdlog/spdlog.h>

namespace vistel::net {
namespace {

constexpr auto kTimerPeriod = std::chrono::milliseconds(5);

// Reconnecting backs off like a refused join but is bounded by time, not attempts.
BackoffSettings reconnectBackoff(BackoffSettings b) {
  b.max_attempts = std::numeric_limits<int>::max();
  return b;
}

std::uint64_t backoffSeed(const std::string& name, std::uint64_t salt) {
  return (std::random_device{}() ^ std::hash<std::string>{}(name)) + salt;
}

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
                                             const BackoffSettings& backoff,
                                             const tls::ClientTlsSettings& tls) {
  return std::shared_ptr<NetDriver>(
      new NetDriver(io, std::move(server), std::move(settings), std::move(cache), backoff, tls));
}

NetDriver::NetDriver(asio::io_context& io, ServerAddress server, SessionSettings settings,
                     std::shared_ptr<AvatarCache> cache, const BackoffSettings& backoff,
                     const tls::ClientTlsSettings& tls)
    : io_(io),
      strand_(asio::make_strand(io)),
      server_(std::move(server)),
      resolver_(strand_),
      tcp_(asio::ip::tcp::socket(strand_)),
      udp_(strand_),
      timer_(strand_),
      settings_(std::move(settings)),
      cache_(std::move(cache)),
      session_(std::make_unique<ClientSession>(settings_, cache_)),
      backoff_(backoff, backoffSeed(settings_.name, 0)),
      reconnect_backoff_(reconnectBackoff(backoff), backoffSeed(settings_.name, 1)),
      retry_timer_(strand_),
      read_buffer_(16u << 10),
      datagram_buffer_(65536),
      tls_(tls) {
  (void)monotonicSeconds();
  if (tls_.enabled) {
    auto context = tls::makeClientContext(tls_);
    if (context) {
      tls_context_ = std::move(*context);
    } else {
      tls_error_ = context.error().message;
    }
  }
}

NetDriver::~NetDriver() = default;

int NetDriver::rejoins() const {
  std::lock_guard lock(mutex_);
  return rejoins_;
}

int NetDriver::reconnects() const {
  std::lock_guard lock(mutex_);
  return reconnects_;
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
    if (stopping_ || ended_ || session_->state() != SessionState::kClosed) return;
    const double now = monotonicSeconds();
    const CloseCause cause = session_->closeCause();
    const std::string& why = session_->error();
    if (!why.empty()) last_close_reason_ = why;  // kept across the fresh sessions below
    // The newest Welcome is what a later join resumes.
    if (session_->memberId() != 0) {
      resume_member_id_ = session_->memberId();
      resume_secret_ = session_->resumeSecret();
    }

    // Whether to try again: a busy server always (within the backoff's attempts); after a
    // live session, whatever may clear by itself (within the give-up time).
    const bool reconnecting = ever_live_ && settings_.reconnect_give_up_s > 0.0;
    double hint = 0.0;
    bool retry = false;
    switch (cause) {
      case CloseCause::kBusy:
        retry = true;
        hint = session_->retryAfter();
        break;
      case CloseCause::kLost:
        retry = reconnecting;
        break;
      case CloseCause::kTaken:
        retry = reconnecting;  // our stale member may hold the name until it times out
        hint = 1.0;
        break;
      case CloseCause::kNone:
      case CloseCause::kLeft:
      case CloseCause::kRefused:
        break;
    }
    if (!retry) {
      ended_ = true;
      if (reconnecting && cause == CloseCause::kRefused) {
        spdlog::error("'{}': the server refused to take us back: {}", settings_.name, why);
      }
      return;
    }

    if (reconnecting) {
      // Back off with jitter until live again or the give-up time has passed.
      if (lost_at_ < 0.0) {
        lost_at_ = now;
        spdlog::warn("'{}': lost the session ({}); reconnecting", settings_.name, why);
      }
      if (now - lost_at_ > settings_.reconnect_give_up_s) {
        spdlog::error("'{}': not back within {:.0f} s; giving up: {}", settings_.name,
                      settings_.reconnect_give_up_s, why);
        ended_ = true;
        return;
      }
      delay = reconnect_backoff_.nextDelay(hint);
      if (reconnect_backoff_.attempts() == 1) {
        spdlog::info("'{}': reconnecting in {:.1f} s (attempt 1)", settings_.name, delay);
      } else {
        spdlog::info("'{}': not back yet ({}); reconnecting in {:.1f} s (attempt {})",
                     settings_.name, why, delay, reconnect_backoff_.attempts());
      }
      settings_.resume_member_id = resume_member_id_;
      settings_.resume_secret = resume_secret_;
    } else {
      // A join refused for a transient reason: again, backing off.
      delay = backoff_.nextDelay(hint);
      if (delay < 0.0) {
        spdlog::warn("'{}': the join was refused {} times in a row; giving up: {}", settings_.name,
                     backoff_.attempts(), why);
        ended_ = true;
        return;
      }
      if (backoff_.attempts() == 1) {
        spdlog::warn("'{}': {}; joining again in {:.2f} s (and backing off while refused)",
                     settings_.name, why, delay);
      } else {
        spdlog::debug("'{}': refused again ({}); attempt {} in {:.2f} s", settings_.name, why,
                      backoff_.attempts() + 1, delay);
      }
    }
    // A fresh session that continues the counters.
    SessionStats stats = session_->stats();
    session_ = std::make_unique<ClientSession>(settings_, cache_);
    session_->carryStats(std::move(stats));
    session_live_ = false;
    ++rejoins_;
  }
  retry_timer_.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(delay)));
  retry_timer_.async_wait([this, self = shared_from_this()](const boost::system::error_code& ec) {
    if (ec || stopping_) return;
    connect();
  });
}

void NetDriver::noteLive(double now) {
  if (session_live_ || session_->state() != SessionState::kLive) return;
  session_live_ = true;
  ever_live_ = true;
  if (live_after_s_ < 0.0) live_after_s_ = now - started_at_;
  backoff_.reset();
  if (lost_at_ >= 0.0) {
    ++reconnects_;
    session_->countReconnect();
    spdlog::info("'{}': rejoined room '{}' as '{}' after {:.1f} s (reconnect {})", settings_.name,
                 session_->roomName(), settings_.name, now - lost_at_, reconnects_);
    lost_at_ = -1.0;
    reconnect_backoff_.reset();
  }
}

void NetDriver::connect() {
  // A fresh connection: the previous one's handlers have all run (they were aborted when
  // its sockets closed, before any retry delay ended).
  closed_ = false;
  connected_ = false;
  writing_ = false;
  close_after_write_ = false;
  write_queue_.clear();
  tcp_ = tls_context_ ? tls::ControlStream(asio::ip::tcp::socket(strand_), *tls_context_)
                      : tls::ControlStream(asio::ip::tcp::socket(strand_));
  tls_handshaken_ = false;
  stream_answered_ = false;
  if (tls_.enabled && !tls_context_) {
    fail("TLS: " + tls_error_);
    return;
  }
  udp_ = asio::ip::udp::socket(strand_);
  auto self = shared_from_this();
  auto on_resolved = [this, self](const boost::system::error_code& ec,
                                  asio::ip::tcp::resolver::results_type results) {
    if (ec) {
      fail("cannot resolve '" + server_.host + "': " + ec.message());
      return;
    }
    auto on_connect = [this, self](const boost::system::error_code& cec,
                                   const asio::ip::tcp::endpoint& endpoint) {
      if (cec) {
        fail("cannot connect to " + server_.host + ":" + std::to_string(server_.port) + ": " +
             cec.message());
        return;
      }
      onConnected(endpoint);
    };
    asio::async_connect(tcp_.socket(), results, std::move(on_connect));
  };
  resolver_.async_resolve(server_.host, std::to_string(server_.port), std::move(on_resolved));
}

void NetDriver::onConnected(const asio::ip::tcp::endpoint& endpoint) {
  boost::system::error_code e;
  tcp_.socket().set_option(asio::ip::tcp::no_delay(true), e);
  // TLS: the handshake first (then here again).
  if (tcp_.isTls() && !tls_handshaken_) {
    tls_note_->clear();
    if (Status st = tls::prepareClientStream(tcp_, tls_, server_.host, tls_note_); !st) {
      fail(st.error().message);
      return;
    }
    // A server that never answers the handshake: given up after the join timeout (the
    // retry timer is idle while a connection is being made).
    retry_timer_.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(settings_.join_timeout_s)));
    spdlog::debug("'{}': TLS handshake with {}:{}", settings_.name, server_.host, server_.port);
    retry_timer_.async_wait([this, self = shared_from_this()](const boost::system::error_code& ec) {
      if (ec || closed_ || tls_handshaken_) return;
      *tls_note_ =
          "no answer in " + std::to_string(static_cast<int>(settings_.join_timeout_s)) + " s";
      tcp_.close();
    });
    tcp_.asyncHandshake(asio::ssl::stream_base::client, [this, self = shared_from_this(), endpoint](
                                                            const boost::system::error_code& hec) {
      retry_timer_.cancel();
      if (closed_) return;
      if (hec) {
        fail("TLS handshake with " + server_.host + ":" + std::to_string(server_.port) +
             " failed: " + tls::describeTlsError(hec) +
             (tls_note_->empty() ? std::string(" (a server without TLS?)")
                                 : " (" + *tls_note_ + ")"));
        return;
      }
      tls_handshaken_ = true;
      onConnected(endpoint);
    });
    return;
  }
  // UDP to the same address and port, connected (only its datagrams arrive).
  udp_server_ = asio::ip::udp::endpoint(endpoint.address(), endpoint.port());
  udp_.open(udp_server_.protocol(), e);
  if (!e) udp_.connect(udp_server_, e);
  if (e) {
    fail("cannot open UDP to " + udp_server_.address().to_string() + ": " + e.message());
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
}

void NetDriver::stop(const std::string& reason) {
  auto self = shared_from_this();
  asio::post(strand_, [this, self, reason] {
    stopping_ = true;
    retry_timer_.cancel();
    {
      std::lock_guard lock(mutex_);
      ended_ = true;
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

bool NetDriver::sendVoice(const OutgoingVoice& frame) {
  bool sent = false;
  {
    std::lock_guard lock(mutex_);
    sent = session_->sendVoice(frame);
  }
  if (sent) asio::post(strand_, [self = shared_from_this()] { self->flush(); });
  return sent;
}

void NetDriver::takeVoice(std::vector<ReceivedVoice>& out, VoiceCounters* counters) {
  std::lock_guard lock(mutex_);
  session_->voiceInbox().takeAll(out);
  if (counters != nullptr) *counters = session_->voiceInbox().counters;
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

bool NetDriver::sendDents(const BodyDents& dents) {
  bool sent = false;
  {
    std::lock_guard lock(mutex_);
    sent = session_->sendDents(dents);
  }
  if (sent) asio::post(strand_, [self = shared_from_this()] { self->flush(); });
  return sent;
}

void NetDriver::takeDents(std::vector<BodyDents>& out) {
  out.clear();
  std::lock_guard lock(mutex_);
  std::swap(out, session_->receivedDents());
}

SessionState NetDriver::state() const {
  std::lock_guard lock(mutex_);
  // A closed session about to be replaced (a rejoin pending) is still joining.
  const SessionState s = session_->state();
  return s == SessionState::kClosed && !ended_ ? SessionState::kJoining : s;
}

void NetDriver::reopenDatagramSocket() {
  asio::post(strand_, [this, self = shared_from_this()] {
    if (!connected_ || closed_) return;
    boost::system::error_code e;
    udp_.close(e);
    udp_ = asio::ip::udp::socket(strand_);
    udp_.open(udp_server_.protocol(), e);
    if (!e) udp_.connect(udp_server_, e);
    if (e) {
      fail("cannot reopen UDP to " + udp_server_.address().to_string() + ": " + e.message());
      return;
    }
    spdlog::info("'{}': UDP socket reopened on local port {}", settings_.name,
                 udp_.local_endpoint(e).port());
    readDatagram();
  });
}

std::string NetDriver::error() const {
  std::lock_guard lock(mutex_);
  return session_->error();
}

std::string NetDriver::lastCloseReason() const {
  std::lock_guard lock(mutex_);
  return last_close_reason_;
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
  if (netsim_) netsim_->clear();  // what was in flight went with the sockets
  tcp_.close();
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
    if (netsim_) {
      netsim_->send(d, monotonicSeconds());  // sent by the simulator when due
      continue;
    }
    boost::system::error_code ec;
    udp_.send(asio::buffer(d), 0, ec);
  }
  if (!stream.empty()) write_queue_.push_back(std::move(stream));
  if (close) {
    // Only a Leave is worth waiting for; a lost or refused session closes at once (a dead
    // server may never take the bytes).
    bool left = false;
    {
      std::lock_guard lock(mutex_);
      left = session_->closeCause() == CloseCause::kLeft;
    }
    if (!left) {
      closeSockets();
      return;
    }
    close_after_write_ = true;
  }
  writeStream();
}

void NetDriver::writeStream() {
  if (writing_ || closed_) return;
  if (write_queue_.empty()) {
    if (close_after_write_) closeSockets();
    return;
  }
  writing_ = true;
  tcp_.asyncWrite(
      asio::buffer(write_queue_.front()),
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
  tcp_.asyncReadSome(
      asio::buffer(read_buffer_),
      [this, self = shared_from_this()](const boost::system::error_code& ec, std::size_t n) {
        if (closed_) return;
        if (ec) {
          std::string why =
              ec == asio::error::eof ? "the server closed the connection" : ec.message();
          // A TLS server drops a plain client's first bytes without an answer.
          if (!stream_answered_ && !tcp_.isTls())
            why += " without answering (a TLS server? try --tls)";
          fail(why);
          return;
        }
        stream_answered_ = true;
        {
          std::lock_guard lock(mutex_);
          session_->onStreamBytes(std::span(read_buffer_.data(), n), monotonicSeconds());
        }
        flush();
        readStream();
      });
}

void NetDriver::readDatagram() {
  // Each socket's reads carry its generation: those of a replaced socket end quietly.
  const std::uint64_t generation = ++udp_generation_;
  auto on_datagram = [this, self = shared_from_this(), generation](
                         const boost::system::error_code& ec, std::size_t n) {
    if (closed_ || generation != udp_generation_) return;
    if (!ec && netsim_) {
      netsim_->receive(std::span(datagram_buffer_.data(), n), monotonicSeconds());
    } else if (!ec) {
      deliverDatagram(std::span(datagram_buffer_.data(), n));
    }
    // Errors such as ICMP port unreachable are transient on UDP: keep receiving.
    readDatagram();
  };
  udp_.async_receive(asio::buffer(datagram_buffer_), std::move(on_datagram));
}

void NetDriver::deliverDatagram(std::span<const std::uint8_t> datagram) {
  std::lock_guard lock(mutex_);
  const double now = monotonicSeconds();
  session_->onDatagram(datagram, now);
  noteLive(now);  // the handshake may just have finished
}

void NetDriver::setNetSim(const NetSimSpec& spec) {
  if (!spec.active()) {
    netsim_.reset();
    return;
  }
  std::uint64_t seed = 0;
  {
    std::lock_guard lock(mutex_);
    seed = netSimSeed(spec, settings_.name);
  }
  // The simulator hands datagrams back on the strand; it does not keep the driver alive.
  std::weak_ptr<NetDriver> weak = weak_from_this();
  auto to_server = [weak](std::span<const std::uint8_t> d) {
    auto self = weak.lock();
    if (!self || self->closed_ || !self->connected_) return;
    boost::system::error_code ec;
    self->udp_.send(asio::buffer(d.data(), d.size()), 0, ec);
  };
  auto to_program = [weak](std::span<const std::uint8_t> d) {
    auto self = weak.lock();
    if (self && !self->closed_) self->deliverDatagram(d);
  };
  netsim_ =
      std::make_shared<NetSim>(strand_, spec, seed, std::move(to_server), std::move(to_program));
  spdlog::info("'{}': simulating the network: {}", settings_.name, describeNetSim(spec));
}

void NetDriver::armTimer() {
  timer_.expires_after(kTimerPeriod);
  timer_.async_wait([this, self = shared_from_this()](const boost::system::error_code& ec) {
    if (ec || closed_) return;
    {
      std::lock_guard lock(mutex_);
      const double now = monotonicSeconds();
      session_->update(now);
      noteLive(now);
    }
    flush();
    armTimer();
  });
}

}  // namespace vistel::net
