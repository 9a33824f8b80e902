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
//
// Reconnecting: once a session has been live, losing it (the connection drops, the
// server shuts down or restarts, it goes silent, it drops us) is not the end: the driver
// joins again on a new connection after a jittered, growing delay (JoinBackoff from
// base_s, windows up to max_s, no attempt limit) with the same room, name and avatar,
// resuming the lost member (Join.resume_*: the server replaces our stale member rather
// than refusing the name), and logs "reconnecting in 1.3 s (attempt 3)" and "rejoined room
// R as N". A refused join meanwhile is retried too when it may clear (busy, name or room
// taken by our stale member). Refusals for good (protocol version, bad name, avatar
// rejected) end it at once, and so does SessionSettings::reconnect_give_up_s passing
// since the loss; then state() is kClosed and error() says why. Until then state() is
// never kClosed. The session's stats carry over (reconnects counted there too).
//
// NAT rebinding is the session's business (ClientSession re-says hello when the
// server's datagrams stop); reopenDatagramSocket() makes one happen on purpose.
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
#include "client/net/net_sim.hpp"
#include "common/tls/tls_context.hpp"

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
                                           const BackoffSettings& backoff = {},
                                           const tls::ClientTlsSettings& tls = {});
  ~NetDriver();

  // Resolves, connects, joins (asynchronously). Then the session runs by itself.
  void start();
  // Sends Leave and closes once it is written; the io_context then has no more work
  // from this driver.
  void stop(const std::string& reason);

  // Thread-safe calls.
  bool sendPosture(const Posture& posture);
  // One voice frame (ClientSession::sendVoice); and the frames received since the last
  // call, appended to out (with the voice counters, when counters is not null).
  bool sendVoice(const OutgoingVoice& frame);
  void takeVoice(std::vector<ReceivedVoice>& out, VoiceCounters* counters = nullptr);
  // ClientSession::requestBall (a ball above our head; the server rate-limits).
  bool requestBall();
  // ClientSession::sendDents; and the dents received since the last call (the newest per
  // body), swapped into out (whose old contents are dropped).
  bool sendDents(const BodyDents& dents);
  void takeDents(std::vector<BodyDents>& out);
  SessionState state() const;
  std::string error() const;
  // Why the last session closed (a refusal's text, a lost connection), kept across the
  // fresh sessions of retries and reconnects; empty when none has closed.
  std::string lastCloseReason() const;
  // Runs f(session, now) under the session lock (keep it short: the network waits).
  template <typename F>
  auto withSession(F&& f) const {
    std::lock_guard lock(mutex_);
    return f(static_cast<const ClientSession&>(*session_), monotonicSeconds());
  }
  // Joins tried again so far (after a refusal or a lost session), the lost sessions
  // resumed (live again), and the seconds from start() to the first kLive (negative until
  // then).
  int rejoins() const;
  int reconnects() const;
  double secondsToLive() const;

  // Replaces the UDP socket with a fresh one (a new local port) toward the same server
  // address: to the server this is a NAT rebinding. For tests and for a known change of
  // the local network. Nothing happens when not connected.
  void reopenDatagramSocket();

  // Puts a network simulator (net_sim.hpp) between this driver's UDP socket and the
  // session, both ways as the spec says; its seed mixes in the participant's name. Call
  // before start(). An inactive spec removes it.
  void setNetSim(const NetSimSpec& spec);

 private:
  NetDriver(asio::io_context& io, ServerAddress server, SessionSettings settings,
            std::shared_ptr<AvatarCache> cache, const BackoffSettings& backoff,
            const tls::ClientTlsSettings& tls);
  // Resolves and connects (strand), then starts the session.
  void connect();
  // The TCP connection is up (strand): UDP opened toward the same endpoint, session started.
  void onConnected(const asio::ip::tcp::endpoint& endpoint);
  // The session closed: another join after a backoff when the refusal was transient or
  // a live session was lost (and the give-up time has not passed); else the end.
  void maybeRejoin();
  // Under the lock, each timer tick: notes the first kLive and a resumed one.
  void noteLive(double now);
  // Under the lock: takes the session's outbox; then (strand) writes it out.
  void flush();
  void writeStream();
  void readStream();
  void readDatagram();
  // A datagram from the server (strand): to the session (from the socket or the simulator).
  void deliverDatagram(std::span<const std::uint8_t> datagram);
  void armTimer();
  void fail(const std::string& reason);
  void closeSockets();

  asio::io_context& io_;
  asio::strand<asio::io_context::executor_type> strand_;
  ServerAddress server_;
  asio::ip::tcp::resolver resolver_;
  tls::ControlStream tcp_;  // the control connection: plain TCP, or TLS (server_.tls)
  asio::ip::udp::socket udp_;
  asio::steady_timer timer_;

  mutable std::mutex mutex_;  // the fields down to retry_timer_
  SessionSettings settings_;
  std::shared_ptr<AvatarCache> cache_;
  std::unique_ptr<ClientSession> session_;
  int rejoins_ = 0;
  int reconnects_ = 0;
  double started_at_ = 0.0;
  double live_after_s_ = -1.0;
  bool ever_live_ = false;              // some session of this driver reached kLive
  bool session_live_ = false;           // the current one has (noted)
  double lost_at_ = -1.0;               // when the live session was lost (< 0: not reconnecting)
  bool ended_ = false;                  // closed for good: state() reports kClosed
  std::uint32_t resume_member_id_ = 0;  // the newest Welcome's id
  std::string last_close_reason_;       // see lastCloseReason()
  wire::ResumeSecret resume_secret_{};  // that session's resume secret (WIRE.md §3.9)

  // Strand only.
  std::deque<std::vector<std::uint8_t>> write_queue_;
  bool writing_ = false;
  bool close_after_write_ = false;
  bool closed_ = false;
  bool connected_ = false;
  bool stopping_ = false;
  JoinBackoff backoff_;
  JoinBackoff reconnect_backoff_;
  asio::steady_timer retry_timer_;
  asio::ip::udp::endpoint udp_server_;  // where the UDP socket is connected
  std::uint64_t udp_generation_ = 0;    // bumped per UDP socket (stale reads stop)
  std::vector<std::uint8_t> read_buffer_;
  std::vector<std::uint8_t> datagram_buffer_;
  std::shared_ptr<NetSim> netsim_;  // null: no simulation (setNetSim)
  // TLS (strand only): the context (or why there is none), this connection's handshake.
  tls::ClientTlsSettings tls_;  // the control channel over TLS (--tls, --tls-ca, --tls-pin)
  std::unique_ptr<asio::ssl::context> tls_context_;
  std::string tls_error_;
  bool tls_handshaken_ = false;
  bool stream_answered_ = false;  // any control bytes from the server on this connection
  std::shared_ptr<std::string> tls_note_ = std::make_shared<std::string>();
};

}  // namespace vistel::net
