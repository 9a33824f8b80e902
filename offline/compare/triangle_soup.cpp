#include "offline/compare/triangle_soup.hpp"

#include <cmath>
#include <filesystem>
#include <unordered_map>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>

namespace vistel {
namespace {

using ReadMesh = OpenMesh::PolyMesh_ArrayKernelT<>;

struct CellHash {
  std::size_t operator()(const glm::ivec3& c) const {
    return static_cast<std::size_t>(c.x) * 73856093u ^ static_cast<std::size_t>(c.y) * 19349663u ^
           static_cast<std::size_t>(c.z) * 83492791u;
  }
};

}  // namespace

Status validateSoup(const TriangleSoup& soup) {
  if (soup.indices.size() % 3 != 0) {
    return fail("{} triangle indices, not a multiple of 3", soup.indices.size());
  }
  for (std::size_t v = 0; v < soup.positions.size(); ++v) {
    const glm::vec3& p = soup.positions[v];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      return fail("vertex {} has a non-finite position", v);
    }
  }
  for (std::size_t i = 0; i < soup.indices.size(); ++i) {
    if (soup.indices[i] >= soup.positions.size()) {
      return fail("triangle {} refers to vertex {} of {}", i / 3, soup.indices[i],
                  soup.positions.size());
    }
  }
  return {};
}

TriangleSoup weldVertices(const TriangleSoup& soup, float tolerance) {
  const float cell = tolerance > 0.0f ? tolerance : 1e-9f;
  std::unordered_map<glm::ivec3, std::vector<std::uint32_t>, CellHash> grid;
  std::vector<std::uint32_t> remap(soup.positions.size());
  TriangleSoup out;
  for (std::size_t v = 0; v < soup.positions.size(); ++v) {
    const glm::vec3& p = soup.positions[v];
    const glm::ivec3 c(glm::floor(p / cell));
    std::uint32_t found = UINT32_MAX;
    for (int dz = -1; dz <= 1 && found == UINT32_MAX; ++dz) {
      for (int dy = -1; dy <= 1 && found == UINT32_MAX; ++dy) {
        for (int dx = -1; dx <= 1 && found == UINT32_MAX; ++dx) {
          const auto it = grid.find(c + glm::ivec3(dx, dy, dz));
          if (it == grid.end()) continue;
          for (std::uint32_t w : it->second) {
            if (glm::distance(out.positions[w], p) <= tolerance) {
              found = w;
              break;
            }
          }
        }
      }
    }
    if (found == UINT32_MAX) {
      found = static_cast<std::uint32_t>(out.positions.size());
      out.positions.push_back(p);
      grid[c].push_back(found);
    }
    remap[v] = found;
  }
  out.indices.reserve(soup.indices.size());
  for (std::size_t t = 0; t + 2 < soup.indices.size(); t += 3) {
    const std::uint32_t a = remap[soup.indices[t]];
    const std::uint32_t b = remap[soup.indices[t + 1]];
    const std::uint32_t c = remap[soup.indices[t + 2]];
    if (a == b || b == c || a == c) continue;
    out.indices.insert(out.indices.end(), {a, b, c});
  }
  return out;
}

Result<TriangleSoup> readMeshFile(const std::string& path, std::vector<glm::vec2>* uvs) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return fail("{}: no such file", path);
  ReadMesh mesh;
  OpenMesh::IO::Options options;
  if (uvs != nullptr) {
    mesh.request_vertex_texcoords2D();
    options += OpenMesh::IO::Options::VertexTexCoord;
  }
  if (!OpenMesh::IO::read_mesh(mesh, path, options)) {
    return fail("{}: OpenMesh could not read it (a .obj, .ply, .off or .stl mesh?)", path);
  }
  TriangleSoup soup;
  const bool with_uvs = uvs != nullptr && options.vertex_has_texcoord();
  if (uvs != nullptr) uvs->clear();
  soup.positions.reserve(mesh.n_vertices());
  for (const auto vh : mesh.vertices()) {
    const auto& p = mesh.point(vh);
    soup.positions.emplace_back(p[0], p[1], p[2]);
    if (with_uvs) {
      const auto& t = mesh.texcoord2D(vh);
      if (!std::isfinite(t[0]) || !std::isfinite(t[1])) {
        return fail("{}: a texture coordinate is not finite", path);
      }
      uvs->emplace_back(t[0], t[1]);
    }
  }
  for (const auto fh : mesh.faces()) {
    std::vector<std::uint32_t> corners;
    for (const auto vh : mesh.fv_range(fh)) corners.push_back(static_cast<std::uint32_t>(vh.idx()));
    for (std::size_t i = 1; i + 1 < corners.size(); ++i) {
      soup.indices.insert(soup.indices.end(), {corners[0], corners[i], corners[i + 1]});
    }
  }
  if (soup.indices.empty()) return fail("{}: no faces", path);
  if (Status st = validateSoup(soup); !st) return fail("{}: {}", path, st.error().message);
  return soup;
}

}  // namespace vistel
