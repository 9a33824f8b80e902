#include "offline/gltf/gltf_look.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include <stb_image.h>
#include <stb_image_resize.h>
#include <stb_image_write.h>

#include "common/avatar/avatar_io.hpp"
#include "offline/gltf/gltf_import.hpp"

namespace vistel {
namespace {

// A name that fits the .vavatar (kMaxLookNameBytes; cut at a UTF-8 character boundary).
std::string lookName(std::string name) {
  if (name.size() <= kMaxLookNameBytes) return name;
  std::size_t n = kMaxLookNameBytes;
  while (n > 0 && (static_cast<unsigned char>(name[n]) & 0xC0) == 0x80) --n;
  name.resize(n);
  return name;
}

float unitFactor(double v) {
  return static_cast<float>(std::clamp(std::isfinite(v) ? v : 1.0, 0.0, 1.0));
}

// The encoded bytes of image `i`: from its buffer view (range-checked) or as the loader
// kept them (data URIs and external files, see gltf_load.cpp).
Result<std::vector<std::uint8_t>> imageBytes(const tinygltf::Model& model, int i,
                                             std::string_view source) {
  const tinygltf::Image& image = model.images[static_cast<std::size_t>(i)];
  if (image.bufferView < 0) {
    if (image.image.empty()) {
      return fail("{}: image {} ('{}'): no data (external file '{}' missing?)", source, i,
                  image.name, image.uri);
    }
    return std::vector<std::uint8_t>(image.image.begin(), image.image.end());
  }
  if (static_cast<std::size_t>(image.bufferView) >= model.bufferViews.size()) {
    return fail("{}: image {}: buffer view {} of {}", source, i, image.bufferView,
                model.bufferViews.size());
  }
  const tinygltf::BufferView& view = model.bufferViews[static_cast<std::size_t>(image.bufferView)];
  if (view.buffer < 0 || static_cast<std::size_t>(view.buffer) >= model.buffers.size()) {
    return fail("{}: image {}: buffer view {} refers to buffer {} of {}", source, i,
                image.bufferView, view.buffer, model.buffers.size());
  }
  const std::vector<unsigned char>& data =
      model.buffers[static_cast<std::size_t>(view.buffer)].data;
  if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset) {
    return fail(
        "{}: image {}: buffer view {} (offset {}, {} bytes) runs past its buffer ({} bytes)",
        source, i, image.bufferView, view.byteOffset, view.byteLength, data.size());
  }
  const auto first = data.begin() + static_cast<std::ptrdiff_t>(view.byteOffset);
  return std::vector<std::uint8_t>(first, first + static_cast<std::ptrdiff_t>(view.byteLength));
}

std::string sniffMime(const std::vector<std::uint8_t>& b) {
  if (b.size() >= 8 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G') {
    return std::string(kMimePng);
  }
  if (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return std::string(kMimeJpeg);
  return {};
}

class LookImporter {
 public:
  LookImporter(const tinygltf::Model& model, std::string_view source,
               std::vector<std::string>& warnings)
      : model_(model), source_(source), warnings_(warnings) {}

  // Index into look_.materials of glTF material m (-1: the default material).
  Result<int> material(int m);

  AvatarLook look_;

 private:
  // Index into look_.textures of glTF texture t used as `role` (-1: dropped, warned).
  Result<int> texture(int t, int tex_coord, std::string_view role, std::string_view material);
  void warn(std::string text) { warnings_.push_back(fmt::format("{}: {}", source_, text)); }

  const tinygltf::Model& model_;
  std::string source_;
  std::vector<std::string>& warnings_;
  std::map<int, int> materials_;  // glTF material -> look material
  std::map<int, int> images_;     // glTF image -> look texture (-1: unusable)
};

Result<int> LookImporter::texture(int t, int tex_coord, std::string_view role,
                                  std::string_view material) {
  if (t < 0) return -1;
  if (static_cast<std::size_t>(t) >= model_.textures.size()) {
    return fail("{}: material '{}': {} texture {} of {}", source_, material, role, t,
                model_.textures.size());
  }
  if (tex_coord != 0) {
    warn(
        fmt::format("material '{}': the {} texture uses TEXCOORD_{}; only TEXCOORD_0 is kept, "
                    "so the texture is dropped",
                    material, role, tex_coord));
    return -1;
  }
  const tinygltf::Texture& tex = model_.textures[static_cast<std::size_t>(t)];
  const int source = tex.source;
  if (source < 0) {
    warn(fmt::format("texture {} has no PNG/JPEG source image (an extension's format?); dropped",
                     t));
    return -1;
  }
  if (static_cast<std::size_t>(source) >= model_.images.size()) {
    return fail("{}: texture {}: image {} of {}", source_, t, source, model_.images.size());
  }
  if (auto it = images_.find(source); it != images_.end()) return it->second;
  images_[source] = -1;
  if (look_.textures.size() >= static_cast<std::size_t>(kMaxLookTextures)) {
    warn(fmt::format("more than {} textures; image {} dropped", kMaxLookTextures, source));
    return -1;
  }
  Result<std::vector<std::uint8_t>> bytes = imageBytes(model_, source, source_);
  if (!bytes) {
    warn(bytes.error().message + "; texture dropped");
    return -1;
  }
  AvatarTexture out;
  const tinygltf::Image& image = model_.images[static_cast<std::size_t>(source)];
  out.name = image.name.empty() ? fmt::format("image{}", source) : lookName(image.name);
  out.mime = sniffMime(*bytes);
  if (out.mime.empty()) {
    warn(fmt::format("image {} ('{}', {}): not PNG or JPEG; texture dropped", source, out.name,
                     image.mimeType));
    return -1;
  }
  if (bytes->size() > kMaxTextureBytes || !textureImageSize(*bytes, out.width, out.height) ||
      out.width > kMaxTextureSide || out.height > kMaxTextureSide) {
    warn(fmt::format("image {} ('{}'): unreadable header or beyond {} pixels a side; dropped",
                     source, out.name, kMaxTextureSide));
    return -1;
  }
  out.encoded = std::move(*bytes);
  const int index = static_cast<int>(look_.textures.size());
  look_.textures.push_back(std::move(out));
  images_[source] = index;
  return index;
}

Result<int> LookImporter::material(int m) {
  if (auto it = materials_.find(m); it != materials_.end()) return it->second;
  if (look_.materials.size() >= static_cast<std::size_t>(kMaxLookMaterials)) {
    return fail("{}: more than {} materials", source_, kMaxLookMaterials);
  }
  AvatarMaterial out;
  if (m >= 0) {
    if (static_cast<std::size_t>(m) >= model_.materials.size()) {
      return fail("{}: a primitive uses material {} of {}", source_, m, model_.materials.size());
    }
    const tinygltf::Material& mat = model_.materials[static_cast<std::size_t>(m)];
    out.name = mat.name.empty() ? fmt::format("material{}", m) : lookName(mat.name);
    const auto& pbr = mat.pbrMetallicRoughness;
    for (std::size_t c = 0; c < 4 && c < pbr.baseColorFactor.size(); ++c) {
      out.base_color[static_cast<glm::length_t>(c)] = unitFactor(pbr.baseColorFactor[c]);
    }
    out.metallic = unitFactor(pbr.metallicFactor);
    out.roughness = unitFactor(pbr.roughnessFactor);
    Result<int> base =
        texture(pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord, "base colour", out.name);
    if (!base) return base.error();
    out.base_color_texture = *base;
    Result<int> normal =
        texture(mat.normalTexture.index, mat.normalTexture.texCoord, "normal", out.name);
    if (!normal) return normal.error();
    out.normal_texture = *normal;
    out.normal_scale = std::isfinite(mat.normalTexture.scale)
                           ? static_cast<float>(std::clamp(mat.normalTexture.scale, -100.0, 100.0))
                           : 1.0f;
    out.alpha_mode = mat.alphaMode == "MASK"    ? AlphaMode::kMask
                     : mat.alphaMode == "BLEND" ? AlphaMode::kBlend
                                                : AlphaMode::kOpaque;
    out.alpha_cutoff = unitFactor(mat.alphaCutoff);
    out.double_sided = mat.doubleSided;
    if (mat.pbrMetallicRoughness.baseColorTexture.extensions.count("KHR_texture_transform") != 0) {
      warn(fmt::format("material '{}': KHR_texture_transform is ignored", out.name));
    }
  } else {
    out.name = "default";
  }
  const int index = static_cast<int>(look_.materials.size());
  look_.materials.push_back(std::move(out));
  materials_[m] = index;
  return index;
}

}  // namespace

Result<AvatarLook> importGltfLook(const tinygltf::Model& model, std::string_view source,
                                  std::span<const GltfPrimitiveRun> runs,
                                  std::vector<glm::vec2> uvs, const GltfImportOptions& options,
                                  std::vector<std::string>& warnings) {
  if (!options.import_look) return AvatarLook{};
  // A file with no materials and no texture coordinates has no look to keep.
  bool any_material = false;
  for (const GltfPrimitiveRun& run : runs) any_material = any_material || run.material >= 0;
  if (!any_material && uvs.empty()) return AvatarLook{};

  LookImporter importer(model, source, warnings);
  for (const GltfPrimitiveRun& run : runs) {
    Result<int> m = importer.material(run.material);
    if (!m) return m.error();
    auto& subs = importer.look_.submeshes;
    if (!subs.empty() && subs.back().material == *m &&
        subs.back().first_index + subs.back().index_count == run.first_index) {
      subs.back().index_count += run.index_count;
    } else {
      subs.push_back({run.first_index, run.index_count, *m});
    }
  }
  if (importer.look_.materials.size() == 1) importer.look_.submeshes.clear();  // implied
  importer.look_.uvs = std::move(uvs);
  return std::move(importer.look_);
}

bool textureImageSize(std::span<const std::uint8_t> encoded, int& width, int& height) {
  if (encoded.empty() || encoded.size() > static_cast<std::size_t>(INT32_MAX)) return false;
  int comp = 0;
  return stbi_info_from_memory(encoded.data(), static_cast<int>(encoded.size()), &width, &height,
                               &comp) == 1 &&
         width > 0 && height > 0;
}

Result<RgbaImage> decodeTextureImage(std::span<const std::uint8_t> encoded, std::string_view what) {
  int w = 0, h = 0;
  if (!textureImageSize(encoded, w, h) || w > kMaxTextureSide || h > kMaxTextureSide) {
    return fail("{}: not a readable PNG/JPEG image of at most {} pixels a side", what,
                kMaxTextureSide);
  }
  int comp = 0;
  stbi_uc* pixels =
      stbi_load_from_memory(encoded.data(), static_cast<int>(encoded.size()), &w, &h, &comp, 4);
  if (pixels == nullptr) return fail("{}: cannot decode: {}", what, stbi_failure_reason());
  RgbaImage out;
  out.width = w;
  out.height = h;
  out.rgba.assign(pixels, pixels + static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4);
  stbi_image_free(pixels);
  return out;
}

namespace {
void appendBytes(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(context);
  const auto* p = static_cast<const std::uint8_t*>(data);
  out->insert(out->end(), p, p + size);
}
}  // namespace

std::vector<std::uint8_t> encodePng(const RgbaImage& image) {
  std::vector<std::uint8_t> out;
  stbi_write_png_to_func(&appendBytes, &out, image.width, image.height, 4, image.rgba.data(),
                         image.width * 4);
  return out;
}

std::vector<std::uint8_t> encodeJpeg(const RgbaImage& image) {
  std::vector<std::uint8_t> out;
  stbi_write_jpg_to_func(&appendBytes, &out, image.width, image.height, 4, image.rgba.data(), 90);
  return out;
}

Result<int> fitAvatarTextures(AvatarModel& avatar, std::size_t max_bytes,
                              std::vector<std::string>& warnings) {
  AvatarLook& look = avatar.look;
  if (look.textures.empty()) return 0;
  const std::size_t total = encodeAvatar(avatar).size();
  if (total <= max_bytes) return 0;
  const std::size_t others = total - look.textureBytes();  // everything but texture bytes
  // Normal maps are filtered linearly, colour textures in sRGB.
  std::vector<bool> is_normal(look.textures.size(), false);
  for (const AvatarMaterial& m : look.materials) {
    if (m.normal_texture >= 0) is_normal[static_cast<std::size_t>(m.normal_texture)] = true;
  }
  std::vector<int> original_w(look.textures.size()), original_h(look.textures.size());
  for (std::size_t i = 0; i < look.textures.size(); ++i) {
    original_w[i] = look.textures[i].width;
    original_h[i] = look.textures[i].height;
  }
  std::vector<bool> changed(look.textures.size(), false);
  while (others + look.textureBytes() > max_bytes) {
    // The largest texture that can still shrink.
    int pick = -1;
    for (std::size_t i = 0; i < look.textures.size(); ++i) {
      const AvatarTexture& t = look.textures[i];
      if (std::max(t.width, t.height) <= 1) continue;
      if (pick < 0 ||
          t.encoded.size() > look.textures[static_cast<std::size_t>(pick)].encoded.size()) {
        pick = static_cast<int>(i);
      }
    }
    if (pick < 0) {
      warnings.push_back(fmt::format(
          "avatar '{}': {} bytes even with every texture at 1 pixel; beyond the limit of {} bytes",
          avatar.name, others + look.textureBytes(), max_bytes));
      break;
    }
    AvatarTexture& t = look.textures[static_cast<std::size_t>(pick)];
    Result<RgbaImage> image = decodeTextureImage(t.encoded, fmt::format("texture '{}'", t.name));
    if (!image) return image.error();
    RgbaImage half;
    half.width = std::max(1, image->width / 2);
    half.height = std::max(1, image->height / 2);
    half.rgba.resize(static_cast<std::size_t>(half.width) * static_cast<std::size_t>(half.height) *
                     4);
    if (is_normal[static_cast<std::size_t>(pick)]) {
      stbir_resize_uint8(image->rgba.data(), image->width, image->height, 0, half.rgba.data(),
                         half.width, half.height, 0, 4);
    } else {
      stbir_resize_uint8_srgb(image->rgba.data(), image->width, image->height, 0, half.rgba.data(),
                              half.width, half.height, 0, 4, 3, 0);
    }
    t.encoded = t.mime == kMimeJpeg ? encodeJpeg(half) : encodePng(half);
    t.width = half.width;
    t.height = half.height;
    changed[static_cast<std::size_t>(pick)] = true;
  }
  int count = 0;
  for (std::size_t i = 0; i < look.textures.size(); ++i) {
    if (!changed[i]) continue;
    ++count;
    warnings.push_back(fmt::format(
        "avatar '{}': texture '{}' downscaled from {}x{} to {}x{} so that the avatar fits {} "
        "bytes (the server's avatar size limit)",
        avatar.name, look.textures[i].name, original_w[i], original_h[i], look.textures[i].width,
        look.textures[i].height, max_bytes));
  }
  return count;
}

}  // namespace vistel
