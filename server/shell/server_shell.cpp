#include "server/shell/server_shell.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <exception>
#include <map>

#if defined(__linux__)
#include <poll.h>
#include <sys/socket.h>
#include <sys/uio.h>
#endif

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "common/tls/tls_context.hpp"
#include "common/wire/framing.hpp"

namespace vistel::server {
namespace {

constexpr std::size_t kReadChunk = 16u << 10;

wire::Endpoint toWire(const asio::ip::udp::endpoint& e) {
  const asio::ip::address a = e.address();
  if (a.is_v4()) return wire::Endpoint::ipv4(a.to_v4().to_uint(), e.port());
  wire::Endpoint w;
  const auto bytes = a.to_v6().to_bytes();
  std::copy(bytes.begin(), bytes.end(), w.address.begin());
  w.port = e.port();
  return w;
}

asio::ip::udp::endpoint toAsio(const wire::Endpoint& w) {
  if (w.isIpv4()) return {asio::ip::address_v4(w.ipv4Address()), w.port};
  asio::ip::address_v6::bytes_type bytes;
  std::copy(w.address.begin(), w.address.end(), bytes.begin());
  return {asio::ip::address_v6(bytes), w.port};
}

// Runs f, logging instead of propagating any exception (the shell's last line of defence).
template <typename F>
void guarded(const char* where, F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    spdlog::error("{}: unexpected exception: {}", where, e.what());
  } catch (...) {
    spdlog::error("{}: unexpected exception", where);
  }
}

}  // namespace

struct ServerShell::TcpSession {
  TcpSession(tls::ControlStream s, ConnId c) : stream(std::move(s)), conn(c) {}
  tls::ControlStream stream;  // plain TCP, or TLS with [tls]
  bool handshaking = false;   // TLS handshake in progress: nothing is written yet
  ConnId conn;
  std::string address;    // the peer's IP address (ConnectionLimits key)
  bool released = false;  // given back to ConnectionLimits
  std::vector<std::uint8_t> read_buffer = std::vector<std::uint8_t>(kReadChunk);
  std::deque<std::vector<std::uint8_t>> queue;  // frames waiting to be written
  std::size_t queued_bytes = 0;
  bool writing = false;
  bool close_after_flush = false;
  bool closed = false;
};

struct ServerShell::RoomHost {
  RoomHost(asio::io_context& io, RoomId id, std::string name, const RoomSettings& settings,
           double now)
      : strand(asio::make_strand(io)), timer(strand), room(id, std::move(name), settings, now) {}
  Strand strand;
  asio::steady_timer timer;
  Room room;   // its strand only
  Effects fx;  // its strand only; reused so that ticks allocate nothing once warm
  bool closed = false;
  std::map<std::string, std::uint64_t, std::less<>> drops_seen;  // room.drops() counted so far
  VoiceForwardingStats voice_seen;                               // room.voiceStats() counted so far
  std::uint64_t timer_generation = 0;  // a wait that is not the newest does nothing
  double armed_for = 0.0;              // server time the newest wait ends
};

ServerShell::ServerShell(asio::io_context& io, const ServerConfig& config)
    : io_(io),
      config_(config),
      start_(std::chrono::steady_clock::now()),
      lobby_strand_(asio::make_strand(io)),
      acceptor_(lobby_strand_),
      lobby_timer_(lobby_strand_),
      stats_timer_(lobby_strand_),
      accept_timer_(lobby_strand_),
      limits_(config.max_connections, config.max_connections_per_address, config.limit_loopback),
      lobby_(config, 0),
      udp_(io),
      udp_buffer_(65536) {}

ServerShell::~ServerShell() = default;

double ServerShell::now() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

