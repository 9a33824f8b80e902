#include "tests/motion/glb_skeleton.hpp"

#include <cstdint>
#include <cstring>
#include <functional>
#include <unordered_map>

#include <nlohmann/json.hpp>

#include "common/base/file.hpp"

namespace vistel::test {

Result<Skeleton> loadGlbSkeleton(const std::string& path) {
  Result<std::vector<std::uint8_t>> bytes = readFileBytes(path);
  if (!bytes) return bytes.error();
  const std::vector<std::uint8_t>& b = *bytes;
  const auto u32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    std::memcpy(&v, b.data() + at, 4);
    return v;
  };
  if (b.size() < 20 || std::memcmp(b.data(), "glTF", 4) != 0 || u32(16) != 0x4E4F534Au) {
    return fail("{}: not a glb with a JSON chunk", path);
  }
  const std::uint32_t json_length = u32(12);
  if (20 + static_cast<std::size_t>(json_length) > b.size()) return fail("{}: truncated", path);
  const nlohmann::json doc =
      nlohmann::json::parse(b.begin() + 20, b.begin() + 20 + json_length, nullptr, false);
  if (doc.is_discarded() || !doc.contains("skins") || doc["skins"].empty()) {
    return fail("{}: no skin", path);
  }
  const nlohmann::json& nodes = doc["nodes"];
  std::unordered_map<int, int> joint_slot;  // node -> position in skin.joints
  for (const auto& n : doc["skins"][0]["joints"]) joint_slot[n.get<int>()] = 0;

  // Depth first from the scene's roots: joints in an order where parents come first.
  Skeleton s;
  std::unordered_map<int, int> index_of_node;
  std::function<void(int, int)> visit = [&](int node, int parent_joint) {
    const nlohmann::json& n = nodes[static_cast<std::size_t>(node)];
    int here = parent_joint;
    if (joint_slot.count(node) != 0) {
      Transform t;
      if (n.contains("translation")) {
        const auto& v = n["translation"];
        t.translation = glm::vec3(v[0].get<float>(), v[1].get<float>(), v[2].get<float>());
      }
      if (n.contains("rotation")) {
        const auto& v = n["rotation"];
        t.rotation =
            glm::quat(v[3].get<float>(), v[0].get<float>(), v[1].get<float>(), v[2].get<float>());
      }
      if (n.contains("scale")) {
        const auto& v = n["scale"];
        t.scale = glm::vec3(v[0].get<float>(), v[1].get<float>(), v[2].get<float>());
      }
      here = s.jointCount();
      index_of_node[node] = here;
      s.names.push_back(n.value("name", "joint" + std::to_string(node)));
      s.parents.push_back(parent_joint);
      s.rest_local.push_back(t);
    }
    if (n.contains("children")) {
      for (const auto& c : n["children"]) visit(c.get<int>(), here);
    }
  };
  const int scene = doc.value("scene", 0);
  for (const auto& root : doc["scenes"][static_cast<std::size_t>(scene)]["nodes"]) {
    visit(root.get<int>(), kNoParent);
  }
  computeInverseBind(s);
  if (Status st = validateSkeleton(s); !st) return withContext(path, st.error());
  return s;
}

}  // namespace vistel::test
