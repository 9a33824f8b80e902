// The bundled gesture clips: a canonical T-pose skeleton and four keyframed motions.
// Arms are placed by two-bone IK at the keys (gesture_rig.hpp), keys are blended by
// smoothstep slerp, and every clip starts and ends on the same relaxed pose.
#include "offline/gestures/gestures.hpp"

#include <array>
#include <cmath>
#include <filesystem>
#include <string>

#include "common/base/file.hpp"
#include "common/motion/joint_map.hpp"
#include "offline/gestures/gesture_rig.hpp"

namespace vistel {
namespace {

using gesture::ArmGoal;
using gesture::Curl;
using gesture::joint;
using gesture::Key;

// Model-space joint positions of the left side and the midline at rest (metres, T-pose);
// the right side mirrors x.
struct RestJoint {
  std::string_view name;
  glm::vec3 position;
};
constexpr RestJoint kRest[] = {
    {"hips", {0.0f, 0.95f, 0.0f}},           {"spine", {0.0f, 1.05f, -0.01f}},
    {"chest", {0.0f, 1.17f, -0.01f}},        {"upper_chest", {0.0f, 1.29f, -0.005f}},
    {"neck", {0.0f, 1.45f, -0.01f}},         {"head", {0.0f, 1.55f, 0.0f}},
    {"l_clavicle", {0.02f, 1.40f, 0.03f}},   {"l_upperarm", {0.17f, 1.42f, -0.01f}},
    {"l_forearm", {0.46f, 1.42f, -0.01f}},   {"l_hand", {0.71f, 1.42f, -0.01f}},
    {"l_thumb1", {0.735f, 1.41f, 0.015f}},   {"l_thumb2", {0.765f, 1.405f, 0.04f}},
    {"l_thumb3", {0.79f, 1.405f, 0.055f}},   {"l_index1", {0.805f, 1.42f, 0.012f}},
    {"l_index2", {0.845f, 1.42f, 0.014f}},   {"l_index3", {0.87f, 1.42f, 0.015f}},
    {"l_middle1", {0.81f, 1.42f, -0.008f}},  {"l_middle2", {0.855f, 1.42f, -0.008f}},
    {"l_middle3", {0.883f, 1.42f, -0.008f}}, {"l_ring1", {0.805f, 1.42f, -0.028f}},
    {"l_ring2", {0.847f, 1.42f, -0.03f}},    {"l_ring3", {0.873f, 1.42f, -0.031f}},
    {"l_pinky1", {0.795f, 1.42f, -0.046f}},  {"l_pinky2", {0.827f, 1.42f, -0.049f}},
    {"l_pinky3", {0.847f, 1.42f, -0.05f}},   {"l_thigh", {0.09f, 0.90f, 0.0f}},
    {"l_shin", {0.09f, 0.48f, 0.005f}},      {"l_foot", {0.09f, 0.08f, -0.01f}},
    {"l_toes", {0.09f, 0.02f, 0.12f}},
};

glm::vec3 restPosition(std::string_view name) {
  const bool right = name.starts_with("r_");
  const std::string key = right ? "l_" + std::string(name.substr(2)) : std::string(name);
  for (const RestJoint& r : kRest) {
    if (r.name == key)
      return right ? glm::vec3(-r.position.x, r.position.y, r.position.z) : r.position;
  }
  return glm::vec3(0.0f);  // unreachable: kRest names every canonical joint's left/mid form
}

constexpr int kFps = 30;
int at(double seconds) { return static_cast<int>(std::lround(seconds * kFps)); }

// The relaxed standing pose every clip starts and ends with: arms hanging, elbows a little
// bent, palms towards the thighs, fingers slightly curled.
Posture relaxedPose(const Skeleton& s) {
  Posture p = restPosture(s);
  for (bool left : {true, false}) {
    const float x = left ? 1.0f : -1.0f;
    ArmGoal goal;
    goal.wrist = glm::vec3(0.21f * x, 0.90f, 0.04f);
    goal.pole = glm::vec3(0.3f * x, 0.0f, -1.0f);
    goal.fingers = glm::vec3(0.05f * x, -1.0f, 0.08f);
    goal.palm_normal = glm::vec3(-x, 0.0f, 0.0f);
    gesture::placeArm(s, left, goal, p);
    gesture::curlFingers(s, left, {0.25f, 0.25f, 0.3f, 0.35f, 0.4f}, p);
  }
  return p;
}

glm::vec3 shoulder(bool left) { return restPosition(left ? "l_upperarm" : "r_upperarm"); }

glm::quat yaw(float degrees) { return glm::angleAxis(glm::radians(degrees), glm::vec3(0, 1, 0)); }

// "wave": the right hand rises beside the head, palm forward, and the forearm swings
// about the elbow three times.
std::vector<Posture> wave(const Skeleton& s) {
  const Posture relaxed = relaxedPose(s);
  const glm::vec3 elbow = shoulder(false) + glm::vec3(-0.24f, -0.06f, 0.14f);
  const auto raised = [&](float swing_degrees) {
    Posture p = relaxed;
    // The clavicle lifts a little with the arm.
    p.rotations[static_cast<std::size_t>(joint("r_clavicle"))] =
        glm::angleAxis(glm::radians(-8.0f), glm::vec3(0, 0, 1));
    const glm::quat sway = glm::angleAxis(glm::radians(swing_degrees), glm::vec3(0, 0, 1));
    const glm::vec3 up = sway * glm::vec3(0.0f, 1.0f, 0.0f);
    ArmGoal goal;
    goal.wrist = elbow + 0.25f * up;
    goal.pole = glm::vec3(-0.6f, -1.0f, -0.2f);
    goal.fingers = up;
    goal.palm_normal = glm::vec3(0.0f, 0.0f, 1.0f);
    gesture::placeArm(s, false, goal, p);
    gesture::curlFingers(s, false, {0.1f, 0.05f, 0.05f, 0.05f, 0.08f}, p);
    p.rotations[static_cast<std::size_t>(joint("head"))] =
        glm::angleAxis(glm::radians(-6.0f), glm::vec3(0, 0, 1)) * yaw(-8.0f);
    return p;
  };
  std::vector<Key> keys = {{0, relaxed}, {at(1.3), raised(0.0f)}};
  int frame = at(1.3);
  for (int i = 0; i < 3; ++i) {
    keys.push_back({frame += at(0.4), raised(25.0f)});
    keys.push_back({frame += at(0.4), raised(-20.0f)});
  }
  keys.push_back({frame += at(0.4), raised(0.0f)});
  keys.push_back({frame += at(1.3), relaxed});
  return gesture::interpolate(keys, kGestureFrameTime);
}

// "point": the right arm points straight ahead, then to the right side; the index finger
// is out, the other fingers curled, and the head turns to look along the arm.
std::vector<Posture> point(const Skeleton& s) {
  const Posture relaxed = relaxedPose(s);
  const auto pointing = [&](glm::vec3 direction, float head_yaw) {
    Posture p = relaxed;
    const glm::vec3 d = glm::normalize(direction);
    ArmGoal goal;
    goal.wrist = shoulder(false) + 0.53f * d;
    goal.pole = glm::vec3(-0.3f, -1.0f, 0.0f);
    goal.fingers = d;
    goal.palm_normal = glm::vec3(0.3f, -1.0f, 0.0f);
    gesture::placeArm(s, false, goal, p);
    gesture::curlFingers(s, false, {0.6f, 0.0f, 1.4f, 1.45f, 1.5f}, p);
    p.rotations[static_cast<std::size_t>(joint("neck"))] = yaw(head_yaw * 0.4f);
    p.rotations[static_cast<std::size_t>(joint("head"))] = yaw(head_yaw * 0.6f);
    return p;
  };
  const Posture ahead = pointing(glm::vec3(-0.1f, -0.05f, 1.0f), -5.0f);
  const Posture side = pointing(glm::vec3(-1.0f, -0.05f, 0.25f), -55.0f);
  const std::vector<Key> keys = {{0, relaxed},    {at(1.0), ahead}, {at(2.0), ahead},
                                 {at(3.0), side}, {at(4.0), side},  {at(5.0), relaxed}};
  return gesture::interpolate(keys, kGestureFrameTime);
}

// "clap": both hands in front of the chest, palms facing, fingers up and forward; the
// palms' skins meet at x = 0 three times (kGesturePalmHalfThickness from each centre).
std::vector<Posture> clap(const Skeleton& s) {
  const Posture relaxed = relaxedPose(s);
  const glm::vec3 fingers = glm::normalize(glm::vec3(0.0f, 0.6f, 0.8f));
  const glm::vec3 palm_from_wrist =
      0.5f * restPosition("l_middle1") - 0.5f * restPosition("l_hand");
  const float palm_reach = glm::length(palm_from_wrist);
  const auto hands = [&](float half_gap) {
    Posture p = relaxed;
    for (bool left : {true, false}) {
      const float x = left ? 1.0f : -1.0f;
      // Palm centre at (x * (half thickness + half gap), 1.22, 0.30), palm facing inwards.
      const glm::vec3 centre(x * (kGesturePalmHalfThickness + half_gap), 1.22f, 0.30f);
      ArmGoal goal;
      goal.wrist = centre - palm_reach * fingers;
      goal.pole = glm::vec3(0.35f * x, -1.0f, -0.3f);
      goal.fingers = fingers;
      goal.palm_normal = glm::vec3(-x, 0.0f, 0.0f);
      gesture::placeArm(s, left, goal, p);
      gesture::curlFingers(s, left, {0.05f, 0.03f, 0.03f, 0.05f, 0.08f}, p);
    }
    return p;
  };
  const Posture apart = hands(0.12f);
  const Posture together = hands(0.0f);
  std::vector<Key> keys = {{0, relaxed}, {at(0.8), apart}};
  int frame = at(0.8);
  for (int i = 0; i < 3; ++i) {
    keys.push_back({frame += at(0.4), together});
    keys.push_back({frame += at(0.3), apart});
  }
  keys.push_back({frame += at(0.8), relaxed});
  return gesture::interpolate(keys, kGestureFrameTime);
}

// "idle": two slow breaths (the chest rises and leans back a little) and a weight shift
// from the right foot to the left and back; the legs bend to keep the feet planted.
std::vector<Posture> idle(const Skeleton& s) {
  const Posture relaxed = relaxedPose(s);
  const auto stance = [&](float shift, float breath) {
    Posture p = relaxed;
    // Hips: over the weight-bearing foot, a little lower, rolled towards the free side.
    p.root_translation =
        restPosition("hips") + glm::vec3(shift, -0.012f - 0.2f * std::abs(shift), 0.0f);
    p.rotations[static_cast<std::size_t>(joint("hips"))] =
        glm::angleAxis(glm::radians(-60.0f * shift), glm::vec3(0, 0, 1));
    // The spine straightens the torso over the shifted hips; the chest breathes.
    p.rotations[static_cast<std::size_t>(joint("spine"))] =
        glm::angleAxis(glm::radians(90.0f * shift), glm::vec3(0, 0, 1));
    const glm::quat lift = glm::angleAxis(glm::radians(-1.5f * breath), glm::vec3(1, 0, 0));
    p.rotations[static_cast<std::size_t>(joint("chest"))] = lift;
    p.rotations[static_cast<std::size_t>(joint("upper_chest"))] = lift;
    p.rotations[static_cast<std::size_t>(joint("neck"))] = glm::inverse(lift);
    p.rotations[static_cast<std::size_t>(joint("head"))] =
        glm::angleAxis(glm::radians(-30.0f * shift), glm::vec3(0, 0, 1));
    for (bool left : {true, false}) {
      const glm::vec3 ankle = restPosition(left ? "l_foot" : "r_foot");
      gesture::placeLeg(s, left, ankle, glm::vec3(left ? 0.15f : -0.15f, 0.0f, 1.0f), p);
    }
    return p;
  };
  const Posture neutral = stance(0.0f, 0.0f);
  const std::vector<Key> keys = {{0, neutral},
                                 {at(1.5), stance(0.025f, 1.0f)},
                                 {at(3.0), stance(0.0f, 0.0f)},
                                 {at(4.5), stance(-0.025f, 1.0f)},
                                 {at(6.0), neutral}};
  return gesture::interpolate(keys, kGestureFrameTime);
}

}  // namespace

Skeleton makeGestureSkeleton() {
  Skeleton s;
  const auto names = canonicalJoints();
  const auto parents = canonicalParents();
  s.rest_local.resize(names.size());
  for (std::size_t j = 0; j < names.size(); ++j) {
    s.names.emplace_back(names[j]);
    s.parents.push_back(parents[j]);
    const glm::vec3 p = restPosition(names[j]);
    s.rest_local[j].translation =
        parents[j] < 0 ? p : p - restPosition(names[static_cast<std::size_t>(parents[j])]);
  }
  computeInverseBind(s);
  return s;
}

std::vector<MotionClip> makeBundledGestures() {
  const Skeleton s = makeGestureSkeleton();
  std::vector<MotionClip> clips;
  const std::pair<const char*, std::vector<Posture>> motions[] = {
      {"wave", wave(s)}, {"point", point(s)}, {"clap", clap(s)}, {"idle", idle(s)}};
  for (const auto& [name, frames] : motions) {
    clips.push_back(clipFromPostures(s, frames, kGestureFrameTime, 1.0f, name));
  }
  return clips;
}

Status writeBundledGestures(const std::string& out_dir) {
  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) return fail("{}: cannot create the folder: {}", out_dir, ec.message());
  for (const MotionClip& clip : makeBundledGestures()) {
    const std::string path = (std::filesystem::path(out_dir) / (clip.source + ".bvh")).string();
    if (Status s = writeFileText(path, writeBvh(clip)); !s) return s;
  }
  return {};
}

}  // namespace vistel
