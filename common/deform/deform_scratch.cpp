// The scratch of deformSkin (see deform_scratch.hpp): sized once per body (adjacency, vertex
// patches, lane sets, lists) and the per-frame setup (the collider table, the packed own
// fields).
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "common/deform/deform_scratch.hpp"
#include "common/deform/vertex_solve.hpp"

namespace vistel {
namespace {

// Groups the vertices into patches: vertices with the same defining primitives p0..p2,
// grown breadth-first over the triangles into compact groups of at most kPatchSize (each
// next patch seeded at the previous one's frontier), with the union of their always-pair
// primitives. Deterministic; init time only.
void buildPatches(const Calibration& cal, DeformScratch& sc) {
  const std::size_t nv = cal.prims.size();
  const auto idx = std::span<const std::uint32_t>(sc.vf_faces);  // face ids per vertex
  std::vector<std::uint8_t> taken(nv, 0);
  std::vector<std::uint32_t> queue, seeds;
  sc.order.clear();
  sc.order.reserve(nv);
  sc.patch_offsets.assign(1, 0);
  sc.patch_max_w.clear();
  sc.patch_always_offsets.assign(1, 0);
  sc.patch_always.clear();
  const auto same_key = [&cal](std::uint32_t a, std::uint32_t b) {
    return cal.prims[a][0] == cal.prims[b][0] && cal.prims[a][1] == cal.prims[b][1] &&
           cal.prims[a][2] == cal.prims[b][2];
  };
  std::size_t next_index = 0;
  while (sc.order.size() < nv) {
    std::uint32_t seed = 0;
    bool found = false;
    while (!seeds.empty() && !found) {
      seed = seeds.back();
      seeds.pop_back();
      found = taken[seed] == 0;
    }
    if (!found) {
      while (taken[next_index] != 0) ++next_index;
      seed = static_cast<std::uint32_t>(next_index);
    }
    queue.assign(1, seed);
    taken[seed] = 1;
    std::size_t head = 0;
    while (head < queue.size() && head < kPatchSize) {
      const std::uint32_t v = queue[head++];
      sc.order.push_back(v);
      for (std::uint32_t k = sc.vf_offsets[v]; k < sc.vf_offsets[v + 1]; ++k) {
        const std::uint32_t f = idx[k];
        for (std::uint32_t j = 0; j < 3; ++j) {
          const std::uint32_t u = sc.face_vertices[3 * f + j];
          if (taken[u] == 0 && same_key(u, seed)) {
            taken[u] = 1;
            queue.push_back(u);
          }
        }
      }
    }
    // Queued but not placed: seeds of the next patches.
    for (std::size_t i = queue.size(); i-- > head;) {
      taken[queue[i]] = 0;
      seeds.push_back(queue[i]);
    }
    // Always-pair primitives of the patch's vertices.
    const std::size_t first_always = sc.patch_always.size();
    for (std::size_t i = sc.patch_offsets.back(); i < sc.order.size(); ++i) {
      const std::uint32_t v = sc.order[i];
      for (std::uint32_t q = cal.pair_offsets[v]; q < cal.pair_offsets[v + 1]; ++q) {
        if ((cal.pairs[q].flags & kPairAlways) == 0) continue;
        const std::int16_t prim = cal.pairs[q].prim;
        if (std::find(sc.patch_always.begin() + static_cast<std::ptrdiff_t>(first_always),
                      sc.patch_always.end(), prim) == sc.patch_always.end()) {
          sc.patch_always.push_back(prim);
        }
      }
    }
    sc.patch_offsets.push_back(static_cast<std::uint32_t>(sc.order.size()));
    float w_max = 0.0f;
    for (std::size_t i = sc.patch_offsets[sc.patch_offsets.size() - 2]; i < sc.order.size(); ++i) {
      w_max = std::max(w_max, cal.w[sc.order[i]]);
    }
    sc.patch_max_w.push_back(w_max);
    sc.patch_always_offsets.push_back(static_cast<std::uint32_t>(sc.patch_always.size()));
  }
}

// The sets of own primitives evaluated together (see DeformScratch::own_lanes): one per
// distinct (p0, p1, p2, bone) of the joint vertices and of the limb vertices with a bone.
void buildLaneSets(const Calibration& cal, DeformScratch& sc) {
  const std::size_t nv = cal.vertex_class.size();
  sc.lane_set.assign(nv, -1);
  sc.lane_set_prims.clear();
  for (std::size_t v = 0; v < nv; ++v) {
    const auto& pr = cal.prims[v];
    const bool joint = cal.vertex_class[v] == VertexClass::kJoint;
    const bool limb_bone = cal.vertex_class[v] == VertexClass::kLimb && pr[3] >= 0;
    if ((!joint && !limb_bone) || pr[0] < 0) continue;
    const auto found = std::find(sc.lane_set_prims.begin(), sc.lane_set_prims.end(), pr);
    if (found == sc.lane_set_prims.end() && sc.lane_set_prims.size() >= 0x7FFF) continue;
    sc.lane_set[v] = static_cast<std::int16_t>(found - sc.lane_set_prims.begin());
    if (found == sc.lane_set_prims.end()) sc.lane_set_prims.push_back(pr);
  }
  sc.own_lanes.assign(sc.lane_set_prims.size(), FieldLanes{});
  sc.lane_set_packed.assign(sc.lane_set_prims.size(), 0);
}

}  // namespace

void initDeformScratch(const ImplicitModel& model, std::span<const std::uint32_t> indices,
                       DeformScratch& sc) {
  const int nvert = model.calibration.vertexCount();
  const auto nv = static_cast<std::size_t>(nvert);
  const auto nprim = model.primitives.items.size();
  sc.prim_to_world.assign(model.primitives.items.size(), glm::mat4(1.0f));
  sc.relaxed.assign(nv, glm::vec3(0.0f));
  sc.relax_list.assign(nv, 0);
  sc.contact_list.assign(nv, 0);
  sc.resting.assign(nv, 0);
  sc.any_inelastic =
      std::any_of(model.primitives.items.begin(), model.primitives.items.end(),
                  [](const Primitive& p) { return p.elasticity != Elasticity::kElastic; });
  sc.adopted.resize(nprim);
  for (std::size_t i = 0; i < nprim; ++i) {
    const std::string& name = model.primitives.items[i].name;
    sc.adopted[i] = primitivePart(name) != name ? 1 : 0;
  }
  sc.fixed_kind.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    sc.fixed_kind[v] =
        (model.calibration.rigid[v] != 0 || model.calibration.vertex_class[v] == VertexClass::kFree)
            ? 1
            : 0;
  }
  sc.lone_kind.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    sc.lone_kind[v] = loneKind(model.calibration, v, sc.fixed_kind[v] != 0) ? 1 : 0;
  }
  sc.solve_list.assign(nv, 0);
  sc.lone_list.assign(nv, 0);
  sc.joint_prefix.assign(nv + 1, 0);
  for (std::size_t v = 0; v < nv; ++v) {
    sc.joint_prefix[v + 1] =
        sc.joint_prefix[v] + (model.calibration.vertex_class[v] == VertexClass::kJoint ? 1 : 0);
  }
  sc.relax_problems.assign(sc.joint_prefix[nv] * kKeptProblemBytes, std::byte{0});
  sc.cand_count.assign(nv, 0);
  sc.dirty.assign(nv, 0);
  sc.candidates.assign(nv * kMaxCandidates, DeformScratch::CandidateSlot{});
  sc.field_gradient.assign(nv, glm::vec3(NAN));
  // Joint vertices, and free vertices beside them (a vertex of a joint region demoted at
  // calibration): the vertices the smoothing of corrections may move.
  sc.smooth_pool.clear();
  const Calibration& cal = model.calibration;
  for (std::size_t v = 0; v < nv; ++v) {
    bool pooled = cal.vertex_class[v] == VertexClass::kJoint;
    if (cal.vertex_class[v] == VertexClass::kFree) {
      for (std::uint32_t k = cal.ring_offsets[v]; k < cal.ring_offsets[v + 1] && !pooled; ++k) {
        pooled = cal.vertex_class[cal.ring[k]] == VertexClass::kJoint;
      }
    }
    if (pooled) sc.smooth_pool.push_back(static_cast<std::uint32_t>(v));
  }
  sc.smooth_list.clear();
  sc.smooth_list.reserve(sc.smooth_pool.size());
  sc.correction.assign(nv, glm::vec3(0.0f));
  sc.correction_next.assign(nv, glm::vec3(0.0f));
  sc.smooth_mark.assign(nv, 0);
  sc.colliders.clear();
  sc.colliders.reserve(512);
  sc.prim_collider_offsets.assign(nprim + 1, 0);
  sc.prim_colliders.clear();
  sc.prim_colliders.reserve(4096);
  sc.always_collider.assign(nprim, -1);
  // Primitives named by always-pairs.
  std::vector<std::uint8_t> named(nprim, 0);
  for (const VertexPair& p : model.calibration.pairs) {
    if ((p.flags & kPairAlways) != 0 && p.prim >= 0 && static_cast<std::size_t>(p.prim) < nprim) {
      named[static_cast<std::size_t>(p.prim)] = 1;
    }
  }
  sc.always_prims.clear();
  for (std::size_t p = 0; p < nprim; ++p) {
    if (named[p] != 0) sc.always_prims.push_back(static_cast<std::int16_t>(p));
  }
  sc.face_vertices.assign(indices.begin(), indices.end());
  sc.face_cross.assign(indices.size() / 3, glm::vec3(0.0f));
  sc.orient_vertices.clear();
  sc.orient_vertices.reserve(nv);
  sc.orient_faces.clear();
  sc.orient_faces.reserve(indices.size() / 3);
  sc.orient_vertex_mark.assign(nv, 0);
  sc.orient_face_mark.assign(indices.size() / 3, 0);
  // Vertex -> face adjacency.
  sc.vf_offsets.assign(nv + 1, 0);
  for (const std::uint32_t i : indices) ++sc.vf_offsets[i + 1];
  for (std::size_t v = 0; v < nv; ++v) sc.vf_offsets[v + 1] += sc.vf_offsets[v];
  sc.vf_faces.assign(indices.size(), 0);
  std::vector<std::uint32_t> fill(sc.vf_offsets.begin(), sc.vf_offsets.end() - 1);
  for (std::size_t i = 0; i < indices.size(); ++i) {
    sc.vf_faces[fill[indices[i]]++] = static_cast<std::uint32_t>(i / 3);
  }
  buildPatches(model.calibration, sc);
  buildLaneSets(model.calibration, sc);
  sc.chunk_counters.assign(static_cast<std::size_t>((nvert + 511) / 512) + 1, DeformCounters{});
}

