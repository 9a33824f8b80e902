#include "server/web/web_config.hpp"

#include <toml++/toml.h>

#include "common/config/config_table.hpp"
#include "server/web/web_request.hpp"

namespace vistel::server {

Result<WebConfig> parseWebConfig(std::string_view toml_text, std::string_view source_name) {
  auto parsed = parseConfigText(toml_text, source_name);
  if (!parsed) return parsed.error();
  const toml::table& root = *parsed;
  WebConfig c;
  ConfigTable web(root, "web", source_name);
  VISTEL_CONFIG_TRY(web.number("port", c.port, -1, 65535));
  VISTEL_CONFIG_TRY(web.number("max_connections", c.max_connections, 1, 100000));
  VISTEL_CONFIG_TRY(
      web.number("max_connections_per_address", c.max_connections_per_address, 1, 100000));
  VISTEL_CONFIG_TRY(web.number("request_rate_hz", c.request_rate_hz, 0.1, 100000.0));
  VISTEL_CONFIG_TRY(web.number("request_burst", c.request_burst, 1, 100000));
  VISTEL_CONFIG_TRY(web.number("max_header_bytes", c.max_header_bytes, 1024, 1 << 20));
  VISTEL_CONFIG_TRY(web.number("read_timeout_s", c.read_timeout_s, 0.1, 3600.0));
  VISTEL_CONFIG_TRY(web.number("idle_timeout_s", c.idle_timeout_s, 0.1, 3600.0));
  VISTEL_CONFIG_TRY(web.number("write_timeout_s", c.write_timeout_s, 0.1, 3600.0));
  VISTEL_CONFIG_TRY(web.number("max_spectators_per_room", c.max_spectators_per_room, 1, 100000));
  VISTEL_CONFIG_TRY(web.number("max_stream_rate_hz", c.max_stream_rate_hz, 1.0, 240.0));
  VISTEL_CONFIG_TRY(web.number("max_ws_queue_bytes", c.max_ws_queue_bytes, 65536, 1 << 30));
  VISTEL_CONFIG_TRY(web.boolean("public_room_list", c.public_room_list));
  std::string hosts;
  VISTEL_CONFIG_TRY(web.string("allowed_hosts", hosts));
  auto allowed = parseAllowedHosts(hosts);
  if (!allowed) return fail("{}: [web] {}", source_name, allowed.error().message);
  c.allowed_hosts = std::move(*allowed);
  VISTEL_CONFIG_TRY(web.boolean("members", c.members));
  VISTEL_CONFIG_TRY(web.number("max_members", c.max_members, 1, 10000));
  VISTEL_CONFIG_TRY(web.number("member_pose_rate_hz", c.member_pose_rate_hz, 1.0, 60.0));
  VISTEL_CONFIG_TRY(web.checkUnknown());
  return c;
}

}  // namespace vistel::server
