#include "tests/synth/mesh_checks.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <numbers>
#include <numeric>
#include <set>
#include <unordered_map>
#include <vector>

namespace vistel::test {
namespace {

std::uint64_t edgeKey(std::uint32_t a, std::uint32_t b) {
  return (static_cast<std::uint64_t>(a) << 32) | b;
}

// Whether segment [p, q] crosses triangle (a, b, c) (Moller-Trumbore, double precision).
bool segmentHitsTriangle(const glm::dvec3& p, const glm::dvec3& q, const glm::dvec3& a,
                         const glm::dvec3& b, const glm::dvec3& c) {
  const glm::dvec3 d = q - p;
  const glm::dvec3 e1 = b - a, e2 = c - a;
  const glm::dvec3 h = glm::cross(d, e2);
  const double det = glm::dot(e1, h);
  if (std::abs(det) < 1e-18) return false;
  const double inv = 1.0 / det;
  const glm::dvec3 s = p - a;
  const double u = inv * glm::dot(s, h);
  if (u < 0.0 || u > 1.0) return false;
  const glm::dvec3 qv = glm::cross(s, e1);
  const double v = inv * glm::dot(d, qv);
  if (v < 0.0 || u + v > 1.0) return false;
  const double t = inv * glm::dot(e2, qv);
  return t >= 0.0 && t <= 1.0;
}

}  // namespace

Topology analyseTopology(std::span<const glm::vec3> positions,
                         std::span<const std::uint32_t> indices) {
  Topology out;
  const std::size_t nv = positions.size();
  const std::size_t nt = indices.size() / 3;
  // Directed edges: each must appear once, and its reverse once.
  std::unordered_map<std::uint64_t, int> directed;
  directed.reserve(indices.size());
  for (std::size_t t = 0; t < nt; ++t) {
    for (std::size_t k = 0; k < 3; ++k) {
      ++directed[edgeKey(indices[3 * t + k], indices[3 * t + (k + 1) % 3])];
    }
  }
  out.edges_paired = true;
  for (const auto& [key, count] : directed) {
    const auto a = static_cast<std::uint32_t>(key >> 32), b = static_cast<std::uint32_t>(key);
    const auto reverse = directed.find(edgeKey(b, a));
    if (count != 1 || reverse == directed.end() || reverse->second != 1) out.edges_paired = false;
  }
  // Degenerate triangles.
  for (std::size_t t = 0; t < nt; ++t) {
    const std::uint32_t a = indices[3 * t], b = indices[3 * t + 1], c = indices[3 * t + 2];
    const double area =
        0.5 * glm::length(glm::cross(glm::dvec3(positions[b]) - glm::dvec3(positions[a]),
                                     glm::dvec3(positions[c]) - glm::dvec3(positions[a])));
    if (a == b || b == c || a == c || area < 1e-12) ++out.degenerate_triangles;
  }
  // Fans: around each vertex, following "next" (b -> c of triangle (v, b, c)) must visit
  // all its triangles in one cycle.
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> fan(nv);
  for (std::size_t t = 0; t < nt; ++t) {
    for (std::size_t k = 0; k < 3; ++k) {
      fan[indices[3 * t + k]].emplace_back(indices[3 * t + (k + 1) % 3],
                                           indices[3 * t + (k + 2) % 3]);
    }
  }
  for (std::size_t v = 0; v < nv; ++v) {
    if (fan[v].empty()) {
      ++out.unused_vertices;
      continue;
    }
    std::map<std::uint32_t, std::uint32_t> next;
    for (const auto& [b, c] : fan[v]) next[b] = c;
    std::size_t steps = 0;
    std::uint32_t at = fan[v].front().first;
    do {
      const auto it = next.find(at);
      if (it == next.end()) break;
      at = it->second;
      ++steps;
    } while (at != fan[v].front().first && steps <= fan[v].size());
    if (steps != fan[v].size() || next.size() != fan[v].size()) ++out.nonmanifold_vertices;
  }
  // Components by union-find over triangle vertices.
  std::vector<std::uint32_t> parent(nv);
  std::iota(parent.begin(), parent.end(), 0u);
  const auto find = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::size_t t = 0; t < nt; ++t) {
    for (std::size_t k = 1; k < 3; ++k) parent[find(indices[3 * t + k])] = find(indices[3 * t]);
  }
  std::set<std::uint32_t> roots;
  for (std::size_t v = 0; v < nv; ++v) {
    if (!fan[v].empty()) roots.insert(find(static_cast<std::uint32_t>(v)));
  }
  out.components = static_cast<int>(roots.size());
  const long edges = static_cast<long>(directed.size()) / 2;
  out.euler = static_cast<long>(nv - static_cast<std::size_t>(out.unused_vertices)) - edges +
              static_cast<long>(nt);
  return out;
}

