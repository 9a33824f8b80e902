// VRM (.vrm: glTF 2.0 with a humanoid extension): the humanoid bone map of VRMC_vrm 1.0
// (extensions.VRMC_vrm.humanoid.humanBones.<bone>.node) or VRM 0.x
// (extensions.VRM.humanoid.humanBones[] = {bone, node}), in vistel's canonical joint names
// (common/motion/joint_map.hpp). Bones with no canonical joint (eyes, jaw) are left out.
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <tiny_gltf.h>

#include "common/base/result.hpp"

namespace vistel {

struct VrmHumanoid {
  std::string version;  // "1.0" (VRMC_vrm) or "0.x" (VRM)
  // canonical joint name -> glTF node, in canonical order, each canonical name once.
  std::vector<std::pair<std::string, int>> bones;
  std::vector<std::string> ignored;  // VRM bone names with no canonical joint
};

// The humanoid of a VRM file; an empty version when the file has neither extension.
// Fails (naming the bone) on a node index out of range, a node used by two bones or a
// malformed humanoid object. VRMC_vrm wins when a file has both. Cost: O(bones).
Result<VrmHumanoid> readVrmHumanoid(const tinygltf::Model& model, std::string_view source);

// The canonical joint of a VRM humanoid bone name ("leftUpperArm" -> "l_upperarm"), or
// empty. The thumb differs by version: 1.0's Metacarpal/Proximal/Distal and 0.x's
// Proximal/Intermediate/Distal are both thumb1/2/3.
std::string_view canonicalForVrmBone(std::string_view bone, bool vrm0);

}  // namespace vistel
