// The spectator web server: HTTP/1.1 and WebSocket (Boost.Beast) on its own TCP port, in
// the session server's io_context (web_request.hpp lists the paths).
//
// - The room list (HTML, JSON) and each room's spectator page (web/spectator.*), three.js
//   and the page's scripts, all embedded in the binary (web_assets.hpp).
// - Avatars as skinned .glb by content hash (avatar_glb.hpp), converted from the
//   server's .vavatar once and cached (at most kGlbCacheEntries).
// - /ws/room/NAME: a WebSocket per spectator. One feed per watched room samples it
//   (ServerShell::spectate) at the room's tick rate (at most [web] max_stream_rate_hz)
//   and sends every spectator of the room the same messages (spectator_stream.hpp): the
//   roster when it changes, the room's state when it changes, and a binary frame per
//   sample. A spectator that falls behind skips frames (only the newest waits); one more
//   than max_ws_queue_bytes behind is dropped. With join tokens (a join secret), a
//   WebSocket needs ?token=T, a valid token for that room (any name): otherwise it gets
//   a status "unauthorized" and is closed (1008, policy violation). An upgrade from a page
//   of another site (an Origin header other than this server's) is refused with 403.
//
// Host names (DNS-rebinding defence): a request whose Host is not an IP address,
// localhost or one of [web] allowed_hosts gets 421 before anything else (hostAllowed).
//
// Visible spectators (--web-members, web_member.hpp): a page may ask to join its room as a
// member; the server then joins the room for it as a client of its own session server
// (NetDriver over loopback) with the camera-headed avatar, and sends the page's camera as
// that member's posture [web] member_pose_rate_hz times a second until the page leaves or
// its socket closes.
//
// Bounds (WebConfig): connections in all and per address, requests per second per
// address (429 beyond), a request head within max_header_bytes (431) and
// read_timeout_s, kept-alive connections idle_timeout_s, writes write_timeout_s,
// spectators per room (503 beyond), WebSocket messages from the browser at most 1 KiB
// and 20 a second (more closes the socket). Only GET.
//
// Threads: every connection and feed has its own strand; the shared tables a mutex.
// stop() closes everything so that io.run() can return; destroy the server after.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/base/result.hpp"
#include "common/scene/seat_layout.hpp"
#include "server/http/prometheus.hpp"
#include "server/shell/asio.hpp"
#include "server/shell/server_shell.hpp"
#include "server/web/web_config.hpp"

namespace vistel::server {

struct WebServerOptions {
  WebConfig config;
  std::string bind_address = "127.0.0.1";
  SeatLayout seat_layout;                 // the server's ([room]): where members stand
  double tick_rate_hz = 60.0;             // the rooms' rate
  std::vector<std::uint8_t> join_secret;  // non-empty: WebSockets need a token
  // Visible spectators (config.members): they join the session server at
  // bind_address (the loopback address for a wildcard one) and this port, over TLS
  // pinned to this certificate when it is set.
  std::uint16_t session_port = 0;
  std::string tls_cert_file;
};

class WebServer {
 public:
  static constexpr std::size_t kGlbCacheEntries = 32;

  struct Stats {
    std::uint64_t requests = 0;        // request heads answered
    std::uint64_t errors = 0;          // ... with a 4xx or 5xx status
    std::uint64_t refused = 0;         // connections closed at accept (limits)
    std::uint64_t rate_limited = 0;    // requests answered 429
    std::uint64_t timed_out = 0;       // connections closed by a read or write deadline
    std::uint64_t spectators = 0;      // WebSockets accepted
    std::uint64_t unauthorized = 0;    // WebSockets refused for their token
    std::uint64_t frames_sent = 0;     // binary frames written to spectators
    std::uint64_t frames_skipped = 0;  // frames a slow spectator skipped
    // For /metrics (metricFamilies):
    std::uint64_t spectators_open = 0;  // WebSockets watching a room now
    std::uint64_t http_bytes_sent = 0;  // HTTP responses, heads included
    std::uint64_t ws_bytes_sent = 0;    // WebSocket messages (frames as written)
    // Answers by route class (kRouteClasses) and status class (1xx .. 5xx: index 0 .. 4);
    // a WebSocket counts its 101 (or its failed handshake) under "websocket".
    std::array<std::array<std::uint64_t, 5>, 6> answers{};
    // Refusals counted here: "token" (a WebSocket's join token), "bad request" (an answer
    // 4xx other than 404, 421 and 429), "spectators per room", "host" (a Host header not
    // allowed: 421), "bad message" (a page's message that could not be used), "members
    // off" and "visible spectators" (a join as a visible spectator without --web-members,
    // or beyond [web] max_members). metricFamilies() adds WebLimits' ("connection limit",
    // "connections per address", "request rate").
    std::map<std::string, std::uint64_t, std::less<>> refusals;
  };
  // The route classes of Stats::answers, in order (label route="...").
  static constexpr std::array<const char*, 6> kRouteClasses = {"room_list", "room_page", "asset",
                                                               "avatar",    "websocket", "other"};

  // Binds options.bind_address:options.config.port (0: a free port) and starts
  // accepting. The error names the address and the reason.
  static Result<std::unique_ptr<WebServer>> start(asio::io_context& io, ServerShell& shell,
                                                  WebServerOptions options);
  ~WebServer();

  std::string localAddress() const;  // "ADDRESS:PORT"
  Stats stats() const;
  // The web side's figures for /metrics (appended after the session server's families):
  //   vistel_web_requests_total{route,status}  counter: answers by route and status class
  //   vistel_web_spectators                    gauge: WebSockets watching a room now
  //   vistel_web_connections                   gauge: HTTP and WebSocket connections open
  //   vistel_web_sent_bytes_total{transport}   counter: "http" responses, "websocket" messages
  //   vistel_web_refused_total{reason}         counter: connections, requests and sockets
  //                                            refused (reasons as in Stats::refusals)
  //   vistel_web_timeouts_total                counter: closed by a read or write deadline
  //   vistel_web_frames_sent_total, vistel_web_frames_skipped_total  counters
  // Thread-safe (takes the server's mutex); cost O(reasons).
  std::vector<MetricFamily> metricFamilies() const;
  // Stops accepting and closes every connection (spectators get a close "going away").
  void stop();

  struct State;

 private:
  explicit WebServer(std::shared_ptr<State> state);
  std::shared_ptr<State> state_;
};

}  // namespace vistel::server
