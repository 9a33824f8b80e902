// Settings of the spectator web server (server/web): the [web] section of the server's
// TOML (config/server.toml), every key optional; `--web-port` overrides `port`.
// Unknown keys and out-of-range values are errors naming the source and the key.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "common/base/result.hpp"

namespace vistel::server {

struct WebConfig {
  int port = -1;                              // -1: no web server; 0: a free port
  int max_connections = 256;                  // HTTP and WebSocket connections open at once
  int max_connections_per_address = 32;       // ... from one source address
  double request_rate_hz = 20.0;              // HTTP requests per second per address, sustained
  int request_burst = 120;                    // ... and at once (a page load is ~10)
  std::size_t max_header_bytes = 8192;        // request line and headers (431 beyond)
  double read_timeout_s = 10.0;               // a request head must arrive within this
  double idle_timeout_s = 30.0;               // a kept-alive connection idle this long is closed
  double write_timeout_s = 30.0;              // a response or frame must be sent within this
  int max_spectators_per_room = 64;           // WebSockets watching one room
  double max_stream_rate_hz = 60.0;           // frames per second (the room's tick rate, at most)
  std::size_t max_ws_queue_bytes = 1u << 20;  // a spectator this far behind is dropped
  bool public_room_list = false;  // with join tokens, list rooms anyway (otherwise hidden)
  // DNS-rebinding defence (web_request.hpp hostAllowed): names besides IP addresses and
  // localhost that a request's Host may carry ("name" or "name:port"); others get 421.
  // In TOML a string of names separated by commas or spaces.
  std::vector<std::string> allowed_hosts;
  // Visible spectators (web_member.hpp; `--web-members`): a page may join its room as a
  // member others see (a camera-headed avatar at its camera). Off: such requests are refused.
  bool members = false;
  int max_members = 16;               // visible spectators at once, all rooms
  double member_pose_rate_hz = 10.0;  // postures sent per visible spectator (at most)
};

// Reads [web] from the server's TOML text (other sections are ignored: the server's own
// parser checks them).
Result<WebConfig> parseWebConfig(std::string_view toml_text, std::string_view source_name);

}  // namespace vistel::server
