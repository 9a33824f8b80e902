// How a glove's wrist sensors (pitch = flexion, yaw = radial/ulnar deviation) turn the hand
// relative to the forearm. Shared by the simulator (which reads the angles off a posture)
// and the solver (which applies them), so both use one convention.
//
// The axes are fixed in the forearm's frame at the calibration posture, where the arms hang
// with the palms facing the thighs: flexion turns the hand towards the palm (medially),
// deviation towards the thumb (forwards). Angle 0 = the calibration posture's wrist.
#pragma once

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/sensors/body_roles.hpp"

namespace vistel {

struct WristModel {
  glm::vec3 forearm_axis{1.0f, 0.0f, 0.0f};  // forearm frame: elbow -> wrist, unit
  glm::vec3 pitch_axis{0.0f, 1.0f, 0.0f};    // forearm frame, unit, perpendicular to the axis
  glm::vec3 yaw_axis{0.0f, 0.0f, 1.0f};      // forearm frame, unit, perpendicular to both
  glm::quat rest_relative{1.0f, 0.0f, 0.0f, 0.0f};  // hand relative to forearm at calibration
};

// side 0 = left, 1 = right. forearm_axis_local: the hand joint's offset direction in the
// forearm frame. Rotations are model-space world rotations at the calibration posture.
WristModel makeWristModel(int side, const BodyFrame& body, const glm::quat& forearm_world,
                          const glm::quat& hand_world, const glm::vec3& forearm_axis_local);

// The hand's world rotation for a forearm world rotation and wrist angles (radians).
glm::quat handFromWrist(const WristModel& wrist, const glm::quat& forearm_world, float pitch,
                        float yaw);

// The wrist angles that best explain a hand rotation (twist about the forearm axis, which a
// glove does not measure, is dropped). handFromWrist(wristAngles(...)) reproduces the hand
// exactly when the hand is not twisted relative to the calibration.
void wristAngles(const WristModel& wrist, const glm::quat& forearm_world,
                 const glm::quat& hand_world, float& pitch, float& yaw);

}  // namespace vistel
