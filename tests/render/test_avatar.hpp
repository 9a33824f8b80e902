// A synthetic humanoid for render tests: canonical joint names, a skin of capsules each
// bound rigidly to one joint (model space, metres, +Y up, facing +Z, left = +X).
#pragma once

#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "common/anim/posture.hpp"
#include "common/avatar/avatar_model.hpp"

namespace vistel::test {

// One capsule of the skin: the segment a-b (rest, model space), its radius, its joint.
struct TestCapsule {
  int joint;
  glm::vec3 a;
  glm::vec3 b;
  float radius;
};

struct TestAvatar {
  std::shared_ptr<AvatarModel> model;
  std::vector<TestCapsule> capsules;
};

// About 1.85 m tall, T-posed at rest; `rings` sets the tessellation (vertices grow
// with rings^2).
TestAvatar makeTestAvatar(int rings = 8);

// A posture on that skeleton: arms lowered 70 degrees, elbows bent, head turned.
Posture makeTestPosture(const AvatarModel& avatar);

}  // namespace vistel::test
