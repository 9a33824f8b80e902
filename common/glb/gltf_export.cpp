#include "common/glb/gltf_export.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <nlohmann/json.hpp>

#include "common/base/file.hpp"
#include "common/glb/glb_builder.hpp"
#include "common/glb/glb_container.hpp"
#include "common/math/transform.hpp"

namespace vistel {
namespace {

using nlohmann::json;

bool finite3(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

int addVec3s(GlbBuilder& b, std::span<const glm::vec3> values, int target, bool bounds) {
  return b.addFloats(
      std::span<const float>(reinterpret_cast<const float*>(values.data()), values.size() * 3), 3,
      "VEC3", target, bounds);
}

Status checkScene(const GltfScene& scene) {
  const GltfMesh& mesh = scene.mesh;
  const std::size_t n = mesh.positions.size();
  if (n == 0) return fail("mesh has no vertices");
  if (n > std::numeric_limits<std::uint32_t>::max() - 1) return fail("mesh has too many vertices");
  if (!mesh.normals.empty() && mesh.normals.size() != n) {
    return fail("mesh has {} normals for {} vertices", mesh.normals.size(), n);
  }
  if (mesh.indices.empty() || mesh.indices.size() % 3 != 0) {
    return fail("mesh has {} indices (need a positive multiple of 3)", mesh.indices.size());
  }
  for (std::size_t i = 0; i < mesh.indices.size(); ++i) {
    if (mesh.indices[i] >= n)
      return fail("triangle {} refers to vertex {} of {}", i / 3, mesh.indices[i], n);
  }
  for (std::size_t v = 0; v < n; ++v) {
    if (!finite3(mesh.positions[v])) return fail("vertex {} has a non-finite position", v);
    if (!mesh.normals.empty() && !finite3(mesh.normals[v]))
      return fail("vertex {} has a non-finite normal", v);
  }
  if (scene.skin) {
    const GltfSkin& skin = *scene.skin;
    const std::size_t nj = skin.joint_names.size();
    const auto k = static_cast<std::size_t>(skin.influences);
    if (nj == 0 || nj >= 65535) return fail("skin has {} joints (1..65534)", nj);
    if (skin.parents.size() != nj || skin.joint_model.size() != nj) {
      return fail("skin arrays disagree: {} names, {} parents, {} transforms", nj,
                  skin.parents.size(), skin.joint_model.size());
    }
    for (std::size_t j = 0; j < nj; ++j) {
      const int p = skin.parents[j];
      if (j == 0 ? p != kNoParent : (p < 0 || static_cast<std::size_t>(p) >= j)) {
        return fail("joint {} '{}' has parent {} (joint 0 must be the root, parents first)", j,
                    skin.joint_names[j], p);
      }
      const float det = glm::determinant(glm::mat3(skin.joint_model[j]));
      if (!std::isfinite(det) || std::abs(det) < 1e-12f) {
        return fail("joint {} '{}' has a singular or non-finite transform", j, skin.joint_names[j]);
      }
    }
    if (skin.influences < 1 || skin.influences > kMaxInfluences) {
      return fail("skin has {} influences per vertex (1..{})", skin.influences, kMaxInfluences);
    }
    if (skin.joints.size() != n * k || skin.weights.size() != n * k) {
      return fail("skin has {} joint slots and {} weights for {} vertices x {} influences",
                  skin.joints.size(), skin.weights.size(), n, k);
    }
    for (std::size_t v = 0; v < n; ++v) {
      float sum = 0.0f;
      for (std::size_t s = 0; s < k; ++s) {
        const float w = skin.weights[v * k + s];
        if (!(w >= 0.0f) || !std::isfinite(w)) return fail("vertex {} has weight {}", v, w);
        if (w > 0.0f && skin.joints[v * k + s] >= nj) {
          return fail("vertex {} is bound to joint {} of {}", v, skin.joints[v * k + s], nj);
        }
        sum += w;
      }
      if (!(sum > 0.0f)) return fail("vertex {} has no weight", v);
    }
  }
  if (Status s = validateLook(scene.look, n, mesh.indices.size()); !s) {
    return withContext("look", s.error());
  }
  if (!scene.frames.empty()) {
    if (!(scene.frame_time > 0.0) || !std::isfinite(scene.frame_time)) {
      return fail("frame time {} must be positive", scene.frame_time);
    }
    if (scene.frames.size() > kMaxGltfFrames) {
      return fail("{} frames (at most {} in one file)", scene.frames.size(), kMaxGltfFrames);
    }
    const bool normals = !scene.frames[0].normals.empty();
    for (std::size_t f = 0; f < scene.frames.size(); ++f) {
      const GltfFrame& frame = scene.frames[f];
      if (frame.positions.size() != n) {
        return fail("frame {} has {} positions for {} vertices", f, frame.positions.size(), n);
      }
      if (normals != !frame.normals.empty() || (normals && frame.normals.size() != n)) {
        return fail("frame {} has {} normals (every frame needs {} or none)", f,
                    frame.normals.size(), n);
      }
      for (std::size_t v = 0; v < n; ++v) {
        if (!finite3(frame.positions[v]) || (normals && !finite3(frame.normals[v]))) {
          return fail("frame {} vertex {} is not finite", f, v);
        }
      }
    }
  }
  return {};
}

glm::vec3 unitOrUp(const glm::vec3& v) {
  const float len = glm::length(v);
  return len > 1e-12f ? v / len : glm::vec3(0.0f, 1.0f, 0.0f);
}

// Slots per vertex: joints merged, zero slots (joint 0, weight 0) last, normalised so
// that the float sum is 1 to rounding. Writes 4 or 8 slots per vertex.
void normalisedSlots(const GltfSkin& skin, std::size_t nvert, int slots,
                     std::vector<std::uint16_t>& joints, std::vector<float>& weights) {
  const auto k = static_cast<std::size_t>(skin.influences);
  const auto out_k = static_cast<std::size_t>(slots);
  joints.assign(nvert * out_k, 0);
  weights.assign(nvert * out_k, 0.0f);
  std::vector<std::pair<std::uint16_t, double>> list;
  for (std::size_t v = 0; v < nvert; ++v) {
    list.clear();
    double total = 0.0;
    for (std::size_t s = 0; s < k; ++s) {
      const float w = skin.weights[v * k + s];
      if (w <= 0.0f) continue;
      const std::uint16_t j = skin.joints[v * k + s];
      auto it = std::find_if(list.begin(), list.end(), [j](const auto& e) { return e.first == j; });
      if (it == list.end()) {
        list.emplace_back(j, w);
      } else {
        it->second += w;
      }
      total += w;
    }
    std::sort(list.begin(), list.end(),
              [](const auto& a, const auto& b) { return a.second > b.second; });
    float sum = 0.0f;
    for (std::size_t s = 0; s < list.size(); ++s) {
      joints[v * out_k + s] = list[s].first;
      weights[v * out_k + s] = static_cast<float>(list[s].second / total);
      sum += weights[v * out_k + s];
    }
    float& strongest = weights[v * out_k];
    strongest = std::min(1.0f, strongest + (1.0f - sum));
  }
}

// Column-major floats of a matrix.
void appendMatrix(const glm::mat4& m, std::vector<float>& out) {
  for (int c = 0; c < 4; ++c) {
    for (int r = 0; r < 4; ++r) out.push_back(m[c][r]);
  }
}

}  // namespace

Result<std::vector<std::uint8_t>> encodeGlb(const GltfScene& scene) {
  if (Status s = checkScene(scene); !s) return withContext("glTF export", s.error());
  const GltfMesh& mesh = scene.mesh;
  const std::size_t nvert = mesh.positions.size();
  GlbBuilder b;
  json primitive = {{"mode", 4}};
  json& attributes = primitive["attributes"];

  // Base mesh: positions, unit normals, triangles.
  attributes["POSITION"] = addVec3s(b, mesh.positions, kGltfArrayBuffer, true);
  std::vector<glm::vec3> base_normals;
  if (!mesh.normals.empty()) {
    base_normals.resize(nvert);
    for (std::size_t v = 0; v < nvert; ++v) base_normals[v] = unitOrUp(mesh.normals[v]);
    attributes["NORMAL"] = addVec3s(b, base_normals, kGltfArrayBuffer, true);
  }
  const bool with_uvs = !scene.look.uvs.empty();
  if (with_uvs) {
    attributes["TEXCOORD_0"] =
        b.addFloats(std::span<const float>(reinterpret_cast<const float*>(scene.look.uvs.data()),
                                           scene.look.uvs.size() * 2),
                    2, "VEC2", kGltfArrayBuffer, false);
  }

  json nodes = json::array();
  json mesh_node = {{"name", mesh.name}, {"mesh", 0}};
  json root_nodes = json::array({0});
  json skins = json::array();

  // Skin: JOINTS_n / WEIGHTS_n, joint nodes in the given posture, inverse bind matrices.
  if (scene.skin) {
    const GltfSkin& skin = *scene.skin;
    const int slots = skin.influences <= 4 ? 4 : 8;
    std::vector<std::uint16_t> joints;
    std::vector<float> weights;
    normalisedSlots(skin, nvert, slots, joints, weights);
    for (int set = 0; set < slots / 4; ++set) {
      std::vector<std::uint16_t> js(nvert * 4);
      std::vector<float> ws(nvert * 4);
      for (std::size_t v = 0; v < nvert; ++v) {
        for (std::size_t s = 0; s < 4; ++s) {
          js[v * 4 + s] =
              joints[v * static_cast<std::size_t>(slots) + static_cast<std::size_t>(set) * 4 + s];
          ws[v * 4 + s] =
              weights[v * static_cast<std::size_t>(slots) + static_cast<std::size_t>(set) * 4 + s];
        }
      }
      attributes[fmt::format("JOINTS_{}", set)] =
          b.addIntegers(js, kGltfUnsignedShort, "VEC4", 4, kGltfArrayBuffer);
      attributes[fmt::format("WEIGHTS_{}", set)] =
          b.addFloats(ws, 4, "VEC4", kGltfArrayBuffer, false);
    }

    const std::size_t nj = skin.joint_names.size();
    std::vector<float> ibm;
    ibm.reserve(nj * 16);
    json joint_nodes = json::array();
    std::vector<json> children(nj, json::array());
    for (std::size_t j = 0; j < nj; ++j) {
      const int p = skin.parents[j];
      const glm::mat4 local =
          p == kNoParent
              ? skin.joint_model[j]
              : glm::inverse(skin.joint_model[static_cast<std::size_t>(p)]) * skin.joint_model[j];
      const Transform t = Transform::fromMatrix(local);
      const glm::quat q = glm::normalize(t.rotation);
      json node = {{"name", skin.joint_names[j]},
                   {"translation", {t.translation.x, t.translation.y, t.translation.z}},
                   {"rotation", {q.x, q.y, q.z, q.w}}};
      if (glm::any(glm::greaterThan(glm::abs(t.scale - glm::vec3(1.0f)), glm::vec3(1e-6f)))) {
        node["scale"] = {t.scale.x, t.scale.y, t.scale.z};
      }
      nodes.push_back(std::move(node));  // joint j is node j + 1 (after the mesh node)
      joint_nodes.push_back(static_cast<int>(j) + 1);
      if (p != kNoParent) children[static_cast<std::size_t>(p)].push_back(static_cast<int>(j) + 1);
      glm::mat4 inv = glm::inverse(skin.joint_model[j]);
      inv[0][3] = inv[1][3] = inv[2][3] = 0.0f;
      inv[3][3] = 1.0f;
      appendMatrix(inv, ibm);
    }
    for (std::size_t j = 0; j < nj; ++j) {
      if (!children[j].empty()) nodes[j]["children"] = children[j];
    }
    const int ibm_accessor = b.addFloats(ibm, 16, "MAT4", 0, false);
    skins.push_back(
        {{"joints", joint_nodes}, {"inverseBindMatrices", ibm_accessor}, {"skeleton", 1}});
    mesh_node["skin"] = 0;
    root_nodes.push_back(1);
  }

  // Vertex animation: one morph target per frame, a STEP weights channel.
  json animations = json::array();
  json mesh_json = {{"name", mesh.name}};
  if (!scene.frames.empty()) {
    const std::size_t nf = scene.frames.size();
    const bool with_normals = !base_normals.empty() && !scene.frames[0].normals.empty();
    json targets = json::array();
    std::vector<glm::vec3> delta(nvert);
    for (const GltfFrame& frame : scene.frames) {
      json target;
      for (std::size_t v = 0; v < nvert; ++v) delta[v] = frame.positions[v] - mesh.positions[v];
      target["POSITION"] = addVec3s(b, delta, kGltfArrayBuffer, true);
      if (with_normals) {
        for (std::size_t v = 0; v < nvert; ++v)
          delta[v] = unitOrUp(frame.normals[v]) - base_normals[v];
        target["NORMAL"] = addVec3s(b, delta, kGltfArrayBuffer, false);
      }
      targets.push_back(std::move(target));
    }
    primitive["targets"] = std::move(targets);
    mesh_json["weights"] = std::vector<float>(nf, 0.0f);

    std::vector<float> times(nf);
    std::vector<float> one_hot(nf * nf, 0.0f);
    for (std::size_t f = 0; f < nf; ++f) {
      times[f] = static_cast<float>(static_cast<double>(f) * scene.frame_time);
      one_hot[f * nf + f] = 1.0f;
    }
    for (std::size_t f = 1; f < nf; ++f) {
      if (!(times[f] > times[f - 1])) {
        return fail("glTF export: frame times are not increasing at frame {} (frame time {} s)", f,
                    scene.frame_time);
      }
    }
    const int input = b.addFloats(times, 1, "SCALAR", 0, true);
    const int output = b.addFloats(one_hot, 1, "SCALAR", 0, false);
    animations.push_back(
        {{"name", "frames"},
         {"samplers",
          json::array({{{"input", input}, {"output", output}, {"interpolation", "STEP"}}})},
         {"channels",
          json::array({{{"sampler", 0}, {"target", {{"node", 0}, {"path", "weights"}}}}})}});
  }
  // One primitive per submesh (the attributes and targets shared), with its material.
  json primitives = json::array();
  for (const AvatarSubmesh& sm : effectiveSubmeshes(scene.look, mesh.indices.size())) {
    json prim = primitive;
    prim["indices"] = b.addIntegers(
        std::span<const std::uint32_t>(mesh.indices).subspan(sm.first_index, sm.index_count),
        kGltfUnsignedInt, "SCALAR", 1, kGltfElementArrayBuffer);
    if (sm.material >= 0) prim["material"] = sm.material;
    primitives.push_back(std::move(prim));
  }
  mesh_json["primitives"] = std::move(primitives);
  GltfLooks looks;
  looks.append(scene.look, b);

  // The document.
  nodes.insert(nodes.begin(), mesh_node);
  if (b.bin().size() > std::numeric_limits<std::uint32_t>::max() - 1024) {
    return fail("glTF export: {} bytes of data exceed the 4 GiB GLB limit", b.bin().size());
  }
  while (b.bin().size() % 4 != 0) b.bin().push_back(0);
  json doc = {{"asset", {{"version", "2.0"}, {"generator", scene.generator}}},
              {"scene", 0},
              {"scenes", json::array({{{"nodes", root_nodes}}})},
              {"nodes", nodes},
              {"meshes", json::array({mesh_json})},
              {"accessors", b.accessors()},
              {"bufferViews", b.views()},
              {"buffers", json::array({{{"byteLength", b.bin().size()}}})}};
  if (!skins.empty()) doc["skins"] = skins;
  looks.writeTo(doc);
  if (!animations.empty()) doc["animations"] = animations;
  return assembleGlb(doc.dump(), b.bin());
}

Status writeGlb(const std::string& path, const GltfScene& scene) {
  Result<std::vector<std::uint8_t>> bytes = encodeGlb(scene);
  if (!bytes) return withContext(path, bytes.error());
  return writeFileBytes(path, *bytes);
}

GltfSkin gltfSkinFromAvatar(const AvatarModel& avatar, std::span<const glm::mat4> joint_model) {
  GltfSkin skin;
  skin.joint_names = avatar.skeleton.names;
  skin.parents = avatar.skeleton.parents;
  skin.joint_model.assign(joint_model.begin(), joint_model.end());
  skin.influences = avatar.skin.influences;
  skin.joints = avatar.skin.joints;
  skin.weights = avatar.skin.weights;
  return skin;
}

GltfScene posedAvatarScene(const AvatarModel& avatar, std::span<const glm::mat4> joint_model,
                           std::span<const glm::vec3> positions,
                           std::span<const glm::vec3> normals) {
  GltfScene scene;
  scene.mesh.name = avatar.name.empty() ? "avatar" : avatar.name;
  scene.mesh.positions.assign(positions.begin(), positions.end());
  scene.mesh.normals.assign(normals.begin(), normals.end());
  scene.mesh.indices = avatar.skin.indices;
  scene.skin = gltfSkinFromAvatar(avatar, joint_model);
  scene.look = avatar.look;
  return scene;
}

GltfScene restAvatarScene(const AvatarModel& avatar) {
  const std::vector<glm::mat4> rest = restModelTransforms(avatar.skeleton);
  return posedAvatarScene(avatar, rest, avatar.skin.positions, avatar.skin.normals);
}

void keepLargestInfluences(GltfSkin& skin, int k) {
  if (k < 1 || skin.influences <= k) return;
  const auto from_slots = static_cast<std::size_t>(skin.influences);
  const auto to_slots = static_cast<std::size_t>(k);
  const std::size_t nvert = skin.weights.size() / from_slots;
  std::vector<std::uint16_t> joints(nvert * to_slots, 0);
  std::vector<float> weights(nvert * to_slots, 0.0f);
  std::vector<std::size_t> order(from_slots);
  for (std::size_t v = 0; v < nvert; ++v) {
    const std::size_t base = v * from_slots;
    for (std::size_t s = 0; s < from_slots; ++s) order[s] = base + s;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return skin.weights[a] > skin.weights[b];
    });
    float sum = 0.0f;
    for (std::size_t s = 0; s < to_slots; ++s) sum += skin.weights[order[s]];
    for (std::size_t s = 0; s < to_slots; ++s) {
      joints[v * to_slots + s] = skin.joints[order[s]];
      weights[v * to_slots + s] =
          sum > 0.0f ? skin.weights[order[s]] / sum : (s == 0 ? 1.0f : 0.0f);
    }
  }
  skin.influences = k;
  skin.joints = std::move(joints);
  skin.weights = std::move(weights);
}

