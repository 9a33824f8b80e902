#include "server/web/web_config.hpp"

#include <sstream>

#include <toml++/toml.h>

#include "common/config/config_table.hpp"

namespace vistel::server {
namespace {

#define VISTEL_WEB_TRY(expr)      \
  do {                            \
    Status st_ = (expr);          \
    if (!st_) return st_.error(); \
  } while (false)

}  // namespace

Result<WebConfig> parseWebConfig(std::string_view toml_text, std::string_view source_name) {
  toml::table root;
  try {
    root = toml::parse(toml_text, source_name);
  } catch (const toml::parse_error& e) {
    std::ostringstream where;
    where << e.source().begin;
    return fail("{}: {} ({})", source_name, e.description(), where.str());
  }
  WebConfig c;
  ConfigTable web(root, "web", source_name);
  VISTEL_WEB_TRY(web.number("port", c.port, -1, 65535));
  VISTEL_WEB_TRY(web.number("max_connections", c.max_connections, 1, 100000));
  VISTEL_WEB_TRY(
      web.number("max_connections_per_address", c.max_connections_per_address, 1, 100000));
  VISTEL_WEB_TRY(web.number("request_rate_hz", c.request_rate_hz, 0.1, 100000.0));
  VISTEL_WEB_TRY(web.number("request_burst", c.request_burst, 1, 100000));
  VISTEL_WEB_TRY(web.number("max_header_bytes", c.max_header_bytes, 1024, 1 << 20));
  VISTEL_WEB_TRY(web.number("read_timeout_s", c.read_timeout_s, 0.1, 3600.0));
  VISTEL_WEB_TRY(web.number("idle_timeout_s", c.idle_timeout_s, 0.1, 3600.0));
  VISTEL_WEB_TRY(web.number("write_timeout_s", c.write_timeout_s, 0.1, 3600.0));
  VISTEL_WEB_TRY(web.number("max_spectators_per_room", c.max_spectators_per_room, 1, 100000));
  VISTEL_WEB_TRY(web.number("max_stream_rate_hz", c.max_stream_rate_hz, 1.0, 240.0));
  VISTEL_WEB_TRY(web.number("max_ws_queue_bytes", c.max_ws_queue_bytes, 65536, 1 << 30));
  VISTEL_WEB_TRY(web.boolean("public_room_list", c.public_room_list));
  VISTEL_WEB_TRY(web.checkUnknown());
  return c;
}

}  // namespace vistel::server
