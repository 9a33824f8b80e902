// Settings of the session server, from TOML (config/server.toml, compiled in as the
// default). Every key is optional; unknown keys and out-of-range values are errors that
// name the source and the key.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "common/base/result.hpp"

namespace vistel::server {

struct ServerConfig {
  // [network]
  std::string bind_address = "127.0.0.1";  // TCP and UDP listen on the same address/port
  std::uint16_t port = 7400;               // 0 = an ephemeral port (printed at start)
  int io_threads = 2;                      // Asio threads (rooms tick on their own strands)
  // [session]
  double tick_rate_hz = 60.0;      // snapshot rate of every room
  double member_timeout_s = 10.0;  // UDP silence after which a member is dropped
  double join_timeout_s = 5.0;     // a connection must send Join within this
  // [limits]
  int max_rooms = 64;
  int max_members = 1024;  // over all rooms (<= 65535)
  int max_members_per_room = 16;
  std::size_t max_frame_bytes = 256u << 10;    // TCP control frame payload
  std::size_t max_avatar_bytes = 16u << 20;    // one avatar file
  std::size_t avatar_chunk_bytes = 64u << 10;  // AvatarChunk.data, both directions (<= 512 KiB)
  // [room]
  float seat_radius_m = 1.5f;  // members stand on a circle of this radius facing its centre
  // [log]
  std::string log_level = "info";  // trace, debug, info, warn, error
};

// Parses TOML text (source_name for messages).
Result<ServerConfig> parseServerConfig(std::string_view toml_text, std::string_view source_name);

// readConfigText(path) then parseServerConfig: "config/server.toml" falls back to the
// embedded copy when the file is absent.
Result<ServerConfig> loadServerConfig(const std::string& path);

}  // namespace vistel::server
