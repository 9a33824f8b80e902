// A posture: what changes per frame on a skeleton.
#pragma once

#include <span>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/anim/skeleton.hpp"

namespace vistel {

struct Posture {
  double time = 0.0;                    // capture time, seconds (server clock once networked)
  glm::vec3 root_translation{0.0f};     // model-space position of joint 0, metres (replaces its
                                        // rest translation)
  std::vector<glm::quat> rotations;     // local rotation per joint (njoint), replacing the rest
                                        // rotation; unit quaternions
  std::vector<glm::vec3> translations;  // optional local translation per joint (njoint or
                                        // empty = rest translations); entry 0 is unused
                                        // (root_translation wins). Motion clips whose
                                        // non-root joints carry position channels use it;
                                        // the network stream does not.
};

// The rest posture: rest rotations and the root's rest translation.
Posture restPosture(const Skeleton& skeleton);

// Model-space joint transforms (njoint) of a posture: joint j gets
// parent * T(t_j) * R(rotations[j]) * S(rest scale), t_0 = root_translation, t_j =
// translations[j] when present, else the rest translation.
// out_model.size() == skeleton.jointCount(); allocates nothing.
void poseSkeleton(const Skeleton& skeleton, const Posture& posture, std::span<glm::mat4> out_model);

// Skinning matrices (njoint): model[j] * inverse_bind[j] (bind-pose model space -> posed
// model space). Allocates nothing.
void skinningMatrices(const Skeleton& skeleton, std::span<const glm::mat4> model,
                      std::span<glm::mat4> out_skin);

// Spherical blend of two postures on the same skeleton (t in [0,1]); out is resized.
void blendPostures(const Posture& a, const Posture& b, float t, Posture& out);

}  // namespace vistel