Status ServerShell::start() {
  boost::system::error_code ec;
  const auto address = asio::ip::make_address(config_.bind_address, ec);
  if (ec) return fail("bind address '{}': {}", config_.bind_address, ec.message());
  if (!config_.tls_cert_file.empty()) {
    auto context = tls::makeServerContext(config_.tls_cert_file, config_.tls_key_file);
    if (!context) return context.error();
    tls_context_ = std::move(*context);
  }

  // TCP first (port 0 picks one), then UDP on the same number; retry if that is taken.
  for (int attempt = 0; attempt < 20; ++attempt) {
    asio::ip::tcp::endpoint tcp_ep(address, config_.port);
    acceptor_.open(tcp_ep.protocol(), ec);
    if (!ec) acceptor_.set_option(asio::socket_base::reuse_address(true), ec);
    if (!ec) acceptor_.bind(tcp_ep, ec);
    if (!ec) acceptor_.listen(asio::socket_base::max_listen_connections, ec);
    if (ec) {
      return fail("cannot listen on TCP {}:{}: {}", config_.bind_address, config_.port,
                  ec.message());
    }
    port_ = acceptor_.local_endpoint().port();
    asio::ip::udp::endpoint udp_ep(address, port_);
    udp_.open(udp_ep.protocol(), ec);
    if (!ec) udp_.bind(udp_ep, ec);
    if (!ec) break;
    udp_.close();
    acceptor_.close();
    if (config_.port != 0) {
      return fail("cannot bind UDP {}:{}: {}", config_.bind_address, config_.port, ec.message());
    }
  }
  if (!udp_.is_open()) return fail("cannot find a port free for both TCP and UDP");

  asio::post(lobby_strand_, [this] { accept(); });
  {
    std::lock_guard lock(udp_mutex_);
    receiveDatagram();
  }
  // The lobby's own timer: join timeouts; and the load report.
  asio::post(lobby_strand_, [this] {
    armLobbyTimer();
    armStatsTimer();
  });
  return {};
}

std::string ServerShell::localAddress() const {
  return fmt::format("{}:{}", config_.bind_address, port_);
}

// ---------------------------------------------------------------- TCP (lobby strand)

void ServerShell::armLobbyTimer() {
  lobby_timer_.expires_after(std::chrono::milliseconds(250));
  lobby_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (ec || stopping_) return;
    guarded("lobby update", [&] {
      Effects fx;
      lobby_.update(now(), fx);
      applyLobbyEffects(fx);
    });
    armLobbyTimer();
  });
}

void ServerShell::armStatsTimer() {
  if (config_.stats_interval_s <= 0.0) return;
  stats_timer_.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(config_.stats_interval_s)));
  stats_timer_.async_wait([this](const boost::system::error_code& ec) {
    if (ec || stopping_) return;
    load_.setPopulation(lobby_.roomCount(), lobby_.memberCount());
    const std::string line = load_.report(now());
    if (lobby_.memberCount() > 0) {
      spdlog::info("{}", line);
    } else {
      spdlog::debug("{}", line);
    }
    armStatsTimer();
  });
}

void ServerShell::acceptFailed(const boost::system::error_code& ec) {
  // Out of file descriptors (EMFILE) and the like last a while: retrying at once only
  // spins. Wait, from 50 ms doubling to 1 s, and log at most every 5 s with a count.
  ++accept_failures_;
  const double t = now();
  if (t - accept_logged_at_ >= 5.0) {
    spdlog::warn("accept failed: {} ({} failures since the last report); retrying in {:.0f} ms",
                 ec.message(), accept_failures_, 1e3 * std::max(0.05, accept_backoff_s_));
    accept_logged_at_ = t;
    accept_failures_ = 0;
  }
  accept_backoff_s_ = std::clamp(accept_backoff_s_ * 2.0, 0.05, 1.0);
  accept_timer_.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(accept_backoff_s_)));
  accept_timer_.async_wait([this](const boost::system::error_code& wait_ec) {
    if (wait_ec || stopping_) return;
    accept();
  });
}