int GltfLooks::append(const AvatarLook& look, GlbBuilder& b) {
  const int first_material = static_cast<int>(materials_.size());
  const bool with_uvs = !look.uvs.empty();
  std::vector<int> texture_of(look.textures.size(), -1);
  auto textureIndex = [&](int t) {
    auto& slot = texture_of[static_cast<std::size_t>(t)];
    if (slot >= 0) return slot;
    const AvatarTexture& tex = look.textures[static_cast<std::size_t>(t)];
    const int view = b.addView(tex.encoded.data(), tex.encoded.size(), 0);
    json image = {{"bufferView", view}, {"mimeType", tex.mime}};
    if (!tex.name.empty()) image["name"] = tex.name;
    images_.push_back(std::move(image));
    textures_.push_back({{"sampler", 0}, {"source", images_.size() - 1}});
    slot = static_cast<int>(textures_.size()) - 1;
    return slot;
  };
  for (const AvatarMaterial& m : look.materials) {
    json pbr = {
        {"baseColorFactor", {m.base_color.r, m.base_color.g, m.base_color.b, m.base_color.a}},
        {"metallicFactor", m.metallic},
        {"roughnessFactor", m.roughness}};
    json mat = json::object();
    if (!m.name.empty()) mat["name"] = m.name;
    if (with_uvs && m.base_color_texture >= 0) {
      pbr["baseColorTexture"] = {{"index", textureIndex(m.base_color_texture)}};
    }
    mat["pbrMetallicRoughness"] = std::move(pbr);
    if (with_uvs && m.normal_texture >= 0) {
      mat["normalTexture"] = {{"index", textureIndex(m.normal_texture)}, {"scale", m.normal_scale}};
    }
    if (m.alpha_mode == AlphaMode::kMask) {
      mat["alphaMode"] = "MASK";
      mat["alphaCutoff"] = m.alpha_cutoff;
    } else if (m.alpha_mode == AlphaMode::kBlend) {
      mat["alphaMode"] = "BLEND";
    }
    if (m.double_sided) mat["doubleSided"] = true;
    materials_.push_back(std::move(mat));
  }
  return first_material;
}

void GltfLooks::writeTo(json& doc) const {
  if (!materials_.empty()) doc["materials"] = materials_;
  if (textures_.empty()) return;
  doc["textures"] = textures_;
  doc["images"] = images_;
  // Linear magnification, trilinear minification, repeat (glTF's defaults, said).
  doc["samplers"] =
      json::array({{{"magFilter", 9729}, {"minFilter", 9987}, {"wrapS", 10497}, {"wrapT", 10497}}});
}

}  // namespace vistel
