#include "common/record/room_glb.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "common/glb/glb_builder.hpp"
#include "common/glb/glb_container.hpp"
#include "common/glb/gltf_export.hpp"
#include "common/math/transform.hpp"

namespace vistel::record {
namespace {

using nlohmann::json;

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}
bool finite(const glm::quat& q) {
  return std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z) && std::isfinite(q.w);
}

glm::vec3 unitOrUp(const glm::vec3& v) {
  const float len = glm::length(v);
  return len > 1e-12f && std::isfinite(len) ? v / len : glm::vec3(0.0f, 1.0f, 0.0f);
}

glm::quat unitOrIdentity(const glm::quat& q) {
  const float len = glm::length(q);
  return len > 1e-12f && std::isfinite(len) ? q / len : glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
}

void append(std::vector<float>& out, const glm::vec3& v) { out.insert(out.end(), {v.x, v.y, v.z}); }
void append(std::vector<float>& out, const glm::quat& q) {
  const glm::quat u = unitOrIdentity(q);
  out.insert(out.end(), {u.x, u.y, u.z, u.w});
}

json toJson(const glm::vec3& v) { return {v.x, v.y, v.z}; }
json toJson(const glm::quat& q) {
  const glm::quat u = unitOrIdentity(q);
  return {u.x, u.y, u.z, u.w};
}

bool nearOne(const glm::vec3& s) {
  return glm::all(glm::lessThan(glm::abs(s - glm::vec3(1.0f)), glm::vec3(1e-6f)));
}

// The document being built: nodes, meshes, skins and the animation's samplers and channels.
class RoomDocument {
 public:
  explicit RoomDocument(RecordingSummary& summary) : summary_(summary) {}

  int addNode(json node) {
    nodes_.push_back(std::move(node));
    return static_cast<int>(nodes_.size()) - 1;
  }
  json& node(int i) { return nodes_[static_cast<std::size_t>(i)]; }
  void addRoot(int node) { roots_.push_back(node); }

  // A track as the node's static value (constant, or never sampled: `rest`) or a LINEAR
  // channel.
  template <typename V>
  Status setTrack(int node_index, const char* path, const KeyframeTrack<V>& track, const V& rest,
                  const V& identity) {
    for (const V& v : track.values()) {
      if (!finite(v)) return fail("{} of node '{}' is not finite", path, name(node_index));
    }
    if (track.times().empty() || track.constant()) {
      const V v = track.times().empty() ? rest : track.values().front();
      if (v != identity) node(node_index)[path] = toJson(v);
      return {};
    }
    std::vector<float> times, values;
    for (std::size_t i = 0; i < track.times().size(); ++i) {
      const auto t = static_cast<float>(track.times()[i]);
      if (!times.empty() && !(t > times.back())) continue;  // float32 cannot keep it apart
      times.push_back(t);
      append(values, track.values()[i]);
    }
    addChannel(node_index, path, times, values, sizeof(V) / sizeof(float), "LINEAR");
    return {};
  }

  // A STEP scale channel: 1 within the spans, 0 outside; nothing when one span covers the
  // whole recording.
  void setVisibility(int node_index, const std::vector<Span>& spans, double duration) {
    if (spans.empty()) return;
    if (spans.size() == 1 && spans[0].start <= 0.0 && spans[0].end >= duration) return;
    std::vector<float> times, values;
    auto key = [&](double t, float s) {
      const auto tf = static_cast<float>(t);
      if (!times.empty() && !(tf > times.back())) {
        values.resize(values.size() - 3);  // the later state wins at an equal time
        times.pop_back();
      }
      times.push_back(tf);
      values.insert(values.end(), {s, s, s});
    };
    if (spans[0].start > 0.0) key(0.0, 0.0f);
    for (const Span& span : spans) {
      key(span.start, 1.0f);
      if (span.end < duration) key(span.end, 0.0f);
    }
    if (times.size() == 1 && values[0] == 1.0f) return;
    addChannel(node_index, "scale", times, values, 3, "STEP");
  }

  void addChannel(int node_index, const char* path, const std::vector<float>& times,
                  const std::vector<float>& values, std::size_t components,
                  const char* interpolation) {
    const int input = bin_.addFloats(times, 1, "SCALAR", 0, true);
    const int output = bin_.addFloats(values, static_cast<int>(components),
                                      components == 4 ? "VEC4" : "VEC3", 0, false);
    samplers_.push_back({{"input", input}, {"output", output}, {"interpolation", interpolation}});
    channels_.push_back({{"sampler", static_cast<int>(samplers_.size()) - 1},
                         {"target", {{"node", node_index}, {"path", path}}}});
    summary_.keys += static_cast<std::int64_t>(times.size());
  }

