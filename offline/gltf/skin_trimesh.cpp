#include "offline/gltf/skin_trimesh.hpp"

#include <cassert>

#include <OpenMesh/Core/System/omstream.hh>

namespace vistel {

SkinTopology buildSkinTriMesh(const SkinMesh& skin, SkinTriMesh& out) {
  assert(out.n_vertices() == 0);
  SkinTopology topo;
  const std::size_t n = skin.positions.size();
  const auto k = static_cast<std::size_t>(skin.influences);

  // Vertices with their normals and skin-weight slots.
  OpenMesh::VPropHandleT<SkinJointSlots> joints;
  OpenMesh::VPropHandleT<SkinWeightSlots> weights;
  out.add_property(joints, kSkinJointsProperty);
  out.add_property(weights, kSkinWeightsProperty);
  out.reserve(n, 3 * skin.indices.size() / 3, skin.indices.size() / 3);
  for (std::size_t v = 0; v < n; ++v) {
    const glm::vec3& p = skin.positions[v];
    const auto vh = out.add_vertex(SkinTriMesh::Point(p.x, p.y, p.z));
    if (v < skin.normals.size()) {
      const glm::vec3& nrm = skin.normals[v];
      out.set_normal(vh, SkinTriMesh::Normal(nrm.x, nrm.y, nrm.z));
    }
    SkinJointSlots js{};
    SkinWeightSlots ws{};
    for (std::size_t s = 0; s < k && v * k + s < skin.weights.size(); ++s) {
      js[s] = skin.joints[v * k + s];
      ws[s] = skin.weights[v * k + s];
    }
    out.property(joints, vh) = js;
    out.property(weights, vh) = ws;
  }

  // Faces; OpenMesh reports refused ones on its error stream, which is muted meanwhile.
  const bool was_enabled = omerr().is_enabled();
  omerr().disable();
  for (std::size_t t = 0; t + 2 < skin.indices.size(); t += 3) {
    const std::uint32_t a = skin.indices[t], b = skin.indices[t + 1], c = skin.indices[t + 2];
    if (a >= n || b >= n || c >= n || a == b || b == c || a == c) {
      ++topo.degenerate_triangles;
      continue;
    }
    const auto fh = out.add_face(out.vertex_handle(a), out.vertex_handle(b), out.vertex_handle(c));
    if (!fh.is_valid()) ++topo.rejected_triangles;
  }
  if (was_enabled) omerr().enable();

  // Topology: boundary edges, fans, unused vertices.
  for (const auto eh : out.edges()) {
    if (out.is_boundary(eh)) ++topo.boundary_edges;
  }
  for (const auto vh : out.vertices()) {
    if (out.is_isolated(vh)) {
      ++topo.isolated_vertices;
    } else if (!out.is_manifold(vh)) {
      ++topo.non_manifold_vertices;
    }
  }
  return topo;
}

void flattenSkinTriMesh(const SkinTriMesh& mesh, SkinMesh& skin) {
  const std::size_t n = mesh.n_vertices();
  const auto k = static_cast<std::size_t>(skin.influences);
  assert(n == skin.positions.size());
  OpenMesh::VPropHandleT<SkinJointSlots> joints;
  OpenMesh::VPropHandleT<SkinWeightSlots> weights;
  const bool have_slots = mesh.get_property_handle(joints, kSkinJointsProperty) &&
                          mesh.get_property_handle(weights, kSkinWeightsProperty);
  skin.normals.resize(n);
  skin.joints.resize(n * k);
  skin.weights.resize(n * k);
  for (const auto vh : mesh.vertices()) {
    const auto v = static_cast<std::size_t>(vh.idx());
    const auto& p = mesh.point(vh);
    const auto& nrm = mesh.normal(vh);
    skin.positions[v] = glm::vec3(p[0], p[1], p[2]);
    skin.normals[v] = glm::vec3(nrm[0], nrm[1], nrm[2]);
    if (!have_slots) continue;
    const SkinJointSlots& js = mesh.property(joints, vh);
    const SkinWeightSlots& ws = mesh.property(weights, vh);
    for (std::size_t s = 0; s < k; ++s) {
      skin.joints[v * k + s] = js[s];
      skin.weights[v * k + s] = ws[s];
    }
  }
}

}  // namespace vistel