void ServerShell::accept() {
  acceptor_.async_accept(
      asio::make_strand(io_),
      asio::bind_executor(lobby_strand_, [this](const boost::system::error_code& ec,
                                                asio::ip::tcp::socket socket) {
        if (ec) {
          if (ec != asio::error::operation_aborted && !stopping_) acceptFailed(ec);
          return;
        }
        accept_backoff_s_ = 0.0;
        if (stopping_) return;
        // Admission: limits on connections in all and per source address.
        boost::system::error_code ignored;
        const auto peer = socket.remote_endpoint(ignored);
        const std::string address = ignored ? std::string("?") : peer.address().to_string();
        const bool loopback = !ignored && peer.address().is_loopback();
        if (const std::string_view refused = limits_.admit(address, loopback); !refused.empty()) {
          guarded("refuse", [&] { refuse(std::move(socket), address, refused); });
          accept();
          return;
        }
        socket.set_option(asio::ip::tcp::no_delay(true), ignored);
        auto session = std::make_shared<TcpSession>(
            tls_context_ ? tls::ControlStream(std::move(socket), *tls_context_)
                         : tls::ControlStream(std::move(socket)),
            next_conn_++);
        session->address = address;
        sessions_[session->conn] = session;
        guarded("connect", [&] {
          Effects fx;
          lobby_.onConnect(session->conn, now(), fx);
          // Loopback peers are not limited per address unless the config says so.
          lobby_.setConnectionAddress(session->conn,
                                      loopback && !config_.limit_loopback ? "" : address);
          applyLobbyEffects(fx);
        });
        if (session->stream.isTls()) {
          handshake(session);
        } else {
          read(session);
        }
        accept();
      }));
}

void ServerShell::handshake(std::shared_ptr<TcpSession> s) {
  s->handshaking = true;
  s->stream.asyncHandshake(
      asio::ssl::stream_base::server,
      asio::bind_executor(lobby_strand_, [this, s](const boost::system::error_code& ec) {
        s->handshaking = false;
        if (s->closed) return;
        if (ec) {
          // Not TLS (a plain client), a certificate the client refused, or a timeout
          // (logged at a bounded rate: a flood of plain connections cannot fill the log).
          refused_.drop(now(), "TLS handshake failed",
                        fmt::format("connection {} from {}: {}", s->conn, s->address,
                                    tls::describeTlsError(ec)));
          closeSession(*s);
          return;
        }
        read(s);
        write(s);
      }));
}

void ServerShell::refuse(asio::ip::tcp::socket socket, const std::string& address,
                         std::string_view reason) {
  refused_.drop(now(), reason,
                fmt::format("{} ({} open, {} from this address)", address, limits_.open(),
                            limits_.openFrom(address)));
  // One ErrorReply, written in the background, then the socket closes.
  control::ServerMessage msg;
  msg.mutable_error()->set_code(control::ErrorReply::SERVER_FULL);
  msg.mutable_error()->set_message(fmt::format("refused: {} reached", reason));
  msg.mutable_error()->set_retry_after_s(5.0f);
  const std::string payload = msg.SerializeAsString();
  auto frame = std::make_shared<std::vector<std::uint8_t>>();
  wire::appendFrame(
      std::span(reinterpret_cast<const std::uint8_t*>(payload.data()), payload.size()), *frame);
  auto held = std::make_shared<asio::ip::tcp::socket>(std::move(socket));
  asio::async_write(*held, asio::buffer(*frame),
                    [held, frame](const boost::system::error_code& /*ec*/, std::size_t /*n*/) {
                      boost::system::error_code ignored;
                      held->shutdown(asio::ip::tcp::socket::shutdown_both, ignored);
                      held->close(ignored);
                    });
}

void ServerShell::read(std::shared_ptr<TcpSession> s) {
  s->stream.asyncReadSome(
      asio::buffer(s->read_buffer),
      asio::bind_executor(
          lobby_strand_, [this, s](const boost::system::error_code& ec, std::size_t n) {
            if (s->closed) return;
            if (ec) {
              closeSession(*s);
              return;
            }
            Effects fx;
            guarded("control frame", [&] {
              lobby_.onStreamBytes(s->conn, std::span(s->read_buffer.data(), n), now(), fx);
            });
            applyLobbyEffects(fx);
            if (!s->closed && !s->close_after_flush) read(s);
          }));
}

