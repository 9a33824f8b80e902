// An avatar's look from a glTF file (materials, textures; texture coordinates come from
// the importer), texture downscaling to fit a size limit, and the image helpers both use
// (stb: PNG/JPEG decode and encode, sRGB-aware resampling).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <tiny_gltf.h>

#include "common/avatar/avatar_look.hpp"
#include "common/avatar/avatar_model.hpp"
#include "common/base/result.hpp"

namespace vistel {

struct GltfImportOptions;

// The triangles one glTF primitive added to the merged index list.
struct GltfPrimitiveRun {
  std::uint32_t first_index = 0;
  std::uint32_t index_count = 0;
  int material = -1;  // glTF material index, -1: the default material
};

// The look of the merged skin: materials used by the runs (glTF's default material for
// runs with none), the textures and images they use (PNG and JPEG kept as encoded bytes;
// other formats, missing images and unsupported texture coordinate sets dropped with a
// warning), submeshes from the runs (neighbours with one material merged), `uvs` kept as
// given (nvert or empty). An out-of-range material, texture or image index is an Error
// naming it. Without options.import_look the look is empty.
Result<AvatarLook> importGltfLook(const tinygltf::Model& model, std::string_view source,
                                  std::span<const GltfPrimitiveRun> runs,
                                  std::vector<glm::vec2> uvs, const GltfImportOptions& options,
                                  std::vector<std::string>& warnings);

// Halves the largest texture (both sides, at least 1 pixel; sRGB-correct filtering for
// colour textures, linear for normal maps; re-encoded in its format) until
// encodeAvatar(avatar) is at most max_bytes or no texture can shrink further (warned).
// Each downscaled texture gets a warning line with its old and new size. Returns how
// many textures were downscaled. Fails only when a texture cannot be decoded.
Result<int> fitAvatarTextures(AvatarModel& avatar, std::size_t max_bytes,
                              std::vector<std::string>& warnings);

// RGBA8 pixels, rows from the top.
struct RgbaImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgba;
};

// Decodes PNG or JPEG bytes to RGBA8 (what = name in messages).
Result<RgbaImage> decodeTextureImage(std::span<const std::uint8_t> encoded, std::string_view what);
// PNG (lossless) or JPEG (quality 90) bytes of an RGBA8 image (JPEG drops alpha).
std::vector<std::uint8_t> encodePng(const RgbaImage& image);
std::vector<std::uint8_t> encodeJpeg(const RgbaImage& image);
// The size of a PNG or JPEG from its header, or false.
bool textureImageSize(std::span<const std::uint8_t> encoded, int& width, int& height);

}  // namespace vistel
