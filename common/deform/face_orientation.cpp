// The face orientation guard (face_orientation.hpp).
#include "common/deform/face_orientation.hpp"

#include <cstddef>
#include <cstdint>

namespace vistel {
namespace {

constexpr int kHalvingRounds = 3;  // rounds that halve corrections before returning vertices
                                   // to their skinned positions

bool touching(const DeformState& st, std::uint32_t v) {
  return (st.flags[v] & kVertexContact) != 0 || st.depth[v] > 0.0f;
}

// Whether face f is turned against its skinned orientation, outside contacts.
bool inverted(const DeformFrame& fr, std::uint32_t f) {
  const DeformState& st = *fr.st;
  const std::uint32_t* const t = &fr.sc->face_vertices[3 * static_cast<std::size_t>(f)];
  if (touching(st, t[0]) || touching(st, t[1]) || touching(st, t[2])) return false;
  const auto rigid = fr.in->rigid_positions;
  const auto& pos = st.positions;
  const glm::vec3 nr = glm::cross(rigid[t[1]] - rigid[t[0]], rigid[t[2]] - rigid[t[0]]);
  const glm::vec3 nd = glm::cross(pos[t[1]] - pos[t[0]], pos[t[2]] - pos[t[0]]);
  return glm::dot(nr, nd) < 0.0f;
}

// Lists in sc.orient_faces the inverted faces around the vertices of `vertices` (each once).
void collectInverted(DeformFrame& fr, const std::vector<std::uint32_t>& vertices) {
  DeformScratch& sc = *fr.sc;
  sc.orient_faces.clear();
  for (const std::uint32_t v : vertices) {
    for (std::uint32_t k = sc.vf_offsets[v]; k < sc.vf_offsets[v + 1]; ++k) {
      const std::uint32_t f = sc.vf_faces[k];
      if (sc.orient_face_mark[f] != 0) continue;
      sc.orient_face_mark[f] = 1;
      if (inverted(fr, f)) sc.orient_faces.push_back(f);
    }
  }
  // Clear the marks of every face looked at (the same walk).
  for (const std::uint32_t v : vertices) {
    for (std::uint32_t k = sc.vf_offsets[v]; k < sc.vf_offsets[v + 1]; ++k)
      sc.orient_face_mark[sc.vf_faces[k]] = 0;
  }
}

}  // namespace

int restoreFaceOrientation(DeformFrame& fr) {
  DeformState& st = *fr.st;
  DeformScratch& sc = *fr.sc;
  const auto rigid = fr.in->rigid_positions;
  // The vertices the deformation moved, outside contacts.
  sc.orient_vertices.clear();
  for (std::uint32_t v = 0; v < static_cast<std::uint32_t>(fr.nvert); ++v) {
    if (st.positions[v] != rigid[v] && !touching(st, v)) sc.orient_vertices.push_back(v);
  }
  collectInverted(fr, sc.orient_vertices);
  int pulled = 0;
  for (int round = 0; !sc.orient_faces.empty(); ++round) {
    // The moved vertices of the inverted faces, each once.
    sc.orient_vertices.clear();
    for (const std::uint32_t f : sc.orient_faces) {
      for (int j = 0; j < 3; ++j) {
        const std::uint32_t u = sc.face_vertices[3 * static_cast<std::size_t>(f) + j];
        if (sc.orient_vertex_mark[u] != 0 || st.positions[u] == rigid[u]) continue;
        sc.orient_vertex_mark[u] = 1;
        sc.orient_vertices.push_back(u);
      }
    }
    const bool halve = round < kHalvingRounds;
    for (const std::uint32_t u : sc.orient_vertices) {
      sc.orient_vertex_mark[u] = 0;
      st.positions[u] = halve ? rigid[u] + 0.5f * (st.positions[u] - rigid[u]) : rigid[u];
      if (st.positions[u] == rigid[u]) st.flags[u] &= static_cast<std::uint8_t>(~kVertexMoved);
      st.flags[u] |= kVertexReshaped;
      markReshaped(fr, static_cast<int>(u));
      ++pulled;
    }
    // Faces around what moved: those still (or newly) inverted. Each round past the halving
    // ones returns at least one vertex of every listed face to its skinned position for good
    // (a face all of whose moved vertices are back cannot be listed again), so this ends.
    collectInverted(fr, sc.orient_vertices);
  }
  return pulled;
}

}  // namespace vistel
