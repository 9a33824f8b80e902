// Step 3 of the deformable component (see contact_forces.hpp): normals of the deformed skin,
// contact areas and reaction forces per partner body from the vertices' pressures (Gascuel
// 1993), and the pairs made equal and opposite across a scene.
#include "common/deform/contact_forces.hpp"

#include <algorithm>

namespace vistel {
namespace {

// Step 3a: normals. Vertices untouched by deformation (and whose neighbours are too; a move
// below kReshapeOffset counts as untouched) keep their rigid normals; the others get
// area-weighted normals of the deformed faces. First the faces with a dirty vertex (each
// once), then the vertices.
void passFaceNormals(DeformFrame& fr, int first, int last) {
  DeformState& st = *fr.st;
  DeformScratch& sc = *fr.sc;
  const auto idx = fr.in->indices;
  for (int face = first; face < last; ++face) {
    const std::size_t f = 3u * static_cast<std::size_t>(face);
    const std::uint32_t a = idx[f], b = idx[f + 1], c = idx[f + 2];
    if ((sc.dirty[a] | sc.dirty[b] | sc.dirty[c]) == 0) continue;
    const glm::vec3& pa = st.positions[a];
    sc.face_cross[static_cast<std::size_t>(face)] =
        glm::cross(st.positions[b] - pa, st.positions[c] - pa);
  }
}

void passNormals(DeformFrame& fr, int first, int last) {
  DeformState& st = *fr.st;
  DeformScratch& sc = *fr.sc;
  // The rigid normals in one copy, then the dirty vertices' own.
  std::copy(fr.in->rigid_normals.begin() + first, fr.in->rigid_normals.begin() + last,
            st.normals.begin() + first);
  for (int v = first; v < last; ++v) {
    const auto vi = static_cast<std::size_t>(v);
    if (sc.dirty[vi] == 0) continue;
    glm::vec3 n(0.0f);
    for (std::uint32_t k = sc.vf_offsets[vi]; k < sc.vf_offsets[vi + 1]; ++k)
      n += sc.face_cross[sc.vf_faces[k]];
    const float len = glm::length(n);
    st.normals[vi] = len > 0.0f ? n / len : fr.in->rigid_normals[vi];
  }
}

}  // namespace

void skinNormals(DeformFrame& fr, TaskPool* pool) {
  const int nface = static_cast<int>(fr.sc->face_cross.size());
  const int face_chunks = (nface + fr.chunk - 1) / fr.chunk;
  auto face_normals = [&](int c) {
    passFaceNormals(fr, c * fr.chunk, std::min(nface, (c + 1) * fr.chunk));
  };
  parallelFor(pool, face_chunks, face_normals);
  auto normals = [&](int c) {
    const auto [b, e] = chunkRange(fr, c);
    passNormals(fr, b, e);
  };
  parallelFor(pool, chunkCount(fr), normals);
}

// Step 3b: contact areas and forces per partner (serial, fixed order: the chunks' contact
// lists one after the other, each in vertex order).
void passContacts(DeformFrame& fr) {
  const int chunks = chunkCount(fr);
  DeformState& st = *fr.st;
  DeformScratch& sc = *fr.sc;
  const auto idx = fr.in->indices;
  st.contacts.clear();
  const auto entry = [&st](int partner) -> BodyContact& {
    for (BodyContact& c : st.contacts) {
      if (c.partner == partner) return c;
    }
    st.contacts.push_back(BodyContact{});
    st.contacts.back().partner = partner;
    return st.contacts.back();
  };
  for (int chunk = 0; chunk < chunks; ++chunk) {
    const int first = chunk * fr.chunk;
    const int count = sc.chunk_counters[static_cast<std::size_t>(chunk)].contact_vertices;
    for (int i = 0; i < count; ++i) {
      const std::uint32_t v = sc.contact_list[static_cast<std::size_t>(first + i)];
      const int partner = st.contact_body[v];
      BodyContact& bc = entry(partner);
      ++bc.vertices;
      bc.max_depth = std::max(bc.max_depth, static_cast<double>(st.depth[v]));
      // Each contact face once: from its lowest vertex.
      for (std::uint32_t k = sc.vf_offsets[v]; k < sc.vf_offsets[v + 1]; ++k) {
        const std::size_t f = 3u * sc.vf_faces[k];
        const std::uint32_t a = idx[f], b = idx[f + 1], c = idx[f + 2];
        if (std::min({a, b, c}) != v) continue;
        if (st.contact_body[b] != partner || st.contact_body[c] != partner ||
            st.contact_body[a] != partner) {
          continue;
        }
        const glm::dvec3 pa(st.positions[a]), pb(st.positions[b]), pc(st.positions[c]);
        const glm::dvec3 cr = glm::cross(pb - pa, pc - pa);
        const double twice_area = glm::length(cr);
        if (!(twice_area > 0.0)) continue;
        // The skin in contact is the skin that was there: a face stretched by projecting its
        // vertices along diverging normals (a nose tip deep in a ball) counts with its
        // skinned area, so area and force stay bounded at any depth.
        const glm::dvec3 ra(fr.in->rigid_positions[a]);
        const double rigid_twice_area =
            glm::length(glm::cross(glm::dvec3(fr.in->rigid_positions[b]) - ra,
                                   glm::dvec3(fr.in->rigid_positions[c]) - ra));
        const double area = 0.5 * std::min(twice_area, rigid_twice_area);
        const double p_mean =
            (static_cast<double>(st.pressure[a]) + st.pressure[b] + st.pressure[c]) / 3.0;
        bc.force -= (p_mean * area / twice_area) * cr;
        bc.area += area;
        bc.centre += area * (pa + pb + pc) / 3.0;
      }
    }
  }
  for (BodyContact& bc : st.contacts) {
    if (bc.area > 0.0) bc.centre /= bc.area;
  }
}

void combineContacts(std::span<const DeformState* const> states, std::vector<PairContact>& out) {
  out.clear();
  for (std::size_t a = 0; a < states.size(); ++a) {
    if (states[a] == nullptr) continue;
    for (const BodyContact& ca : states[a]->contacts) {
      const auto b = static_cast<std::size_t>(ca.partner);
      if (b == a) continue;  // self-contact: internal, no net force
      // Each pair once: from the lower body, or from the only side that measured it.
      const BodyContact* cb = nullptr;
      if (b < states.size() && states[b] != nullptr) {
        for (const BodyContact& x : states[b]->contacts) {
          if (x.partner == static_cast<int>(a)) cb = &x;
        }
      }
      if (cb != nullptr && b < a) continue;
      PairContact pc;
      pc.body_a = static_cast<int>(a);
      pc.body_b = static_cast<int>(b);
      pc.area_a = ca.area;
      pc.force_on_a = cb != nullptr ? 0.5 * (ca.force - cb->force) : ca.force;
      pc.area_b = cb != nullptr ? cb->area : 0.0;
      out.push_back(pc);
    }
  }
}

glm::dvec3 netContactForce(std::span<const PairContact> pairs, int body) {
  glm::dvec3 f(0.0);
  for (const PairContact& p : pairs) {
    if (p.body_a == body) f += p.force_on_a;
    if (p.body_b == body) f -= p.force_on_a;
  }
  return f;
}

}  // namespace vistel
