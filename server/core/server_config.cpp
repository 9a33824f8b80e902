#include "server/core/server_config.hpp"

#include <set>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "common/base/embedded.hpp"
#include "common/config/config_table.hpp"

namespace vistel::server {
namespace {

// A stiffness in Pa per metre, or the string "rigid".
Status readStiffness(ConfigTable& t, std::string_view key, float& out) {
  if (const toml::node* n = t.node(key); n != nullptr && n->is_string()) {
    if (n->value_exact<std::string>() != "rigid") {
      return t.error(key, "expected a number (Pa/m) or \"rigid\"");
    }
    out = kRigidStiffness;
    return {};
  }
  return t.number(key, out, 1.0, 1e9);
}

// "elastic", "plastic" or "viscoelastic".
Status readElasticity(ConfigTable& t, std::string_view key, Elasticity& out) {
  std::string text;
  if (Status st = t.string(key, text); !st) return st;
  if (text.empty()) return {};
  if (text == "elastic") {
    out = Elasticity::kElastic;
  } else if (text == "plastic") {
    out = Elasticity::kPlastic;
  } else if (text == "viscoelastic") {
    out = Elasticity::kViscoelastic;
  } else {
    return t.error(key, fmt::format("'{}': expected elastic, plastic or viscoelastic", text));
  }
  return {};
}

// A ball's keys (prefix "ball_" in [props], none in [[prop]]), then the whole spec checked.
Status readBall(ConfigTable& t, std::string_view prefix, PropSpec& spec, std::string_view source,
                std::string_view where) {
  const auto key = [&](std::string_view k) { return std::string(prefix) + std::string(k); };
  VISTEL_CONFIG_TRY(t.number(key("radius"), spec.ball.radius, 0.01, 2.0));
  VISTEL_CONFIG_TRY(t.number(key("reach"), spec.ball.reach, 1.05, 4.0));
  VISTEL_CONFIG_TRY(t.number(key("mass"), spec.mass, 0.001, 1000.0));
  VISTEL_CONFIG_TRY(t.number(key("restitution"), spec.restitution, 0.0, 1.0));
  VISTEL_CONFIG_TRY(readStiffness(t, key("stiffness"), spec.ball.stiffness));
  VISTEL_CONFIG_TRY(readElasticity(t, key("elasticity"), spec.ball.elasticity));
  VISTEL_CONFIG_TRY(t.number(key("time_constant"), spec.ball.time_constant, 0.001, 100.0));
  if (Status st = validatePropSpec(spec); !st) {
    return fail("{}: {}: {}", source, where, st.error().message);
  }
  return {};
}

}  // namespace

Result<ServerConfig> parseServerConfig(std::string_view toml_text, std::string_view source_name) {
  auto parsed = parseConfigText(toml_text, source_name);
  if (!parsed) return parsed.error();
  const toml::table& root = *parsed;
  for (const auto& [key, node] : root) {
    // [web] is read by server/web (parseWebConfig).
    static const std::set<std::string, std::less<>> kSections = {
        "network", "session", "limits", "room", "log",  "world",
        "props",   "auth",    "tls",    "web",  "voice"};
    if (key.str() == "prop" && node.is_array_of_tables()) continue;
    if (!kSections.count(key.str()) || !node.is_table()) {
      return fail("{}: unknown section or key '{}'", source_name, key.str());
    }
  }

  ServerConfig c;
  ConfigTable network(root, "network", source_name);
  VISTEL_CONFIG_TRY(network.string("bind", c.bind_address));
  VISTEL_CONFIG_TRY(network.number("port", c.port, 0, 65535));
  VISTEL_CONFIG_TRY(network.number("io_threads", c.io_threads, 1, 64));
  VISTEL_CONFIG_TRY(network.checkUnknown());

  ConfigTable session(root, "session", source_name);
  VISTEL_CONFIG_TRY(session.number("tick_rate_hz", c.tick_rate_hz, 1, 240));
  VISTEL_CONFIG_TRY(session.number("member_timeout_s", c.member_timeout_s, 0.1, 3600));
  VISTEL_CONFIG_TRY(session.number("join_timeout_s", c.join_timeout_s, 0.1, 3600));
  VISTEL_CONFIG_TRY(session.number("forward_interval_s", c.forward_interval_s, 0, 0.1));
  VISTEL_CONFIG_TRY(session.number("stats_interval_s", c.stats_interval_s, 0, 86400));
  VISTEL_CONFIG_TRY(session.number("max_capture_age_s", c.max_capture_age_s, 0.1, 3600));
  VISTEL_CONFIG_TRY(session.checkUnknown());

  ConfigTable limits(root, "limits", source_name);
  VISTEL_CONFIG_TRY(limits.number("max_rooms", c.max_rooms, 1, 65535));
  VISTEL_CONFIG_TRY(limits.number("max_members", c.max_members, 1, 65535));
  VISTEL_CONFIG_TRY(limits.number("max_members_per_room", c.max_members_per_room, 1, 255));
  VISTEL_CONFIG_TRY(limits.number("max_frame_bytes", c.max_frame_bytes, 1024, 64 << 20));
  VISTEL_CONFIG_TRY(limits.number("max_avatar_bytes", c.max_avatar_bytes, 1024, 1 << 30));
  // Chunks stay well below the 1 MiB control frames clients accept.
  VISTEL_CONFIG_TRY(limits.number("avatar_chunk_bytes", c.avatar_chunk_bytes, 256, 512 << 10));
  VISTEL_CONFIG_TRY(
      limits.number("max_upload_bytes_total", c.max_upload_bytes_total, 1024, 16.0 * (1ull << 30)));
  VISTEL_CONFIG_TRY(limits.number("upload_stall_timeout_s", c.upload_stall_timeout_s, 0.1, 3600));
  VISTEL_CONFIG_TRY(
      limits.number("upload_min_rate_bytes_per_s", c.upload_min_rate_bytes_per_s, 0, 1e12));
  VISTEL_CONFIG_TRY(limits.number("upload_rate_window_s", c.upload_rate_window_s, 0.1, 3600));
  VISTEL_CONFIG_TRY(limits.number("upload_grace_s", c.upload_grace_s, 0, 3600));
  VISTEL_CONFIG_TRY(limits.number("upload_deadline_base_s", c.upload_deadline_base_s, 0.1, 86400));
  VISTEL_CONFIG_TRY(limits.number("upload_deadline_rate_bytes_per_s",
                                  c.upload_deadline_rate_bytes_per_s, 1, 1e12));
  VISTEL_CONFIG_TRY(limits.number("max_connections", c.max_connections, 0, 1000000));
  VISTEL_CONFIG_TRY(
      limits.number("max_connections_per_address", c.max_connections_per_address, 0, 1000000));
  VISTEL_CONFIG_TRY(limits.number("max_rooms_per_address", c.max_rooms_per_address, 0, 65535));
  VISTEL_CONFIG_TRY(limits.boolean("limit_loopback", c.limit_loopback));
  VISTEL_CONFIG_TRY(limits.number("max_queued_bytes_per_connection",
                                  c.max_queued_bytes_per_connection, 4096, 16.0 * (1ull << 30)));
  VISTEL_CONFIG_TRY(
      limits.number("max_queued_bytes_total", c.max_queued_bytes_total, 4096, 64.0 * (1ull << 30)));
  VISTEL_CONFIG_TRY(limits.number("control_rate_hz", c.control_rate_hz, 0.1, 100000));
  VISTEL_CONFIG_TRY(limits.number("control_burst", c.control_burst, 1, 1000000));
  VISTEL_CONFIG_TRY(
      limits.number("max_primitives_per_avatar", c.max_primitives_per_avatar, 1, kMaxPrimitives));
  VISTEL_CONFIG_TRY(limits.number("max_primitive_extent_m", c.max_primitive_extent_m, 0.01, 100));
  VISTEL_CONFIG_TRY(limits.number("max_dent_vertices", c.max_dent_vertices, 0, 1 << 24));
  VISTEL_CONFIG_TRY(limits.number("dents_interval_s", c.dents_interval_s, 0, 60));
  VISTEL_CONFIG_TRY(limits.number("dents_bytes_per_s", c.dents_bytes_per_s, 256, 1e9));
  VISTEL_CONFIG_TRY(limits.checkUnknown());
  if (c.max_queued_bytes_per_connection < c.max_avatar_bytes + c.max_frame_bytes) {
    return fail(
        "{}: [limits] max_queued_bytes_per_connection ({}) must hold an avatar and a frame "
        "({} + {})",
        source_name, c.max_queued_bytes_per_connection, c.max_avatar_bytes, c.max_frame_bytes);
  }
  if (c.max_queued_bytes_total < c.max_queued_bytes_per_connection) {
    return fail(
        "{}: [limits] max_queued_bytes_total ({}) is below max_queued_bytes_per_connection "
        "({})",
        source_name, c.max_queued_bytes_total, c.max_queued_bytes_per_connection);
  }
  if (c.avatar_chunk_bytes + 1024 > c.max_frame_bytes) {
    return fail(
        "{}: [limits] avatar_chunk_bytes ({}) must be at least 1024 below max_frame_bytes "
        "({})",
        source_name, c.avatar_chunk_bytes, c.max_frame_bytes);
  }

  ConfigTable room(root, "room", source_name);
  VISTEL_CONFIG_TRY(room.number("seat_radius_m", c.seat_layout.first_radius_m, 0.1, 100));
  VISTEL_CONFIG_TRY(room.number("seat_spacing_m", c.seat_layout.spacing_m, 0.1, 100));
  VISTEL_CONFIG_TRY(room.number("ring_gap_m", c.seat_layout.ring_gap_m, 0.1, 100));
  VISTEL_CONFIG_TRY(room.number("near_members", c.interest_near_members, 1, 255));
  VISTEL_CONFIG_TRY(room.number("far_rate_divisor", c.interest_max_rate_divisor, 1, 16));
  VISTEL_CONFIG_TRY(room.checkUnknown());
  if (Status layout = validateSeatLayout(c.seat_layout); !layout) {
    return fail("{}: [room] {}", source_name, layout.error().message);
  }

  ConfigTable world(root, "world", source_name);
  VISTEL_CONFIG_TRY(world.number("gravity_mps2", c.gravity_mps2, 0, 100));
  VISTEL_CONFIG_TRY(world.number("floor_height_m", c.floor_height_m, -2, 2));
  VISTEL_CONFIG_TRY(world.number("extent_m", c.world_extent_m, 1, 30));
  VISTEL_CONFIG_TRY(world.number("max_interaction_datagrams", c.max_interaction_datagrams, 1, 32));
  VISTEL_CONFIG_TRY(world.boolean("send_self_contact", c.send_self_contact));
  VISTEL_CONFIG_TRY(world.number("contact_window_s", c.contact_window_s, 0, 0.5));
  VISTEL_CONFIG_TRY(world.number("contact_lead_s", c.contact_lead_s, 0, 0.5));
  VISTEL_CONFIG_TRY(world.checkUnknown());

  ConfigTable props(root, "props", source_name);
  VISTEL_CONFIG_TRY(props.number("max_per_room", c.max_props_per_room, 0, 32));
  VISTEL_CONFIG_TRY(props.number("spawn_interval_s", c.spawn_interval_s, 0, 3600));
  VISTEL_CONFIG_TRY(props.number("spawn_height_m", c.spawn_height_m, 0, 10));
  VISTEL_CONFIG_TRY(readBall(props, "ball_", c.spawn_ball, source_name, "[props] ball"));
  VISTEL_CONFIG_TRY(props.checkUnknown());

  if (const toml::array* list = root["prop"].as_array()) {
    for (std::size_t i = 0; i < list->size(); ++i) {
      const std::string where = fmt::format("prop[{}]", i);
      ConfigTable t((*list)[i].as_table(), where, source_name);
      std::string kind = "ball";
      VISTEL_CONFIG_TRY(t.string("kind", kind));
      if (kind != "ball") {
        return fail("{}: [{}] kind '{}': the only prop kind is \"ball\"", source_name, where, kind);
      }
      RoomPropConfig prop;
      prop.spec = c.spawn_ball;  // [props] ball_* keys are the defaults
      VISTEL_CONFIG_TRY(t.vec3("position", prop.position, -30, 30));
      VISTEL_CONFIG_TRY(t.vec3("velocity", prop.velocity, -30, 30));
      VISTEL_CONFIG_TRY(readBall(t, "", prop.spec, source_name, where));
      VISTEL_CONFIG_TRY(t.checkUnknown());
      c.room_props.push_back(prop);
    }
    if (static_cast<int>(c.room_props.size()) > c.max_props_per_room) {
      return fail("{}: {} [[prop]] entries but [props] max_per_room is {}", source_name,
                  c.room_props.size(), c.max_props_per_room);
    }
  }

  ConfigTable voice(root, "voice", source_name);
  VISTEL_CONFIG_TRY(voice.boolean("enabled", c.voice.enabled));
  VISTEL_CONFIG_TRY(voice.number("hearing_radius_m", c.voice.hearing_radius_m, 0.1, 1000));
  VISTEL_CONFIG_TRY(voice.number("max_speakers", c.voice.max_speakers, 0, 64));
  VISTEL_CONFIG_TRY(voice.number("hold_s", c.voice.hold_s, 0, 10));
  VISTEL_CONFIG_TRY(voice.number("silence_s", c.voice.silence_s, 0.02, 10));
  VISTEL_CONFIG_TRY(voice.number("max_frames_per_s", c.voice.max_frames_per_s, 1, 1000));
  VISTEL_CONFIG_TRY(voice.number("max_frames_burst", c.voice.max_frames_burst, 1, 1000));
  VISTEL_CONFIG_TRY(voice.number("max_bytes_per_s", c.voice.max_bytes_per_s, 100, 1e7));
  VISTEL_CONFIG_TRY(voice.checkUnknown());

  ConfigTable auth(root, "auth", source_name);
  VISTEL_CONFIG_TRY(auth.string("secret_file", c.secret_file));
  VISTEL_CONFIG_TRY(auth.checkUnknown());
  ConfigTable tls(root, "tls", source_name);
  VISTEL_CONFIG_TRY(tls.string("cert_file", c.tls_cert_file));
  VISTEL_CONFIG_TRY(tls.string("key_file", c.tls_key_file));
  VISTEL_CONFIG_TRY(tls.checkUnknown());
  if (c.tls_cert_file.empty() != c.tls_key_file.empty()) {
    return fail("{}: [tls] needs both cert_file and key_file", source_name);
  }

  ConfigTable log(root, "log", source_name);
  VISTEL_CONFIG_TRY(log.string("level", c.log_level));
  VISTEL_CONFIG_TRY(log.checkUnknown());
  static const std::set<std::string, std::less<>> kLevels = {"trace", "debug", "info",
                                                             "warn",  "error", "off"};
  if (!kLevels.count(c.log_level)) {
    return fail("{}: [log] level '{}': expected trace, debug, info, warn, error or off",
                source_name, c.log_level);
  }
  return c;
}

Result<ServerConfig> loadServerConfig(const std::string& path) {
  auto text = readConfigText(path);
  if (!text) return text.error();
  return parseServerConfig(*text, path);
}

}  // namespace vistel::server
