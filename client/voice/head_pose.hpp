// Where a participant's head is and where it faces, for the spatialiser (common/voice):
// from its avatar's skeleton, its posture and its seat placement.
//
// Space: the room (world), metres, +Y up. The avatar's model space faces +Z with its left
// on +X, as the spatialiser's head space does; so the head's orientation is the placement's
// rotation times the head joint's rotation away from its rest (a head at rest faces where
// the seat faces, whatever the joint's own axes). Cost: one forward kinematics pass
// (O(joints)), no allocation once the scratch has the joint count.
#pragma once

#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"
#include "common/voice/spatialiser.hpp"

namespace vistel {

class HeadPoser {
 public:
  explicit HeadPoser(const Skeleton& skeleton);

  int headJoint() const { return head_; }
  // The head in the room for `posture` (of this skeleton; a posture of another joint count
  // gives the rest head) placed by `placement` (model -> room).
  HeadPose pose(const Skeleton& skeleton, const Posture& posture, const glm::mat4& placement);

 private:
  int head_ = -1;
  glm::quat rest_inverse_{1.0f, 0.0f, 0.0f, 0.0f};  // the head joint's rest rotation, inverted
  glm::vec3 rest_position_{0.0f};                   // ... its rest position, model space
  std::vector<glm::mat4> model_;
};

// A head pose from a seat alone (a participant whose avatar or posture is not here): at
// standing head height above the seat, facing where the placement faces.
HeadPose seatHeadPose(const glm::mat4& placement, float head_height_m = 1.6f);

}  // namespace vistel
