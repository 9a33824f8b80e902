// Where an avatar's head is: the head joint, an eye point and the top of the head, from
// the skeleton and the skin in the rest posture (model space, metres, +Y up, facing +Z).
#pragma once

#include <glm/glm.hpp>

#include "common/avatar/avatar_model.hpp"

namespace vistel {

struct HeadLandmarks {
  int joint = -1;              // head joint index
  glm::mat4 rest_model{1.0f};  // the head joint's rest transform, model space
  glm::vec3 eye_rest{0.0f};    // eye point at rest, model space (inside the head,
                               // a little behind the face)
  glm::vec3 top_rest{0.0f};    // top of the head at rest, model space
};

// Measures the head from the skin vertices bound mostly to the head joint or its
// descendants; without such vertices, fixed offsets from the joint (eye 8 cm up and
// 8 cm forward, top 20 cm up). Allocates (call once per avatar).
HeadLandmarks measureHead(const AvatarModel& avatar, int head_joint);

}  // namespace vistel
