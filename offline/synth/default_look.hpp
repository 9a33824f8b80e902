// The default avatar's look (avatar_look.hpp): one material whose base colour texture is
// drawn by code — shoes, trousers, a striped shirt and skin — mapped by body region: each
// vertex's strongest joint picks a column of the texture (regions that meet on the body
// are neighbouring columns), its height the row. Deterministic (same bytes every run).
#pragma once

#include <cstdint>
#include <vector>

#include "common/avatar/avatar_model.hpp"

namespace vistel {

inline constexpr int kDefaultLookWidth = 64;    // pixels: 4 columns of 16
inline constexpr int kDefaultLookHeight = 128;  // pixels along the body's height

// The look for an avatar on the canonical joints (joint_map.hpp) in model space (+Y up,
// soles at y = 0): texture coordinates per vertex, one material, one PNG texture. Joints
// with other names count as skin.
AvatarLook makeDefaultLook(const AvatarModel& avatar);

// The texture's pixels (RGBA8, sRGB, rows from the top: the crown at row 0).
std::vector<std::uint8_t> defaultLookPixels();

}  // namespace vistel
