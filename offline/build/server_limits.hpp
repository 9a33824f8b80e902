// The server's limits that offline tools must respect when they write avatars.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace vistel {

// [limits] max_avatar_bytes of <config_dir>/server.toml (the disk file, else the
// compiled-in config/server.toml), or 16 MiB (the shipped value) when the file or the key
// is missing or unreadable (a line in `warnings` then says why).
std::size_t serverMaxAvatarBytes(const std::string& config_dir,
                                 std::vector<std::string>* warnings = nullptr);

}  // namespace vistel
