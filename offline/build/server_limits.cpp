#include "offline/build/server_limits.hpp"

#include <toml++/toml.h>

#include "common/base/embedded.hpp"

namespace vistel {

std::size_t serverMaxAvatarBytes(const std::string& config_dir,
                                 std::vector<std::string>* warnings) {
  constexpr std::size_t kShipped = 16u << 20;
  const std::string path = config_dir + "/server.toml";
  auto note = [&](const std::string& why) {
    if (warnings != nullptr) {
      warnings->push_back(fmt::format("{}: {}; assuming the server's avatar limit is {} bytes",
                                      path, why, kShipped));
    }
    return kShipped;
  };
  Result<std::string> text = readConfigText(path);
  if (!text) text = readConfigText("config/server.toml");  // the compiled-in copy
  if (!text) return note(text.error().message);
  toml::table table;
  try {
    table = toml::parse(*text, path);
  } catch (const toml::parse_error& e) {
    return note(std::string(e.description()));
  }
  const std::optional<std::int64_t> value =
      table["limits"]["max_avatar_bytes"].value<std::int64_t>();
  if (!value) return kShipped;  // the key is optional: the server's default
  if (*value < 1024) return note(fmt::format("max_avatar_bytes = {} is out of range", *value));
  return static_cast<std::size_t>(*value);
}

}  // namespace vistel
