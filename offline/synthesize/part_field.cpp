#include "offline/synthesize/part_field.hpp"

namespace vistel {

PartField::PartField(const PartMesh& part) : part_(part), tree_(part.mesh) {}

FieldSample PartField::at(const glm::vec3& p) const {
  const NearestTriangle hit = tree_.nearest(p);
  FieldSample out;
  out.distance = hit.distance;
  out.point = hit.point;
  // Barycentric coordinates of the nearest point in its triangle.
  const std::uint32_t* corner = &part_.mesh.indices[3 * static_cast<std::size_t>(hit.face)];
  const glm::vec3& a = part_.mesh.positions[corner[0]];
  const glm::vec3& b = part_.mesh.positions[corner[1]];
  const glm::vec3& c = part_.mesh.positions[corner[2]];
  const glm::vec3 e0 = b - a, e1 = c - a, e2 = hit.point - a;
  const float d00 = glm::dot(e0, e0), d01 = glm::dot(e0, e1), d11 = glm::dot(e1, e1);
  const float d20 = glm::dot(e2, e0), d21 = glm::dot(e2, e1);
  const float denom = d00 * d11 - d01 * d01;
  float v = 1.0f / 3.0f, w = 1.0f / 3.0f;
  if (denom > 1e-20f) {
    v = (d11 * d20 - d01 * d21) / denom;
    w = (d00 * d21 - d01 * d20) / denom;
  }
  // The normal there, from the corners' normals; the face's when they cancel.
  glm::vec3 n = (1.0f - v - w) * part_.normals[corner[0]] + v * part_.normals[corner[1]] +
                w * part_.normals[corner[2]];
  if (glm::dot(n, n) < 1e-12f) n = glm::cross(e0, e1);
  const float len = glm::length(n);
  out.normal = len > 0.0f ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
  out.value = glm::dot(p - hit.point, out.normal);
  return out;
}

}  // namespace vistel
