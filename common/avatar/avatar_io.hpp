// The .vavatar file: an AvatarModel saved by vistel and loaded back bit-identically.
//
// Layout (little-endian): "VAVATAR\0", u32 format version, u32 chunk count, then chunks
// of { char tag[4], u32 payload size, payload, u32 CRC-32 of the payload }. Chunks:
// "META" (name), "SKEL" (skeleton), "SKIN" (skin mesh); "PRIM", "GRPH", "CALB" (the
// deformable component, optional); "LOOK" (version 2: texture coordinates, materials,
// encoded textures; optional, absent when the look is empty). Version 1 files (no LOOK)
// still load; unknown chunks are skipped. Loading validates every size, index and checksum and the
// decoded model (validateAvatar); errors name the file, the chunk and the reason.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"

namespace vistel {

inline constexpr std::uint32_t kAvatarFormatVersion = 2;        // what encodeAvatar writes
inline constexpr std::uint32_t kAvatarOldestFormatVersion = 1;  // the oldest decodeAvatar reads

std::vector<std::uint8_t> encodeAvatar(const AvatarModel& avatar);
Result<AvatarModel> decodeAvatar(std::span<const std::uint8_t> bytes, std::string_view source_name);

Status saveAvatar(const AvatarModel& avatar, const std::string& path);
Result<AvatarModel> loadAvatar(const std::string& path);

// Content hash of an encoded avatar (hex SHA-256), how avatars travel between sites.
std::string avatarContentHash(std::span<const std::uint8_t> encoded);

}  // namespace vistel
