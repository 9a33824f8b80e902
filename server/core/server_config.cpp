#include "server/core/server_config.hpp"

#include <set>
#include <sstream>

#include <toml++/toml.h>

#include "common/base/embedded.hpp"

namespace vistel::server {
namespace {

// Reads typed, range-checked keys from one TOML table, remembering which keys it knew.
class TableReader {
 public:
  TableReader(const toml::table& root, std::string_view section, std::string_view source)
      : source_(source), section_(section) {
    if (const toml::node* n = root.get(section)) table_ = n->as_table();
  }

  template <typename T>
  Status number(std::string_view key, T& out, double min, double max) {
    known_.insert(std::string(key));
    if (table_ == nullptr) return {};
    const toml::node* n = table_->get(key);
    if (n == nullptr) return {};
    double v = 0.0;
    if (auto i = n->value_exact<std::int64_t>()) {
      v = static_cast<double>(*i);
    } else if (auto f = n->value_exact<double>()) {
      v = *f;
    } else {
      return fail("{}: [{}] {}: expected a number", source_, section_, key);
    }
    if (!(v >= min && v <= max)) {
      return fail("{}: [{}] {} = {}: out of range [{}, {}]", source_, section_, key, v, min, max);
    }
    out = static_cast<T>(v);
    return {};
  }

  Status string(std::string_view key, std::string& out) {
    known_.insert(std::string(key));
    if (table_ == nullptr) return {};
    const toml::node* n = table_->get(key);
    if (n == nullptr) return {};
    auto s = n->value_exact<std::string>();
    if (!s) return fail("{}: [{}] {}: expected a string", source_, section_, key);
    out = *s;
    return {};
  }

  // Fails on a key that no call above asked for.
  Status checkUnknown() const {
    if (table_ == nullptr) return {};
    for (const auto& [key, node] : *table_) {
      if (!known_.count(std::string(key.str()))) {
        return fail("{}: [{}] unknown key '{}'", source_, section_, key.str());
      }
    }
    return {};
  }

 private:
  std::string_view source_;
  std::string_view section_;
  const toml::table* table_ = nullptr;
  std::set<std::string> known_;
};

#define VISTEL_TRY(expr)          \
  do {                            \
    Status st_ = (expr);          \
    if (!st_) return st_.error(); \
  } while (false)

}  // namespace

Result<ServerConfig> parseServerConfig(std::string_view toml_text, std::string_view source_name) {
  // Parse (toml++ reports syntax errors by exception; they stop here).
  toml::table root;
  try {
    root = toml::parse(toml_text, source_name);
  } catch (const toml::parse_error& e) {
    std::ostringstream where;
    where << e.source().begin;
    return fail("{}: {} ({})", source_name, e.description(), where.str());
  }
  for (const auto& [key, node] : root) {
    static const std::set<std::string, std::less<>> kSections = {"network", "session", "limits",
                                                                 "room", "log"};
    if (!kSections.count(key.str()) || !node.is_table()) {
      return fail("{}: unknown section or key '{}'", source_name, key.str());
    }
  }

  ServerConfig c;
  TableReader network(root, "network", source_name);
  VISTEL_TRY(network.string("bind", c.bind_address));
  VISTEL_TRY(network.number("port", c.port, 0, 65535));
  VISTEL_TRY(network.number("io_threads", c.io_threads, 1, 64));
  VISTEL_TRY(network.checkUnknown());

  TableReader session(root, "session", source_name);
  VISTEL_TRY(session.number("tick_rate_hz", c.tick_rate_hz, 1, 240));
  VISTEL_TRY(session.number("member_timeout_s", c.member_timeout_s, 0.1, 3600));
  VISTEL_TRY(session.number("join_timeout_s", c.join_timeout_s, 0.1, 3600));
  VISTEL_TRY(session.checkUnknown());

  TableReader limits(root, "limits", source_name);
  VISTEL_TRY(limits.number("max_rooms", c.max_rooms, 1, 65535));
  VISTEL_TRY(limits.number("max_members", c.max_members, 1, 65535));
  VISTEL_TRY(limits.number("max_members_per_room", c.max_members_per_room, 1, 255));
  VISTEL_TRY(limits.number("max_frame_bytes", c.max_frame_bytes, 1024, 64 << 20));
  VISTEL_TRY(limits.number("max_avatar_bytes", c.max_avatar_bytes, 1024, 1 << 30));
  // Chunks stay well below the 1 MiB control frames clients accept.
  VISTEL_TRY(limits.number("avatar_chunk_bytes", c.avatar_chunk_bytes, 256, 512 << 10));
  VISTEL_TRY(limits.checkUnknown());
  if (c.avatar_chunk_bytes + 1024 > c.max_frame_bytes) {
    return fail(
        "{}: [limits] avatar_chunk_bytes ({}) must be at least 1024 below max_frame_bytes "
        "({})",
        source_name, c.avatar_chunk_bytes, c.max_frame_bytes);
  }

  TableReader room(root, "room", source_name);
  VISTEL_TRY(room.number("seat_radius_m", c.seat_radius_m, 0.1, 100));
  VISTEL_TRY(room.checkUnknown());

  TableReader log(root, "log", source_name);
  VISTEL_TRY(log.string("level", c.log_level));
  VISTEL_TRY(log.checkUnknown());
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
