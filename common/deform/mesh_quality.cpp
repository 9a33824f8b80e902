#include "common/deform/mesh_quality.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_set>

namespace vistel {
namespace {

// Whether segment pq crosses triangle abc (Moller-Trumbore with the segment's range).
bool segmentHitsTriangle(const glm::vec3& p, const glm::vec3& q, const glm::vec3& a,
                         const glm::vec3& b, const glm::vec3& c) {
  const glm::vec3 d = q - p;
  const glm::vec3 e1 = b - a;
  const glm::vec3 e2 = c - a;
  const glm::vec3 h = glm::cross(d, e2);
  const float det = glm::dot(e1, h);
  // Parallel (or coplanar) within float precision: no crossing.
  if (std::abs(det) <= 1e-6f * glm::length(e1) * glm::length(e2) * glm::length(d)) return false;
  const float inv = 1.0f / det;
  const glm::vec3 s = p - a;
  const float u = inv * glm::dot(s, h);
  if (u < 0.0f || u > 1.0f) return false;
  const glm::vec3 qv = glm::cross(s, e1);
  const float v = inv * glm::dot(d, qv);
  if (v < 0.0f || u + v > 1.0f) return false;
  const float t = inv * glm::dot(e2, qv);
  return t >= 0.0f && t <= 1.0f;
}

}  // namespace

bool trianglesIntersect(const glm::vec3& a0, const glm::vec3& a1, const glm::vec3& a2,
                        const glm::vec3& b0, const glm::vec3& b1, const glm::vec3& b2) {
  return segmentHitsTriangle(a0, a1, b0, b1, b2) || segmentHitsTriangle(a1, a2, b0, b1, b2) ||
         segmentHitsTriangle(a2, a0, b0, b1, b2) || segmentHitsTriangle(b0, b1, a0, a1, a2) ||
         segmentHitsTriangle(b1, b2, a0, a1, a2) || segmentHitsTriangle(b2, b0, a0, a1, a2);
}

int countInvertedFaces(std::span<const glm::vec3> ref, std::span<const glm::vec3> def,
                       std::span<const std::uint32_t> idx) {
  int count = 0;
  for (std::size_t f = 0; f + 2 < idx.size(); f += 3) {
    const glm::vec3 n0 = glm::cross(ref[idx[f + 1]] - ref[idx[f]], ref[idx[f + 2]] - ref[idx[f]]);
    const glm::vec3 n1 = glm::cross(def[idx[f + 1]] - def[idx[f]], def[idx[f + 2]] - def[idx[f]]);
    if (glm::dot(n0, n1) < 0.0f) ++count;
  }
  return count;
}

int countSelfIntersections(std::span<const glm::vec3> pos, std::span<const std::uint32_t> idx,
                           std::span<const std::uint32_t> faces) {
  std::vector<std::uint32_t> all;
  if (faces.empty()) {
    all.resize(idx.size() / 3);
    for (std::size_t f = 0; f < all.size(); ++f) all[f] = static_cast<std::uint32_t>(f);
    faces = all;
  }
  if (faces.empty()) return 0;
  // Cell size: twice the mean edge length.
  double edge = 0.0;
  for (const std::uint32_t f : faces) edge += glm::length(pos[idx[3 * f + 1]] - pos[idx[3 * f]]);
  const float cell =
      std::max(2.0f * static_cast<float>(edge / static_cast<double>(faces.size())), 1e-6f);
  struct Entry {
    std::int64_t key;
    std::uint32_t face;
  };
  std::vector<Entry> entries;
  std::vector<glm::ivec3> lo(faces.size()), hi(faces.size());
  const auto key = [](int x, int y, int z) {
    return (static_cast<std::int64_t>(x) & 0x1FFFFF) |
           ((static_cast<std::int64_t>(y) & 0x1FFFFF) << 21) |
           ((static_cast<std::int64_t>(z) & 0x1FFFFF) << 42);
  };
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const std::uint32_t f = faces[i];
    const glm::vec3 a = pos[idx[3 * f]], b = pos[idx[3 * f + 1]], c = pos[idx[3 * f + 2]];
    lo[i] = glm::ivec3(glm::floor(glm::min(a, glm::min(b, c)) / cell));
    hi[i] = glm::ivec3(glm::floor(glm::max(a, glm::max(b, c)) / cell));
    for (int x = lo[i].x; x <= hi[i].x; ++x) {
      for (int y = lo[i].y; y <= hi[i].y; ++y) {
        for (int z = lo[i].z; z <= hi[i].z; ++z)
          entries.push_back({key(x, y, z), static_cast<std::uint32_t>(i)});
      }
    }
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& x, const Entry& y) {
    return x.key < y.key || (x.key == y.key && x.face < y.face);
  });
  int count = 0;
  for (std::size_t s = 0; s < entries.size();) {
    std::size_t e = s;
    while (e < entries.size() && entries[e].key == entries[s].key) ++e;
    for (std::size_t i = s; i < e; ++i) {
      for (std::size_t j = i + 1; j < e; ++j) {
        const std::uint32_t fi = faces[entries[i].face], fj = faces[entries[j].face];
        const std::uint32_t* ti = &idx[3 * fi];
        const std::uint32_t* tj = &idx[3 * fj];
        bool shared = false;
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b < 3; ++b) shared = shared || ti[a] == tj[b];
        }
        if (shared) continue;
        // Test each pair once: in the lowest cell both boxes share.
        const glm::ivec3 l = glm::max(lo[entries[i].face], lo[entries[j].face]);
        const glm::ivec3 h = glm::min(hi[entries[i].face], hi[entries[j].face]);
        if (l.x > h.x || l.y > h.y || l.z > h.z || key(l.x, l.y, l.z) != entries[s].key) continue;
        if (trianglesIntersect(pos[ti[0]], pos[ti[1]], pos[ti[2]], pos[tj[0]], pos[tj[1]],
                               pos[tj[2]])) {
          ++count;
        }
      }
    }
    s = e;
  }
  return count;
}

