#include "tests/gltf/gltf_look_models.hpp"

#include <string_view>

#include <stb_image_write.h>
#include <glm/gtc/matrix_transform.hpp>

#include "common/glb/glb_container.hpp"

namespace vistel::test {
namespace {

void appendBytes(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(context);
  const auto* p = static_cast<const std::uint8_t*>(data);
  out->insert(out->end(), p, p + size);
}

}  // namespace

std::vector<std::uint8_t> makePng(int w, int h,
                                  const std::function<glm::u8vec4(int x, int y)>& pixel) {
  std::vector<std::uint8_t> rgba(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const glm::u8vec4 c = pixel(x, y);
      std::uint8_t* p = &rgba[(static_cast<std::size_t>(y) * static_cast<std::size_t>(w) +
                               static_cast<std::size_t>(x)) *
                              4];
      p[0] = c.r;
      p[1] = c.g;
      p[2] = c.b;
      p[3] = c.a;
    }
  }
  std::vector<std::uint8_t> out;
  stbi_write_png_to_func(&appendBytes, &out, w, h, 4, rgba.data(), w * 4);
  return out;
}

GltfScene texturedBoxScene(const std::vector<std::uint8_t>& texture, const glm::vec4& base_color,
                           float width, float height, float depth) {
  GltfScene scene;
  scene.mesh.name = "box";
  const glm::vec3 lo(-width / 2, 0.0f, -depth / 2), hi(width / 2, height, depth / 2);
  // Each face: outward normal, then corners bottom-left, bottom-right, top-right, top-left
  // as seen from outside.
  struct Face {
    glm::vec3 n;
    glm::vec3 c[4];
  };
  const Face faces[6] = {
      {{0, 0, 1}, {{lo.x, lo.y, hi.z}, {hi.x, lo.y, hi.z}, {hi.x, hi.y, hi.z}, {lo.x, hi.y, hi.z}}},
      {{0, 0, -1},
       {{hi.x, lo.y, lo.z}, {lo.x, lo.y, lo.z}, {lo.x, hi.y, lo.z}, {hi.x, hi.y, lo.z}}},
      {{1, 0, 0}, {{hi.x, lo.y, hi.z}, {hi.x, lo.y, lo.z}, {hi.x, hi.y, lo.z}, {hi.x, hi.y, hi.z}}},
      {{-1, 0, 0},
       {{lo.x, lo.y, lo.z}, {lo.x, lo.y, hi.z}, {lo.x, hi.y, hi.z}, {lo.x, hi.y, lo.z}}},
      {{0, 1, 0}, {{lo.x, hi.y, hi.z}, {hi.x, hi.y, hi.z}, {hi.x, hi.y, lo.z}, {lo.x, hi.y, lo.z}}},
      {{0, -1, 0},
       {{lo.x, lo.y, lo.z}, {hi.x, lo.y, lo.z}, {hi.x, lo.y, hi.z}, {lo.x, lo.y, hi.z}}},
  };
  const glm::vec2 uv[4] = {{0, 1}, {1, 1}, {1, 0}, {0, 0}};
  for (const Face& f : faces) {
    const auto base = static_cast<std::uint32_t>(scene.mesh.positions.size());
    for (int i = 0; i < 4; ++i) {
      scene.mesh.positions.push_back(f.c[i]);
      scene.mesh.normals.push_back(f.n);
      scene.look.uvs.push_back(uv[i]);
    }
    for (std::uint32_t i : {0u, 1u, 2u, 0u, 2u, 3u}) scene.mesh.indices.push_back(base + i);
  }
  GltfSkin skin;
  skin.joint_names = {"root"};
  skin.parents = {-1};
  skin.joint_model = {glm::mat4(1.0f)};
  skin.influences = 1;
  skin.joints.assign(scene.mesh.positions.size(), 0);
  skin.weights.assign(scene.mesh.positions.size(), 1.0f);
  scene.skin = std::move(skin);
  AvatarMaterial material;
  material.name = "box";
  material.base_color = base_color;
  if (!texture.empty()) {
    AvatarTexture t;
    t.name = "box-texture";
    t.mime = "image/png";
    t.encoded = texture;
    // The size from the IHDR chunk (big-endian at bytes 16..23).
    auto be32 = [&](std::size_t at) {
      return static_cast<int>((texture[at] << 24) | (texture[at + 1] << 16) |
                              (texture[at + 2] << 8) | texture[at + 3]);
    };
    t.width = be32(16);
    t.height = be32(20);
    scene.look.textures.push_back(std::move(t));
    material.base_color_texture = 0;
  }
  scene.look.materials.push_back(material);
  return scene;
}

