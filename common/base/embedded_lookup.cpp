#include <filesystem>

#include "common/base/embedded.hpp"
#include "common/base/file.hpp"

namespace vistel {

std::optional<std::string_view> embeddedConfig(std::string_view relative) {
  for (const EmbeddedFile& f : embeddedFiles()) {
    if (f.path == relative) return f.data;
  }
  return std::nullopt;
}

Result<std::string> readConfigText(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::exists(path, ec)) return readFileText(path, 16u << 20);
  constexpr std::string_view kPrefix = "config/";
  std::string_view rel(path);
  if (rel.starts_with("./")) rel.remove_prefix(2);
  if (rel.starts_with(kPrefix)) {
    if (auto data = embeddedConfig(rel.substr(kPrefix.size()))) return std::string(*data);
  }
  return fail("{}: no such file (and no built-in default of that name)", path);
}

}  // namespace vistel