glm::vec3 closestPointOnTriangle(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b,
                                 const glm::vec3& c) {
  // Voronoi regions of the triangle (vertices, edges, face).
  const glm::vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return a;
  const glm::vec3 bp = p - b;
  const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0f && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return a + (d1 / (d1 - d3)) * ab;
  const glm::vec3 cp = p - c;
  const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0f && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) return a + (d2 / (d2 - d6)) * ac;
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  }
  const float denom = 1.0f / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

double windingNumber(std::span<const glm::vec3> pos, std::span<const std::uint32_t> idx,
                     const glm::vec3& p) {
  // Van Oosterom & Strackee's solid angle of each triangle seen from p.
  double total = 0.0;
  for (std::size_t f = 0; f + 2 < idx.size(); f += 3) {
    const glm::dvec3 a = glm::dvec3(pos[idx[f]]) - glm::dvec3(p);
    const glm::dvec3 b = glm::dvec3(pos[idx[f + 1]]) - glm::dvec3(p);
    const glm::dvec3 c = glm::dvec3(pos[idx[f + 2]]) - glm::dvec3(p);
    const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
    if (la == 0.0 || lb == 0.0 || lc == 0.0) continue;
    const double det = glm::dot(a, glm::cross(b, c));
    const double den =
        la * lb * lc + glm::dot(a, b) * lc + glm::dot(b, c) * la + glm::dot(c, a) * lb;
    total += 2.0 * std::atan2(det, den);
  }
  return total / (4.0 * 3.14159265358979323846);
}

float penetrationDepth(std::span<const glm::vec3> pos, std::span<const std::uint32_t> idx,
                       std::span<const std::uint32_t> faces,
                       std::span<const std::uint32_t> vertices, float max_distance) {
  // Partner faces' boxes, to skip faces farther than the best so far.
  std::vector<glm::vec3> lo(faces.size()), hi(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const std::uint32_t f = faces[i];
    const glm::vec3 a = pos[idx[3 * f]], b = pos[idx[3 * f + 1]], c = pos[idx[3 * f + 2]];
    lo[i] = glm::min(a, glm::min(b, c));
    hi[i] = glm::max(a, glm::max(b, c));
  }
  float deepest = 0.0f;
  for (const std::uint32_t v : vertices) {
    const glm::vec3 p = pos[v];
    // Nearest partner face (cheap), then the winding number only for a vertex behind it.
    float best = max_distance;
    glm::vec3 normal(0.0f), closest(0.0f);
    for (std::size_t i = 0; i < faces.size(); ++i) {
      const glm::vec3 out = glm::max(glm::max(lo[i] - p, p - hi[i]), glm::vec3(0.0f));
      if (glm::dot(out, out) >= best * best) continue;
      const std::uint32_t f = faces[i];
      const std::uint32_t i0 = idx[3 * f], i1 = idx[3 * f + 1], i2 = idx[3 * f + 2];
      if (i0 == v || i1 == v || i2 == v) continue;
      const glm::vec3 q = closestPointOnTriangle(p, pos[i0], pos[i1], pos[i2]);
      const float d = glm::length(p - q);
      if (d < best) {
        best = d;
        closest = q;
        normal = glm::cross(pos[i1] - pos[i0], pos[i2] - pos[i0]);
      }
    }
    if (best >= max_distance || best <= deepest || glm::dot(p - closest, normal) >= 0.0f) continue;
    if (windingNumber(pos, idx, p) > 1.0) deepest = best;
  }
  return deepest;
}

}  // namespace vistel
