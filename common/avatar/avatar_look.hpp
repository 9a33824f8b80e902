// AvatarLook: how an avatar's skin looks — texture coordinates, materials and the
// textures they use (a subset of glTF 2.0's metallic-roughness materials: base colour
// factor and texture, normal map). Kept in the .vavatar (chunk "LOOK", format version 2),
// written back by the glTF exporter, drawn by the client's renderer.
//
// Textures stay encoded (PNG or JPEG bytes, as they came from the glTF file or as vistel
// wrote them); decoding is the renderer's business, so the runtime data stays small and
// the bytes go back to glTF unchanged. Colour textures hold sRGB-encoded values; factors
// are linear (glTF's conventions).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "common/base/result.hpp"

namespace vistel {

inline constexpr int kMaxLookTextures = 64;
inline constexpr int kMaxLookMaterials = 256;
inline constexpr int kMaxTextureSide = 16384;               // pixels
inline constexpr std::size_t kMaxTextureBytes = 64u << 20;  // one encoded image
inline constexpr std::size_t kMaxLookNameBytes = 1024;      // texture and material names
inline constexpr std::string_view kMimePng = "image/png";
inline constexpr std::string_view kMimeJpeg = "image/jpeg";

struct AvatarTexture {
  std::string name;  // optional, for messages and export
  std::string mime;  // kMimePng or kMimeJpeg
  int width = 0;     // pixels, as the encoded header says (1..kMaxTextureSide)
  int height = 0;
  std::vector<std::uint8_t> encoded;  // the PNG or JPEG file's bytes
};

enum class AlphaMode : std::uint8_t { kOpaque = 0, kMask = 1, kBlend = 2 };

struct AvatarMaterial {
  std::string name;
  glm::vec4 base_color{1.0f};   // linear RGBA factor, each in [0, 1]
  int base_color_texture = -1;  // index into AvatarLook::textures, -1: none
  int normal_texture = -1;      // tangent-space normal map (linear), -1: none
  float normal_scale = 1.0f;    // glTF normalTexture.scale
  float metallic = 0.0f;        // [0, 1]
  float roughness = 1.0f;       // [0, 1]
  AlphaMode alpha_mode = AlphaMode::kOpaque;
  float alpha_cutoff = 0.5f;  // (kMask)
  bool double_sided = false;
};

// A run of triangles drawn with one material: indices [first_index, first_index + count)
// of SkinMesh::indices (multiples of 3).
struct AvatarSubmesh {
  std::uint32_t first_index = 0;
  std::uint32_t index_count = 0;
  int material = 0;  // index into AvatarLook::materials
};

struct AvatarLook {
  std::vector<glm::vec2> uvs;  // TEXCOORD_0 per skin vertex (glTF convention: v down),
                               // empty = none (textures then sample (0, 0))
  std::vector<AvatarMaterial> materials;
  std::vector<AvatarTexture> textures;
  // Triangle runs in index order, covering all of SkinMesh::indices without overlap;
  // empty = every triangle uses material 0 (or none when there are no materials).
  std::vector<AvatarSubmesh> submeshes;

  bool empty() const { return uvs.empty() && materials.empty() && textures.empty(); }
  // Encoded bytes of all textures.
  std::size_t textureBytes() const;
};

// Checks sizes against the skin (uvs: nvert or 0, finite), names (at most
// kMaxLookNameBytes), submeshes (in order, covering
// index_count indices exactly), material and texture indices, factors in range, texture
// mime types, sizes and that each texture's bytes start like its mime type says. The
// message names the part and the element.
Status validateLook(const AvatarLook& look, std::size_t vertex_count, std::size_t index_count);

// The material of each submesh, with the implicit single submesh when `submeshes` is
// empty (then material 0, or -1 with no materials). For drawing and export.
std::vector<AvatarSubmesh> effectiveSubmeshes(const AvatarLook& look, std::size_t index_count);

}  // namespace vistel
