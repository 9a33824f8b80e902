// Whole-file reads and atomic whole-file writes, with errors that name the path.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "common/base/result.hpp"

namespace vistel {

// Reads a whole file. Fails (naming the path and the OS reason) when it cannot be
// opened or read, or when it is larger than max_bytes.
Result<std::vector<std::uint8_t>> readFileBytes(const std::string& path,
                                                std::size_t max_bytes = std::size_t{1} << 31);
Result<std::string> readFileText(const std::string& path,
                                 std::size_t max_bytes = std::size_t{1} << 31);

// Writes a whole file through a temporary name and a rename, so a reader never sees a
// half-written file.
Status writeFileBytes(const std::string& path, std::span<const std::uint8_t> bytes);
Status writeFileText(const std::string& path, std::string_view text);

}  // namespace vistel
