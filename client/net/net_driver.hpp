// Runs a ClientSession over real sockets (the client's and the bot's network side,
// DESIGN.md §6 "Threads": Asio runs on a network thread). One TCP connection for
// control, one UDP socket connected to the server's address and the same port (the
// kernel then delivers only the server's datagrams). Every socket operation runs on the
// driver's strand; the public calls are thread-safe (a mutex guards the session), so a
// source thread can send postures and the render thread can sample remote ones while
// the network thread runs.
//
// A join the server refuses for a transient reason (ClientSession::retryAfter() > 0:
// SERVER_FULL, a timed-out upload, no Welcome in time) is tried again on a new
// connection after a JoinBackoff delay, with the same settings; the first refusal's
// reason is logged at warn, later ones at debug. Meanwhile state() is kJoining. After
// BackoffSettings::max_attempts refusals in a row the session stays closed.
#pragma once

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "client/net/asio.hpp"
#include "client/net/client_session.hpp"
#include "client/net/join_backoff.hpp"

namespace vistel::net {

// "host:port" (host a name, an IPv4 address or a bracketed IPv6 address). The error
// names the text.
struct ServerAddress {
  std::string host;
  std::uint16_t port = 0;
};
Result<ServerAddress> parseServerAddress(const std::string& text);

// Seconds on the steady clock since the first call in this process (the time base the
// drivers feed their sessions).
double monotonicSeconds();

class NetDriver : public std::enable_shared_from_this<NetDriver> {
 public:
  // io is not owned and may be shared by many drivers (bots); run it on any threads.
  static std::shared_ptr<NetDriver> create(asio::io_context& io, ServerAddress server,
                                           SessionSettings settings,
                                           std::shared_ptr<AvatarCache> cache,
                                           const BackoffSettings& backoff = {});
  ~NetDriver();

  // Resolves, connects, joins (asynchronously). Then the session runs by itself.
  void start();
  // Sends Leave and closes once it is written; the io_context then has no more work
  // from this driver.
  void stop(const std::string& reason);

  // Thread-safe calls.
  bool sendPosture(const Posture& posture);
  // ClientSession::requestBall (a ball above our head; the server rate-limits).
  bool requestBall();
  SessionState state() const;
  std::string error() const;
  // Runs f(session, now) under the session lock (keep it short: the network waits).
  template <typename F>
  auto withSession(F&& f) const {
    std::lock_guard lock(mutex_);
    return f(static_cast<const ClientSession&>(*session_), monotonicSeconds());
  }
  // Joins refused and tried again so far, and the seconds from start() to the first
  // kLive (negative until then).
  int rejoins() const;
  double secondsToLive() const;

 private:
  NetDriver(asio::io_context& io, ServerAddress server, SessionSettings settings,
            std::shared_ptr<AvatarCache> cache, const BackoffSettings& backoff);
  // Resolves and connects (strand), then starts the session.
  void connect();
  // The session closed: another join after a backoff when the refusal was transient.
  void maybeRejoin();
  // Under the lock: takes the session's outbox; then (strand) writes it out.
  void flush();
  void writeStream();
  void readStream();
  void readDatagram();
  void armTimer();
  void fail(const std::string& reason);
  void closeSockets();

  asio::io_context& io_;
  asio::strand<asio::io_context::executor_type> strand_;
  ServerAddress server_;
  asio::ip::tcp::resolver resolver_;
  asio::ip::tcp::socket tcp_;
  asio::ip::udp::socket udp_;
  asio::steady_timer timer_;

  mutable std::mutex mutex_;  // session_, rejoins_, live_after_s_
  SessionSettings settings_;
  std::shared_ptr<AvatarCache> cache_;
  std::unique_ptr<ClientSession> session_;
  int rejoins_ = 0;
  double started_at_ = 0.0;
  double live_after_s_ = -1.0;

  // Strand only.
  std::deque<std::vector<std::uint8_t>> write_queue_;
  bool writing_ = false;
  bool close_after_write_ = false;
  bool closed_ = false;
  bool connected_ = false;
  bool stopping_ = false;
  JoinBackoff backoff_;
  asio::steady_timer retry_timer_;
  std::vector<std::uint8_t> read_buffer_;
  std::vector<std::uint8_t> datagram_buffer_;
};

}  // namespace vistel::net
