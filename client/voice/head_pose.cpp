#include "client/voice/head_pose.hpp"

#include <algorithm>
#include <string>

#include <glm/gtc/quaternion.hpp>

namespace vistel {
namespace {

// The rotation part of a transform with scale taken out.
glm::quat rotationOf(const glm::mat4& m) {
  glm::mat3 r(m);
  for (int c = 0; c < 3; ++c) {
    const float length = glm::length(r[c]);
    if (length > 0.0f) r[c] /= length;
  }
  return glm::normalize(glm::quat_cast(r));
}

}  // namespace

HeadPoser::HeadPoser(const Skeleton& skeleton) : head_(findHeadJoint(skeleton)) {
  if (head_ < 0) return;
  const std::vector<glm::mat4> rest = restModelTransforms(skeleton);
  const glm::mat4& m = rest[static_cast<std::size_t>(head_)];
  rest_inverse_ = glm::inverse(rotationOf(m));
  rest_position_ = glm::vec3(m[3]);
  model_.resize(static_cast<std::size_t>(skeleton.jointCount()));
}

HeadPose HeadPoser::pose(const Skeleton& skeleton, const Posture& posture,
                         const glm::mat4& placement) {
  HeadPose out;
  const glm::quat placed = rotationOf(placement);
  if (head_ < 0 || posture.rotations.size() != model_.size() ||
      skeleton.jointCount() != static_cast<int>(model_.size())) {
    out.position = glm::vec3(placement * glm::vec4(rest_position_, 1.0f));
    out.orientation = placed;
    return out;
  }
  poseSkeleton(skeleton, posture, model_);
  const glm::mat4& m = model_[static_cast<std::size_t>(head_)];
  out.position = glm::vec3(placement * m[3]);
  out.orientation = glm::normalize(placed * rotationOf(m) * rest_inverse_);
  return out;
}

HeadPose seatHeadPose(const glm::mat4& placement, float head_height_m) {
  HeadPose out;
  out.position = glm::vec3(placement * glm::vec4(0.0f, head_height_m, 0.0f, 1.0f));
  out.orientation = rotationOf(placement);
  return out;
}

}  // namespace vistel
