// BVH clips as skeletons and postures: the zero pose as rest, frames as local rotations.
#include <algorithm>
#include <cassert>
#include <cmath>

#include <glm/gtc/quaternion.hpp>

#include "common/motion/bvh.hpp"

namespace vistel {
namespace {

const glm::vec3 kAxes[3] = {{1.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 0.0f}, {0.0f, 0.0f, 1.0f}};

// Local rotation and translation (metres) of one joint from one frame's values.
void jointPose(const MotionClip& clip, const BvhJoint& joint, std::span<const float> values,
               glm::quat& rotation, glm::vec3& translation) {
  rotation = glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  translation = joint.offset;
  for (std::size_t c = 0; c < joint.channels.size(); ++c) {
    const float v = values[static_cast<std::size_t>(joint.first_channel) + c];
    const auto axis = static_cast<int>(joint.channels[c]);
    if (axis < 3) {
      translation[axis] = v;
    } else {
      // R = R_first * R_second * R_third: each later channel rotates in the frame of the
      // earlier ones.
      rotation = rotation * glm::angleAxis(glm::radians(v), kAxes[axis - 3]);
    }
  }
  rotation = glm::normalize(rotation);
  translation *= clip.unit_scale;
}

bool hasNonRootPositions(const MotionClip& clip) {
  for (std::size_t j = 1; j < clip.joints.size(); ++j) {
    for (BvhChannel c : clip.joints[j].channels) {
      if (c <= BvhChannel::kZposition) return true;
    }
  }
  return false;
}

void sizePosture(const MotionClip& clip, Posture& out) {
  const std::size_t n = clip.joints.size();
  out.rotations.resize(n);
  out.translations.resize(hasNonRootPositions(clip) ? n : 0);
}

}  // namespace

Skeleton clipSkeleton(const MotionClip& clip) {
  Skeleton s;
  const std::size_t n = clip.joints.size();
  s.names.reserve(n);
  s.parents.reserve(n);
  s.rest_local.resize(n);
  for (std::size_t j = 0; j < n; ++j) {
    s.names.push_back(clip.joints[j].name);
    s.parents.push_back(clip.joints[j].parent);
    s.rest_local[j].translation = clip.joints[j].offset * clip.unit_scale;
  }
  computeInverseBind(s);
  return s;
}

void samplePosture(const MotionClip& clip, int frame, Posture& out) {
  assert(frame >= 0 && frame < clip.frame_count);
  sizePosture(clip, out);
  const std::span<const float> values = clip.frame(frame);
  const bool translated = !out.translations.empty();
  for (std::size_t j = 0; j < clip.joints.size(); ++j) {
    glm::vec3 t;
    jointPose(clip, clip.joints[j], values, out.rotations[j], t);
    if (j == 0) {
      out.root_translation = t;
      if (translated) out.translations[0] = t;
    } else if (translated) {
      out.translations[j] = t;
    }
  }
  out.time = frame * clip.frame_time;
}

void samplePostureAt(const MotionClip& clip, double t, Posture& out) {
  assert(clip.frame_count > 0 && clip.frame_time > 0.0);
  const double last = (clip.frame_count - 1) * clip.frame_time;
  const double time = std::clamp(t, 0.0, last);
  const double f = time / clip.frame_time;
  int k = static_cast<int>(std::floor(f));
  float a = static_cast<float>(f - k);
  if (k >= clip.frame_count - 1) {
    k = clip.frame_count - 1;
    a = 0.0f;
  }
  const int k1 = std::min(k + 1, clip.frame_count - 1);

  sizePosture(clip, out);
  const bool translated = !out.translations.empty();
  const std::span<const float> v0 = clip.frame(k);
  const std::span<const float> v1 = clip.frame(k1);
  for (std::size_t j = 0; j < clip.joints.size(); ++j) {
    glm::quat r0, r1;
    glm::vec3 t0, t1;
    jointPose(clip, clip.joints[j], v0, r0, t0);
    jointPose(clip, clip.joints[j], v1, r1, t1);
    out.rotations[j] = glm::normalize(glm::slerp(r0, r1, a));
    const glm::vec3 p = glm::mix(t0, t1, a);
    if (j == 0) {
      out.root_translation = p;
      if (translated) out.translations[0] = p;
    } else if (translated) {
      out.translations[j] = p;
    }
  }
  out.time = time;
}

}  // namespace vistel
