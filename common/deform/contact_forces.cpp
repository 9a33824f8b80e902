// Step 3 of the deformable component (see contact_forces.hpp): normals of the deformed skin,
// contact areas and reaction forces per partner body from the vertices' pressures (Gascuel
// 1993), and the pairs made equal and opposite across a scene.
#include "common/deform/contact_forces.hpp"

#include <algorithm>
#include <cmath>

#include "common/deform/prop.hpp"

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
  // The contact vertices in their fixed order: each chunk's list, in vertex order.
  const auto forEachContactVertex = [&](const auto& f) {
    for (int chunk = 0; chunk < chunks; ++chunk) {
      const int first = chunk * fr.chunk;
      const int count = sc.chunk_counters[static_cast<std::size_t>(chunk)].contact_vertices;
      for (int i = 0; i < count; ++i) f(sc.contact_list[static_cast<std::size_t>(first + i)]);
    }
  };
  // Each contact vertex's pressure by the contact law (prop.hpp), before the faces read it:
  // pass A's series stiffness times the vertex's depth below the partner's skin, plus the
  // cores' (contactCorePressure) from its own skin radius and the partner's on that ray.
  forEachContactVertex([&](std::uint32_t v) {
    if (!(st.depth[v] > 0.0f) || !(st.pressure[v] > 0.0f)) return;
    const glm::vec3& p = fr.in->rigid_positions[v];
    // The vertex's own skin radius: its distance from its primitive's skeleton.
    float own_radius = 0.0f;
    const float k_own = ownStiffness(fr, static_cast<int>(v));
    const std::int16_t own = fr.model->calibration.prims[v][0];
    if (own >= 0 && fr.posed != nullptr) {
      float scale = 1.0f;
      const glm::vec3 off =
          skeletonOffset(fr.posed->items[static_cast<std::size_t>(own)].shape, p, scale);
      own_radius = std::sqrt(glm::dot(off, off));
    }
    // The partner's, on the ray through the vertex of the partner primitive it is deepest in.
    float partner_radius = 0.0f;
    float deepest = -INFINITY;
    const int nc = sc.cand_count[v] & 0x7f;
    for (int j = 0; j < nc; ++j) {
      const DeformScratch::CandidateSlot& cs =
          sc.candidates[static_cast<std::size_t>(v) * kMaxCandidates + static_cast<std::size_t>(j)];
      const DeformScratch::Collider& col = sc.colliders[cs.collider];
      if (col.body != st.contact_body[v] || col.posed == nullptr) continue;
      float scale = 1.0f;
      const glm::vec3 off = skeletonOffset(col.posed->shape, p, scale);
      const float units = scale > 0.0f ? 1.0f / scale : 1.0f;
      const float surface = skinSurfaceDistance(*col.posed, cs.omega) * units;
      const float depth = surface - std::sqrt(glm::dot(off, off));
      if (depth > deepest) {
        deepest = depth;
        partner_radius = surface;
      }
    }
    // The common law on the skins' own geometry: the depth below the partner's skin on that
    // ray, exact for every profile (pass A's first-order estimate x / |grad x| grows without
    // bound towards a primitive's centre), times the series stiffness, plus the cores'.
    const float k = st.pressure[v] / st.depth[v];
    const float depth = deepest > -INFINITY ? std::max(deepest, 0.0f) : st.depth[v];
    const float law = k * depth;
    st.pressure[v] = law + contactCorePressure(depth, law, k_own, own_radius, partner_radius);
  });
  forEachContactVertex([&](std::uint32_t v) {
    const int partner = st.contact_body[v];
    BodyContact& bc = entry(partner);
    ++bc.vertices;
    bc.max_depth = std::max(bc.max_depth, static_cast<double>(st.depth[v]));
    // Each face touching the contact once: from its lowest vertex in contact with this
    // partner. The pressure is linear over the face, zero at a vertex not in contact with
    // this partner, so the forces integrate it over every face it covers (a face on the
    // contact's rim carries part of it); the area counts faces wholly in contact.
    for (std::uint32_t k = sc.vf_offsets[v]; k < sc.vf_offsets[v + 1]; ++k) {
      const std::size_t f = 3u * sc.vf_faces[k];
      const std::uint32_t a = idx[f], b = idx[f + 1], c = idx[f + 2];
      const bool in_a = st.contact_body[a] == partner;
      const bool in_b = st.contact_body[b] == partner;
      const bool in_c = st.contact_body[c] == partner;
      if ((in_a && a < v) || (in_b && b < v) || (in_c && c < v)) continue;
      const glm::dvec3 pa(st.positions[a]), pb(st.positions[b]), pc(st.positions[c]);
      const glm::dvec3 cr = glm::cross(pb - pa, pc - pa);
      const double twice_area = glm::length(cr);
      if (!(twice_area > 0.0)) continue;
      // The skin in contact is the skin that was there: a face stretched by projecting its
      // vertices along diverging normals (a nose tip deep in a ball) counts with its
      // skinned area, so area and force stay bounded at any depth.
      const glm::dvec3 ra(fr.in->rigid_positions[a]);
      const double rigid_twice_area = glm::length(glm::cross(
          glm::dvec3(fr.in->rigid_positions[b]) - ra, glm::dvec3(fr.in->rigid_positions[c]) - ra));
      const double area = 0.5 * std::min(twice_area, rigid_twice_area);
      const double p_mean = ((in_a ? static_cast<double>(st.pressure[a]) : 0.0) +
                             (in_b ? static_cast<double>(st.pressure[b]) : 0.0) +
                             (in_c ? static_cast<double>(st.pressure[c]) : 0.0)) /
                            3.0;
      // The law integrates over the skin where the depths were measured, the skinned skin
      // (a dent pressed towards the bone shrinks its faces, not the load they carry), along
      // the deformed face's normal.
      bc.force -= (p_mean * 0.5 * rigid_twice_area / twice_area) * cr;
      if (in_a && in_b && in_c) {
        bc.area += area;
        bc.centre += area * (pa + pb + pc) / 3.0;
      }
    }
  });
  for (BodyContact& bc : st.contacts) {
    if (bc.area > 0.0) bc.centre /= bc.area;
  }
  // Restitution: while a partner separates from this body (it moves away along the push the
  // contact gives it, -force) the pair's force and pressures are e^2 of the law's, as in the
  // ball dynamics (prop.hpp).
  const auto nbody = static_cast<int>(fr.bodies.size());
  if (fr.self < 0 || fr.self >= nbody) return;
  const BodyView& me = fr.bodies[static_cast<std::size_t>(fr.self)];
  for (BodyContact& bc : st.contacts) {
    if (bc.partner == fr.self || bc.partner < 0 || bc.partner >= nbody) continue;
    const BodyView& other = fr.bodies[static_cast<std::size_t>(bc.partner)];
    const float s =
        separationScale(me.restitution, other.restitution, me.velocity, other.velocity, -bc.force);
    if (s == 1.0f) continue;
    bc.force *= static_cast<double>(s);
    forEachContactVertex([&](std::uint32_t v) {
      if (st.contact_body[v] == bc.partner) st.pressure[v] *= s;
    });
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
