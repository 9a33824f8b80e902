#include "client/voice/voice_scene.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <string>

#include <glm/gtc/quaternion.hpp>

namespace vistel {
namespace {

constexpr float kJawOpenRad = 0.35f;   // 20 degrees
constexpr float kChinLiftRad = 0.10f;  // 6 degrees

int jawJoint(const Skeleton& skeleton) {
  for (int j = 0; j < skeleton.jointCount(); ++j) {
    std::string name = skeleton.names[static_cast<std::size_t>(j)];
    std::transform(name.begin(), name.end(), name.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (name.find("jaw") != std::string::npos) return j;
  }
  return -1;
}

// The joint's model-space rest rotation (the product of its chain's rest rotations).
glm::quat restModelRotation(const Skeleton& skeleton, int joint) {
  glm::quat q(1.0f, 0.0f, 0.0f, 0.0f);
  for (int j = joint; j >= 0; j = skeleton.parents[static_cast<std::size_t>(j)]) {
    q = skeleton.rest_local[static_cast<std::size_t>(j)].rotation * q;
  }
  return q;
}

}  // namespace

void VoiceScene::begin() { spots_.clear(); }

void VoiceScene::add(std::uint32_t id, bool is_self, const Skeleton* skeleton,
                     const Posture* posture, const glm::mat4& placement) {
  HeadPose head;
  if (skeleton != nullptr && posture != nullptr) {
    auto it = posers_.find(skeleton);
    if (it == posers_.end()) it = posers_.emplace(skeleton, HeadPoser(*skeleton)).first;
    head = it->second.pose(*skeleton, *posture, placement);
  } else {
    head = seatHeadPose(placement);
  }
  if (is_self) {
    listener_ = head;
  } else {
    spots_.push_back({id, head.position});
  }
}

void VoiceScene::commit(VoiceEngine& engine) { engine.setScene(listener_, spots_); }

float mouthOpening(float rms) {
  if (!(rms > 0.0f)) return 0.0f;
  const float db = 20.0f * std::log10(rms);
  return std::clamp((db + 50.0f) / 30.0f, 0.0f, 1.0f);
}

float applyVoiceToPosture(const Skeleton& skeleton, float opening, Posture& posture) {
  if (!(opening > 0.0f) || static_cast<int>(posture.rotations.size()) != skeleton.jointCount()) {
    return 0.0f;
  }
  opening = std::min(opening, 1.0f);
  int joint = jawJoint(skeleton);
  // Model +X is the avatar's left: a positive turn about it tips the face down (a jaw
  // opening), a negative one lifts the chin.
  float angle = kJawOpenRad * opening;
  if (joint < 0) {
    joint = findHeadJoint(skeleton);
    angle = -kChinLiftRad * opening;
  }
  if (joint < 0) return 0.0f;
  const glm::vec3 axis =
      glm::normalize(glm::inverse(restModelRotation(skeleton, joint)) * glm::vec3(1, 0, 0));
  auto& r = posture.rotations[static_cast<std::size_t>(joint)];
  r = glm::normalize(r * glm::angleAxis(angle, axis));
  return opening;
}

}  // namespace vistel
