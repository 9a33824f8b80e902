// Rigid-plus-scale transforms (translation, rotation, scale), metres and radians,
// right-handed, +Y up.
#pragma once

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace vistel {

struct Transform {
  glm::vec3 translation{0.0f};
  glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};  // (w, x, y, z) constructor order
  glm::vec3 scale{1.0f};

  // T * R * S as a 4x4 matrix.
  glm::mat4 matrix() const;
  // Decomposes an affine matrix without shear (the inverse of matrix()); a negative
  // determinant is folded into scale.x.
  static Transform fromMatrix(const glm::mat4& m);
};

// Rotation that takes unit vector `from` to unit vector `to` along the shortest arc
// (a half-turn about an axis perpendicular to `from` when they are opposite).
glm::quat rotationBetween(const glm::vec3& from, const glm::vec3& to);

// Quaternion with non-negative w (q and -q are the same rotation).
inline glm::quat canonical(const glm::quat& q) { return q.w < 0.0f ? -q : q; }

// Angle in radians between two rotations (0..pi).
float angleBetween(const glm::quat& a, const glm::quat& b);

}  // namespace vistel
