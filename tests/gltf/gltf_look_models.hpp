// Test models for the look (materials, textures) and VRM import: PNG images made in the
// test, a textured box avatar, a small humanoid whose joints a VRM humanoid extension maps,
// and editing the JSON of a .glb.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "common/glb/gltf_export.hpp"

namespace vistel::test {

// A PNG of w x h pixels coloured by `pixel(x, y)` (RGBA8, sRGB, rows from the top).
std::vector<std::uint8_t> makePng(int w, int h,
                                  const std::function<glm::u8vec4(int x, int y)>& pixel);

// A one-joint box avatar, `width` x `height` x `depth` metres standing on y = 0, centred
// on x = z = 0: 24 vertices (4 per face), texture coordinates spanning [0, 1]^2 on every
// face (u left to right as seen from outside, v top to bottom), one material with the
// given base colour factor and `texture` (PNG bytes; empty: none).
GltfScene texturedBoxScene(const std::vector<std::uint8_t>& texture,
                           const glm::vec4& base_color = glm::vec4(1.0f), float width = 0.8f,
                           float height = 1.6f, float depth = 0.3f);

// The .glb with its JSON edited by `edit` (container rebuilt).
std::vector<std::uint8_t> editGlbJson(const std::vector<std::uint8_t>& glb,
                                      const std::function<void(nlohmann::json&)>& edit);

// A humanoid of 17 joints in a T-pose facing +Z (or -Z when facing_minus_z, as VRM 0.x
// models do: then the left arm is at -X), joint i named names[i] (hierarchy order: hips,
// spine, chest, neck, head, l_upperarm, l_forearm, l_hand, r_upperarm, r_forearm, r_hand,
// l_thigh, l_shin, l_foot, r_thigh, r_shin, r_foot), a small tetrahedron of skin around each
// joint bound to it. Joint j is node j + 1 in the exported file.
GltfScene humanoidScene(const std::vector<std::string>& names, bool facing_minus_z = false);
// The canonical names of humanoidScene's joints, and their VRM 1.0 bone names.
const std::vector<std::string>& humanoidCanonicalNames();
const std::vector<std::string>& humanoidVrmBones();

}  // namespace vistel::test
