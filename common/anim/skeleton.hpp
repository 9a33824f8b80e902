// The static skeleton of an avatar or a motion clip: joint names, parents and rest
// transforms, in model space (metres, +Y up).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "common/base/result.hpp"
#include "common/math/transform.hpp"

namespace vistel {

inline constexpr int kNoParent = -1;

struct Skeleton {
  std::vector<std::string> names;       // joint name (njoint), unique
  std::vector<int> parents;             // parent joint (njoint); joint 0 is the single root
                                        // (kNoParent) and parents[j] < j for every other j
  std::vector<Transform> rest_local;    // rest transform relative to the parent (njoint);
                                        // the root's is relative to model space
  std::vector<glm::mat4> inverse_bind;  // model space -> joint space in the bind (= rest)
                                        // posture (njoint)

  int jointCount() const { return static_cast<int>(names.size()); }
  // Index of the joint with this exact name, or -1.
  int find(std::string_view name) const;
  // Children of joint j, in index order (allocates; not for per-frame use).
  std::vector<int> children(int j) const;
};

// Checks the structural contract above (sizes agree, one root at 0, parents precede
// children, unique non-empty names, finite transforms). The message names the joint.
Status validateSkeleton(const Skeleton& skeleton);

// Model-space rest transforms (njoint), from rest_local.
std::vector<glm::mat4> restModelTransforms(const Skeleton& skeleton);

// The head joint: a joint named exactly "head" (vistel's canonical name), else one named
// "head" in any case, else the first whose name contains "head" (any case) and is not an
// end site ("end", "top", "nub"), else the joint highest (+Y) at rest. -1 only for an empty
// skeleton.
int findHeadJoint(const Skeleton& skeleton);

// Sets inverse_bind from rest_local (the bind posture is the rest posture).
void computeInverseBind(Skeleton& skeleton);

}  // namespace vistel
