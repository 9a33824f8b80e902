#include "client/view/head_landmarks.hpp"

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

namespace vistel {

HeadLandmarks measureHead(const AvatarModel& avatar, int head_joint) {
  HeadLandmarks head;
  const Skeleton& skeleton = avatar.skeleton;
  head.joint = head_joint;
  if (head_joint < 0 || head_joint >= skeleton.jointCount()) return head;
  const std::vector<glm::mat4> rest = restModelTransforms(skeleton);
  head.rest_model = rest[static_cast<std::size_t>(head_joint)];
  const glm::vec3 joint_pos(head.rest_model[3]);

  // The head joint and its descendants (parents precede children).
  std::vector<bool> in_head(static_cast<std::size_t>(skeleton.jointCount()), false);
  in_head[static_cast<std::size_t>(head_joint)] = true;
  for (int j = head_joint + 1; j < skeleton.jointCount(); ++j) {
    const int p = skeleton.parents[static_cast<std::size_t>(j)];
    if (p >= 0 && in_head[static_cast<std::size_t>(p)]) in_head[static_cast<std::size_t>(j)] = true;
  }

  // Bounds of the vertices whose dominant influence lies in the head.
  const SkinMesh& skin = avatar.skin;
  const auto k = static_cast<std::size_t>(std::max(skin.influences, 1));
  glm::vec3 lo(std::numeric_limits<float>::max());
  glm::vec3 hi(std::numeric_limits<float>::lowest());
  int count = 0;
  for (std::size_t v = 0; v < skin.positions.size(); ++v) {
    std::size_t best = v * k;
    for (std::size_t s = 1; s < k; ++s) {
      if (skin.weights[v * k + s] > skin.weights[best]) best = v * k + s;
    }
    const std::size_t joint = skin.joints[best];
    if (joint < in_head.size() && in_head[joint] && skin.weights[best] > 0.0f) {
      lo = glm::min(lo, skin.positions[v]);
      hi = glm::max(hi, skin.positions[v]);
      ++count;
    }
  }
  if (count < 4) {
    head.eye_rest = joint_pos + glm::vec3(0.0f, 0.08f, 0.08f);
    head.top_rest = joint_pos + glm::vec3(0.0f, 0.20f, 0.0f);
    return head;
  }
  // Eyes a little above the middle of the head, a quarter of its depth behind the face.
  const glm::vec3 size = hi - lo;
  head.eye_rest = glm::vec3((lo.x + hi.x) * 0.5f, std::max(lo.y + 0.55f * size.y, joint_pos.y),
                            hi.z - 0.25f * size.z);
  head.top_rest = glm::vec3((lo.x + hi.x) * 0.5f, hi.y, (lo.z + hi.z) * 0.5f);
  return head;
}

}  // namespace vistel
