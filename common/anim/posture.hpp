// A posture: what changes per frame on a skeleton.
#pragma once

#include <span>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/anim/skeleton.hpp"

namespace vistel {

struct Posture {
  double time = 0.0;                  // capture time, seconds (server clock once networked)
  glm::vec3 root_translation{0.0f};   // model-space position of joint 0, metres (replaces its
                                      // rest translation)
  std::vector<glm::quat> rotations;   // local rotation per joint (njoint), replacing the rest
                                      // rotation; unit quaternions
};

// The rest posture: rest rotations and the root's rest translation.
Posture restPosture(const Skeleton& skeleton);

// Model-space joint transforms (njoint) of a posture: joint j gets
// parent * T(rest translation, or root_translation for j = 0) * R(rotations[j]) * S(rest scale).
// out_model.size() == skeleton.jointCount(); allocates nothing.
void poseSkeleton(const Skeleton& skeleton, const Posture& posture,
                  std::span<glm::mat4> out_model);

// Skinning matrices (njoint): model[j] * inverse_bind[j] (bind-pose model space -> posed
// model space). Allocates nothing.
void skinningMatrices(const Skeleton& skeleton, std::span<const glm::mat4> model,
                      std::span<glm::mat4> out_skin);

// Spherical blend of two postures on the same skeleton (t in [0,1]); out is resized.
void blendPostures(const Posture& a, const Posture& b, float t, Posture& out);

}  // namespace vistel
