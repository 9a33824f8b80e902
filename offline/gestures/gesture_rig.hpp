// Posing tools for the bundled gestures: the canonical skeleton's joints by name, forward
// kinematics, two-bone inverse kinematics for arms and legs, finger curls, and keyframe
// interpolation. Internal to vistel_gestures.
#pragma once

#include <span>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/anim/posture.hpp"
#include "common/anim/skeleton.hpp"

namespace vistel::gesture {

// Joint index of a canonical name on makeGestureSkeleton() (its joints are in canonical
// order). The name must be canonical.
int joint(std::string_view canonical_name);

// World (model-space) rotations and positions of a posture, metres.
struct WorldPose {
  std::vector<glm::quat> rotation;  // (njoint)
  std::vector<glm::vec3> position;  // (njoint)
};
WorldPose forwardKinematics(const Skeleton& skeleton, const Posture& posture);

// Where an arm should go, in model space.
struct ArmGoal {
  glm::vec3 wrist;        // wrist (hand joint) position; clamped to the arm's reach
  glm::vec3 pole;         // direction the elbow points to (from the shoulder)
  glm::vec3 fingers;      // direction from the wrist towards the middle knuckle
  glm::vec3 palm_normal;  // direction the palm faces (orthogonalised against fingers)
};

// Sets upper arm, forearm and hand rotations of one side (the clavicle and everything
// above are read from the posture): the elbow is a hinge, the forearm takes the hand's
// twist about its axis, the wrist only swings.
void placeArm(const Skeleton& skeleton, bool left, const ArmGoal& goal, Posture& posture);

// Sets thigh, shin and foot rotations of one side so that the ankle (foot joint) reaches
// `ankle` with the knee towards `knee_pole`, the foot level and facing +Z.
void placeLeg(const Skeleton& skeleton, bool left, glm::vec3 ankle, glm::vec3 knee_pole,
              Posture& posture);

// Curls the fingers of one hand towards the palm: angles (radians) at the first knuckle;
// the second and third joints follow at 1.1x and 0.8x.
struct Curl {
  float thumb = 0.0f;
  float index = 0.0f;
  float middle = 0.0f;
  float ring = 0.0f;
  float pinky = 0.0f;
};
void curlFingers(const Skeleton& skeleton, bool left, const Curl& curl, Posture& posture);

// Centre of a palm on the hand bone's axis and its normal, in model space.
void palm(const Skeleton& skeleton, const WorldPose& world, bool left, glm::vec3& centre,
          glm::vec3& normal);

// A keyframe: a posture at an integer frame.
struct Key {
  int frame = 0;
  Posture posture;
};
// Frames 0..keys.back().frame: smoothstep slerp (rotations) and lerp (root translation)
// between consecutive keys, each key reproduced exactly. Keys ascend strictly from 0.
std::vector<Posture> interpolate(std::span<const Key> keys, double frame_time);

}  // namespace vistel::gesture
