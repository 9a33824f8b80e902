#include "common/sensors/hand_model.hpp"

#include <cmath>

#include "common/sensors/rotation_utils.hpp"

namespace vistel {

WristModel makeWristModel(int side, const BodyFrame& body, const glm::quat& forearm_world,
                          const glm::quat& hand_world, const glm::vec3& forearm_axis_local) {
  WristModel w;
  w.forearm_axis = glm::normalize(forearm_axis_local);
  const glm::vec3 axis_world = forearm_world * w.forearm_axis;
  // The palm faces the body's midline in the calibration posture.
  const glm::vec3 palm = side == 0 ? -body.left : body.left;
  glm::vec3 pitch_world = glm::cross(axis_world, palm);
  if (glm::dot(pitch_world, pitch_world) < 1e-6f) pitch_world = anyPerpendicular(axis_world);
  const glm::quat inv = glm::inverse(forearm_world);
  const glm::mat3 f = frameFrom(w.forearm_axis, inv * pitch_world);
  w.pitch_axis = f[1];
  w.yaw_axis = f[2];
  // Deviation towards the thumb (forward) is positive.
  const glm::vec3 toward = glm::cross(axis_world, forearm_world * w.yaw_axis);
  if (glm::dot(toward, body.forward) < 0.0f) w.yaw_axis = -w.yaw_axis;
  w.rest_relative = glm::normalize(inv * hand_world);
  return w;
}

glm::quat handFromWrist(const WristModel& w, const glm::quat& forearm_world, float pitch,
                        float yaw) {
  const glm::vec3 r = w.pitch_axis * pitch + w.yaw_axis * yaw;
  return glm::normalize(forearm_world * fromRotationVector(r) * w.rest_relative);
}

void wristAngles(const WristModel& w, const glm::quat& forearm_world, const glm::quat& hand_world,
                 float& pitch, float& yaw) {
  const glm::quat g = glm::inverse(forearm_world) * hand_world * glm::inverse(w.rest_relative);
  glm::quat swing, twist;
  swingTwist(normalizeSafe(g), w.forearm_axis, swing, twist);
  const glm::vec3 r = rotationVector(swing);
  pitch = glm::dot(r, w.pitch_axis);
  yaw = glm::dot(r, w.yaw_axis);
}

}  // namespace vistel