void ServerShell::write(std::shared_ptr<TcpSession> s) {
  if (s->writing || s->closed) return;
  if (s->handshaking) {
    // Written after the handshake; a close meanwhile ends the handshake (its handler
    // forgets the session).
    if (s->close_after_flush) s->stream.close();
    return;
  }
  if (s->queue.empty()) {
    if (s->close_after_flush) {
      s->closed = true;
      s->stream.close();
      forget(*s);
      // Once stopping, the last closed connection ends the wait for stragglers.
      if (stopping_ && sessions_.empty()) lobby_timer_.cancel();
    }
    return;
  }
  s->writing = true;
  s->stream.asyncWrite(
      asio::buffer(s->queue.front()),
      asio::bind_executor(lobby_strand_,
                          [this, s](const boost::system::error_code& ec, std::size_t /*n*/) {
                            s->writing = false;
                            if (s->closed) return;
                            s->queued_bytes -= std::min(s->queued_bytes, s->queue.front().size());
                            queued_total_ -= std::min(queued_total_, s->queue.front().size());
                            s->queue.pop_front();
                            if (ec) {
                              closeSession(*s);
                              return;
                            }
                            write(s);
                          }));
}

void ServerShell::forget(TcpSession& s) {
  // The queue itself goes with the session (a write in flight still uses its front).
  queued_total_ -= std::min(queued_total_, s.queued_bytes);
  s.queued_bytes = 0;
  if (!s.released) limits_.release(s.address);
  s.released = true;
  sessions_.erase(s.conn);
}

void ServerShell::closeSession(TcpSession& s) {
  Effects fx;
  guarded("disconnect", [&] { lobby_.onDisconnect(s.conn, now(), fx); });
  s.closed = true;
  s.stream.close();
  forget(s);
  applyLobbyEffects(fx);
}

void ServerShell::dropSlowPeer(TcpSession& s, std::string_view limit) {
  spdlog::warn(
      "connection {}: peer is not reading ({} bytes queued, {} bytes in all; the {} "
      "limit): dropping it",
      s.conn, s.queued_bytes, queued_total_, limit);
  Effects drop_fx;
  lobby_.onDisconnect(s.conn, now(), drop_fx);
  // What is being written stays (its buffer is in use); the rest goes.
  while (s.queue.size() > (s.writing ? 1u : 0u)) {
    queued_total_ -= std::min(queued_total_, s.queue.back().size());
    s.queued_bytes -= std::min(s.queued_bytes, s.queue.back().size());
    s.queue.pop_back();
  }
  s.close_after_flush = true;
  applyLobbyEffects(drop_fx);
}

void ServerShell::applyLobbyEffects(Effects& fx) {
  // Frames and closes, in order, per connection.
  for (OutFrame& f : fx.frames) {
    auto it = sessions_.find(f.conn);
    if (it == sessions_.end()) continue;
    TcpSession& s = *it->second;
    s.queued_bytes += f.bytes.size();
    queued_total_ += f.bytes.size();
    s.queue.push_back(std::move(f.bytes));
    if (s.queued_bytes > config_.max_queued_bytes_per_connection && !s.close_after_flush) {
      dropSlowPeer(s, "per-connection");
    }
    // Past the server's total, the peer holding the most goes (it is not reading).
    while (queued_total_ > config_.max_queued_bytes_total) {
      TcpSession* largest = nullptr;
      for (auto& [conn, other] : sessions_) {
        if (!other->close_after_flush &&
            (largest == nullptr || other->queued_bytes > largest->queued_bytes)) {
          largest = other.get();
        }
      }
      if (largest == nullptr || largest->queued_bytes == 0) break;
      dropSlowPeer(*largest, "total");
    }
  }
  for (ConnId conn : fx.closes) {
    auto it = sessions_.find(conn);
    if (it != sessions_.end()) it->second->close_after_flush = true;
  }
  for (OutFrame& f : fx.frames) {
    auto it = sessions_.find(f.conn);
    if (it != sessions_.end()) write(it->second);
  }
  for (ConnId conn : fx.closes) {
    auto it = sessions_.find(conn);
    if (it != sessions_.end()) write(it->second);
  }
  sendDatagrams(fx.datagrams);
  load_.setPopulation(lobby_.roomCount(), lobby_.memberCount());

  // Room commands: create/close rooms, route, forward in order to each room's strand.
  for (RoomCommand& c : fx.room_commands) {
    std::shared_ptr<RoomHost> host;
    {
      std::lock_guard lock(rooms_mutex_);
      router_.apply(c);
      if (c.kind == RoomCommand::Kind::kCreate) {
        host = std::make_shared<RoomHost>(io_, c.room, c.name, roomSettings(config_), now());
        rooms_[c.room.value] = host;
        armRoomTimer(host);
        continue;
      }
      auto it = rooms_.find(c.room.value);
      if (it == rooms_.end()) continue;
      host = it->second;
      if (c.kind == RoomCommand::Kind::kClose) rooms_.erase(it);
    }
    if (c.kind == RoomCommand::Kind::kClose && room_closed_) {
      guarded("room closed", [&] { room_closed_(host->room.name()); });  // name is immutable
    }
    asio::post(host->strand, [this, host, c] {
      if (c.kind == RoomCommand::Kind::kClose) {
        host->closed = true;
        host->timer.cancel();
        return;
      }
      guarded("room command", [&] { host->room.apply(c, now()); });
    });
  }
  fx.clear();
}

