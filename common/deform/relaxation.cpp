// The last parts of Step 2 (see relaxation.hpp): the tangential relaxation of the moved joint
// vertices with a final projection (Vaillant et al. 2013, "Implicit skinning: real-time skin
// deformation with contact modeling"), and the smoothing of the joint regions' corrections.
#include "common/deform/relaxation.hpp"

#include <cmath>

#include "common/deform/vertex_solve.hpp"

namespace vistel {
namespace {

// One tangential relaxation pass over the flagged vertices of a chunk (relax_list from
// `first`, `count` of them): move towards the rest barycentre of the one-ring within the
// tangent plane, then project back onto F = T along the outward field normal. Reads
// positions, writes relaxed.
void passRelax(DeformFrame& fr, int first, int count, DeformCounters& cnt) {
  DeformState& st = *fr.st;
  DeformScratch& sc = *fr.sc;
  const Calibration& cal = fr.model->calibration;
  const DeformOptions& opt = *fr.opt;
  VertexProblem vp;
  for (int k = 0; k < count; ++k) {
    const std::uint32_t v = sc.relax_list[static_cast<std::size_t>(first + k)];
    const auto vi = static_cast<std::size_t>(v);
    sc.relaxed[vi] = st.positions[vi];
    const std::uint32_t r0 = cal.ring_offsets[vi];
    const std::uint32_t r1 = cal.ring_offsets[vi + 1];
    if (r0 == r1) continue;
    // The problem as pass B gathered it (the reference way gathers it again: the same).
    if (opt.reference) {
      gatherVertexProblem(fr, static_cast<int>(v), true, vp);
    } else {
      keptProblem(
          sc, sc.joint_prefix[static_cast<std::size_t>(first)] + static_cast<std::size_t>(k), vp);
    }
    // Outward field normal at the current position.
    const glm::vec3 p = st.positions[vi];
    // From the solve that put the vertex at p (both ways): the gradient of its last evaluation,
    // within a final Newton step of p (gradientNear), or NaN.
    glm::vec3 grad = sc.field_gradient[vi];
    if (std::isnan(grad.x)) {
      evaluate(vp, p, grad);
      ++cnt.evaluations;
    }
    const float gn = glm::length(grad);
    if (!(gn > 0.0f)) continue;
    glm::vec3 nu = -grad / gn;
    // Tangential move towards the barycentre.
    glm::vec3 centre(0.0f);
    for (std::uint32_t j = r0; j < r1; ++j)
      centre += cal.ring_weights[j] * st.positions[cal.ring[j]];
    glm::vec3 delta = centre - p;
    delta -= glm::dot(delta, nu) * nu;
    const glm::vec3 q = p + opt.relax_rate * delta;
    // Final projection along the field normal.
    glm::vec3 gq;
    const float g0 = evaluate(vp, q, gq);
    ++cnt.evaluations;
    const float own_side_start = vp.own_side;
    vp.p0 = q;
    vp.p0_rigid = false;
    bool iterated = false;
    const std::int64_t iterations = cnt.iterations;  // the projection's count as relaxation's
    const RootResult res =
        solveVertex(vp, nu, 0.0f, g0, gq, searchReach(vp), opt.root, cnt, iterated);
    cnt.relax_iterations += cnt.iterations - iterations;
    cnt.iterations = iterations;
    if (res.found && ownSideHolds(vp, own_side_start, q + res.s * nu, opt)) {
      sc.relaxed[vi] = q + res.s * nu;
      sc.field_gradient[vi] = gradientNear(vp, sc.relaxed[vi], opt.root.final_step);
    }
  }
}

}  // namespace

void relaxJointVertices(DeformFrame& fr, TaskPool* pool) {
  DeformState& st = *fr.st;
  DeformScratch& sc = *fr.sc;
  const int chunks = chunkCount(fr);
  // Relaxation passes (Jacobi: read positions, write relaxed, then copy back).
  for (int pass = 0; pass < fr.opt->relax_passes; ++pass) {
    // Each chunk's relaxed vertices are listed from its first vertex on (see passSolve).
    auto relax = [&](int c) {
      DeformCounters& cnt = sc.chunk_counters[static_cast<std::size_t>(c)];
      passRelax(fr, chunkRange(fr, c).first, cnt.relaxed_vertices, cnt);
    };
    parallelFor(pool, chunks, relax);
    auto copy = [&](int c) {
      const int b = chunkRange(fr, c).first;
      const int n = sc.chunk_counters[static_cast<std::size_t>(c)].relaxed_vertices;
      for (int k = 0; k < n; ++k) {
        const std::uint32_t v = sc.relax_list[static_cast<std::size_t>(b + k)];
        st.positions[v] = sc.relaxed[v];
        // Its ring needs new normals: marked once a frame (a reshaped vertex is marked).
        if ((st.flags[v] & kVertexReshaped) == 0) {
          st.flags[v] |= kVertexReshaped;
          markReshaped(fr, static_cast<int>(v));
        }
      }
    };
    parallelFor(pool, chunks, copy);
  }
}

// Whether a collision term may have shaped vertex v's solution this frame: it touches, it
// penetrated a collider in the rigid pose, or a collider may bulge it (another body's, or any
// with self-propagation). A vertex whose only colliders are its own body's, neither touched
// nor penetrated, solved its own equation alone (the joint's opposite limb, always paired
// with a joint vertex, acts only where the vertex enters it).
bool collisionShaped(const DeformFrame& fr, std::uint32_t v) {
  const DeformState& st = *fr.st;
  const DeformScratch& sc = *fr.sc;
  const int n = sc.cand_count[v] & 0x7F;
  if (n == 0) return false;
  if ((sc.cand_count[v] & 0x80) != 0) return true;  // more colliders than were listed
  if ((st.flags[v] & kVertexContact) != 0 || st.depth[v] > 0.0f) return true;
  for (int i = 0; i < n; ++i) {
    const std::uint16_t c =
        sc.candidates[static_cast<std::size_t>(v) * kMaxCandidates + static_cast<std::size_t>(i)]
            .collider;
    if (sc.colliders[c].body != fr.self || fr.opt->self_propagation) return true;
  }
  return false;
}

namespace {

// Whether moving vertex v to p would turn one of its faces inside out against the skinned
// skin (rigid positions) that is not turned now.
bool turnsAFace(const DeformFrame& fr, std::uint32_t v, const glm::vec3& p) {
  const DeformScratch& sc = *fr.sc;
  const auto rigid = fr.in->rigid_positions;
  const auto& pos = fr.st->positions;
  for (std::uint32_t k = sc.vf_offsets[v]; k < sc.vf_offsets[v + 1]; ++k) {
    const std::uint32_t* f = &sc.face_vertices[3 * static_cast<std::size_t>(sc.vf_faces[k])];
    const glm::vec3 nr = glm::cross(rigid[f[1]] - rigid[f[0]], rigid[f[2]] - rigid[f[0]]);
    const glm::vec3 now = glm::cross(pos[f[1]] - pos[f[0]], pos[f[2]] - pos[f[0]]);
    glm::vec3 q[3] = {pos[f[0]], pos[f[1]], pos[f[2]]};
    for (int i = 0; i < 3; ++i) {
      if (f[i] == v) q[i] = p;
    }
    const glm::vec3 moved = glm::cross(q[1] - q[0], q[2] - q[0]);
    if (glm::dot(nr, moved) <= 0.0f && glm::dot(nr, now) > 0.0f) return true;
  }
  return false;
}

}  // namespace

// The last part of Step 2: smooths the corrections c = P' - P of the joint regions (see
// the header and DeformOptions::smooth_passes). The vertices smoothed are those of the pool
// (joint vertices and the free ones beside them) that no collision term shaped (see
// collisionShaped), so none in contact, that moved or have a neighbour that moved (beyond
// them nothing spreads); each pass moves their corrections smooth_rate of the way to the
// one-ring's mean (rest barycentric weights), reading the others' as they are. Serial and in
// vertex order (Jacobi), so the result does not depend on threads. Returns how many moved.
int smoothCorrections(DeformFrame& fr) {
  DeformState& st = *fr.st;
  DeformScratch& sc = *fr.sc;
  const DeformOptions& opt = *fr.opt;
  const Calibration& cal = fr.model->calibration;
  const auto rigid = fr.in->rigid_positions;
  const auto moved = [&](std::uint32_t u) {
    return (st.flags[u] & (kVertexMoved | kVertexRelaxed)) != 0;
  };
  sc.smooth_list.clear();
  for (const std::uint32_t v : sc.smooth_pool) {
    // A vertex whose own field is wholly faded keeps its skinned surface: its correction
    // is not the joint region's to smooth (dragged to its neighbours' it folds thin faces).
    if (collisionShaped(fr, v) || skinnedShare(fr, v) >= 1.0f) continue;
    bool active = moved(v);
    for (std::uint32_t k = cal.ring_offsets[v]; k < cal.ring_offsets[v + 1] && !active; ++k) {
      active = moved(cal.ring[k]);
    }
    if (!active) continue;
    sc.smooth_list.push_back(v);
    sc.smooth_mark[v] = 1;
    sc.correction[v] = st.positions[v] - rigid[v];
  }
  const float a = opt.smooth_rate;
  for (int pass = 0; pass < opt.smooth_passes; ++pass) {
    for (const std::uint32_t v : sc.smooth_list) {
      glm::vec3 mean(0.0f);
      for (std::uint32_t k = cal.ring_offsets[v]; k < cal.ring_offsets[v + 1]; ++k) {
        const std::uint32_t u = cal.ring[k];
        mean += cal.ring_weights[k] *
                (sc.smooth_mark[u] != 0 ? sc.correction[u] : st.positions[u] - rigid[u]);
      }
      sc.correction_next[v] = (1.0f - a) * sc.correction[v] + a * mean;
    }
    for (const std::uint32_t v : sc.smooth_list) sc.correction[v] = sc.correction_next[v];
  }
  int count = 0;
  for (const std::uint32_t v : sc.smooth_list) {
    sc.smooth_mark[v] = 0;
    const glm::vec3 c = sc.correction[v];
    const glm::vec3 p = rigid[v] + c;
    if (p == st.positions[v]) continue;
    // Smoothing evens out the skin; where it would turn a face inside out (a small face
    // between a vertex that moved and one that did not), the vertex keeps its solution.
    if (turnsAFace(fr, v, p)) continue;
    st.positions[v] = p;
    ++count;
    std::uint8_t& flags = st.flags[v];
    flags |= kVertexSmoothed;
    if (p != rigid[v]) {
      flags |= kVertexMoved;
    } else {
      flags &= static_cast<std::uint8_t>(~kVertexMoved);
    }
    if ((flags & kVertexReshaped) == 0 && glm::dot(c, c) > kReshapeOffset * kReshapeOffset) {
      flags |= kVertexReshaped;
      markReshaped(fr, static_cast<int>(v));
    }
  }
  return count;
}

}  // namespace vistel
