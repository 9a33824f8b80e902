#include "server/web/avatar_glb.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <numeric>

#include <nlohmann/json.hpp>

namespace vistel::server {
namespace {

constexpr std::uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr std::uint32_t kChunkJson = 0x4E4F534A;
constexpr std::uint32_t kChunkBin = 0x004E4942;
constexpr int kFloat = 5126, kUnsignedShort = 5123, kUnsignedInt = 5125;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

void append(std::vector<std::uint8_t>& out, const void* data, std::size_t bytes) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  out.insert(out.end(), p, p + bytes);
}
void appendU32(std::vector<std::uint8_t>& out, std::uint32_t v) { append(out, &v, 4); }

struct Builder {
  std::vector<std::uint8_t> bin;
  nlohmann::json views = nlohmann::json::array();
  nlohmann::json accessors = nlohmann::json::array();

  // A buffer view of `bytes` (4-aligned) and one accessor over it; returns the accessor.
  int add(const void* data, std::size_t bytes, int component, std::size_t count, const char* type,
          int target, nlohmann::json extra = nlohmann::json::object()) {
    while (bin.size() % 4 != 0) bin.push_back(0);
    nlohmann::json view = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes}};
    if (target != 0) view["target"] = target;
    append(bin, data, bytes);
    views.push_back(view);
    nlohmann::json accessor = {{"bufferView", views.size() - 1},
                               {"componentType", component},
                               {"count", count},
                               {"type", type}};
    accessor.update(extra);
    accessors.push_back(accessor);
    return static_cast<int>(accessors.size()) - 1;
  }
};

}  // namespace

