// An avatar's look on the GPU (common/avatar/avatar_look.hpp): its textures decoded once
// (stb_image) and uploaded with mipmaps — base colour textures as sRGB (GL_SRGB8_ALPHA8,
// so sampling returns linear values), normal maps as linear RGBA8 — and the submeshes
// with their materials. The texture coordinates go to the mesh itself
// (GpuMesh/GpuSkinMesh::attachUvs). Drawn by SceneRenderer::drawMeshLook and
// drawSkinnedMeshLook.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <epoxy/gl.h>

#include "common/avatar/avatar_look.hpp"
#include "common/base/result.hpp"

namespace vistel {

// Puts texture coordinates into a mesh's vertex array as attribute 6 (creating `buffer` on
// first use): GpuMesh and GpuSkinMesh's attachUvs.
void attachUvAttribute(GLuint vao, GLuint& buffer, std::span<const glm::vec2> uvs);

// Textures larger than this (pixels) are not decoded (4096 x 4096: 64 MiB of RGBA).
inline constexpr std::int64_t kMaxDrawnTexturePixels = std::int64_t{4096} * 4096;

class GpuLook {
 public:
  GpuLook() = default;
  ~GpuLook();  // needs the context current when created
  GpuLook(const GpuLook&) = delete;
  GpuLook& operator=(const GpuLook&) = delete;

  // Decodes and uploads the textures of a valid look (validateLook) for a skin with
  // index_count indices; an empty look (AvatarLook::empty) leaves it empty. A texture that does not
  // decode is left out (its materials draw with their factor alone) and named in warning().
  // Replaces any previous contents.
  void create(const AvatarLook& look, std::size_t index_count);

  struct Part {
    std::uint32_t first_index = 0;
    std::uint32_t index_count = 0;
    glm::vec4 base_color{1.0f};  // linear factor
    GLuint base_texture = 0;     // 0: none (white)
    GLuint normal_texture = 0;   // 0: none (flat)
    float normal_scale = 1.0f;
    float alpha_cutoff = -1.0f;  // < 0: opaque (and blended parts)
    bool blend = false;          // alphaMode BLEND: drawn blended after the others, depth
                                 // read but not written
    bool double_sided = false;
  };

  const std::vector<Part>& parts() const { return parts_; }
  bool empty() const { return parts_.empty(); }
  bool hasUvs() const { return has_uvs_; }
  const std::string& warning() const { return warning_; }

 private:
  void release();

  std::vector<GLuint> textures_;
  std::vector<Part> parts_;
  bool has_uvs_ = false;
  std::string warning_;
};

}  // namespace vistel
