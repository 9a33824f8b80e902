// The project's config/ folder, compiled into every program (see cmake/EmbedFiles.cmake),
// so the programs run with their defaults from any folder and with no files installed.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "common/base/result.hpp"

namespace vistel {

struct EmbeddedFile {
  std::string_view path;  // relative to config/, e.g. "skeletons/cmu_131.toml"
  std::string_view data;
};

// Every embedded file, sorted by path.
std::span<const EmbeddedFile> embeddedFiles();

// The embedded copy of config/<relative>, if there is one.
std::optional<std::string_view> embeddedConfig(std::string_view relative);

// Text of a configuration file: an explicit path is read from disk (error if missing);
// a path of the form "config/<relative>" that does not exist on disk falls back to the
// embedded copy. The error names the path.
Result<std::string> readConfigText(const std::string& path);

}  // namespace vistel
