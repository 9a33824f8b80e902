// A small valid avatar for generating seed inputs (the .vavatar and glTF targets): a
// three-joint chain along +Y and a closed box skinned to it, in model space (metres).
#pragma once

#include <algorithm>
#include <cstdint>
#include <iterator>
#include <string>

#include <glm/glm.hpp>

#include "common/anim/skeleton.hpp"
#include "common/anim/skin_mesh.hpp"
#include "common/avatar/avatar_model.hpp"

namespace vistel::fuzz {

// joints: 1..3 (a chain root -> mid -> tip, 0.1 m apart); influences: 1..kMaxInfluences.
inline AvatarModel tinyAvatar(int joints = 3, int influences = 2) {
  AvatarModel avatar;
  avatar.name = "tiny";

  // Skeleton: a chain up +Y.
  static constexpr const char* kNames[] = {"root", "mid", "tip"};
  Skeleton& s = avatar.skeleton;
  for (int j = 0; j < joints; ++j) {
    s.names.emplace_back(kNames[j]);
    s.parents.push_back(j == 0 ? kNoParent : j - 1);
    Transform t;
    t.translation = glm::vec3(0.0f, j == 0 ? 0.5f : 0.1f, 0.0f);
    s.rest_local.push_back(t);
  }
  computeInverseBind(s);

  // Skin: an axis-aligned box around the chain, 8 corners, 12 outward triangles.
  SkinMesh& m = avatar.skin;
  for (int c = 0; c < 8; ++c) {
    m.positions.emplace_back((c & 1) ? 0.05f : -0.05f, (c & 2) ? 0.75f : 0.45f,
                             (c & 4) ? 0.05f : -0.05f);
  }
  static constexpr std::uint32_t kBox[] = {0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                                           2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5};
  m.indices.assign(std::begin(kBox), std::end(kBox));
  m.normals.resize(m.positions.size());
  computeVertexNormals(m.positions, m.indices, m.normals);

  // Weights: the lower corners follow the root, the upper ones blend the last two joints.
  m.influences = influences;
  for (int v = 0; v < 8; ++v) {
    const bool upper = (v & 2) != 0;
    for (int k = 0; k < influences; ++k) {
      const int joint = upper ? std::max(0, joints - 1 - k) : 0;
      const float weight = influences == 1 ? 1.0f
                           : k == 0        ? (upper ? 0.75f : 1.0f)
                           : k == 1        ? (upper ? 0.25f : 0.0f)
                                           : 0.0f;
      m.joints.push_back(static_cast<std::uint16_t>(joint));
      m.weights.push_back(weight);
    }
  }
  return avatar;
}

}  // namespace vistel::fuzz
