// Mesh relaxation in the manner of isotropic remeshing (Botsch & Kobbelt 2004) without the
// splits and collapses: intrinsic Delaunay flips, tangential Laplacian smoothing and
// projection onto the implicit surface.
#include "offline/synth/relax.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

// GCC 12 at -O1 with sanitizers reports a false "maybe uninitialized" inside OpenMesh's
// property containers (instantiated here); it is not our code.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

namespace vistel::synth {
namespace {

using Mesh = OpenMesh::TriMesh_ArrayKernelT<>;

glm::vec3 toGlm(const Mesh::Point& p) { return {p[0], p[1], p[2]}; }

float angleAt(const glm::vec3& apex, const glm::vec3& a, const glm::vec3& b) {
  const glm::vec3 u = a - apex, v = b - apex;
  return std::atan2(glm::length(glm::cross(u, v)), glm::dot(u, v));
}

glm::vec3 unitNormal(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  const glm::vec3 n = glm::cross(b - a, c - a);
  const float len = glm::length(n);
  return len > 0.0f ? n / len : glm::vec3(0.0f);
}

// Flips edges that are not locally Delaunay, where the surface is nearly flat across them.
int flipPass(Mesh& mesh) {
  int flips = 0;
  for (const auto eh : mesh.edges()) {
    if (!mesh.is_flip_ok(eh)) continue;
    const auto h0 = mesh.halfedge_handle(eh, 0);
    const auto h1 = mesh.halfedge_handle(eh, 1);
    const auto v0 = mesh.from_vertex_handle(h0);
    const auto v1 = mesh.to_vertex_handle(h0);
    if (mesh.valence(v0) <= 4 || mesh.valence(v1) <= 4) continue;
    const glm::vec3 p0 = toGlm(mesh.point(v0));
    const glm::vec3 p1 = toGlm(mesh.point(v1));
    const glm::vec3 c = toGlm(mesh.point(mesh.to_vertex_handle(mesh.next_halfedge_handle(h0))));
    const glm::vec3 d = toGlm(mesh.point(mesh.to_vertex_handle(mesh.next_halfedge_handle(h1))));
    if (angleAt(c, p0, p1) + angleAt(d, p1, p0) <= std::numbers::pi_v<float> + 1e-3f) continue;
    // Faces (p0, p1, c), (p1, p0, d) become (p0, d, c), (d, p1, c): both must stay close to
    // the old ones in orientation.
    const glm::vec3 n0 = unitNormal(p0, p1, c), n1 = unitNormal(p1, p0, d);
    const glm::vec3 na = unitNormal(p0, d, c), nb = unitNormal(d, p1, c);
    if (glm::dot(n0, n1) < 0.8f || glm::dot(na, nb) < 0.8f) continue;
    const glm::vec3 mean = n0 + n1;
    if (glm::dot(na, mean) < 0.8f * glm::length(mean) ||
        glm::dot(nb, mean) < 0.8f * glm::length(mean)) {
      continue;
    }
    mesh.flip(eh);
    ++flips;
  }
  return flips;
}

}  // namespace

RelaxStats relax(TriangleMesh& tm, const ImplicitBody& body, int rounds) {
  RelaxStats stats;
  Mesh mesh;
  std::vector<Mesh::VertexHandle> handles;
  handles.reserve(tm.positions.size());
  for (const glm::vec3& p : tm.positions)
    handles.push_back(mesh.add_vertex(Mesh::Point(p.x, p.y, p.z)));
  for (std::size_t t = 0; t < tm.indices.size(); t += 3) {
    mesh.add_face(handles[tm.indices[t]], handles[tm.indices[t + 1]], handles[tm.indices[t + 2]]);
  }

  std::vector<glm::vec3> moved(mesh.n_vertices());
  ShapeSubset subset;
  for (int round = 0; round < rounds; ++round) {
    stats.flips += flipPass(mesh);
    // Tangential smoothing towards the neighbours' centroid (Jacobi: all from old positions),
    // then projection onto the surface.
    for (const auto vh : mesh.vertices()) {
      const glm::vec3 p = toGlm(mesh.point(vh));
      glm::vec3 centroid(0.0f);
      int count = 0;
      for (const auto nb : mesh.vv_range(vh)) {
        centroid += toGlm(mesh.point(nb));
        ++count;
      }
      centroid /= static_cast<float>(count);
      // Only the primitives near this vertex matter (it moves by less than its ring).
      float reach = 0.0f;
      for (const auto nb : mesh.vv_range(vh))
        reach = std::max(reach, glm::distance(toGlm(mesh.point(nb)), p));
      body.select(p, reach + 0.005f, subset);
      glm::vec3 n = body.gradient(p, subset);
      const float len = glm::length(n);
      n = len > 0.0f ? n / len : glm::vec3(0.0f);
      glm::vec3 step = centroid - p;
      step -= glm::dot(step, n) * n;
      moved[static_cast<std::size_t>(vh.idx())] = body.project(p + 0.5f * step, subset);
    }
    for (const auto vh : mesh.vertices()) {
      const glm::vec3& q = moved[static_cast<std::size_t>(vh.idx())];
      mesh.set_point(vh, Mesh::Point(q.x, q.y, q.z));
    }
  }

  // Back to flat arrays (vertex order unchanged; faces in OpenMesh order, counter-clockwise).
  for (const auto vh : mesh.vertices()) {
    const glm::vec3 p = toGlm(mesh.point(vh));
    tm.positions[static_cast<std::size_t>(vh.idx())] = p;
    stats.max_residual = std::max(stats.max_residual, std::abs(body.value(p)));
  }
  tm.indices.clear();
  for (const auto fh : mesh.faces()) {
    for (const auto vh : mesh.fv_range(fh))
      tm.indices.push_back(static_cast<std::uint32_t>(vh.idx()));
  }
  return stats;
}

}  // namespace vistel::synth