// ---------------------------------------------------------------- rooms (room strands)

void ServerShell::armRoomTimer(std::shared_ptr<RoomHost> host) {
  asio::post(host->strand, [this, host] {
    if (host->closed || stopping_) return;
    // Until the room's next work (a tick, or a batch of postures to forward), at most
    // 0.1 s (timeouts); a newer wait replaces this one.
    const double t = now();
    const double wait = std::min(0.1, std::max(0.0, host->room.nextWakeTime() - t));
    const std::uint64_t generation = ++host->timer_generation;
    host->armed_for = t + wait;
    host->timer.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(wait)));
    host->timer.async_wait([this, host, generation](const boost::system::error_code& ec) {
      if (ec || host->closed || stopping_ || generation != host->timer_generation) return;
      guarded("room tick", [&] {
        const auto start = std::chrono::steady_clock::now();
        host->room.update(now(), host->fx);
        applyRoomEffects(host->fx);
        if (host->room.ticked()) {
          load_.addTick(
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
              host->room.memberCount());
        }
      });
      armRoomTimer(host);
    });
  });
}

void ServerShell::applyRoomEffects(Effects& fx) {
  sendDatagrams(fx.datagrams);
  if (!fx.timed_out.empty()) {
    asio::post(lobby_strand_, [this, members = fx.timed_out] {
      guarded("timeout", [&] {
        Effects lobby_fx;
        for (MemberId m : members) lobby_.onTimedOut(m, now(), lobby_fx);
        applyLobbyEffects(lobby_fx);
      });
    });
  }
  fx.clear();
}

// ---------------------------------------------------------------- UDP

void ServerShell::sendDatagrams(DatagramQueue& datagrams) {
  if (datagrams.empty()) return;
  std::lock_guard lock(udp_mutex_);
  if (!udp_.is_open()) return;
#if defined(__linux__)
  // Up to 64 datagrams a system call (a posture batch of a 100-member room is ~100).
  constexpr std::size_t kBatch = 64;
  std::array<mmsghdr, kBatch> messages{};
  std::array<iovec, kBatch> parts{};
  std::array<sockaddr_storage, kBatch> addresses{};
  const int fd = udp_.native_handle();
  std::size_t next = 0;
  bool waited = false;
  while (next < datagrams.size()) {
    const std::size_t count = std::min(kBatch, datagrams.size() - next);
    for (std::size_t k = 0; k < count; ++k) {
      OutDatagram& d = datagrams[next + k];
      const asio::ip::udp::endpoint to = toAsio(d.to);
      std::memcpy(&addresses[k], to.data(), to.size());
      parts[k] = {d.bytes.data(), d.bytes.size()};
      messages[k] = {};
      messages[k].msg_hdr.msg_name = &addresses[k];
      messages[k].msg_hdr.msg_namelen = static_cast<socklen_t>(to.size());
      messages[k].msg_hdr.msg_iov = &parts[k];
      messages[k].msg_hdr.msg_iovlen = 1;
    }
    const int sent = ::sendmmsg(fd, messages.data(), static_cast<unsigned>(count), 0);
    if (sent < 0) {
      if (errno == EINTR) continue;
      // A full send buffer (Asio keeps the socket non-blocking): wait a little for room,
      // as a blocking send would, then try again.
      if ((errno == EAGAIN || errno == EWOULDBLOCK) && !waited) {
        pollfd writable{fd, POLLOUT, 0};
        waited = true;
        if (::poll(&writable, 1, 5) > 0) continue;
      }
      waited = false;
      // The first datagram of the batch failed (a full buffer, an unreachable address):
      // count it and go on with the rest.
      load_.addSendFailure();
      spdlog::debug("send to {} failed: {}", datagrams[next].to.toString(), std::strerror(errno));
      ++next;
      continue;
    }
    waited = false;
    for (int k = 0; k < sent; ++k)
      load_.addSent(datagrams[next + static_cast<std::size_t>(k)].bytes.size());
    next += static_cast<std::size_t>(sent);
  }
#else
  for (const OutDatagram& d : datagrams) {
    boost::system::error_code ec;
    udp_.send_to(asio::buffer(d.bytes), toAsio(d.to), 0, ec);
    if (ec) {
      load_.addSendFailure();
      spdlog::debug("send to {} failed: {}", d.to.toString(), ec.message());
    } else {
      load_.addSent(d.bytes.size());
    }
  }
#endif
  datagrams.clear();
}

