#include "offline/parts/part_files.hpp"

#include <array>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/PolyMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

namespace vistel {

Status writePartMesh(const std::string& path, const CutPart& part) {
  OpenMesh::PolyMesh_ArrayKernelT<> mesh;
  const bool with_uvs = part.uvs.size() == part.mesh.positions.size();
  if (with_uvs) mesh.request_vertex_texcoords2D();
  std::vector<OpenMesh::VertexHandle> handles;
  handles.reserve(part.mesh.positions.size());
  for (std::size_t v = 0; v < part.mesh.positions.size(); ++v) {
    const glm::vec3& p = part.mesh.positions[v];
    handles.push_back(mesh.add_vertex({p.x, p.y, p.z}));
    if (with_uvs) mesh.set_texcoord2D(handles.back(), {part.uvs[v].x, part.uvs[v].y});
  }
  for (std::size_t t = 0; t + 2 < part.mesh.indices.size(); t += 3) {
    std::array<OpenMesh::VertexHandle, 3> corner;
    for (int c = 0; c < 3; ++c) corner[c] = handles[part.mesh.indices[t + c]];
    if (mesh.add_face(corner[0], corner[1], corner[2]).is_valid()) continue;
    // A triangle the halfedge structure refuses (it would make an edge or a vertex
    // non-manifold) gets corners of its own, as OpenMesh's readers do: nothing is lost.
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t v = part.mesh.indices[t + c];
      const glm::vec3& p = part.mesh.positions[v];
      corner[c] = mesh.add_vertex({p.x, p.y, p.z});
      if (with_uvs) mesh.set_texcoord2D(corner[c], {part.uvs[v].x, part.uvs[v].y});
    }
    mesh.add_face(corner[0], corner[1], corner[2]);
  }
  omlog().disable();  // OpenMesh's writers announce every file on the log stream
  OpenMesh::IO::Options options;
  if (with_uvs) options += OpenMesh::IO::Options::VertexTexCoord;
  if (!OpenMesh::IO::write_mesh(mesh, path, options)) {
    return fail("{}: OpenMesh could not write it (a .obj, .ply, .off or .stl path?)", path);
  }
  return {};
}

}  // namespace vistel
