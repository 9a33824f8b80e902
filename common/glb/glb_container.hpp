// The GLB container of binary glTF 2.0: a 12-byte header, a JSON chunk, an optional BIN
// chunk (little-endian, every chunk 4-byte aligned).
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "common/base/result.hpp"

namespace vistel {

inline constexpr std::uint32_t kGlbMagic = 0x46546C67;      // "glTF"
inline constexpr std::uint32_t kGlbChunkJson = 0x4E4F534A;  // "JSON"
inline constexpr std::uint32_t kGlbChunkBin = 0x004E4942;   // "BIN\0"

struct GlbChunks {
  std::span<const std::uint8_t> json;  // the JSON chunk's payload (views into the input)
  std::span<const std::uint8_t> bin;   // the first BIN chunk's payload, empty when absent
  bool has_bin = false;
};

// True when the bytes start with the GLB magic.
bool looksLikeGlb(std::span<const std::uint8_t> bytes);

// Checks the container (magic, version 2, total length equal to the input size, chunk
// headers and lengths within the input, JSON first) and returns views of its chunks.
// Unknown chunks after the first are skipped. Errors name the source, the byte offset and
// the reason. Cost: O(number of chunks); copies nothing.
Result<GlbChunks> parseGlbContainer(std::span<const std::uint8_t> bytes, std::string_view source);

// A GLB file from JSON text and a binary payload: the JSON is padded with spaces and the
// payload with zeros to 4 bytes; an empty payload gives no BIN chunk.
std::vector<std::uint8_t> assembleGlb(std::string_view json, std::span<const std::uint8_t> bin);

}  // namespace vistel