int countSelfIntersections(std::span<const glm::vec3> positions,
                           std::span<const std::uint32_t> indices) {
  const std::size_t nt = indices.size() / 3;
  // Uniform grid of cells about twice the mean edge length; triangles go in every cell
  // their bounding box touches.
  glm::dvec3 lo(1e30), hi(-1e30);
  double edge_sum = 0.0;
  for (std::size_t t = 0; t < nt; ++t) {
    for (std::size_t k = 0; k < 3; ++k) {
      const glm::dvec3 p(positions[indices[3 * t + k]]);
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
      edge_sum += glm::distance(p, glm::dvec3(positions[indices[3 * t + (k + 1) % 3]]));
    }
  }
  const double cell = 2.0 * edge_sum / static_cast<double>(3 * nt);
  const glm::ivec3 dims = glm::ivec3((hi - lo) / cell) + 1;
  std::unordered_map<std::int64_t, std::vector<std::uint32_t>> grid;
  const auto cellOf = [&](const glm::dvec3& p) {
    return glm::clamp(glm::ivec3((p - lo) / cell), glm::ivec3(0), dims - 1);
  };
  for (std::size_t t = 0; t < nt; ++t) {
    glm::dvec3 a(1e30), b(-1e30);
    for (std::size_t k = 0; k < 3; ++k) {
      a = glm::min(a, glm::dvec3(positions[indices[3 * t + k]]));
      b = glm::max(b, glm::dvec3(positions[indices[3 * t + k]]));
    }
    const glm::ivec3 c0 = cellOf(a), c1 = cellOf(b);
    for (int z = c0.z; z <= c1.z; ++z) {
      for (int y = c0.y; y <= c1.y; ++y) {
        for (int x = c0.x; x <= c1.x; ++x) {
          grid[(static_cast<std::int64_t>(z) * dims.y + y) * dims.x + x].push_back(
              static_cast<std::uint32_t>(t));
        }
      }
    }
  }
  std::set<std::pair<std::uint32_t, std::uint32_t>> hits;
  for (const auto& [key, list] : grid) {
    for (std::size_t i = 0; i < list.size(); ++i) {
      for (std::size_t j = i + 1; j < list.size(); ++j) {
        const std::uint32_t s = std::min(list[i], list[j]), t = std::max(list[i], list[j]);
        std::array<std::uint32_t, 3> a{indices[3 * s], indices[3 * s + 1], indices[3 * s + 2]};
        std::array<std::uint32_t, 3> b{indices[3 * t], indices[3 * t + 1], indices[3 * t + 2]};
        bool shared = false;
        for (const std::uint32_t x : a)
          shared = shared || std::find(b.begin(), b.end(), x) != b.end();
        if (shared || hits.count({s, t}) != 0) continue;
        std::array<glm::dvec3, 3> pa, pb;
        for (std::size_t k = 0; k < 3; ++k) {
          pa[k] = glm::dvec3(positions[a[k]]);
          pb[k] = glm::dvec3(positions[b[k]]);
        }
        bool hit = false;
        for (std::size_t k = 0; k < 3 && !hit; ++k) {
          hit = segmentHitsTriangle(pa[k], pa[(k + 1) % 3], pb[0], pb[1], pb[2]) ||
                segmentHitsTriangle(pb[k], pb[(k + 1) % 3], pa[0], pa[1], pa[2]);
        }
        if (hit) hits.insert({s, t});
      }
    }
  }
  return static_cast<int>(hits.size());
}

double windingNumber(std::span<const glm::vec3> positions, std::span<const std::uint32_t> indices,
                     const glm::vec3& p) {
  // Sum of the solid angles of the triangles seen from p (Van Oosterom & Strackee 1983).
  double total = 0.0;
  for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
    const glm::dvec3 a = glm::dvec3(positions[indices[t]]) - glm::dvec3(p);
    const glm::dvec3 b = glm::dvec3(positions[indices[t + 1]]) - glm::dvec3(p);
    const glm::dvec3 c = glm::dvec3(positions[indices[t + 2]]) - glm::dvec3(p);
    const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
    const double num = glm::dot(a, glm::cross(b, c));
    const double den =
        la * lb * lc + glm::dot(a, b) * lc + glm::dot(b, c) * la + glm::dot(c, a) * lb;
    total += 2.0 * std::atan2(num, den);
  }
  return total / (4.0 * std::numbers::pi);
}

bool writeObj(const std::string& path, std::span<const glm::vec3> positions,
              std::span<const std::uint32_t> indices) {
  std::ofstream out(path);
  for (const glm::vec3& p : positions) out << "v " << p.x << ' ' << p.y << ' ' << p.z << '\n';
  for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
    out << "f " << indices[t] + 1 << ' ' << indices[t + 1] + 1 << ' ' << indices[t + 2] + 1 << '\n';
  }
  return static_cast<bool>(out);
}

}  // namespace vistel::test
