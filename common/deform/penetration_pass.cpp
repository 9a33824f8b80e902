// Pass A of Step 2 (see deform_scratch.hpp): which colliders may touch each vertex (its
// collision candidates, cached for pass B), each vertex's rigid-pose penetration and each
// collider's deepest penetration p_max, whose bulge (Gascuel 1993's propagation zone,
// collision_terms.hpp) pass B then applies. The fast way culls colliders per patch of
// vertices with conservative bounds and tests a patch's points in vectorised loops; the
// reference way (DeformOptions::reference) tests every collider of every vertex directly;
// both keep the same candidates.
#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>

#include "common/deform/collision_terms.hpp"
#include "common/deform/deform_scratch.hpp"

namespace vistel {
namespace {

float atomicMaxBits(std::uint32_t& target, float value) {
  // Non-negative floats order like their bit patterns.
  std::atomic_ref<std::uint32_t> ref(target);
  const std::uint32_t bits = std::bit_cast<std::uint32_t>(value);
  std::uint32_t cur = ref.load(std::memory_order_relaxed);
  while (cur < bits && !ref.compare_exchange_weak(cur, bits, std::memory_order_relaxed)) {
  }
  return value;
}

// Marks a collider list entry as coming from an always-pair (it applies only to the
// vertices that have that pair).
constexpr std::uint16_t kAlwaysEntry = 0x8000;
// Collider list capacity of one patch (or one vertex, when a patch overflows it).
constexpr int kMaxListed = 64;

// Collects into `out` the colliders that may matter to vertices with defining primitives
// key[0..2] and always-pair primitives `always`, whose rigid positions lie in `box`: the
// colliders Step 1 found for the key primitives (same-body ones other than the key's own),
// and the always-pairs' primitives, each once and only when its support (grown by the
// cull margin) overlaps the box. Returns the count, or -1 when more than kMaxListed.
int listColliders(const DeformFrame& fr, const std::array<std::int16_t, 4>& key,
                  std::span<const std::int16_t> always, const Bounds& box,
                  std::uint16_t (&out)[kMaxListed]) {
  const DeformScratch& sc = *fr.sc;
  int n = 0;
  const auto overlaps = [&box](const DeformScratch::Collider& col) {
    const Bounds& c = col.cull;
    return !(box.max.x < c.min.x || box.min.x > c.max.x || box.max.y < c.min.y ||
             box.min.y > c.max.y || box.max.z < c.min.z || box.min.z > c.max.z);
  };
  const auto listed = [&](int c) {
    for (int i = 0; i < n; ++i) {
      if ((out[i] & ~kAlwaysEntry) == c) return true;
    }
    return false;
  };
  for (std::size_t k = 0; k < 3; ++k) {
    const std::int16_t o = key[k];
    if (o < 0) continue;
    const auto ou = static_cast<std::size_t>(o);
    for (std::uint32_t j = sc.prim_collider_offsets[ou]; j < sc.prim_collider_offsets[ou + 1];
         ++j) {
      const int c = sc.prim_colliders[j];
      const DeformScratch::Collider& col = sc.colliders[static_cast<std::size_t>(c)];
      if (col.body == fr.self &&
          (col.prim == key[0] || col.prim == key[1] || col.prim == key[2] || col.prim == key[3])) {
        continue;
      }
      if (!overlaps(col) || listed(c)) continue;
      if (n == kMaxListed) return -1;
      out[n++] = static_cast<std::uint16_t>(c);
    }
  }
  for (const std::int16_t prim : always) {
    const std::int32_t c = sc.always_collider[static_cast<std::size_t>(prim)];
    if (c < 0 || !overlaps(sc.colliders[static_cast<std::size_t>(c)]) || listed(c)) continue;
    if (n == kMaxListed) return -1;
    out[n++] = static_cast<std::uint16_t>(c | kAlwaysEntry);
  }
  return n;
}

// The lowest x = omega F_i - iso at which collider col's term can be non-zero: -width where
// it may bulge (another body, propagation on), else the contact tolerance below 0.
float lowestTerm(const DeformFrame& fr, const DeformScratch::Collider& col) {
  const bool bulges = fr.opt->propagation && (col.body != fr.self || fr.opt->self_propagation);
  return bulges ? -fr.model->primitives.propagation_width : -kContactTolerance;
}

// A collider list entry with what does not depend on the vertex (for vertices whose
// defining primitives are the key the list was made for).
// (No initialisers: a patch makes room for kMaxListed of them, and describeList fills each
// one it uses.)
struct Listed {
  DeformScratch::Collider* col;
  std::uint16_t c;    // collider index
  bool always_entry;  // from an always-pair (see kAlwaysEntry)
  bool same;          // the vertex's own body
  bool adjacent;      // own body, joined to a key primitive in the graph
  bool rigid;         // infinite stiffness
  float lowest;       // lowestTerm
};

// One vertex's own collider list (listColliders for its defining primitives and its
// always-pairs at its rigid position): the count, at most kMaxListed (when more are near it,
// the first ones).
int listVertexColliders(const DeformFrame& fr, std::uint32_t v, std::uint16_t (&out)[kMaxListed]) {
  const Calibration& cal = fr.model->calibration;
  const auto& pr = cal.prims[v];
  std::int16_t own_always[kMaxListed];
  std::size_t na = 0;
  for (std::uint32_t k = cal.pair_offsets[v]; k < cal.pair_offsets[v + 1] && na < kMaxListed; ++k) {
    if ((cal.pairs[k].flags & kPairAlways) != 0) own_always[na++] = cal.pairs[k].prim;
  }
  const glm::vec3 p = fr.in->rigid_positions[v];
  const int n =
      listColliders(fr, {pr[0], pr[1], pr[2], pr[3]}, {own_always, na}, Bounds{p, p}, out);
  return n < 0 ? kMaxListed : n;
}

// Describes `n` entries of a collider list for vertices with defining primitives key[0..2].
void describeList(const DeformFrame& fr, const std::array<std::int16_t, 4>& key,
                  const std::uint16_t* entries, int n, Listed* out) {
  DeformScratch& sc = *fr.sc;
  const CombinationGraph& graph = fr.model->graph;
  for (int i = 0; i < n; ++i) {
    Listed& l = out[i];
    l.c = static_cast<std::uint16_t>(entries[i] & ~kAlwaysEntry);
    l.always_entry = (entries[i] & kAlwaysEntry) != 0;
    l.col = &sc.colliders[l.c];
    l.same = l.col->body == fr.self;
    l.adjacent = l.same && ((key[0] >= 0 && graph.neighbours(key[0], l.col->prim)) ||
                            (key[1] >= 0 && graph.neighbours(key[1], l.col->prim)) ||
                            (key[2] >= 0 && graph.neighbours(key[2], l.col->prim)));
    l.rigid = std::isinf(l.col->posed->stiffness);
    l.lowest = lowestTerm(fr, *l.col);
  }
}

// Points of a patch (at most kPatchSize), one array per coordinate, and their offsets from one
// collider's skeleton: what pass A's first tests need for every vertex of the patch.
struct PatchPoints {
  int count = 0;
  std::uint32_t vertex[kPatchSize];
  float x[kPatchSize], y[kPatchSize], z[kPatchSize];
  float margin[kPatchSize];  // cull margin and warm-start offset (see findCandidates)
  float w[kPatchSize];       // calibration weight
  int bone[kPatchSize];      // bone primitive (Calibration::prims[v][3]; -1 for none)
};
struct PatchOffsets {
  float x[kPatchSize], y[kPatchSize], z[kPatchSize];  // skeletonOffset
  float scale[kPatchSize];                            // its scale
  float len[kPatchSize];                              // |offset|
  float density_near[kPatchSize];  // the profile's largest value within the point's margin
  std::uint8_t near[kPatchSize];   // passes the first tests (see patchOffsets)
  int listed[kPatchSize];          // the points that do, in order
  int nlisted;
};

// skeletonOffset (skeletonOffsets), its length and the first tests for every point of a patch
// against one collider `l`, as loops the compiler vectorises (the square root needs
// -fno-math-errno, see CMakeLists.txt): inside the collider's cull box and within its cull
// distance; not the point's own bone (unless from an always-pair); and x = omega F - iso can
// pass lowestTerm within the point's margin, bounded with the largest scale omega the point can
// give the partner's field and the set's iso (no pair's threshold is lower: VertexPair::iso,
// validated). The points that pass are listed in `o.listed` (most fail: no branch each).
void patchOffsets(const Listed& l, float iso, const PatchPoints& p, PatchOffsets& o) {
  const DeformScratch::Collider& col = *l.col;
  const PosedPrimitive& prim = *col.posed;
  const int m = p.count;
  skeletonOffsets(prim.shape, m, p.x, p.y, p.z, o.x, o.y, o.z, o.scale);
  const Bounds& c = col.cull;
  // Locals, so that the stores below cannot alias them.
  const float cull_distance = col.cull_distance, inv_unit = col.inv_unit;
  const float inv_r_out = prim.inv_r_out, weight = prim.weight, lowest = l.lowest;
  const float max_w = prim.max_skin_weight;
  const bool rigid = l.rigid, same = l.same, adjacent = l.adjacent;
  // The own bone is never a collider of its vertices, except through an always-pair.
  const int skip_bone = l.same && !l.always_entry ? static_cast<int>(col.prim) : -2;
  for (int i = 0; i < m; ++i) {
    o.len[i] = std::sqrt(o.x[i] * o.x[i] + o.y[i] * o.y[i] + o.z[i] * o.z[i]);
    const float d = o.len[i] * o.scale[i];
    const float r_near = std::max(d - p.margin[i] * inv_unit, 0.0f) * inv_r_out;
    o.density_near[i] = r_near;  // (the profile's argument, for the loop below)
  }
  if (prim.density.kind == DensityKind::kWyvill) {
    for (int i = 0; i < m; ++i) {  // densityValue without the branches
      const float r = o.density_near[i];
      const float f = wyvillPolynomial(r * r);
      o.density_near[i] = r <= 0.0f ? 1.0f : (r >= 1.0f ? 0.0f : f);
    }
  } else {
    for (int i = 0; i < m; ++i) o.density_near[i] = densityValue(prim.density, o.density_near[i]);
  }
  for (int i = 0; i < m; ++i) {
    const bool in_box = (p.x[i] >= c.min.x) & (p.x[i] <= c.max.x) & (p.y[i] >= c.min.y) &
                        (p.y[i] <= c.max.y) & (p.z[i] >= c.min.z) & (p.z[i] <= c.max.z);
    const float omega_bound =
        rigid ? 1.0f : (same ? (adjacent ? p.w[i] : std::max(p.w[i], max_w)) : max_w);
    const bool reaches = omega_bound * weight * o.density_near[i] - iso > lowest;
    o.near[i] =
        in_box & !(o.len[i] * o.scale[i] > cull_distance) & reaches & (p.bone[i] != skip_bone);
  }
  int n = 0;
  for (int i = 0; i < m; ++i) {
    o.listed[n] = i;
    n += o.near[i];
  }
  o.nlisted = n;
}

// Pass A for the vertices of a patch: picks each one's collision candidates from `list`
// (listColliders for the patch, described) into the state's cache, each only when its rigid
// position is near the collider's support; records each vertex's rigid-pose penetration
// (depth, pressure) and each collider's deepest penetration this frame. Collider by collider,
// so each vertex's candidates keep the list's order.
void findCandidates(const DeformFrame& fr, const PatchPoints& pts, std::span<const Listed> list) {
  const ImplicitModel& m = *fr.model;
  const Calibration& cal = m.calibration;
  DeformState& st = *fr.st;
  DeformScratch& sc = *fr.sc;
  int count[kPatchSize] = {};
  bool overflow[kPatchSize] = {};
  float best_depth[kPatchSize] = {};
  float best_pressure[kPatchSize] = {};
  PatchOffsets off;
  for (const Listed& l : list) {
    const int c = l.c;
    DeformScratch::Collider& col = *l.col;
    patchOffsets(l, m.primitives.iso, pts, off);
    const PosedPrimitive& prim = *col.posed;
    const float lowest = l.lowest;
    // First each listed point's pair threshold and the partner field's scale omega where it
    // needs no lookup; the points whose omega is the partner's skin weight are looked up
    // after, in a loop of their own (each lookup is independent of the others, so the
    // processor overlaps them); then the rest, point by point in the list's order.
    int kept[kPatchSize];  // the points still in, in order
    float kept_iso[kPatchSize];
    float kept_omega[kPatchSize];
    int nkept = 0;
    int lookup[kPatchSize];  // indices into kept
    int nlookup = 0;
    for (int j = 0; j < off.nlisted; ++j) {
      const int i = off.listed[j];
      const auto vi = static_cast<std::size_t>(pts.vertex[i]);
      // A collider matters only where its term can be non-zero (see lowestTerm). Bound x over
      // the points within the cull margin of where the vertex was solved last frame (its
      // rigid position offset by the warm start): patchOffsets has settled most colliders with
      // the largest omega and the set's iso before the vertex's pairs are looked up.
      const float density_near = off.density_near[i];
      float iso = m.primitives.iso;
      bool always = false;
      if (l.same) {
        for (std::uint32_t q = cal.pair_offsets[vi]; q < cal.pair_offsets[vi + 1]; ++q) {
          if (cal.pairs[q].prim == col.prim) {
            iso = cal.pairs[q].iso;
            always = always || (cal.pairs[q].flags & kPairAlways) != 0;
          }
        }
        if (l.always_entry && !always) continue;  // another vertex's pair
      }
      // The partner field's scale: 1 for a rigid partner; the vertex's own weight for a
      // neighbouring part of its body (joined to one of its primitives through a joint: the
      // two skins meet at a crease calibrated at rest); else the partner's skin weight (first
      // bounded by the grid's largest, which settles most colliders without a lookup).
      const bool neighbour = l.same && (always || l.adjacent);
      float omega = 1.0f;
      if (!l.rigid) {
        if (neighbour) {
          omega = pts.w[i];
        } else {
          if (!(prim.max_skin_weight * prim.weight * density_near - iso > lowest)) continue;
          lookup[nlookup++] = nkept;
        }
      }
      kept[nkept] = i;
      kept_iso[nkept] = iso;
      kept_omega[nkept] = omega;
      ++nkept;
    }
    for (int k = 0; k < nlookup; k += 4) {  // four at a time (the last lanes repeat one)
      int at[4];
      for (int j = 0; j < 4; ++j) at[j] = kept[lookup[std::min(k + j, nlookup - 1)]];
      const auto gather = [&at](const float* a) {
        return FieldVec{a[at[0]], a[at[1]], a[at[2]], a[at[3]]};
      };
      const FieldVec w =
          skinWeightLanes(prim, gather(pts.x), gather(pts.y), gather(pts.z), gather(off.x),
                          gather(off.y), gather(off.z), gather(off.scale), gather(off.len));
      for (int j = 0; j < 4 && k + j < nlookup; ++j) kept_omega[lookup[k + j]] = w[j];
    }
    for (int k = 0; k < nkept; ++k) {
      const int i = kept[k];
      const std::uint32_t v = pts.vertex[i];
      const auto vi = static_cast<std::size_t>(v);
      // The skeleton distance d (as skeletonDistance), keeping the offset; its gradient gd
      // below, where the vertex penetrates.
      const glm::vec3 offset(off.x[i], off.y[i], off.z[i]);
      const float scale = off.scale[i];
      const float len = off.len[i];
      const float d = len * scale;
      const float k_other = prim.stiffness;
      const float iso = kept_iso[k];
      const float omega = kept_omega[k];
      const float x_near = omega * prim.weight * off.density_near[i] - iso;
      if (!(x_near > lowest)) continue;
      if (count[i] == kMaxCandidates) {
        overflow[i] = true;
        continue;
      }
      const std::size_t slot = vi * kMaxCandidates + static_cast<std::size_t>(count[i]);
      DeformScratch::CandidateSlot& cs = sc.candidates[slot];
      cs.iso = iso;
      cs.reach = x_near;
      cs.omega = omega;
      cs.collider = static_cast<std::uint16_t>(c);
      // A free vertex's x at its rigid position, where its solve looks at its partners first
      // (every one hard, see deepestHard), as primitiveField gives it: the same offset
      // (skeletonOffsets), the same fieldAtOffset.
      if (cal.vertex_class[vi] == VertexClass::kFree) {
        cs.x_rigid = inBounds(prim, glm::vec3(pts.x[i], pts.y[i], pts.z[i]))
                         ? omega * fieldAtOffset(prim, offset, scale) - iso
                         : -INFINITY;
      }
      ++count[i];
      // Rigid-pose penetration into this collider.
      const float r = d * prim.inv_r_out;
      if (r >= 1.0f) continue;
      float fp = 0.0f;
      const float f = prim.weight * densityValue(prim.density, r, &fp);
      const float x = omega * f - iso;
      if (!(x > 0.0f)) continue;
      atomicMaxBits(col.pmax_bits, x);
      const glm::vec3 gd = len > 0.0f ? offset * (scale / len) : glm::vec3(0.0f);
      const float gn = omega * prim.weight * std::abs(fp) * prim.inv_r_out * glm::length(gd);
      const float depth = gn > 0.0f ? x / gn : 0.0f;
      if (depth > best_depth[i] && depth > kMinContactDepth) {
        best_depth[i] = depth;
        best_pressure[i] = contactPressure(ownStiffness(fr, static_cast<int>(v)), k_other, depth);
      }
    }
  }
  for (int i = 0; i < pts.count; ++i) {
    const std::uint32_t v = pts.vertex[i];
    sc.cand_count[v] = static_cast<std::uint8_t>(count[i] | (overflow[i] ? 0x80 : 0));
    st.depth[v] = best_depth[i];
    st.pressure[v] = best_pressure[i];
  }
}

// Drops from a patch's collider list the colliders that cannot matter to any of its
// vertices: where x = omega F_i - iso stays at or below lowestTerm everywhere within the cull
// margin (grown by the patch's largest warm-start offset) of the patch's box, bounded with the
// largest omega a vertex of the patch can give the collider (w_max: the patch's largest
// calibration weight) and the set's iso (no pair's threshold is lower). Returns the new count.
int keepReachable(const DeformFrame& fr, const Bounds& box, float offset_max, float w_max,
                  std::uint16_t (&list)[kMaxListed], int n) {
  const DeformScratch& sc = *fr.sc;
  const glm::vec3 centre = 0.5f * (box.min + box.max);
  const float radius = 0.5f * glm::length(box.max - box.min) + kCullMargin + offset_max;
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    const DeformScratch::Collider& col = sc.colliders[list[i] & ~kAlwaysEntry];
    const PosedPrimitive& prim = *col.posed;
    // A part of the vertices' own body may be scaled by their own weight (see findCandidates).
    const float omega =
        std::isinf(prim.stiffness)
            ? 1.0f
            : (col.body == fr.self ? std::max(prim.max_skin_weight, w_max) : prim.max_skin_weight);
    const float d = skeletonDistance(prim.shape, centre);
    const float r_near = std::max(d - radius * col.inv_unit, 0.0f) * prim.inv_r_out;
    const float x_near =
        omega * prim.weight * densityValue(prim.density, r_near) - fr.model->primitives.iso;
    if (x_near > lowestTerm(fr, col)) list[kept++] = list[i];
  }
  return kept;
}

// The box of the n > 0 points pos[index[0..n)] (as glm::min and glm::max), a point to a
// vector (built from its coordinates: a 16-byte load of three stored floats would stall).
Bounds patchBox(const glm::vec3* pos, const std::uint32_t* index, std::uint32_t n) {
  const auto load = [pos](std::uint32_t v) {
    const glm::vec3& q = pos[v];
    return FieldVec{q.x, q.y, q.z, 0.0f};
  };
  FieldVec lo = load(index[0]);
  FieldVec hi = lo;
  for (std::uint32_t i = 1; i < n; ++i) {
    const FieldVec p = load(index[i]);
    lo = p < lo ? p : lo;
    hi = hi < p ? p : hi;
  }
  return {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
}

// Pass A the reference way for vertex v (DeformOptions::reference): every collider of its
// interaction list (listColliders for its own primitives and always-pairs at its rigid
// position), each tested directly with the scalar field functions: the candidates findCandidates
// would keep (the collider's term can be non-zero within the vertex's cull margin), their pair
// threshold, partner scale and x at a free vertex's rigid position, the vertex's rigid-pose
// penetration and the colliders' deepest penetrations.
void referenceCandidates(const DeformFrame& fr, std::uint32_t v, std::span<const Listed> list) {
  const ImplicitModel& m = *fr.model;
  const Calibration& cal = m.calibration;
  DeformState& st = *fr.st;
  DeformScratch& sc = *fr.sc;
  const auto vi = static_cast<std::size_t>(v);
  const glm::vec3 p = fr.in->rigid_positions[vi];
  const float margin = kCullMargin + std::abs(st.offset[vi]);
  int count = 0;
  bool overflow = false;
  float best_depth = 0.0f;
  float best_pressure = 0.0f;
  for (const Listed& l : list) {
    DeformScratch::Collider& col = *l.col;
    const PosedPrimitive& prim = *col.posed;
    // The own bone is never a collider of its vertices, except through an always-pair.
    if (l.same && !l.always_entry && cal.prims[vi][3] == static_cast<int>(col.prim)) continue;
    // Within the collider's cull distance (its box was listColliders' test).
    float scale = 1.0f;
    const glm::vec3 offset = skeletonOffset(prim.shape, p, scale);
    const float len = std::sqrt(offset.x * offset.x + offset.y * offset.y + offset.z * offset.z);
    const float d = len * scale;
    if (d > col.cull_distance) continue;
    // The pair's threshold, and whether an always-pair of another vertex listed it.
    float iso = m.primitives.iso;
    bool always = false;
    if (l.same) {
      for (std::uint32_t q = cal.pair_offsets[vi]; q < cal.pair_offsets[vi + 1]; ++q) {
        if (cal.pairs[q].prim == col.prim) {
          iso = cal.pairs[q].iso;
          always = always || (cal.pairs[q].flags & kPairAlways) != 0;
        }
      }
      if (l.always_entry && !always) continue;
    }
    // The partner field's scale (see findCandidates) and the largest x within the margin.
    const bool neighbour = l.same && (always || l.adjacent);
    const float omega = l.rigid ? 1.0f : (neighbour ? cal.w[vi] : skinWeight(prim, p));
    const float r_near = std::max(d - margin * col.inv_unit, 0.0f) * prim.inv_r_out;
    const float x_near = omega * prim.weight * densityValue(prim.density, r_near) - iso;
    if (!(x_near > l.lowest)) continue;
    if (count == kMaxCandidates) {
      overflow = true;
      continue;
    }
    DeformScratch::CandidateSlot& cs =
        sc.candidates[vi * kMaxCandidates + static_cast<std::size_t>(count)];
    cs.iso = iso;
    cs.reach = x_near;
    cs.omega = omega;
    cs.collider = l.c;
    if (cal.vertex_class[vi] == VertexClass::kFree) {
      cs.x_rigid = inBounds(prim, p) ? omega * primitiveField(prim, p) - iso : -INFINITY;
    }
    ++count;
    // Rigid-pose penetration into this collider: x over |grad x|.
    const float r = d * prim.inv_r_out;
    if (r >= 1.0f) continue;
    glm::vec3 grad;
    const float x = omega * primitiveField(prim, p, &grad) - iso;
    if (!(x > 0.0f)) continue;
    atomicMaxBits(col.pmax_bits, x);
    const float gn = omega * glm::length(grad);
    const float depth = gn > 0.0f ? x / gn : 0.0f;
    if (depth > best_depth && depth > kMinContactDepth) {
      best_depth = depth;
      best_pressure = contactPressure(ownStiffness(fr, static_cast<int>(v)), prim.stiffness, depth);
    }
  }
  sc.cand_count[vi] = static_cast<std::uint8_t>(count | (overflow ? 0x80 : 0));
  st.depth[vi] = best_depth;
  st.pressure[vi] = best_pressure;
}

}  // namespace

// Pass A over patches [first, last): each patch's box, its collider list, then its
// vertices' candidates, rigid-pose penetrations and the colliders' deepest penetrations.
void passPenetration(DeformFrame& fr, int first, int last) {
  DeformState& st = *fr.st;
  DeformScratch& sc = *fr.sc;
  const Calibration& cal = fr.model->calibration;
  const auto pos = fr.in->rigid_positions;
  std::uint16_t list[kMaxListed];
  // Locals: through the vectors, each byte store would make the compiler load the addresses
  // again.
  std::uint8_t* const cand_count = sc.cand_count.data();
  float* const depth = st.depth.data();
  float* const pressure = st.pressure.data();
  const auto clear = [=](std::size_t vi) {
    cand_count[vi] = 0;
    depth[vi] = 0.0f;
    pressure[vi] = 0.0f;
  };
  for (int q = first; q < last; ++q) {
    const std::uint32_t b = sc.patch_offsets[static_cast<std::size_t>(q)];
    const std::uint32_t e = sc.patch_offsets[static_cast<std::size_t>(q) + 1];
    const std::span<const std::int16_t> always(
        sc.patch_always.data() + sc.patch_always_offsets[static_cast<std::size_t>(q)],
        sc.patch_always_offsets[static_cast<std::size_t>(q) + 1] -
            sc.patch_always_offsets[static_cast<std::size_t>(q)]);
    const std::array<std::int16_t, 4> key = cal.prims[sc.order[b]];
    bool any = false;  // any collider for the patch at all (before the box is needed)
    for (std::size_t k = 0; k < 3 && !any; ++k) {
      const auto o = static_cast<std::size_t>(key[k]);
      any = key[k] >= 0 && sc.prim_collider_offsets[o + 1] > sc.prim_collider_offsets[o];
    }
    for (std::size_t k = 0; k < always.size() && !any; ++k)
      any = sc.always_collider[static_cast<std::size_t>(always[k])] >= 0;
    if (!any) {
      for (std::uint32_t i = b; i < e; ++i) clear(sc.order[i]);
      continue;
    }
    const Bounds box = patchBox(pos.data(), sc.order.data() + b, e - b);
    float offset_max = 0.0f;
    for (std::uint32_t i = b; i < e; ++i) {
      offset_max = std::max(offset_max, std::abs(st.offset[sc.order[i]]));
    }
    int n = listColliders(fr, {key[0], key[1], key[2], kNoPrimitive}, always, box, list);
    if (n > 0) {
      n = keepReachable(fr, box, offset_max, sc.patch_max_w[static_cast<std::size_t>(q)], list, n);
    }
    if (n == 0) {
      for (std::uint32_t i = b; i < e; ++i) clear(sc.order[i]);
      continue;
    }
    Listed described[kMaxListed];
    PatchPoints pts;
    const auto point = [&](int i, std::uint32_t v) {
      pts.vertex[i] = v;
      pts.x[i] = pos[v].x;
      pts.y[i] = pos[v].y;
      pts.z[i] = pos[v].z;
      pts.margin[i] = kCullMargin + std::abs(st.offset[v]);
      pts.w[i] = cal.w[v];
      pts.bone[i] = cal.prims[v][3];
    };
    if (n > 0) {
      describeList(fr, key, list, n, described);
      pts.count = static_cast<int>(e - b);
      for (std::uint32_t i = b; i < e; ++i) point(static_cast<int>(i - b), sc.order[i]);
      findCandidates(fr, pts, {described, static_cast<std::size_t>(n)});
      continue;
    }
    for (std::uint32_t i = b; i < e; ++i) {
      const std::uint32_t v = sc.order[i];
      // The patch's list overflowed: list the vertex's own.
      const int nv = listVertexColliders(fr, v, list);
      describeList(fr, cal.prims[v], list, nv, described);
      pts.count = 1;
      point(0, v);
      findCandidates(fr, pts, {described, static_cast<std::size_t>(nv)});
      if (nv == kMaxListed) sc.cand_count[v] |= 0x80;
    }
  }
}

void passPenetrationReference(DeformFrame& fr, int first, int last) {
  const Calibration& cal = fr.model->calibration;
  std::uint16_t list[kMaxListed];
  Listed described[kMaxListed];
  for (int vv = first; vv < last; ++vv) {
    const auto v = static_cast<std::uint32_t>(vv);
    const int n = listVertexColliders(fr, v, list);
    describeList(fr, cal.prims[v], list, n, described);
    referenceCandidates(fr, v, {described, static_cast<std::size_t>(n)});
    if (n == kMaxListed) fr.sc->cand_count[v] |= 0x80;
  }
}

}  // namespace vistel
