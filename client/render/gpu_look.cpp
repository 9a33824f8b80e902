#include "client/render/gpu_look.hpp"

#include <climits>
#include <cstdint>

#include <stb_image.h>

namespace vistel {

GpuLook::~GpuLook() { release(); }

void GpuLook::release() {
  for (GLuint t : textures_) {
    if (t != 0) glDeleteTextures(1, &t);
  }
  textures_.clear();
  parts_.clear();
  has_uvs_ = false;
  warning_.clear();
}

void GpuLook::create(const AvatarLook& look, std::size_t index_count) {
  release();
  if (look.empty()) return;  // drawn plain
  has_uvs_ = !look.uvs.empty();
  // Which textures are normal maps (linear) and which colour (sRGB).
  std::vector<bool> is_normal(look.textures.size(), false);
  for (const AvatarMaterial& m : look.materials) {
    if (m.normal_texture >= 0) is_normal[static_cast<std::size_t>(m.normal_texture)] = true;
  }
  textures_.assign(look.textures.size(), 0);
  GLint max_side = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_side);
  for (std::size_t i = 0; i < look.textures.size(); ++i) {
    const AvatarTexture& t = look.textures[i];
    int w = 0, h = 0, comp = 0;
    // The header first: a small file may claim a huge image (avatars come from other
    // members through the server).
    const bool sane = t.encoded.size() <= static_cast<std::size_t>(INT_MAX) &&
                      stbi_info_from_memory(t.encoded.data(), static_cast<int>(t.encoded.size()),
                                            &w, &h, &comp) == 1 &&
                      w > 0 && h > 0 && w <= max_side && h <= max_side &&
                      static_cast<std::int64_t>(w) * h <= kMaxDrawnTexturePixels;
    stbi_uc* pixels =
        sane ? stbi_load_from_memory(t.encoded.data(), static_cast<int>(t.encoded.size()), &w, &h,
                                     &comp, 4)
             : nullptr;
    if (pixels == nullptr) {
      if (warning_.empty()) {
        warning_ = fmt::format(
            "texture {} ('{}') does not decode, or is beyond {} pixels or the GPU's {} a side; "
            "drawn without it",
            i, t.name, kMaxDrawnTexturePixels, max_side);
      }
      continue;
    }
    GLuint tex = 0;
    glGenTextures(1, &tex);
    glBindTexture(GL_TEXTURE_2D, tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTexImage2D(GL_TEXTURE_2D, 0, is_normal[i] ? GL_RGBA8 : GL_SRGB8_ALPHA8, w, h, 0, GL_RGBA,
                 GL_UNSIGNED_BYTE, pixels);
    stbi_image_free(pixels);
    glGenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
    textures_[i] = tex;
  }
  glBindTexture(GL_TEXTURE_2D, 0);

  auto textureAt = [&](int index) {
    return index >= 0 && static_cast<std::size_t>(index) < textures_.size()
               ? textures_[static_cast<std::size_t>(index)]
               : 0u;
  };
  for (const AvatarSubmesh& sm : effectiveSubmeshes(look, index_count)) {
    Part part;
    part.first_index = sm.first_index;
    part.index_count = sm.index_count;
    if (sm.material >= 0 && static_cast<std::size_t>(sm.material) < look.materials.size()) {
      const AvatarMaterial& m = look.materials[static_cast<std::size_t>(sm.material)];
      part.base_color = m.base_color;
      part.base_texture = has_uvs_ ? textureAt(m.base_color_texture) : 0u;
      part.normal_texture = has_uvs_ ? textureAt(m.normal_texture) : 0u;
      part.normal_scale = m.normal_scale;
      part.alpha_cutoff = m.alpha_mode == AlphaMode::kMask ? m.alpha_cutoff : -1.0f;
      part.blend = m.alpha_mode == AlphaMode::kBlend;
      part.double_sided = m.double_sided;
    }
    parts_.push_back(part);
  }
}

void attachUvAttribute(GLuint vao, GLuint& buffer, std::span<const glm::vec2> uvs) {
  glBindVertexArray(vao);
  if (buffer == 0) glGenBuffers(1, &buffer);
  glBindBuffer(GL_ARRAY_BUFFER, buffer);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(uvs.size_bytes()), uvs.data(),
               GL_STATIC_DRAW);
  glVertexAttribPointer(6, 2, GL_FLOAT, GL_FALSE, sizeof(glm::vec2), nullptr);
  glEnableVertexAttribArray(6);
  glBindVertexArray(0);
  glBindBuffer(GL_ARRAY_BUFFER, 0);
}

}  // namespace vistel
