// Settings of the session server, from TOML (config/server.toml, compiled in as the
// default). Every key is optional; unknown keys and out-of-range values are errors that
// name the source and the key.

#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "common/base/result.hpp"
#include "common/scene/seat_layout.hpp"
#include "server/core/props.hpp"
#include "server/core/voice_forwarding.hpp"

namespace vistel::server {

// A prop every room starts with ([[prop]] entries).
struct RoomPropConfig {
  PropSpec spec;
  glm::vec3 position{0.0f, 1.0f, 0.0f};  // room space, metres
  glm::vec3 velocity{0.0f};              // m/s
};

struct ServerConfig {
  // [network]
  std::string bind_address = "127.0.0.1";  // TCP and UDP listen on the same address/port
  std::uint16_t port = 7400;               // 0 = an ephemeral port (printed at start)
  int io_threads = 2;                      // Asio threads (rooms tick on their own strands)
  // [session]
  double tick_rate_hz = 60.0;         // snapshot rate of every room
  double member_timeout_s = 10.0;     // UDP silence after which a member is dropped
  double join_timeout_s = 5.0;        // a connection must send Join within this
  double forward_interval_s = 0.002;  // postures wait at most this long to be forwarded
  double stats_interval_s = 10.0;     // the server logs its load this often (0: never)
  double max_capture_age_s = 5.0;     // postures captured longer ago than this are dropped
  // [limits]
  int max_rooms = 64;
  int max_members = 1024;  // over all rooms (<= 65535)
  int max_members_per_room = 128;
  std::size_t max_frame_bytes = 256u << 10;        // TCP control frame payload
  std::size_t max_avatar_bytes = 16u << 20;        // one avatar file
  std::size_t avatar_chunk_bytes = 64u << 10;      // AvatarChunk.data, both directions (<= 512 KiB)
  std::size_t max_upload_bytes_total = 64u << 20;  // unfinished uploads, all connections
  // Control bytes waiting to be written: a peer that stops reading is dropped past either.
  std::size_t max_queued_bytes_per_connection = 24u << 20;  // >= an avatar and a frame
  std::size_t max_queued_bytes_total = 256u << 20;
  double upload_stall_timeout_s = 15.0;  // an upload without a chunk for this long is dropped
  // Slow uploads (issue 20, finding 5): after upload_grace_s, an upload must move at least
  // upload_min_rate_bytes_per_s averaged over each upload_rate_window_s (or what is left of
  // it, if less), and finish within upload_deadline_base_s + announced size /
  // upload_deadline_rate_bytes_per_s; else it is aborted (ErrorReply TIMEOUT) and its
  // reservation freed. A rate of 0 turns that check off.
  double upload_min_rate_bytes_per_s = 65536.0;
  double upload_rate_window_s = 5.0;
  double upload_grace_s = 5.0;
  double upload_deadline_base_s = 30.0;
  double upload_deadline_rate_bytes_per_s = 32768.0;
  // Connections and rooms (0: no limit): open TCP connections in total and from one source
  // address (refused at accept), rooms open that were created from one address (a join
  // that would create one more is refused with SERVER_FULL). Loopback peers are exempt
  // from the per-address limits unless limit_loopback (local bots and benchmarks).
  int max_connections = 2048;
  int max_connections_per_address = 32;
  int max_rooms_per_address = 8;
  bool limit_loopback = false;
  double control_rate_hz = 20.0;        // control messages per second per connection,
  int control_burst = 100;              // sustained, and in a burst (avatar chunks are free)
  int max_primitives_per_avatar = 128;  // collision model limits checked at upload
  float max_primitive_extent_m = 2.0f;  // largest side of a primitive's field box at rest
  // Dents (proto/SESSION.md §2.5): the most dented vertices one Dents message may carry, the
  // shortest time between two of one body from one member, and the bytes of Dents a member
  // may have relayed per second (bursts of 4 s worth); what goes past is ignored.
  int max_dent_vertices = 65536;
  double dents_interval_s = 0.2;
  double dents_bytes_per_s = 65536.0;
  // [room]
  SeatLayout seat_layout;  // rings of seats about the centre (seat_radius_m, seat_spacing_m,
                           // ring_gap_m)
  int interest_near_members = 16;     // near_members: heard at every posture (and rate bands)
  int interest_max_rate_divisor = 4;  // far_rate_divisor: the farthest at 1/this of the rate
  // [world]
  float gravity_mps2 = 9.81f;         // downwards (-Y)
  float floor_height_m = 0.0f;        // a rigid floor plane at this height
  float world_extent_m = 20.0f;       // props beyond this (|x|, |z|, height) are reset (<= 30:
                                      // prop states travel in millimetres, WIRE.md §3.7)
  int max_interaction_datagrams = 4;  // per tick and member; more pairs are truncated
  bool send_self_contact = false;     // also send self-contact pairs (clients compute them)
  double contact_window_s = 0.15;     // Step 1 covers each body's motion this far back
  double contact_lead_s = 0.05;       // ... and this far ahead (see WorldSettings)
  // [props]
  int max_props_per_room = 8;     // a spawn beyond removes the oldest client-spawned prop
  double spawn_interval_s = 2.0;  // a member spawns at most one prop per this
  float spawn_height_m = 0.6f;    // a client's ball appears this far above its head joint
  PropSpec spawn_ball;            // the ball a client's spawn request makes
  // [[prop]]
  std::vector<RoomPropConfig> room_props;  // every room starts with these
  // [voice] (proto/SESSION.md §3 "Voice"): selective forwarding and per-member limits.
  VoiceSettings voice;
  // [log]
  std::string log_level = "info";  // trace, debug, info, warn, error
  // [auth] (proto/SESSION.md §2.3): with a secret every Join needs a token signed by it.
  std::string secret_file;                // "" = rooms are open to anyone reaching the port
  std::vector<std::uint8_t> join_secret;  // read from secret_file by the program (not TOML)
  // [tls]: the control channel over TLS (both or neither; PEM files).
  std::string tls_cert_file;  // certificate chain
  std::string tls_key_file;   // its private key
};

// Parses TOML text (source_name for messages).
Result<ServerConfig> parseServerConfig(std::string_view toml_text, std::string_view source_name);

// readConfigText(path) then parseServerConfig: "config/server.toml" falls back to the
// embedded copy when the file is absent.
Result<ServerConfig> loadServerConfig(const std::string& path);

}  // namespace vistel::server
