// Small rotation helpers for the rig simulator and the posture solver (header-only,
// allocation-free). Vectors are unit unless stated; angles are radians.
#pragma once

#include <cmath>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace vistel {

// q = swing * twist, twist about `axis` (unit), swing about an axis perpendicular to it.
inline void swingTwist(const glm::quat& q, const glm::vec3& axis, glm::quat& swing,
                       glm::quat& twist) {
  const glm::vec3 v(q.x, q.y, q.z);
  const glm::vec3 p = axis * glm::dot(v, axis);
  twist = glm::quat(q.w, p.x, p.y, p.z);
  const float n = glm::length(twist);
  twist = n < 1e-9f ? glm::quat(1.0f, 0.0f, 0.0f, 0.0f) : twist / n;
  swing = q * glm::conjugate(twist);
}

// Signed angle of a rotation about a unit axis, in (-pi, pi].
inline float twistAngle(const glm::quat& q, const glm::vec3& axis) {
  const float s = glm::dot(glm::vec3(q.x, q.y, q.z), axis);
  float a = 2.0f * std::atan2(s, q.w);
  if (a > glm::pi<float>()) a -= glm::two_pi<float>();
  if (a <= -glm::pi<float>()) a += glm::two_pi<float>();
  return a;
}

// The rotation part of a rigid transform.
inline glm::quat worldRotation(const glm::mat4& m) {
  return glm::normalize(glm::quat_cast(glm::mat3(m)));
}

// Rotation vector (axis * angle) of a rotation, shortest way round.
inline glm::vec3 rotationVector(const glm::quat& q_in) {
  const glm::quat q = q_in.w < 0.0f ? -q_in : q_in;
  const glm::vec3 v(q.x, q.y, q.z);
  const float s = glm::length(v);
  if (s < 1e-9f) return 2.0f * v;
  return v * (2.0f * std::atan2(s, q.w) / s);
}

inline glm::quat fromRotationVector(const glm::vec3& r) {
  const float a = glm::length(r);
  if (a < 1e-9f) return glm::normalize(glm::quat(1.0f, 0.5f * r.x, 0.5f * r.y, 0.5f * r.z));
  return glm::angleAxis(a, r / a);
}

// Orthonormal frame (columns: a, b', a x b') from a primary direction a and a secondary b
// (b made perpendicular to a). Both non-zero and not parallel.
inline glm::mat3 frameFrom(const glm::vec3& a, const glm::vec3& b) {
  const glm::vec3 x = glm::normalize(a);
  const glm::vec3 y = glm::normalize(b - x * glm::dot(b, x));
  return glm::mat3(x, y, glm::cross(x, y));
}

// Slerp from identity by t (the fraction t of rotation q).
inline glm::quat fractionOf(const glm::quat& q, float t) {
  return fromRotationVector(rotationVector(q) * t);
}

// A unit vector perpendicular to v.
inline glm::vec3 anyPerpendicular(const glm::vec3& v) {
  const glm::vec3 a = std::abs(v.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
  return glm::normalize(glm::cross(v, a));
}

inline glm::quat normalizeSafe(const glm::quat& q) {
  const float n = glm::length(q);
  return n > 1e-12f ? q / n : glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
}

}  // namespace vistel
