// Posing tools for the bundled gestures: FK, analytic two-bone IK (law of cosines with a
// pole vector), swing-twist split of the hand's rotation, finger curls, keyframes.
#include "offline/gestures/gesture_rig.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <string>

#include "common/motion/joint_map.hpp"

namespace vistel::gesture {
namespace {

// Rotation taking the orthonormal pair (a_from, b_from) onto (a_to, b_to).
glm::quat frameRotation(glm::vec3 a_from, glm::vec3 b_from, glm::vec3 a_to, glm::vec3 b_to) {
  const glm::mat3 from(a_from, b_from, glm::cross(a_from, b_from));
  const glm::mat3 to(a_to, b_to, glm::cross(a_to, b_to));
  return glm::normalize(glm::quat_cast(to * glm::transpose(from)));
}

// Unit component of v orthogonal to unit u (fallback when parallel).
glm::vec3 orthogonal(glm::vec3 v, glm::vec3 u, glm::vec3 fallback) {
  glm::vec3 w = v - glm::dot(v, u) * u;
  if (glm::length(w) < 1e-6f) w = fallback - glm::dot(fallback, u) * u;
  return glm::normalize(w);
}

// Two-bone chain from `root` (lengths a, b) reaching towards `target` with the middle
// joint towards `pole`: the two bone directions and the hinge axis (normal of their plane).
struct Chain {
  glm::vec3 upper;
  glm::vec3 lower;
  glm::vec3 hinge;
};
Chain solveTwoBone(glm::vec3 root, float a, float b, glm::vec3 target, glm::vec3 pole) {
  glm::vec3 d = target - root;
  const float reach = std::clamp(glm::length(d), std::abs(a - b) + 1e-4f, a + b - 1e-4f);
  const glm::vec3 u = glm::normalize(d);
  const glm::vec3 v = orthogonal(pole, u, glm::vec3(0.0f, 0.0f, -1.0f));
  const float cos_alpha =
      std::clamp((a * a + reach * reach - b * b) / (2.0f * a * reach), -1.0f, 1.0f);
  const float sin_alpha = std::sqrt(std::max(0.0f, 1.0f - cos_alpha * cos_alpha));
  const glm::vec3 middle = root + a * (cos_alpha * u + sin_alpha * v);
  const glm::vec3 end = root + reach * u;
  return {glm::normalize(middle - root), glm::normalize(end - middle),
          glm::normalize(glm::cross(v, u))};
}

glm::vec3 restOffset(const Skeleton& s, int j) {
  return s.rest_local[static_cast<std::size_t>(j)].translation;
}

std::string sided(bool left, std::string_view part) {
  return std::string(left ? "l_" : "r_") + std::string(part);
}

}  // namespace

int joint(std::string_view canonical_name) {
  const int j = canonicalIndex(canonical_name);
  assert(j >= 0);
  return j;
}

WorldPose forwardKinematics(const Skeleton& s, const Posture& p) {
  const std::size_t n = s.names.size();
  WorldPose w;
  w.rotation.resize(n);
  w.position.resize(n);
  for (std::size_t j = 0; j < n; ++j) {
    const int parent = s.parents[j];
    if (parent == kNoParent) {
      w.rotation[j] = p.rotations[j];
      w.position[j] = p.root_translation;
    } else {
      const auto q = static_cast<std::size_t>(parent);
      w.rotation[j] = glm::normalize(w.rotation[q] * p.rotations[j]);
      w.position[j] = w.position[q] + w.rotation[q] * s.rest_local[j].translation;
    }
  }
  return w;
}

void placeArm(const Skeleton& s, bool left, const ArmGoal& goal, Posture& p) {
  const int clavicle = joint(sided(left, "clavicle"));
  const int upper = joint(sided(left, "upperarm"));
  const int fore = joint(sided(left, "forearm"));
  const int hand = joint(sided(left, "hand"));
  const WorldPose w = forwardKinematics(s, p);
  const glm::vec3 shoulder = w.position[static_cast<std::size_t>(upper)];
  const glm::quat clavicle_world = w.rotation[static_cast<std::size_t>(clavicle)];

  // Bone axes and elbow hinge in the rest frame: flexion swings the forearm forward.
  const glm::vec3 upper_axis = glm::normalize(restOffset(s, fore));
  const glm::vec3 fore_axis = glm::normalize(restOffset(s, hand));
  const glm::vec3 hinge_rest(0.0f, left ? -1.0f : 1.0f, 0.0f);
  const Chain c = solveTwoBone(shoulder, glm::length(restOffset(s, fore)),
                               glm::length(restOffset(s, hand)), goal.wrist, goal.pole);
  const glm::quat upper_world =
      frameRotation(upper_axis, orthogonal(hinge_rest, upper_axis, hinge_rest), c.upper, c.hinge);
  const glm::quat fore_world0 =
      frameRotation(fore_axis, orthogonal(hinge_rest, fore_axis, hinge_rest), c.lower, c.hinge);

  // The hand's world rotation: fingers along goal.fingers, palm (local -Y) to the normal.
  const glm::vec3 finger_axis = glm::normalize(restOffset(s, joint(sided(left, "middle1"))));
  const glm::vec3 palm_rest(0.0f, -1.0f, 0.0f);
  const glm::vec3 fingers = glm::normalize(goal.fingers);
  const glm::quat hand_world =
      frameRotation(finger_axis, orthogonal(palm_rest, finger_axis, palm_rest), fingers,
                    orthogonal(goal.palm_normal, fingers, palm_rest));

  // Swing-twist: the twist about the forearm's axis goes to the forearm.
  const glm::quat hand_local0 = glm::inverse(fore_world0) * hand_world;
  const glm::vec3 along =
      glm::dot(glm::vec3(hand_local0.x, hand_local0.y, hand_local0.z), fore_axis) * fore_axis;
  glm::quat twist(hand_local0.w, along.x, along.y, along.z);
  twist = glm::length(twist) < 1e-6f ? glm::quat(1.0f, 0.0f, 0.0f, 0.0f) : glm::normalize(twist);
  const glm::quat fore_world = glm::normalize(fore_world0 * twist);

  p.rotations[static_cast<std::size_t>(upper)] =
      glm::normalize(glm::inverse(clavicle_world) * upper_world);
  p.rotations[static_cast<std::size_t>(fore)] =
      glm::normalize(glm::inverse(upper_world) * fore_world);
  p.rotations[static_cast<std::size_t>(hand)] =
      glm::normalize(glm::inverse(fore_world) * hand_world);
}

void placeLeg(const Skeleton& s, bool left, glm::vec3 ankle, glm::vec3 knee_pole, Posture& p) {
  const int hips = joint("hips");
  const int thigh = joint(sided(left, "thigh"));
  const int shin = joint(sided(left, "shin"));
  const int foot = joint(sided(left, "foot"));
  const WorldPose w = forwardKinematics(s, p);
  const glm::quat hips_world = w.rotation[static_cast<std::size_t>(hips)];

  // Knee hinge about +X: flexion swings the shin backwards.
  const glm::vec3 upper_axis = glm::normalize(restOffset(s, shin));
  const glm::vec3 lower_axis = glm::normalize(restOffset(s, foot));
  const glm::vec3 hinge_rest(1.0f, 0.0f, 0.0f);
  const Chain c =
      solveTwoBone(w.position[static_cast<std::size_t>(thigh)], glm::length(restOffset(s, shin)),
                   glm::length(restOffset(s, foot)), ankle, knee_pole);
  const glm::quat thigh_world =
      frameRotation(upper_axis, orthogonal(hinge_rest, upper_axis, hinge_rest), c.upper, c.hinge);
  const glm::quat shin_world =
      frameRotation(lower_axis, orthogonal(hinge_rest, lower_axis, hinge_rest), c.lower, c.hinge);
  p.rotations[static_cast<std::size_t>(thigh)] =
      glm::normalize(glm::inverse(hips_world) * thigh_world);
  p.rotations[static_cast<std::size_t>(shin)] =
      glm::normalize(glm::inverse(thigh_world) * shin_world);
  p.rotations[static_cast<std::size_t>(foot)] = glm::normalize(glm::inverse(shin_world));
}

void curlFingers(const Skeleton& s, bool left, const Curl& curl, Posture& p) {
  const glm::vec3 palm_rest(0.0f, -1.0f, 0.0f);
  const std::pair<const char*, float> fingers[] = {{"thumb", curl.thumb},
                                                   {"index", curl.index},
                                                   {"middle", curl.middle},
                                                   {"ring", curl.ring},
                                                   {"pinky", curl.pinky}};
  constexpr float kShare[3] = {1.0f, 1.1f, 0.8f};
  for (const auto& [name, angle] : fingers) {
    for (int k = 1; k <= 3; ++k) {
      const int j = joint(sided(left, std::string(name) + std::to_string(k)));
      // The bone leaving joint j (the last one continues its parent's direction).
      const int next = k < 3 ? joint(sided(left, std::string(name) + std::to_string(k + 1))) : j;
      const glm::vec3 bone = glm::normalize(restOffset(s, next));
      // Rotating about bone x palm turns the bone towards the palm.
      const glm::vec3 axis = glm::normalize(glm::cross(bone, palm_rest));
      p.rotations[static_cast<std::size_t>(j)] = glm::angleAxis(angle * kShare[k - 1], axis);
    }
  }
}

void palm(const Skeleton& s, const WorldPose& w, bool left, glm::vec3& centre, glm::vec3& normal) {
  const auto hand = static_cast<std::size_t>(joint(sided(left, "hand")));
  const auto middle = static_cast<std::size_t>(joint(sided(left, "middle1")));
  centre = w.position[hand] + 0.5f * (w.rotation[hand] * s.rest_local[middle].translation);
  normal = w.rotation[hand] * glm::vec3(0.0f, -1.0f, 0.0f);
}

std::vector<Posture> interpolate(std::span<const Key> keys, double frame_time) {
  assert(!keys.empty() && keys.front().frame == 0);
  std::vector<Posture> frames(static_cast<std::size_t>(keys.back().frame) + 1);
  std::size_t k = 0;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const int frame = static_cast<int>(f);
    while (k + 1 < keys.size() && keys[k + 1].frame <= frame) ++k;
    Posture& out = frames[f];
    if (keys[k].frame == frame || k + 1 == keys.size()) {
      out = keys[k].posture;
    } else {
      const Key& a = keys[k];
      const Key& b = keys[k + 1];
      assert(b.frame > a.frame);
      const float u = static_cast<float>(frame - a.frame) / static_cast<float>(b.frame - a.frame);
      const float t = u * u * (3.0f - 2.0f * u);
      out.rotations.resize(a.posture.rotations.size());
      for (std::size_t j = 0; j < out.rotations.size(); ++j) {
        out.rotations[j] =
            glm::normalize(glm::slerp(a.posture.rotations[j], b.posture.rotations[j], t));
      }
      out.root_translation = glm::mix(a.posture.root_translation, b.posture.root_translation, t);
    }
    out.time = frame * frame_time;
  }
  return frames;
}

}  // namespace vistel::gesture
