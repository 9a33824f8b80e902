#include "common/math/dual_quat.hpp"

namespace vistel {

DualQuat DualQuat::fromRigid(const glm::quat& r, const glm::vec3& t) {
  DualQuat q;
  q.real = r;
  q.dual = glm::quat(0.0f, t.x, t.y, t.z) * r * 0.5f;
  return q;
}

DualQuat DualQuat::fromMatrix(const glm::mat4& m) {
  glm::mat3 r(m);
  r[0] = glm::normalize(r[0]);
  r[1] = glm::normalize(r[1] - r[0] * glm::dot(r[0], r[1]));
  r[2] = glm::cross(r[0], r[1]);
  return fromRigid(glm::normalize(glm::quat_cast(r)), glm::vec3(m[3]));
}

glm::vec3 DualQuat::translation() const {
  const glm::quat t = dual * glm::conjugate(real) * 2.0f;
  return {t.x, t.y, t.z};
}

glm::vec3 DualQuat::transformPoint(const glm::vec3& p) const { return real * p + translation(); }

glm::vec3 DualQuat::transformVector(const glm::vec3& v) const { return real * v; }

DualQuat normalized(const DualQuat& q) {
  const float len = glm::length(q.real);
  DualQuat out;
  out.real = q.real / len;
  out.dual = q.dual / len;
  // Remove the component of dual parallel to real so the result is exactly unit.
  out.dual = out.dual - out.real * glm::dot(out.real, out.dual);
  return out;
}

}  // namespace vistel