  // The mesh of an avatar's skin (skinned: with JOINTS_n / WEIGHTS_n), made once per model.
  int meshFor(const AvatarModel& avatar, bool skinned) {
    const auto key = std::make_pair(&avatar, skinned);
    if (auto found = meshes_by_model_.find(key); found != meshes_by_model_.end())
      return found->second;
    const SkinMesh& skin = avatar.skin;
    const std::size_t nvert = skin.positions.size();
    json attributes;
    // Unskinned (a prop): the vertices in the root joint's space, so that the node's
    // translation is the centre.
    std::vector<float> positions, normals;
    positions.reserve(nvert * 3);
    normals.reserve(nvert * 3);
    const glm::mat4 to_joint = skinned || avatar.skeleton.inverse_bind.empty()
                                   ? glm::mat4(1.0f)
                                   : avatar.skeleton.inverse_bind[0];
    for (std::size_t v = 0; v < nvert; ++v) {
      append(positions, glm::vec3(to_joint * glm::vec4(skin.positions[v], 1.0f)));
      const glm::vec3 n = v < skin.normals.size() ? skin.normals[v] : glm::vec3(0.0f, 1.0f, 0.0f);
      append(normals, unitOrUp(glm::mat3(to_joint) * n));
    }
    attributes["POSITION"] = bin_.addFloats(positions, 3, "VEC3", kGltfArrayBuffer, true);
    attributes["NORMAL"] = bin_.addFloats(normals, 3, "VEC3", kGltfArrayBuffer, false);
    if (skinned) addSkinAttributes(avatar, attributes);
    // The avatar's look: texture coordinates, and one primitive per submesh with its
    // material (the look's materials appended to the document's).
    const AvatarLook& look = avatar.look;
    const bool with_look = !look.materials.empty() || look.uvs.size() == nvert;
    int first_material = 0;
    if (with_look) {
      if (look.uvs.size() == nvert) {
        attributes["TEXCOORD_0"] = bin_.addFloats(
            std::span<const float>(reinterpret_cast<const float*>(look.uvs.data()), nvert * 2), 2,
            "VEC2", kGltfArrayBuffer, false);
      }
      first_material = looks_.append(look, bin_);
    }
    json primitives = json::array();
    for (const AvatarSubmesh& sm : effectiveSubmeshes(look, skin.indices.size())) {
      json primitive = {{"attributes", attributes}, {"mode", 4}};
      const auto part =
          std::span<const std::uint32_t>(skin.indices).subspan(sm.first_index, sm.index_count);
      if (nvert < 65535) {
        std::vector<std::uint16_t> indices(part.begin(), part.end());
        primitive["indices"] =
            bin_.addIntegers(indices, kGltfUnsignedShort, "SCALAR", 1, kGltfElementArrayBuffer);
      } else {
        primitive["indices"] =
            bin_.addIntegers(part, kGltfUnsignedInt, "SCALAR", 1, kGltfElementArrayBuffer);
      }
      if (with_look && sm.material >= 0) primitive["material"] = first_material + sm.material;
      primitives.push_back(std::move(primitive));
    }
    meshes_.push_back({{"name", avatar.name.empty() ? std::string("avatar") : avatar.name},
                       {"primitives", std::move(primitives)}});
    const int index = static_cast<int>(meshes_.size()) - 1;
    meshes_by_model_.emplace(key, index);
    return index;
  }