// Called with udp_mutex_ held.
void ServerShell::receiveDatagram() {
  udp_.async_receive_from(asio::buffer(udp_buffer_), udp_sender_,
                          [this](const boost::system::error_code& ec, std::size_t n) {
                            if (ec == asio::error::operation_aborted || stopping_) return;
                            if (!ec) {
                              load_.addReceived(n);
                              auto bytes = std::make_shared<std::vector<std::uint8_t>>(
                                  udp_buffer_.begin(), udp_buffer_.begin() + n);
                              guarded("datagram",
                                      [&] { onDatagram(std::move(bytes), toWire(udp_sender_)); });
                            }
                            std::lock_guard lock(udp_mutex_);
                            if (udp_.is_open()) receiveDatagram();
                          });
}

void ServerShell::onDatagram(std::shared_ptr<std::vector<std::uint8_t>> bytes,
                             wire::Endpoint from) {
  // Route by type and member id; the room or the lobby validates everything else.
  std::shared_ptr<RoomHost> host;
  DatagramRoute route;
  {
    std::lock_guard lock(rooms_mutex_);
    route = routeDatagram(*bytes, router_);
    if (route.target == DatagramRoute::Target::kRoom) {
      auto it = rooms_.find(route.room.value);
      if (it != rooms_.end()) host = it->second;
    }
  }
  switch (route.target) {
    case DatagramRoute::Target::kLobby:
      asio::post(lobby_strand_, [this, bytes, from] {
        guarded("hello", [&] {
          Effects fx;
          if (lobby_.drops().total() != lobby_drops_total_) syncLobbyDrops(false);
          lobby_.onHello(*bytes, from, now(), fx);
          if (lobby_.drops().total() != lobby_drops_total_) syncLobbyDrops(true);
          applyLobbyEffects(fx);
        });
      });
      break;
    case DatagramRoute::Target::kRoom:
      if (!host) break;
      asio::post(host->strand, [this, host, bytes, from] {
        if (host->closed) return;
        guarded("room datagram", [&] {
          const std::uint64_t dropped = host->room.drops().total();
          host->room.onDatagram(*bytes, from, now(), host->fx);
          if (host->room.drops().total() != dropped) countRoomDrops(*host);
          if (host->room.voiceStats().frames != host->voice_seen.frames) countRoomVoice(*host);
          applyRoomEffects(host->fx);
        });
        // A posture left waiting for its batch: wake up for it.
        if (host->room.nextWakeTime() < host->armed_for - 1e-4) {
          host->armed_for = host->room.nextWakeTime();  // one re-arm per batch
          armRoomTimer(host);
        }
      });
      break;
    case DatagramRoute::Target::kDrop:
      spdlog::debug("dropped datagram: {} ({} bytes from {})", route.reason, bytes->size(),
                    from.toString());
      countDrop(route.reason);
      break;
  }
}