std::vector<std::uint8_t> editGlbJson(const std::vector<std::uint8_t>& glb,
                                      const std::function<void(nlohmann::json&)>& edit) {
  Result<GlbChunks> chunks = parseGlbContainer(glb, "edit");
  if (!chunks) return {};
  nlohmann::json doc = nlohmann::json::parse(chunks->json.begin(), chunks->json.end());
  edit(doc);
  return assembleGlb(doc.dump(), chunks->bin);
}

const std::vector<std::string>& humanoidCanonicalNames() {
  static const std::vector<std::string> names = {
      "hips",      "spine",  "chest",      "neck",      "head",   "l_upperarm",
      "l_forearm", "l_hand", "r_upperarm", "r_forearm", "r_hand", "l_thigh",
      "l_shin",    "l_foot", "r_thigh",    "r_shin",    "r_foot"};
  return names;
}

const std::vector<std::string>& humanoidVrmBones() {
  static const std::vector<std::string> bones = {
      "hips",         "spine",    "chest",         "neck",          "head",      "leftUpperArm",
      "leftLowerArm", "leftHand", "rightUpperArm", "rightLowerArm", "rightHand", "leftUpperLeg",
      "leftLowerLeg", "leftFoot", "rightUpperLeg", "rightLowerLeg", "rightFoot"};
  return bones;
}

GltfScene humanoidScene(const std::vector<std::string>& names, bool facing_minus_z) {
  // Joint positions (model space, +Z facing, left = +X) and parents.
  const std::vector<glm::vec3> at = {
      {0, 1.0f, 0},      {0, 1.15f, 0},     {0, 1.3f, 0},     {0, 1.5f, 0},      {0, 1.6f, 0},
      {0.2f, 1.45f, 0},  {0.45f, 1.45f, 0}, {0.7f, 1.45f, 0}, {-0.2f, 1.45f, 0}, {-0.45f, 1.45f, 0},
      {-0.7f, 1.45f, 0}, {0.1f, 0.95f, 0},  {0.1f, 0.5f, 0},  {0.1f, 0.08f, 0},  {-0.1f, 0.95f, 0},
      {-0.1f, 0.5f, 0},  {-0.1f, 0.08f, 0}};
  const std::vector<int> parents = {-1, 0, 1, 2, 3, 2, 5, 6, 2, 8, 9, 0, 11, 12, 0, 14, 15};
  const float flip = facing_minus_z ? -1.0f : 1.0f;
  GltfScene scene;
  scene.mesh.name = "body";
  GltfSkin skin;
  skin.joint_names = names;
  skin.parents = parents;
  skin.influences = 1;
  for (std::size_t j = 0; j < at.size(); ++j) {
    const glm::vec3 p(flip * at[j].x, at[j].y, flip * at[j].z);
    skin.joint_model.push_back(glm::translate(glm::mat4(1.0f), p));
    const auto base = static_cast<std::uint32_t>(scene.mesh.positions.size());
    const float r = 0.04f;
    for (const glm::vec3& d :
         {glm::vec3(r, r, r), glm::vec3(-r, -r, r), glm::vec3(-r, r, -r), glm::vec3(r, -r, -r)}) {
      scene.mesh.positions.push_back(p + d);
      scene.mesh.normals.push_back(glm::normalize(d));
      skin.joints.push_back(static_cast<std::uint16_t>(j));
      skin.weights.push_back(1.0f);
    }
    for (std::uint32_t i : {0u, 2u, 1u, 0u, 1u, 3u, 0u, 3u, 2u, 1u, 2u, 3u}) {
      scene.mesh.indices.push_back(base + i);
    }
  }
  scene.skin = std::move(skin);
  return scene;
}

}  // namespace vistel::test