  // The inverse bind matrices of an avatar's skeleton (affine; made once per model).
  int inverseBindFor(const AvatarModel& avatar) {
    if (auto found = ibm_by_model_.find(&avatar); found != ibm_by_model_.end())
      return found->second;
    std::vector<float> values;
    for (glm::mat4 m : avatar.skeleton.inverse_bind) {
      m[0][3] = m[1][3] = m[2][3] = 0.0f;
      m[3][3] = 1.0f;
      for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) values.push_back(m[c][r]);
      }
    }
    const int index = bin_.addFloats(values, 16, "MAT4", 0, false);
    ibm_by_model_.emplace(&avatar, index);
    return index;
  }

  int addSkin(json skin) {
    skins_.push_back(std::move(skin));
    return static_cast<int>(skins_.size()) - 1;
  }

  std::vector<std::uint8_t> glb(const std::string& generator) {
    json doc = {{"asset", {{"version", "2.0"}, {"generator", generator}}},
                {"scene", 0},
                {"scenes", json::array({{{"name", "room"}, {"nodes", roots_}}})},
                {"nodes", nodes_}};
    if (!meshes_.empty()) doc["meshes"] = meshes_;
    looks_.writeTo(doc);
    if (!skins_.empty()) doc["skins"] = skins_;
    if (!channels_.empty()) {
      doc["animations"] =
          json::array({{{"name", "room"}, {"samplers", samplers_}, {"channels", channels_}}});
    }
    std::vector<std::uint8_t>& bin = bin_.bin();
    while (bin.size() % 4 != 0) bin.push_back(0);
    if (!bin.empty()) {
      doc["accessors"] = bin_.accessors();
      doc["bufferViews"] = bin_.views();
      doc["buffers"] = json::array({{{"byteLength", bin.size()}}});
    }
    return assembleGlb(doc.dump(), bin);
  }

  std::size_t binSize() { return bin_.bin().size(); }

 private:
  std::string name(int node_index) {
    return node(node_index).value("name", fmt::format("#{}", node_index));
  }

  // JOINTS_n / WEIGHTS_n: a vertex's slots merged by joint, strongest first, renormalised
  // so that the float sum is 1 to rounding; unused slots are joint 0 with weight 0.
  void addSkinAttributes(const AvatarModel& avatar, json& attributes) {
    const SkinMesh& skin = avatar.skin;
    const std::size_t nvert = skin.positions.size();
    const auto k = static_cast<std::size_t>(skin.influences);
    const std::size_t sets = k <= 4 ? 1 : 2;
    const bool bytes = avatar.skeleton.jointCount() <= 256;
    std::vector<std::vector<std::uint16_t>> joints(sets, std::vector<std::uint16_t>(nvert * 4, 0));
    std::vector<std::vector<float>> weights(sets, std::vector<float>(nvert * 4, 0.0f));
    std::vector<std::pair<std::uint16_t, double>> list;
    for (std::size_t v = 0; v < nvert; ++v) {
      list.clear();
      double total = 0.0;
      for (std::size_t s = 0; s < k; ++s) {
        const float w = skin.weights[v * k + s];
        if (!(w > 0.0f)) continue;
        const std::uint16_t j = skin.joints[v * k + s];
        auto it =
            std::find_if(list.begin(), list.end(), [j](const auto& e) { return e.first == j; });
        if (it == list.end()) {
          list.emplace_back(j, w);
        } else {
          it->second += w;
        }
        total += w;
      }
      if (list.empty()) list.emplace_back(0, total = 1.0);  // validated avatars never get here
      std::sort(list.begin(), list.end(),
                [](const auto& a, const auto& b) { return a.second > b.second; });
      float sum = 0.0f;
      for (std::size_t s = 0; s < list.size() && s < sets * 4; ++s) {
        joints[s / 4][v * 4 + s % 4] = list[s].first;
        const auto w = static_cast<float>(list[s].second / total);
        weights[s / 4][v * 4 + s % 4] = w;
        sum += w;
      }
      float& strongest = weights[0][v * 4];
      strongest = std::min(1.0f, strongest + (1.0f - sum));
    }
    for (std::size_t set = 0; set < sets; ++set) {
      if (bytes) {
        std::vector<std::uint8_t> small(joints[set].begin(), joints[set].end());
        attributes[fmt::format("JOINTS_{}", set)] =
            bin_.addIntegers(small, kGltfUnsignedByte, "VEC4", 4, kGltfArrayBuffer);
      } else {
        attributes[fmt::format("JOINTS_{}", set)] =
            bin_.addIntegers(joints[set], kGltfUnsignedShort, "VEC4", 4, kGltfArrayBuffer);
      }
      attributes[fmt::format("WEIGHTS_{}", set)] =
          bin_.addFloats(weights[set], 4, "VEC4", kGltfArrayBuffer, false);
    }
  }

  RecordingSummary& summary_;
  GlbBuilder bin_;
  json nodes_ = json::array();
  json roots_ = json::array();
  json meshes_ = json::array();
  GltfLooks looks_;  // every avatar's look, appended once per model
  json skins_ = json::array();
  json samplers_ = json::array();
  json channels_ = json::array();
  std::map<std::pair<const AvatarModel*, bool>, int> meshes_by_model_;
  std::map<const AvatarModel*, int> ibm_by_model_;
};

const glm::quat kIdentity(1.0f, 0.0f, 0.0f, 0.0f);
const glm::vec3 kZero(0.0f);
const glm::vec3 kOne(1.0f);

