#include "common/avatar/avatar_look.hpp"

#include <cmath>

namespace vistel {
namespace {

bool startsWith(const std::vector<std::uint8_t>& bytes, std::initializer_list<std::uint8_t> head) {
  if (bytes.size() < head.size()) return false;
  std::size_t i = 0;
  for (std::uint8_t b : head) {
    if (bytes[i++] != b) return false;
  }
  return true;
}

bool inUnit(float v) { return std::isfinite(v) && v >= 0.0f && v <= 1.0f; }

}  // namespace

std::size_t AvatarLook::textureBytes() const {
  std::size_t total = 0;
  for (const AvatarTexture& t : textures) total += t.encoded.size();
  return total;
}

Status validateLook(const AvatarLook& look, std::size_t vertex_count, std::size_t index_count) {
  if (!look.uvs.empty() && look.uvs.size() != vertex_count) {
    return fail("{} texture coordinates for {} vertices", look.uvs.size(), vertex_count);
  }
  for (std::size_t v = 0; v < look.uvs.size(); ++v) {
    if (!std::isfinite(look.uvs[v].x) || !std::isfinite(look.uvs[v].y)) {
      return fail("vertex {}: non-finite texture coordinate", v);
    }
  }
  if (look.textures.size() > static_cast<std::size_t>(kMaxLookTextures)) {
    return fail("{} textures (at most {})", look.textures.size(), kMaxLookTextures);
  }
  if (look.materials.size() > static_cast<std::size_t>(kMaxLookMaterials)) {
    return fail("{} materials (at most {})", look.materials.size(), kMaxLookMaterials);
  }
  for (std::size_t i = 0; i < look.textures.size(); ++i) {
    const AvatarTexture& t = look.textures[i];
    if (t.width < 1 || t.height < 1 || t.width > kMaxTextureSide || t.height > kMaxTextureSide) {
      return fail("texture {} ('{}'): size {}x{} is out of range", i, t.name, t.width, t.height);
    }
    if (t.name.size() > kMaxLookNameBytes)
      return fail("texture {}: name of {} bytes", i, t.name.size());
    if (t.encoded.empty() || t.encoded.size() > kMaxTextureBytes) {
      return fail("texture {} ('{}'): {} bytes", i, t.name, t.encoded.size());
    }
    if (t.mime == kMimePng) {
      if (!startsWith(t.encoded, {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A})) {
        return fail("texture {} ('{}'): not a PNG file (bad signature)", i, t.name);
      }
    } else if (t.mime == kMimeJpeg) {
      if (!startsWith(t.encoded, {0xFF, 0xD8, 0xFF})) {
        return fail("texture {} ('{}'): not a JPEG file (bad signature)", i, t.name);
      }
    } else {
      return fail("texture {} ('{}'): mime type '{}' (only image/png and image/jpeg)", i, t.name,
                  t.mime);
    }
  }
  const auto ntex = static_cast<int>(look.textures.size());
  for (std::size_t i = 0; i < look.materials.size(); ++i) {
    const AvatarMaterial& m = look.materials[i];
    if (m.name.size() > kMaxLookNameBytes) {
      return fail("material {}: name of {} bytes", i, m.name.size());
    }
    for (int c = 0; c < 4; ++c) {
      if (!inUnit(m.base_color[c])) {
        return fail("material {} ('{}'): base colour component {} is {} (not in [0, 1])", i, m.name,
                    c, m.base_color[c]);
      }
    }
    if (m.base_color_texture < -1 || m.base_color_texture >= ntex) {
      return fail("material {} ('{}'): base colour texture {} of {}", i, m.name,
                  m.base_color_texture, ntex);
    }
    if (m.normal_texture < -1 || m.normal_texture >= ntex) {
      return fail("material {} ('{}'): normal texture {} of {}", i, m.name, m.normal_texture, ntex);
    }
    if (!std::isfinite(m.normal_scale) || std::abs(m.normal_scale) > 100.0f) {
      return fail("material {} ('{}'): normal scale {}", i, m.name, m.normal_scale);
    }
    if (!inUnit(m.metallic) || !inUnit(m.roughness) || !inUnit(m.alpha_cutoff)) {
      return fail("material {} ('{}'): metallic, roughness or alpha cutoff out of [0, 1]", i,
                  m.name);
    }
    if (static_cast<int>(m.alpha_mode) > 2) {
      return fail("material {} ('{}'): unknown alpha mode {}", i, m.name,
                  static_cast<int>(m.alpha_mode));
    }
  }
  if (!look.submeshes.empty()) {
    std::size_t next = 0;
    for (std::size_t s = 0; s < look.submeshes.size(); ++s) {
      const AvatarSubmesh& sm = look.submeshes[s];
      if (sm.first_index != next) {
        return fail("submesh {} starts at index {}, expected {}", s, sm.first_index, next);
      }
      if (sm.index_count == 0 || sm.index_count % 3 != 0) {
        return fail("submesh {}: {} indices (a positive multiple of 3)", s, sm.index_count);
      }
      if (sm.material < 0 || static_cast<std::size_t>(sm.material) >= look.materials.size()) {
        return fail("submesh {}: material {} of {}", s, sm.material, look.materials.size());
      }
      next += sm.index_count;
      if (next > index_count) break;
    }
    if (next != index_count) {
      return fail("submeshes cover {} indices of the skin's {}", next, index_count);
    }
  }
  return {};
}

std::vector<AvatarSubmesh> effectiveSubmeshes(const AvatarLook& look, std::size_t index_count) {
  if (!look.submeshes.empty()) return look.submeshes;
  AvatarSubmesh all;
  all.first_index = 0;
  all.index_count = static_cast<std::uint32_t>(index_count);
  all.material = look.materials.empty() ? -1 : 0;
  return {all};
}

}  // namespace vistel
