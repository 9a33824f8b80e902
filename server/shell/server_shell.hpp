// The thin Asio shell around the session server's protocol core (STYLE.md: sockets,
// timers and strands live only at the edge). TCP connections and the lobby run on one
// strand; each room runs on its own strand with its own tick timer, so rooms spread
// over the I/O threads. One UDP socket (same port as TCP) serves every room: incoming
// datagrams are routed by member id to their room's strand.
//
// Every handler catches exceptions at its top: one bad peer cannot take the server down.
//
// Load: every room tick's work (world step and sends) is timed into LoadStats, with the
// datagrams and bytes moved; every [session] stats_interval_s the lobby strand logs a
// line of it (rooms, members, tick p50/p99, CPU per member-tick).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "common/base/result.hpp"
#include "common/tls/control_stream.hpp"
#include "server/core/lobby.hpp"
#include "server/core/room.hpp"
#include "server/core/server_core.hpp"
#include "server/shell/asio.hpp"
#include "server/shell/connection_limits.hpp"
#include "server/shell/load_stats.hpp"

namespace vistel::server {

// Spectators (server/web): one sample of a room.
struct SpectatorProp {
  std::uint32_t id = 0;
  glm::vec3 position{0.0f};  // room space, metres
  glm::vec3 velocity{0.0f};  // m/s
  float radius = 0.1f;       // m
};
struct SpectatorPosture {
  std::uint32_t member = 0;
  std::vector<std::uint8_t> record;  // the newest accepted posture, WIRE.md §3.3 bytes
};
struct SpectatorFrame {
  double now = 0.0;  // server clock (seconds since start; the postures' clock)
  LobbyRoomView room;
  std::vector<SpectatorPosture> postures;
  std::vector<SpectatorProp> props;  // as of the room's last tick
};

class ServerShell {
 public:
  ServerShell(asio::io_context& io, const ServerConfig& config);
  ~ServerShell();

  // Binds the TCP acceptor and the UDP socket to config.bind_address:config.port (port
  // 0: a free port, the same number for both) and starts accepting. The error names the
  // address and the OS reason.
  Status start();
  // "ADDRESS:PORT" actually bound (after start()).
  std::string localAddress() const;
  // The load since the start, as JSON (LoadStats::totalsJson).
  std::string loadJson() const { return load_.totalsJson(now()); }
  // One /metrics scrape: gathered on the lobby strand, then reply(text) (any thread).
  // `ready` is what /readyz says.
  void collectMetrics(std::function<void(std::string)> reply, bool ready);
  // Called on the lobby strand with a room's name when it closes (the last member left);
  // set before the io_context runs.
  void onRoomClosed(std::function<void(const std::string&)> handler) {
    room_closed_ = std::move(handler);
  }
  std::uint16_t localPort() const { return port_; }

  // Spectators (server/web). Each reply runs once, on a strand of the shell (keep it
  // short). The open rooms, sampled on the lobby strand:
  void roomViews(std::function<void(std::vector<LobbyRoomView>, double now)> reply);
  // A room by name: the lobby's view, then its postures and props from its strand;
  // nullopt when no such room is open (or the server is stopping).
  void spectate(std::string room, std::function<void(std::optional<SpectatorFrame>)> reply);
  // The .vavatar bytes of an avatar some member uses (null when the server has none).
  void avatarFile(std::string hash,
                  std::function<void(std::shared_ptr<const std::vector<std::uint8_t>>)> reply);

  // Graceful stop: every connection gets a shutting-down error, sockets and timers
  // close, and io.run() returns once the last writes are flushed (at most ~2 s).
  void stop();

 private:
  struct TcpSession;
  struct RoomHost;
  using Strand = asio::strand<asio::io_context::executor_type>;