void ServerShell::countDrop(std::string_view reason) {
  if (auto line = load_.addDatagramDrop(reason, now())) spdlog::info("{}", *line);
}

void ServerShell::syncLobbyDrops(bool hello) {
  for (const auto& [reason, count] : lobby_.drops().counts()) {
    auto it = lobby_drops_seen_.find(reason);
    if (it == lobby_drops_seen_.end()) it = lobby_drops_seen_.emplace(reason, 0).first;
    if (hello && it->second < count) {
      for (std::uint64_t k = it->second; k < count; ++k) countDrop(reason);
      hello_drops_[reason] += count - it->second;
    }
    it->second = count;
  }
  lobby_drops_total_ = lobby_.drops().total();
}

void ServerShell::countRoomVoice(RoomHost& host) {
  const VoiceForwardingStats& now_seen = host.room.voiceStats();
  VoiceForwardingStats& was = host.voice_seen;
  voice_frames_ += now_seen.frames - was.frames;
  voice_forwarded_ += now_seen.forwarded - was.forwarded;
  voice_out_of_range_ += now_seen.out_of_range - was.out_of_range;
  voice_not_selected_ += now_seen.not_selected - was.not_selected;
  was = now_seen;
}

void ServerShell::countRoomDrops(RoomHost& host) {
  // The reasons whose counts grew since the last look (a handful of entries).
  for (const auto& [reason, count] : host.room.drops().counts()) {
    auto it = host.drops_seen.find(reason);
    if (it == host.drops_seen.end()) it = host.drops_seen.emplace(reason, 0).first;
    for (; it->second < count; ++it->second) countDrop(reason);
  }
}

// ---------------------------------------------------------------- metrics

void ServerShell::collectMetrics(std::function<void(std::string)> reply, bool ready) {
  asio::post(lobby_strand_, [this, reply = std::move(reply), ready] {
    MetricsSnapshot s;
    s.members = static_cast<std::uint64_t>(lobby_.memberCount());
    s.rooms = static_cast<std::uint64_t>(lobby_.roomCount());
    s.connections = static_cast<std::uint64_t>(lobby_.connectionCount());
    s.uploads_in_progress = static_cast<std::uint64_t>(lobby_.uploadsInProgress());
    s.ready = ready && !stopping_;
    s.joins_total = lobby_.joinsAccepted();
    s.uptime_seconds = now();
    load_.fillMetrics(s);
    // The lobby's drops name refused joins and dropped connections alike ...
    for (const auto& [reason, count] : lobby_.drops().counts()) {
      auto hello = hello_drops_.find(reason);
      const std::uint64_t datagrams = hello == hello_drops_.end() ? 0 : hello->second;
      if (count > datagrams) s.connections_dropped[reason] = count - datagrams;
    }
    // ... of which refused joins have their own family.
    for (const auto& [reason, count] : lobby_.joinsRefused()) {
      s.joins_refused[reason] = count;
      auto it = s.connections_dropped.find(reason);
      if (it == s.connections_dropped.end()) continue;
      it->second -= std::min(it->second, count);
      if (it->second == 0) s.connections_dropped.erase(it);
    }
    // ... and the connections refused at accept.
    for (const auto& [reason, count] : limits_.refusals()) s.connections_dropped[reason] = count;
    // Voice (refused frames are in vistel_datagrams_dropped_total: "voice rate limit", ...).
    auto counter = [&](std::string name, std::string help, MetricLabels labels, double value) {
      MetricFamily& f = s.extra.emplace_back();
      f.name = std::move(name);
      f.help = std::move(help);
      f.type = MetricType::kCounter;
      f.samples.push_back({std::move(labels), value, {}});
      return &f;
    };
    counter("vistel_voice_frames_total", "Voice frames admitted for forwarding, all rooms", {},
            static_cast<double>(voice_frames_.load()));
    counter("vistel_voice_forwarded_total",
            "Voice frame copies forwarded (one per frame and listener)", {},
            static_cast<double>(voice_forwarded_.load()));
    MetricFamily* skipped = counter(
        "vistel_voice_skipped_total",
        "Voice (frame, listener) pairs not forwarded: beyond the hearing radius, or the speaker "
        "not among the listener's max_speakers",
        {{"reason", "out_of_range"}}, static_cast<double>(voice_out_of_range_.load()));
    skipped->samples.push_back(
        {{{"reason", "not_selected"}}, static_cast<double>(voice_not_selected_.load()), {}});
    reply(formatMetrics(s));
  });
}

