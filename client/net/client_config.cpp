#include "client/net/client_config.hpp"

#include <cstdlib>
#include <filesystem>
#include <optional>
#include <set>

#include <fmt/format.h>
#include <toml++/toml.h>

#include "client/net/net_sim.hpp"
#include "common/base/embedded.hpp"
#include "common/config/config_table.hpp"

namespace vistel::net {

Result<ClientConfig> parseClientConfig(std::string_view toml_text, std::string_view source_name) {
  auto parsed = parseConfigText(toml_text, source_name);
  if (!parsed) return parsed.error();
  const toml::table& root = *parsed;
  for (const auto& [key, node] : root) {
    static const std::set<std::string, std::less<>> kSections = {
        "network", "playback", "source", "avatars", "view", "deform", "lod"};
    if (!kSections.count(key.str()) || !node.is_table()) {
      return fail("{}: unknown section or key '{}'", source_name, key.str());
    }
  }

  ClientConfig c;
  SessionSettings& s = c.session;
  ConfigTable network(root, "network", source_name);
  VISTEL_CONFIG_TRY(network.number("hello_interval_s", s.hello_interval_s, 0.01, 10));
  VISTEL_CONFIG_TRY(network.number("hello_timeout_s", s.hello_timeout_s, 0.1, 600));
  VISTEL_CONFIG_TRY(network.number("join_timeout_s", s.join_timeout_s, 0.1, 600));
  VISTEL_CONFIG_TRY(network.number("ping_interval_s", s.ping_interval_s, 0.01, 60));
  VISTEL_CONFIG_TRY(network.number("server_timeout_s", s.server_timeout_s, 0.5, 3600));
  VISTEL_CONFIG_TRY(network.number("rehello_after_s", s.rehello_after_s, 0.1, 3600));
  VISTEL_CONFIG_TRY(network.number("reconnect_give_up_s", s.reconnect_give_up_s, 0, 86400));
  VISTEL_CONFIG_TRY(network.string("netsim", c.netsim));
  if (auto sim = parseNetSimSpec(c.netsim, fmt::format("{}: [network] netsim", source_name));
      !sim) {
    return sim.error();
  }
  VISTEL_CONFIG_TRY(network.checkUnknown());

  ConfigTable playback(root, "playback", source_name);
  VISTEL_CONFIG_TRY(playback.number("interpolation_delay_s", c.interpolation_delay_s, 0, 5));
  VISTEL_CONFIG_TRY(playback.number("jitter_capacity", s.jitter_capacity, 2, 1024));
  VISTEL_CONFIG_TRY(playback.number("max_extrapolation_s", c.max_extrapolation_s, 0, 1));
  VISTEL_CONFIG_TRY(playback.checkUnknown());

  ConfigTable source(root, "source", source_name);
  VISTEL_CONFIG_TRY(source.number("idle_rate_hz", c.idle_rate_hz, 1, 240));
  VISTEL_CONFIG_TRY(source.checkUnknown());

  ConfigTable avatars(root, "avatars", source_name);
  VISTEL_CONFIG_TRY(avatars.string("cache_dir", c.cache_dir));
  VISTEL_CONFIG_TRY(avatars.checkUnknown());

  ConfigTable view(root, "view", source_name);
  VISTEL_CONFIG_TRY(view.number("width", c.width, 16, 8192));
  VISTEL_CONFIG_TRY(view.number("height", c.height, 16, 8192));
  VISTEL_CONFIG_TRY(view.number("worker_threads", c.worker_threads, 1, 64));
  VISTEL_CONFIG_TRY(view.number("frame_rate_hz", c.frame_rate_hz, 1, 1000));
  VISTEL_CONFIG_TRY(view.boolean("gpu_skinning", c.gpu_skinning));
  std::string skinning(skinningMethodName(c.skinning));
  VISTEL_CONFIG_TRY(view.string("skinning", skinning));
  if (const std::optional<SkinningMethod> method = parseSkinningMethod(skinning); method) {
    c.skinning = *method;
  } else {
    return view.error("skinning", fmt::format("'{}' is not lbs, dqs, ffd or slerp", skinning));
  }
  VISTEL_CONFIG_TRY(view.checkUnknown());
  ConfigTable deform(root, "deform", source_name);
  VISTEL_CONFIG_TRY(deform.boolean("enabled", c.deform));
  VISTEL_CONFIG_TRY(deform.boolean("server_interactions", c.server_interactions));
  VISTEL_CONFIG_TRY(deform.checkUnknown());
  ConfigTable lod(root, "lod", source_name);
  DeformLodSettings& l = c.lod;
  VISTEL_CONFIG_TRY(lod.boolean("enabled", l.enabled));
  VISTEL_CONFIG_TRY(lod.number("full_radius_m", l.full_radius_m, 0, 1000));
  VISTEL_CONFIG_TRY(lod.number("reduced_radius_m", l.reduced_radius_m, 0, 1000));
  VISTEL_CONFIG_TRY(lod.number("hysteresis_m", l.hysteresis_m, 0, 100));
  VISTEL_CONFIG_TRY(lod.number("reduced_every", l.reduced_every, 1, 60));
  VISTEL_CONFIG_TRY(lod.number("max_full", l.max_full, 0, 65535));
  VISTEL_CONFIG_TRY(lod.number("max_reduced", l.max_reduced, 0, 65535));
  VISTEL_CONFIG_TRY(lod.boolean("contact_full", l.contact_full));
  VISTEL_CONFIG_TRY(lod.checkUnknown());
  if (Status valid = validateDeformLodSettings(l); !valid) {
    return fail("{}: [lod] {}", source_name, valid.error().message);
  }
  return c;
}

Result<ClientConfig> loadClientConfig(const std::string& path) {
  auto text = readConfigText(path);
  if (!text) return text.error();
  return parseClientConfig(*text, path);
}

std::string avatarCacheFolder(const std::string& configured) {
  if (!configured.empty()) return configured;
  namespace fs = std::filesystem;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && *xdg != '\0') {
    return (fs::path(xdg) / "vistel" / "avatars").string();
  }
  if (const char* home = std::getenv("HOME"); home != nullptr && *home != '\0') {
    return (fs::path(home) / ".cache" / "vistel" / "avatars").string();
  }
  return (fs::temp_directory_path() / "vistel-avatars").string();
}

}  // namespace vistel::net
