#include "offline/compare/mesh_topology.hpp"

#include <numeric>
#include <unordered_map>

#include "common/base/disjoint_sets.hpp"

namespace vistel {
namespace {

struct EdgeUse {
  int forward = 0;   // uses as (smaller, larger)
  int backward = 0;  // uses as (larger, smaller)
};

std::uint64_t edgeKey(std::uint32_t a, std::uint32_t b) {
  return a < b ? (std::uint64_t{a} << 32) | b : (std::uint64_t{b} << 32) | a;
}

}  // namespace

MeshTopology analyzeTopology(const TriangleSoup& soup) {
  MeshTopology t;
  const std::size_t nv = soup.positions.size();
  const std::size_t nt = soup.indices.size() / 3;
  t.triangles = static_cast<int>(nt);

  // Edges, with the direction of each use; degenerate triangles.
  std::unordered_map<std::uint64_t, EdgeUse> edges;
  edges.reserve(nt * 2);
  DisjointSets pieces(nv);
  std::vector<std::uint32_t> degree(nv + 1, 0);
  for (std::size_t f = 0; f < nt; ++f) {
    const std::uint32_t* v = &soup.indices[3 * f];
    const glm::vec3 n = glm::cross(soup.positions[v[1]] - soup.positions[v[0]],
                                   soup.positions[v[2]] - soup.positions[v[0]]);
    if (!(glm::dot(n, n) > 0.0f)) ++t.degenerate_triangles;
    for (int i = 0; i < 3; ++i) {
      const std::uint32_t a = v[i];
      const std::uint32_t b = v[(i + 1) % 3];
      EdgeUse& use = edges[edgeKey(a, b)];
      (a < b ? use.forward : use.backward) += 1;
      pieces.join(a, b);
      ++degree[a + 1];
    }
  }
  for (const auto& [key, use] : edges) {
    const int count = use.forward + use.backward;
    if (count == 1) ++t.boundary_edges;
    if (count >= 3) ++t.nonmanifold_edges;
    if (count == 2 && use.forward != 1) ++t.misoriented_edges;
  }

  // The triangles around each vertex (compressed rows).
  std::partial_sum(degree.begin(), degree.end(), degree.begin());
  std::vector<std::uint32_t> around(degree.back());
  std::vector<std::uint32_t> fill(degree.begin(), degree.end() - 1);
  for (std::size_t f = 0; f < nt; ++f) {
    for (int i = 0; i < 3; ++i)
      around[fill[soup.indices[3 * f + i]]++] = static_cast<std::uint32_t>(f);
  }

  // Fans: around vertex v, the other two corners of each triangle are joined; the vertex is
  // a manifold one when they form a single chain (or ring).
  std::unordered_map<std::uint32_t, std::uint32_t> local;
  for (std::size_t v = 0; v < nv; ++v) {
    const std::uint32_t begin = degree[v];
    const std::uint32_t end = degree[v + 1];
    if (begin == end) continue;
    ++t.vertices;
    local.clear();
    for (std::uint32_t k = begin; k < end; ++k) {
      const std::uint32_t* c = &soup.indices[3 * around[k]];
      for (int i = 0; i < 3; ++i) {
        if (c[i] == v) continue;
        local.emplace(c[i], static_cast<std::uint32_t>(local.size()));
      }
    }
    DisjointSets fans(local.size());
    for (std::uint32_t k = begin; k < end; ++k) {
      const std::uint32_t* c = &soup.indices[3 * around[k]];
      std::uint32_t other[2];
      int n = 0;
      for (int i = 0; i < 3; ++i) {
        if (c[i] != v && n < 2) other[n++] = c[i];
      }
      if (n == 2) fans.join(local[other[0]], local[other[1]]);
    }
    std::size_t roots = 0;
    for (std::uint32_t i = 0; i < local.size(); ++i) roots += fans.find(i) == i ? 1 : 0;
    if (roots > 1) ++t.nonmanifold_vertices;
  }

  for (std::size_t v = 0; v < nv; ++v) {
    if (degree[v] != degree[v + 1] && pieces.find(static_cast<std::uint32_t>(v)) == v) {
      ++t.components;
    }
  }
  return t;
}

}  // namespace vistel
