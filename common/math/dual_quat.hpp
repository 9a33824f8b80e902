// Unit dual quaternions for rigid transforms and dual-quaternion skinning
// (Kavan, Collins, Zara, O'Sullivan 2007, "Skinning with dual quaternions").
#pragma once

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace vistel {

struct DualQuat {
  glm::quat real{1.0f, 0.0f, 0.0f, 0.0f};  // rotation
  glm::quat dual{0.0f, 0.0f, 0.0f, 0.0f};  // 0.5 * translation * rotation

  // From a rotation then a translation: p -> r p + t.
  static DualQuat fromRigid(const glm::quat& r, const glm::vec3& t);
  // From an affine matrix; any scale or shear is dropped (DQS blends rigid motions).
  static DualQuat fromMatrix(const glm::mat4& m);

  glm::vec3 translation() const;
  // Applies this (assumed unit) dual quaternion.
  glm::vec3 transformPoint(const glm::vec3& p) const;
  glm::vec3 transformVector(const glm::vec3& v) const;
};

// Accumulates w * q into acc, flipping q to the hemisphere of `pivot` first (the
// antipodality fix of DQS).
inline void accumulate(DualQuat& acc, const DualQuat& q, float w, const glm::quat& pivot) {
  const float s = glm::dot(q.real, pivot) < 0.0f ? -w : w;
  acc.real = acc.real + q.real * s;
  acc.dual = acc.dual + q.dual * s;
}

// Normalises a blended dual quaternion back to a unit one.
DualQuat normalized(const DualQuat& q);

}  // namespace vistel