// A member: its seat node, its joints below it, its skinned mesh node at the root.
Status addMember(RoomDocument& doc, const RecordedMember& rec, double duration) {
  const AvatarModel& avatar = *rec.avatar;
  const Skeleton& skeleton = avatar.skeleton;
  const auto nj = static_cast<std::size_t>(skeleton.jointCount());
  const int seat = doc.addNode({{"name", rec.name}});
  doc.addRoot(seat);
  if (Status st = doc.setTrack(seat, "translation", rec.seat_translation, kZero, kZero); !st)
    return st;
  if (Status st = doc.setTrack(seat, "rotation", rec.seat_rotation, kIdentity, kIdentity); !st)
    return st;
  doc.setVisibility(seat, rec.spans, duration);

  // Joints: node first + j, in skeleton order (parents first).
  json joint_nodes = json::array();
  const int first = seat + 1;
  for (std::size_t j = 0; j < nj; ++j) {
    const Transform& rest = skeleton.rest_local[j];
    const int n = doc.addNode({{"name", rec.name + ":" + skeleton.names[j]}});
    joint_nodes.push_back(n);
    const Vec3Track none;
    const Vec3Track& moves = j == 0                     ? rec.root_translation
                             : rec.translations.empty() ? none
                                                        : rec.translations[j];
    if (Status st = doc.setTrack(n, "translation", moves, rest.translation, kZero); !st) return st;
    if (Status st = doc.setTrack(n, "rotation", rec.rotations[j], rest.rotation, kIdentity); !st)
      return st;
    if (!nearOne(rest.scale)) doc.node(n)["scale"] = toJson(rest.scale);
    const int p = skeleton.parents[j];
    json& parent = p == kNoParent ? doc.node(seat) : doc.node(first + p);
    if (!parent.contains("children")) parent["children"] = json::array();
    parent["children"].push_back(n);
  }

  // The skin and the mesh node (a scene root: a skinned mesh ignores its node's transform).
  const int skin = doc.addSkin({{"name", rec.name},
                                {"joints", joint_nodes},
                                {"skeleton", first},
                                {"inverseBindMatrices", doc.inverseBindFor(avatar)}});
  const int mesh_node = doc.addNode(
      {{"name", rec.name + " avatar"}, {"mesh", doc.meshFor(avatar, true)}, {"skin", skin}});
  doc.addRoot(mesh_node);
  return {};
}

Status addProp(RoomDocument& doc, const RecordedProp& rec, double duration) {
  const int n = doc.addNode({{"name", rec.name}, {"mesh", doc.meshFor(*rec.model, false)}});
  doc.addRoot(n);
  if (Status st = doc.setTrack(n, "translation", rec.position, kZero, kZero); !st) return st;
  doc.setVisibility(n, rec.spans, duration);
  return {};
}

}  // namespace

Result<std::vector<std::uint8_t>> encodeRoomGlb(const RoomRecording& recording,
                                                RecordingSummary* summary_out) {
  RecordingSummary summary;
  summary.duration_s = recording.duration_s;
  summary.samples = recording.samples;
  RoomDocument doc(summary);
  for (const RecordedMember& rec : recording.members) {
    if (rec.spans.empty()) continue;
    if (!rec.avatar) {
      summary.warnings.push_back(
          fmt::format("member '{}': its avatar never arrived; left out", rec.name));
      ++summary.members_skipped;
      continue;
    }
    if (static_cast<std::size_t>(rec.avatar->skeleton.jointCount()) != rec.rotations.size()) {
      summary.warnings.push_back(
          fmt::format("member '{}': its postures have {} joints, its avatar {}; left out", rec.name,
                      rec.rotations.size(), rec.avatar->skeleton.jointCount()));
      ++summary.members_skipped;
      continue;
    }
    if (Status st = addMember(doc, rec, recording.duration_s); !st)
      return withContext("room recording", st.error());
    ++summary.members;
  }
  for (const RecordedProp& rec : recording.props) {
    if (rec.spans.empty()) continue;
    if (!rec.model) {
      summary.warnings.push_back(fmt::format("{}: no model for its spec; left out", rec.name));
      continue;
    }
    if (Status st = addProp(doc, rec, recording.duration_s); !st)
      return withContext("room recording", st.error());
    ++summary.props;
  }
  if (summary.members == 0 && summary.props == 0) {
    return fail("room recording: nothing to write ({} samples, {} members without an avatar)",
                recording.samples, summary.members_skipped);
  }
  if (doc.binSize() > std::numeric_limits<std::uint32_t>::max() - (64u << 20)) {
    return fail("room recording: {} bytes of data exceed the 4 GiB GLB limit", doc.binSize());
  }
  std::vector<std::uint8_t> bytes = doc.glb("vistel-client --record-room");
  if (summary_out) *summary_out = std::move(summary);
  return bytes;
}

}  // namespace vistel::record
