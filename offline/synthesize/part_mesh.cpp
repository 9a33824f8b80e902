#include "offline/synthesize/part_mesh.hpp"

#include <cmath>
#include <map>

#include <OpenMesh/Core/System/omstream.hh>

#include "common/anim/seam_copies.hpp"

namespace vistel {

PartMesh makePartMesh(TriangleSoup mesh, std::vector<glm::vec2> uvs) {
  PartMesh part;
  part.mesh = std::move(mesh);
  part.uvs = std::move(uvs);
  const std::size_t nv = part.mesh.positions.size();
  if (part.uvs.size() != nv) part.uvs.clear();

  // Vertices at exactly the same place are one (a file repeats them at texture seams).
  part.weld = firstCopies(part.mesh.positions);

  // Area-weighted normals over the welded fans, shared by every copy of a vertex.
  std::vector<glm::vec3> sum(nv, glm::vec3(0.0f));
  for (std::size_t t = 0; t + 2 < part.mesh.indices.size(); t += 3) {
    const std::uint32_t a = part.weld[part.mesh.indices[t]];
    const std::uint32_t b = part.weld[part.mesh.indices[t + 1]];
    const std::uint32_t c = part.weld[part.mesh.indices[t + 2]];
    const glm::vec3& pa = part.mesh.positions[a];
    const glm::vec3 n =
        glm::cross(part.mesh.positions[b] - pa, part.mesh.positions[c] - pa);  // 2 x area
    sum[a] += n;
    sum[b] += n;
    sum[c] += n;
  }
  part.normals.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    const glm::vec3 n = sum[part.weld[v]];
    const float len = glm::length(n);
    part.normals[v] = len > 0.0f ? n / len : glm::vec3(0.0f, 1.0f, 0.0f);
  }
  return part;
}

Result<PartMesh> readPartMesh(const std::string& path) {
  omlog().disable();
  std::vector<glm::vec2> uvs;
  Result<TriangleSoup> soup = readMeshFile(path, &uvs);
  if (!soup) return soup.error();
  return makePartMesh(std::move(*soup), std::move(uvs));
}

std::vector<BoundaryLoop> boundaryLoops(const PartMesh& part) {
  const std::vector<glm::vec3>& pos = part.mesh.positions;
  // Directed welded edges, counted; a rim edge has no opposite.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  const std::vector<std::uint32_t>& idx = part.mesh.indices;
  for (std::size_t t = 0; t + 2 < idx.size(); t += 3) {
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = part.weld[idx[t + e]];
      const std::uint32_t b = part.weld[idx[t + (e + 1) % 3]];
      if (a != b) ++edges[{a, b}];
    }
  }
  std::multimap<std::uint32_t, std::uint32_t> rim;  // from -> to
  for (const auto& [e, count] : edges) {
    if (edges.find({e.second, e.first}) == edges.end()) rim.emplace(e.first, e.second);
  }

  // Follow rims: at a vertex with several ways on, the one turning least from the way in.
  std::vector<BoundaryLoop> loops;
  while (!rim.empty()) {
    BoundaryLoop loop;
    const std::uint32_t start = rim.begin()->first;
    std::uint32_t from = start;
    std::uint32_t to = rim.begin()->second;
    rim.erase(rim.begin());
    loop.vertices.push_back(from);
    while (to != start) {
      loop.vertices.push_back(to);
      auto [lo, hi] = rim.equal_range(to);
      if (lo == hi) break;  // an open chain (cannot happen on a triangle mesh's rim)
      auto pick = lo;
      const glm::vec3 in = pos[to] - pos[from];
      float best = -2.0f;
      for (auto it = lo; it != hi; ++it) {
        const glm::vec3 out = pos[it->second] - pos[to];
        const float c = glm::dot(in, out) / std::max(1e-12f, glm::length(in) * glm::length(out));
        if (c > best) {
          best = c;
          pick = it;
        }
      }
      from = to;
      to = pick->second;
      rim.erase(pick);
    }
    if (loop.vertices.size() < 3) continue;
    std::map<std::uint32_t, int> seen;
    for (std::size_t i = 0; i < loop.vertices.size(); ++i) {
      const glm::vec3& p = pos[loop.vertices[i]];
      loop.centroid += p;
      loop.length += glm::distance(p, pos[loop.vertices[(i + 1) % loop.vertices.size()]]);
      if (++seen[loop.vertices[i]] > 1) loop.simple = false;
    }
    loop.centroid /= static_cast<float>(loop.vertices.size());
    loops.push_back(std::move(loop));
  }
  return loops;
}

int trimRimSpikes(PartMesh& part, int rounds) {
  int dropped = 0;
  for (int r = 0; r < rounds; ++r) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
    const std::vector<std::uint32_t>& idx = part.mesh.indices;
    for (std::size_t t = 0; t + 2 < idx.size(); t += 3) {
      for (int e = 0; e < 3; ++e) {
        ++edges[{part.weld[idx[t + e]], part.weld[idx[t + (e + 1) % 3]]}];
      }
    }
    std::vector<std::uint32_t> kept;
    int now = 0;
    for (std::size_t t = 0; t + 2 < idx.size(); t += 3) {
      int rim = 0;
      for (int e = 0; e < 3; ++e) {
        const std::uint32_t a = part.weld[idx[t + e]], b = part.weld[idx[t + (e + 1) % 3]];
        if (edges.find({b, a}) == edges.end()) ++rim;
      }
      if (rim >= 2) {
        ++now;
        continue;
      }
      kept.insert(kept.end(), {idx[t], idx[t + 1], idx[t + 2]});
    }
    if (now == 0 || kept.empty()) break;
    dropped += now;
    TriangleSoup mesh = std::move(part.mesh);
    mesh.indices = std::move(kept);
    part = makePartMesh(std::move(mesh), std::move(part.uvs));
  }
  return dropped;
}

}  // namespace vistel
