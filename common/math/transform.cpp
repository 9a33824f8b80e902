#include "common/math/transform.hpp"

#include <algorithm>
#include <cmath>

namespace vistel {

glm::mat4 Transform::matrix() const {
  const glm::mat3 r = glm::mat3_cast(rotation);
  glm::mat4 m(1.0f);
  m[0] = glm::vec4(r[0] * scale.x, 0.0f);
  m[1] = glm::vec4(r[1] * scale.y, 0.0f);
  m[2] = glm::vec4(r[2] * scale.z, 0.0f);
  m[3] = glm::vec4(translation, 1.0f);
  return m;
}

Transform Transform::fromMatrix(const glm::mat4& m) {
  Transform t;
  t.translation = glm::vec3(m[3]);
  glm::vec3 c0(m[0]), c1(m[1]), c2(m[2]);
  t.scale = glm::vec3(glm::length(c0), glm::length(c1), glm::length(c2));
  if (glm::dot(glm::cross(c0, c1), c2) < 0.0f) t.scale.x = -t.scale.x;
  const glm::mat3 r(c0 / t.scale.x, c1 / t.scale.y, c2 / t.scale.z);
  t.rotation = glm::normalize(glm::quat_cast(r));
  return t;
}

glm::quat rotationBetween(const glm::vec3& from, const glm::vec3& to) {
  const float d = glm::dot(from, to);
  if (d < -0.999999f) {
    // Opposite: half-turn about any axis perpendicular to `from`.
    glm::vec3 axis = glm::cross(glm::vec3(1, 0, 0), from);
    if (glm::dot(axis, axis) < 1e-8f) axis = glm::cross(glm::vec3(0, 1, 0), from);
    return glm::angleAxis(glm::pi<float>(), glm::normalize(axis));
  }
  const glm::vec3 c = glm::cross(from, to);
  return glm::normalize(glm::quat(1.0f + d, c.x, c.y, c.z));
}

float angleBetween(const glm::quat& a, const glm::quat& b) {
  const float d = std::min(1.0f, std::abs(glm::dot(a, b)));
  return 2.0f * std::acos(d);
}

}  // namespace vistel