// ---------------------------------------------------------------- spectators (server/web)

void ServerShell::roomViews(std::function<void(std::vector<LobbyRoomView>, double)> reply) {
  asio::post(lobby_strand_, [this, reply = std::move(reply)] {
    guarded("room views", [&] { reply(lobby_.roomViews(), now()); });
  });
}

void ServerShell::spectate(std::string room,
                           std::function<void(std::optional<SpectatorFrame>)> reply) {
  asio::post(lobby_strand_, [this, room = std::move(room), reply = std::move(reply)]() mutable {
    std::optional<LobbyRoomView> view;
    guarded("spectate", [&] { view = lobby_.roomView(room); });
    std::shared_ptr<RoomHost> host;
    if (view && !stopping_) {
      std::lock_guard lock(rooms_mutex_);
      auto it = rooms_.find(view->id);
      if (it != rooms_.end()) host = it->second;
    }
    if (!host) {
      guarded("spectate reply", [&] { reply(std::nullopt); });
      return;
    }
    asio::post(host->strand, [this, host, view = std::move(*view), reply = std::move(reply)] {
      guarded("spectate room", [&] {
        if (host->closed) {
          reply(std::nullopt);
          return;
        }
        SpectatorFrame frame;
        frame.now = now();
        frame.room = std::move(view);
        host->room.forEachPosture([&](std::uint32_t member, std::span<const std::uint8_t> bytes) {
          frame.postures.push_back({member, {bytes.begin(), bytes.end()}});
        });
        for (const WorldBody& body : host->room.world().bodies()) {
          if (!body.is_prop) continue;
          if (const BallState* ball = host->room.world().propState(PropId{body.id})) {
            frame.props.push_back({body.id, ball->position, ball->velocity, ball->radius});
          }
        }
        reply(std::move(frame));
      });
    });
  });
}

void ServerShell::avatarFile(
    std::string hash, std::function<void(std::shared_ptr<const std::vector<std::uint8_t>>)> reply) {
  asio::post(lobby_strand_, [this, hash = std::move(hash), reply = std::move(reply)] {
    guarded("avatar file", [&] {
      const StoredAvatar* stored = lobby_.avatars().find(hash);
      reply(stored != nullptr ? stored->bytes : nullptr);
    });
  });
}

// ---------------------------------------------------------------- shutdown

void ServerShell::stop() {
  asio::post(lobby_strand_, [this] {
    if (stopping_.exchange(true)) return;
    spdlog::info("shutting down: closing {} connections and {} rooms", sessions_.size(),
                 rooms_.size());
    boost::system::error_code ignored;
    acceptor_.close(ignored);
    lobby_timer_.cancel();
    stats_timer_.cancel();
    accept_timer_.cancel();
    // Tell everyone, then close (each session closes after its last write).
    Effects fx;
    guarded("shutdown", [&] { lobby_.shutdown(now(), fx); });
    applyLobbyEffects(fx);
    {
      std::lock_guard lock(udp_mutex_);
      udp_.close(ignored);
    }
    std::vector<std::shared_ptr<RoomHost>> hosts;
    {
      std::lock_guard lock(rooms_mutex_);
      for (auto& [id, host] : rooms_) hosts.push_back(host);
      rooms_.clear();
    }
    for (auto& host : hosts) {
      asio::post(host->strand, [host] {
        host->closed = true;
        host->timer.cancel();
      });
    }
    // A peer that never reads must not hold the process: force-close after 2 s.
    lobby_timer_.expires_after(std::chrono::seconds(2));
    lobby_timer_.async_wait([this](const boost::system::error_code& ec) {
      if (ec) return;
      for (auto& [conn, s] : sessions_) {
        s->closed = true;
        s->stream.close();
      }
      sessions_.clear();
    });
    if (sessions_.empty()) lobby_timer_.cancel();
  });
}

}  // namespace vistel::server