Result<std::vector<std::uint8_t>> avatarGlb(const AvatarModel& avatar) {
  if (Status st = validateAvatar(avatar); !st) return st.error();
  const Skeleton& skeleton = avatar.skeleton;
  const SkinMesh& skin = avatar.skin;
  const std::size_t nvert = skin.positions.size();
  const int njoint = skeleton.jointCount();
  if (skin.indices.empty() || nvert == 0) return fail("avatar '{}' has no triangles", avatar.name);

  // Positions and their bounds; unit normals.
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const glm::vec3& p : skin.positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  std::vector<glm::vec3> normals(nvert);
  if (skin.normals.size() == nvert) {
    std::copy(skin.normals.begin(), skin.normals.end(), normals.begin());
  } else {
    computeVertexNormals(skin.positions, skin.indices, normals);
  }
  for (glm::vec3& n : normals) {
    const float len = glm::length(n);
    n = std::isfinite(len) && len > 1e-12f ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
  }

  // Four influences per vertex: the largest weights, renormalised.
  const int k = std::max(1, skin.influences);
  std::vector<std::uint16_t> joints(nvert * 4, 0);
  std::vector<float> weights(nvert * 4, 0.0f);
  std::vector<int> order(static_cast<std::size_t>(k));
  for (std::size_t v = 0; v < nvert; ++v) {
    const std::size_t base = v * static_cast<std::size_t>(k);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
      return skin.weights[base + static_cast<std::size_t>(a)] >
             skin.weights[base + static_cast<std::size_t>(b)];
    });
    float sum = 0.0f;
    for (int s = 0; s < std::min(4, k); ++s) {
      const std::size_t from = base + static_cast<std::size_t>(order[static_cast<std::size_t>(s)]);
      joints[v * 4 + static_cast<std::size_t>(s)] = skin.joints[from];
      weights[v * 4 + static_cast<std::size_t>(s)] = skin.weights[from];
      sum += skin.weights[from];
    }
    if (sum <= 0.0f) {
      weights[v * 4] = 1.0f;  // validateSkinMesh makes this unreachable; stay valid anyway
      sum = 1.0f;
    }
    for (int s = 0; s < 4; ++s) weights[v * 4 + static_cast<std::size_t>(s)] /= sum;
  }
  std::vector<float> ibm(static_cast<std::size_t>(njoint) * 16);
  for (int j = 0; j < njoint; ++j) {
    std::memcpy(&ibm[static_cast<std::size_t>(j) * 16],
                &skeleton.inverse_bind[static_cast<std::size_t>(j)][0][0], 16 * sizeof(float));
  }

  Builder b;
  const int position = b.add(skin.positions.data(), nvert * 12, kFloat, nvert, "VEC3", kArrayBuffer,
                             {{"min", {lo.x, lo.y, lo.z}}, {"max", {hi.x, hi.y, hi.z}}});
  const int normal = b.add(normals.data(), nvert * 12, kFloat, nvert, "VEC3", kArrayBuffer);
  const int index = b.add(skin.indices.data(), skin.indices.size() * 4, kUnsignedInt,
                          skin.indices.size(), "SCALAR", kElementArrayBuffer);
  const int joint =
      b.add(joints.data(), joints.size() * 2, kUnsignedShort, nvert, "VEC4", kArrayBuffer);
  const int weight = b.add(weights.data(), weights.size() * 4, kFloat, nvert, "VEC4", kArrayBuffer);
  const int inverse_bind =
      b.add(ibm.data(), ibm.size() * 4, kFloat, static_cast<std::size_t>(njoint), "MAT4", 0);

  nlohmann::json nodes = nlohmann::json::array();
  nodes.push_back({{"name", avatar.name.empty() ? std::string("avatar") : avatar.name},
                   {"mesh", 0},
                   {"skin", 0}});
  std::vector<std::vector<int>> children(static_cast<std::size_t>(njoint));
  for (int j = 1; j < njoint; ++j) {
    children[static_cast<std::size_t>(skeleton.parents[static_cast<std::size_t>(j)])].push_back(j +
                                                                                                1);
  }
  nlohmann::json skin_joints = nlohmann::json::array();
  for (int j = 0; j < njoint; ++j) {
    const Transform& t = skeleton.rest_local[static_cast<std::size_t>(j)];
    nlohmann::json node = {{"name", skeleton.names[static_cast<std::size_t>(j)]},
                           {"translation", {t.translation.x, t.translation.y, t.translation.z}},
                           {"rotation", {t.rotation.x, t.rotation.y, t.rotation.z, t.rotation.w}}};
    if (t.scale != glm::vec3(1.0f)) node["scale"] = {t.scale.x, t.scale.y, t.scale.z};
    if (!children[static_cast<std::size_t>(j)].empty())
      node["children"] = children[static_cast<std::size_t>(j)];
    nodes.push_back(node);
    skin_joints.push_back(j + 1);
  }

  nlohmann::json doc = {
      {"asset", {{"version", "2.0"}, {"generator", "vistel-server"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0, 1}}}}},
      {"nodes", nodes},
      {"meshes",
       {{{"name", "skin"},
         {"primitives",
          {{{"attributes",
             {{"POSITION", position},
              {"NORMAL", normal},
              {"JOINTS_0", joint},
              {"WEIGHTS_0", weight}}},
            {"indices", index},
            {"material", 0}}}}}}},
      {"materials",
       {{{"name", "skin"},
         {"pbrMetallicRoughness",
          {{"baseColorFactor", {0.8, 0.78, 0.75, 1.0}},
           {"metallicFactor", 0.0},
           {"roughnessFactor", 0.8}}}}}},
      {"skins",
       {{{"joints", skin_joints}, {"inverseBindMatrices", inverse_bind}, {"skeleton", 1}}}},
      {"accessors", b.accessors},
      {"bufferViews", b.views},
      {"buffers", {{{"byteLength", b.bin.size()}}}},
  };
  std::string json = doc.dump();
  while (json.size() % 4 != 0) json.push_back(' ');
  while (b.bin.size() % 4 != 0) b.bin.push_back(0);
  const std::size_t total = 12 + 8 + json.size() + 8 + b.bin.size();
  if (total > 0xffffffffu) return fail("avatar '{}' is too large for a .glb", avatar.name);

  std::vector<std::uint8_t> out;
  out.reserve(total);
  appendU32(out, kGlbMagic);
  appendU32(out, 2);
  appendU32(out, static_cast<std::uint32_t>(total));
  appendU32(out, static_cast<std::uint32_t>(json.size()));
  appendU32(out, kChunkJson);
  append(out, json.data(), json.size());
  appendU32(out, static_cast<std::uint32_t>(b.bin.size()));
  appendU32(out, kChunkBin);
  append(out, b.bin.data(), b.bin.size());
  return out;
}

}  // namespace vistel::server
