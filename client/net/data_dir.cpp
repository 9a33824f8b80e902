#include "client/net/data_dir.hpp"

#include <cstdlib>
#include <filesystem>

namespace vistel::net {

std::string findDataDir() {
  namespace fs = std::filesystem;
  if (const char* env = std::getenv("VISTEL_DATA_DIR"); env != nullptr && *env != '\0') {
    return env;
  }
  std::error_code ec;
#ifdef VISTEL_BUILD_DATA_DIR
  if (fs::is_directory(VISTEL_BUILD_DATA_DIR, ec)) return VISTEL_BUILD_DATA_DIR;
#endif
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) return (exe.parent_path() / ".." / "data").lexically_normal().string();
  return "data";
}

std::string defaultAvatarPath() {
  return (std::filesystem::path(findDataDir()) / "default.vavatar").string();
}

}  // namespace vistel::net
