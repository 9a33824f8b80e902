#include "common/anim/skin_mesh.hpp"

#include <cmath>
#include <limits>

namespace vistel {
namespace {

bool finite3(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

Status validateSkinMesh(const SkinMesh& m, int joint_count) {
  const std::size_t n = m.positions.size();
  const auto k = static_cast<std::size_t>(m.influences);
  if (m.influences < 1 || m.influences > kMaxInfluences) {
    return fail("skin has {} influence slots per vertex (allowed 1..{})", m.influences,
                kMaxInfluences);
  }
  if (m.normals.size() != n || m.joints.size() != n * k || m.weights.size() != n * k) {
    return fail("skin arrays disagree: {} positions, {} normals, {} joint slots, {} weights", n,
                m.normals.size(), m.joints.size(), m.weights.size());
  }
  if (m.indices.size() % 3 != 0)
    return fail("skin index count {} is not a multiple of 3", m.indices.size());
  for (std::size_t i = 0; i < m.indices.size(); ++i) {
    if (m.indices[i] >= n) {
      return fail("triangle {} refers to vertex {} of {}", i / 3, m.indices[i], n);
    }
  }
  for (std::size_t v = 0; v < n; ++v) {
    if (!finite3(m.positions[v]) || !finite3(m.normals[v])) {
      return fail("vertex {} has a non-finite position or normal", v);
    }
    float sum = 0.0f;
    for (std::size_t s = 0; s < k; ++s) {
      const float w = m.weights[v * k + s];
      if (!(w >= 0.0f && w <= 1.0f)) return fail("vertex {} has weight {} outside [0,1]", v, w);
      if (w > 0.0f && m.joints[v * k + s] >= joint_count) {
        return fail("vertex {} is bound to joint {} of {}", v, m.joints[v * k + s], joint_count);
      }
      sum += w;
    }
    if (std::abs(sum - 1.0f) > 1e-4f) return fail("vertex {} weights sum to {}, not 1", v, sum);
  }
  return {};
}

void computeVertexNormals(std::span<const glm::vec3> positions,
                          std::span<const std::uint32_t> indices, std::span<glm::vec3> out) {
  for (glm::vec3& nrm : out) nrm = glm::vec3(0.0f);
  for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
    const glm::vec3& a = positions[indices[t]];
    const glm::vec3& b = positions[indices[t + 1]];
    const glm::vec3& c = positions[indices[t + 2]];
    const glm::vec3 face = glm::cross(b - a, c - a);  // length = 2 * area
    out[indices[t]] += face;
    out[indices[t + 1]] += face;
    out[indices[t + 2]] += face;
  }
  for (glm::vec3& nrm : out) {
    const float len = glm::length(nrm);
    nrm = len > 0.0f ? nrm / len : glm::vec3(0.0f, 1.0f, 0.0f);
  }
}

int maxInfluencesUsed(const SkinMesh& m) {
  const auto k = static_cast<std::size_t>(m.influences);
  int best = 0;
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    int used = 0;
    for (std::size_t s = 0; s < k; ++s) used += m.weights[v * k + s] > 0.0f ? 1 : 0;
    best = std::max(best, used);
  }
  return best;
}

Bounds computeBounds(std::span<const glm::vec3> points) {
  if (points.empty()) return {};
  Bounds b{glm::vec3(std::numeric_limits<float>::max()),
           glm::vec3(std::numeric_limits<float>::lowest())};
  for (const glm::vec3& p : points) {
    b.min = glm::min(b.min, p);
    b.max = glm::max(b.max, p);
  }
  return b;
}

}  // namespace vistel

namespace vistel {
double enclosedVolume(std::span<const glm::vec3> positions,
                      std::span<const std::uint32_t> indices) {
  double six_v = 0.0;
  for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
    const glm::dvec3 a(positions[indices[t]]);
    const glm::dvec3 b(positions[indices[t + 1]]);
    const glm::dvec3 c(positions[indices[t + 2]]);
    six_v += glm::dot(a, glm::cross(b, c));
  }
  return six_v / 6.0;
}
}  // namespace vistel