  double now() const;
  void armLobbyTimer();
  // Takes a closed session out of the map and its queued bytes out of the total.
  void forget(TcpSession& s);
  // A peer whose queue passed a limit ("per-connection" or "total"): its member is
  // removed, what it has queued dropped (but a write in flight), the connection closed.
  void dropSlowPeer(TcpSession& s, std::string_view limit);
  // The peer is gone (a read, write or handshake failed): the lobby forgets it, its stream
  // closes, and what that causes is applied.
  void closeSession(TcpSession& s);
  void armStatsTimer();
  void accept();
  // A connection refused at accept (ConnectionLimits): one ErrorReply SERVER_FULL saying
  // why, then closed; logged at a bounded rate.
  void refuse(asio::ip::tcp::socket socket, const std::string& address, std::string_view reason);
  // After a failed accept: retry after a growing wait, logging at a bounded rate.
  void acceptFailed(const boost::system::error_code& ec);
  void read(std::shared_ptr<TcpSession> s);
  // TLS ([tls] in the config): the server side of the handshake, then read().
  void handshake(std::shared_ptr<TcpSession> s);
  void write(std::shared_ptr<TcpSession> s);
  void receiveDatagram();
  void onDatagram(std::shared_ptr<std::vector<std::uint8_t>> bytes, wire::Endpoint from);
  // A datagram dropped for `reason`: counted in load_, summarised at info now and then.
  void countDrop(std::string_view reason);
  // Brings lobby_drops_seen_ up to the lobby's counts; with `hello`, what grew was dropped
  // while handling a hello datagram: counted as datagram drops (lobby strand).
  void syncLobbyDrops(bool hello);
  // Adds what a room's voice forwarding did since the last look to the totals (room strand).
  void countRoomVoice(RoomHost& host);
  // Counts what a room's last datagram made it drop (room strand).
  void countRoomDrops(RoomHost& host);
  // Carries out what a core asked for. Lobby effects run on the lobby strand; room
  // effects on the room's strand (their timeouts are posted to the lobby strand).
  void applyLobbyEffects(Effects& fx);
  void applyRoomEffects(Effects& fx);
  void sendDatagrams(DatagramQueue& datagrams);
  void armRoomTimer(std::shared_ptr<RoomHost> host);

  asio::io_context& io_;
  ServerConfig config_;
  std::chrono::steady_clock::time_point start_;
  Strand lobby_strand_;
  asio::ip::tcp::acceptor acceptor_;
  std::unique_ptr<asio::ssl::context> tls_context_;  // set by start() with [tls]
  asio::steady_timer lobby_timer_;
  asio::steady_timer stats_timer_;
  asio::steady_timer accept_timer_;
  double accept_backoff_s_ = 0.0;      // lobby strand: the current wait after failures
  double accept_logged_at_ = -1e300;   // ... the last report
  std::uint64_t accept_failures_ = 0;  // ... failures since it
  LoadStats load_;
  ConnectionLimits limits_;    // lobby strand only
  DropLog refused_{"accept"};  // lobby strand: refusals at accept (logged, bounded)
  // Lobby strand: the lobby's drop counts as last seen, and those that were hellos (the
  // rest are refused or dropped connections).
  std::map<std::string, std::uint64_t, std::less<>> lobby_drops_seen_;
  std::map<std::string, std::uint64_t, std::less<>> hello_drops_;
  std::uint64_t lobby_drops_total_ = 0;
  Lobby lobby_;                                                       // lobby strand only
  std::unordered_map<ConnId, std::shared_ptr<TcpSession>> sessions_;  // lobby strand only
  ConnId next_conn_ = 1;
  std::size_t queued_total_ = 0;  // lobby strand: bytes queued on every connection

  std::mutex udp_mutex_;  // every operation on udp_
  asio::ip::udp::socket udp_;
  std::vector<std::uint8_t> udp_buffer_;
  asio::ip::udp::endpoint udp_sender_;

  mutable std::mutex rooms_mutex_;  // router_ and rooms_
  RoomRouter router_;
  std::unordered_map<std::uint32_t, std::shared_ptr<RoomHost>> rooms_;

  // Voice forwarding, all rooms (room strands add, the metrics read): frames admitted,
  // copies forwarded, (frame, listener) pairs skipped out of range or not selected.
  std::atomic<std::uint64_t> voice_frames_{0};
  std::atomic<std::uint64_t> voice_forwarded_{0};
  std::atomic<std::uint64_t> voice_out_of_range_{0};
  std::atomic<std::uint64_t> voice_not_selected_{0};

  std::function<void(const std::string&)> room_closed_;
  std::uint16_t port_ = 0;
  std::atomic<bool> stopping_{false};
};

}  // namespace vistel::server