// Builds this frame's collider table: the partners Step 1 found for each own primitive,
// plus the same-body primitives named by always-pairs.
void buildColliders(DeformFrame& fr, const InteractionList& list) {
  DeformScratch& sc = *fr.sc;
  const auto nprim = fr.model->primitives.items.size();
  sc.colliders.clear();
  const auto find_or_add = [&](int body, int prim) -> int {
    for (std::size_t c = 0; c < sc.colliders.size(); ++c) {
      if (sc.colliders[c].body == body && sc.colliders[c].prim == prim) return static_cast<int>(c);
    }
    DeformScratch::Collider col;
    col.body = static_cast<std::uint16_t>(body);
    col.prim = static_cast<std::uint16_t>(prim);
    col.posed =
        &fr.bodies[static_cast<std::size_t>(body)].posed->items[static_cast<std::size_t>(prim)];
    col.cull.min = col.posed->bounds.min - glm::vec3(kCullMargin);
    col.cull.max = col.posed->bounds.max + glm::vec3(kCullMargin);
    const Shape& sh = col.posed->shape;
    const float unit =
        sh.kind == ShapeKind::kConeSphere ? std::min(sh.radius_a, sh.radius_b) : 1.0f;
    col.inv_unit = 1.0f / unit;
    col.cull_distance = 1.0f / col.posed->inv_r_out + kCullMargin * col.inv_unit;
    sc.colliders.push_back(col);
    return static_cast<int>(sc.colliders.size() - 1);
  };
  std::fill(sc.prim_collider_offsets.begin(), sc.prim_collider_offsets.end(), 0u);
  sc.prim_colliders.clear();
  const auto entries = fr.opt->collisions ? list.forBody(fr.self) : std::span<const Interaction>();
  // Entries are sorted by own primitive: count and fill in one pass.
  for (const Interaction& e : entries) {
    if (e.prim_a >= nprim) continue;
    if (e.body_b == fr.self && e.prim_b < nprim && sc.adopted[e.prim_b] != 0) continue;
    ++sc.prim_collider_offsets[e.prim_a + 1u];
    sc.prim_colliders.push_back(static_cast<std::uint16_t>(find_or_add(e.body_b, e.prim_b)));
  }
  for (std::size_t p = 0; p < nprim; ++p)
    sc.prim_collider_offsets[p + 1] += sc.prim_collider_offsets[p];
  std::fill(sc.always_collider.begin(), sc.always_collider.end(), -1);
  if (fr.opt->collisions) {
    for (const std::int16_t p : sc.always_prims) {
      sc.always_collider[static_cast<std::size_t>(p)] = find_or_add(fr.self, p);
    }
  }
}

// Packs every lane set from this frame's posed primitives (a set with a primitive the lanes
// do not cover stays unpacked: its vertices evaluate their fields one by one).
void packLaneSets(DeformFrame& fr) {
  DeformScratch& sc = *fr.sc;
  for (std::size_t i = 0; i < sc.lane_set_prims.size(); ++i) {
    bool packed = true;
    for (int k = 0; k < 4 && packed; ++k) {
      const std::int16_t prim = sc.lane_set_prims[i][static_cast<std::size_t>(k)];
      packed = packFieldLane(prim >= 0 ? &fr.posed->items[static_cast<std::size_t>(prim)] : nullptr,
                             k, sc.own_lanes[i]);
    }
    sc.lane_set_packed[i] = packed ? 1 : 0;
  }
}

}  // namespace vistel
