#include "offline/synth/default_look.hpp"

#include <algorithm>
#include <array>
#include <string_view>

#include <stb_image_write.h>

namespace vistel {
namespace {

// Columns, left to right; regions that meet on the body are neighbours.
enum Region { kShoes = 0, kTrousers = 1, kShirt = 2, kSkin = 3 };

Region regionOf(std::string_view joint) {
  auto has = [&](std::string_view part) { return joint.find(part) != std::string_view::npos; };
  if (has("foot") || has("toes")) return kShoes;
  if (joint == "hips" || has("thigh") || has("shin")) return kTrousers;
  if (joint == "spine" || joint == "chest" || joint == "upper_chest" || has("clavicle") ||
      has("upperarm")) {
    return kShirt;
  }
  return kSkin;
}

void appendBytes(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(context);
  const auto* p = static_cast<const std::uint8_t*>(data);
  out->insert(out->end(), p, p + size);
}

}  // namespace

std::vector<std::uint8_t> defaultLookPixels() {
  constexpr int w = kDefaultLookWidth;
  constexpr int h = kDefaultLookHeight;
  constexpr int column = w / 4;
  std::vector<std::uint8_t> rgba(static_cast<std::size_t>(w * h * 4), 255);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      std::array<int, 3> c{};
      // A small deterministic grain so flat areas do not look plastic.
      const int grain = ((x * 37 + y * 91) ^ (x * y * 13)) % 7 - 3;
      switch (x / column) {
        case kShoes:
          c = {62, 46, 38};
          break;
        case kTrousers:
          c = {50 + y / 16, 68 + y / 16, 108 + y / 12};  // denim, lighter higher up
          break;
        case kShirt:
          c = (y / 4) % 2 == 0 ? std::array<int, 3>{38, 128, 138}
                               : std::array<int, 3>{228, 226, 214};
          break;
        default:
          c = {226, 178, 150};
          break;
      }
      std::uint8_t* px = &rgba[static_cast<std::size_t>((y * w + x) * 4)];
      for (int k = 0; k < 3; ++k)
        px[k] =
            static_cast<std::uint8_t>(std::clamp(c[static_cast<std::size_t>(k)] + grain, 0, 255));
    }
  }
  return rgba;
}

AvatarLook makeDefaultLook(const AvatarModel& avatar) {
  AvatarLook look;
  const SkinMesh& skin = avatar.skin;
  const auto nvert = skin.positions.size();
  const auto k = static_cast<std::size_t>(skin.influences);
  float top = 0.0f;
  for (const glm::vec3& p : skin.positions) top = std::max(top, p.y);
  if (top <= 0.0f) top = 1.0f;
  std::vector<Region> regions(avatar.skeleton.names.size());
  for (std::size_t j = 0; j < regions.size(); ++j) regions[j] = regionOf(avatar.skeleton.names[j]);
  look.uvs.resize(nvert);
  for (std::size_t v = 0; v < nvert; ++v) {
    std::size_t best = 0;
    for (std::size_t s = 1; s < k; ++s) {
      if (skin.weights[v * k + s] > skin.weights[v * k + best]) best = s;
    }
    const std::size_t joint = skin.joints[v * k + best];
    const Region r = joint < regions.size() ? regions[joint] : kSkin;
    const float u = (static_cast<float>(r) + 0.5f) / 4.0f;
    const float row = std::clamp(1.0f - skin.positions[v].y / top, 0.0f, 1.0f);
    // Keep half a pixel inside the texture vertically (no wrap at the crown or soles).
    const float half = 0.5f / static_cast<float>(kDefaultLookHeight);
    look.uvs[v] = glm::vec2(u, half + row * (1.0f - 2.0f * half));
  }
  AvatarTexture texture;
  texture.name = "vistel-default-clothes";
  texture.mime = std::string(kMimePng);
  texture.width = kDefaultLookWidth;
  texture.height = kDefaultLookHeight;
  const std::vector<std::uint8_t> pixels = defaultLookPixels();
  stbi_write_png_to_func(&appendBytes, &texture.encoded, kDefaultLookWidth, kDefaultLookHeight, 4,
                         pixels.data(), kDefaultLookWidth * 4);
  look.textures.push_back(std::move(texture));
  AvatarMaterial material;
  material.name = "vistel-default";
  material.base_color = glm::vec4(1.0f);
  material.base_color_texture = 0;
  material.roughness = 0.8f;
  look.materials.push_back(material);
  return look;
}

}  // namespace vistel
