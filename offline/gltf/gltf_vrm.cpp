#include "offline/gltf/gltf_vrm.hpp"

#include <algorithm>
#include <array>
#include <map>

#include "common/motion/joint_map.hpp"

namespace vistel {
namespace {

struct BonePair {
  std::string_view vrm;
  std::string_view canonical;
};

// Bones named alike in both versions (sides added below).
constexpr std::array<BonePair, 6> kCentre = {{{"hips", "hips"},
                                              {"spine", "spine"},
                                              {"chest", "chest"},
                                              {"upperChest", "upper_chest"},
                                              {"neck", "neck"},
                                              {"head", "head"}}};
constexpr std::array<BonePair, 8> kSided = {{{"Shoulder", "clavicle"},
                                             {"UpperArm", "upperarm"},
                                             {"LowerArm", "forearm"},
                                             {"Hand", "hand"},
                                             {"UpperLeg", "thigh"},
                                             {"LowerLeg", "shin"},
                                             {"Foot", "foot"},
                                             {"Toes", "toes"}}};
constexpr std::array<BonePair, 4> kFingers = {
    {{"Index", "index"}, {"Middle", "middle"}, {"Ring", "ring"}, {"Little", "pinky"}}};
constexpr std::array<std::string_view, 3> kSegments = {"Proximal", "Intermediate", "Distal"};
constexpr std::array<std::string_view, 3> kThumb1 = {"Metacarpal", "Proximal", "Distal"};
constexpr std::array<std::string_view, 3> kThumb0 = {"Proximal", "Intermediate", "Distal"};

const tinygltf::Value* member(const tinygltf::Value& v, const std::string& key) {
  if (!v.IsObject() || !v.Has(key)) return nullptr;
  return &v.Get(key);
}

}  // namespace

std::string_view canonicalForVrmBone(std::string_view bone, bool vrm0) {
  for (const BonePair& p : kCentre) {
    if (bone == p.vrm) return p.canonical;
  }
  // Sided names: "left"/"right" + the rest.
  std::string_view side;
  std::string_view rest;
  if (bone.substr(0, 4) == "left") {
    side = "l_";
    rest = bone.substr(4);
  } else if (bone.substr(0, 5) == "right") {
    side = "r_";
    rest = bone.substr(5);
  } else {
    return {};
  }
  std::string name;
  for (const BonePair& p : kSided) {
    if (rest == p.vrm) name = fmt::format("{}{}", side, p.canonical);
  }
  const auto& thumb = vrm0 ? kThumb0 : kThumb1;
  for (std::size_t s = 0; s < 3 && name.empty(); ++s) {
    if (rest == fmt::format("Thumb{}", thumb[s])) {
      name = fmt::format("{}thumb{}", side, s + 1);
    }
    for (const BonePair& f : kFingers) {
      if (rest == fmt::format("{}{}", f.vrm, kSegments[s])) {
        name = fmt::format("{}{}{}", side, f.canonical, s + 1);
      }
    }
  }
  if (name.empty()) return {};
  // Return a view of the static canonical name.
  const int index = canonicalIndex(name);
  return index < 0 ? std::string_view{} : canonicalJoints()[static_cast<std::size_t>(index)];
}

Result<VrmHumanoid> readVrmHumanoid(const tinygltf::Model& model, std::string_view source) {
  VrmHumanoid out;
  std::vector<std::pair<std::string, int>> found;  // VRM bone name, node
  if (auto it = model.extensions.find("VRMC_vrm"); it != model.extensions.end()) {
    out.version = "1.0";
    const tinygltf::Value* humanoid = member(it->second, "humanoid");
    const tinygltf::Value* bones = humanoid ? member(*humanoid, "humanBones") : nullptr;
    if (bones == nullptr || !bones->IsObject()) {
      return fail("{}: VRMC_vrm: no humanoid.humanBones object", source);
    }
    for (const std::string& key : bones->Keys()) {
      const tinygltf::Value* node = member(bones->Get(key), "node");
      if (node == nullptr || !node->IsNumber()) {
        return fail("{}: VRMC_vrm: humanBones.{} has no node index", source, key);
      }
      found.emplace_back(key, node->GetNumberAsInt());
    }
  } else if (auto it0 = model.extensions.find("VRM"); it0 != model.extensions.end()) {
    out.version = "0.x";
    const tinygltf::Value* humanoid = member(it0->second, "humanoid");
    const tinygltf::Value* bones = humanoid ? member(*humanoid, "humanBones") : nullptr;
    if (bones == nullptr || !bones->IsArray()) {
      return fail("{}: VRM: no humanoid.humanBones array", source);
    }
    for (std::size_t i = 0; i < bones->ArrayLen(); ++i) {
      const tinygltf::Value& entry = bones->Get(static_cast<int>(i));
      const tinygltf::Value* bone = member(entry, "bone");
      const tinygltf::Value* node = member(entry, "node");
      if (bone == nullptr || !bone->IsString() || node == nullptr || !node->IsNumber()) {
        return fail("{}: VRM: humanBones[{}] needs a string 'bone' and a number 'node'", source, i);
      }
      found.emplace_back(bone->Get<std::string>(), node->GetNumberAsInt());
    }
  } else {
    return out;
  }

  const bool vrm0 = out.version == "0.x";
  std::map<int, std::string> node_bone;
  std::map<std::string, int> canonical_node;
  for (const auto& [bone, node] : found) {
    if (node < 0 || static_cast<std::size_t>(node) >= model.nodes.size()) {
      return fail("{}: VRM humanoid bone '{}': node {} of {}", source, bone, node,
                  model.nodes.size());
    }
    if (auto [it, fresh] = node_bone.emplace(node, bone); !fresh) {
      return fail("{}: VRM humanoid bones '{}' and '{}' are both node {}", source, it->second, bone,
                  node);
    }
    const std::string_view canonical = canonicalForVrmBone(bone, vrm0);
    if (canonical.empty()) {
      out.ignored.push_back(bone);
      continue;
    }
    if (!canonical_node.emplace(std::string(canonical), node).second) {
      return fail("{}: VRM humanoid bone '{}' appears twice", source, bone);
    }
  }
  for (std::string_view c : canonicalJoints()) {
    if (auto it = canonical_node.find(std::string(c)); it != canonical_node.end()) {
      out.bones.emplace_back(it->first, it->second);
    }
  }
  return out;
}

}  // namespace vistel
