// Step 2 of the deformable component: per-vertex root-finding onto F = T with collision
// terms (Gascuel 1993, "An implicit formulation for precise contact modeling between
// flexible solids": penetration and propagation zones, the partner's field scaled by the
// vertex weight), relative deformability, elastic memory, and a tangential relaxation
// pass with final projection (Vaillant et al. 2013, "Implicit skinning").
#include "common/deform/deform.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <type_traits>

#include "common/deform/vertex_field.hpp"

namespace vistel {
namespace {

// A solved offset below this is snapped to zero (the vertex stays exactly rigid).
constexpr float kSnapOffset = 1e-7f;
// A vertex that moved less than this keeps the rigid normals around it (Step 3).
constexpr float kReshapeOffset = 1e-4f;
// A vertex at its solution is on the contact surface when its deepest partner term is
// within this of the penetration zone.
constexpr float kContactTolerance = 1e-5f;
// A rigid-pose penetration shallower than this (metres) is not a contact: it is below what
// float round-off in the pose can decide (a vertex grazing its partner's skin would be in
// contact in one frame of reference and not in another).
constexpr float kMinContactDepth = 1e-6f;
constexpr float kDefaultStiffness = 3.0e4f;
// A collider is a candidate for a vertex only when the rigid position lies within this
// margin of the collider's support box (a vertex outside the support has its root where
// the collider contributes nothing unless its own root is this far away).
constexpr float kCullMargin = 0.01f;
// A contact root along the projection line farther than this many times the vertex's
// rigid-pose penetration depth (and than kGrazeMinOffset) is re-solved along the contact
// surface's normal (see reprojectOnContact), unless the line already meets the surface
// within acos(kGrazeCos) of that normal.
constexpr float kGrazeFactor = 2.0f;
constexpr float kGrazeMinOffset = 1e-3f;
constexpr float kGrazeCos = 0.95f;
// Vertex patches: at most this many vertices each, and this many patches per pass A task.
constexpr std::uint32_t kPatchSize = 32;
constexpr int kPatchesPerTask = 16;

float shareOf(float k_self, float k_other) {  // 1 - lambda, lambda = k_self / (k_self + k_other)
  const bool rigid_self = std::isinf(k_self);
  const bool rigid_other = std::isinf(k_other);
  if (rigid_self && rigid_other) return 0.5f;
  if (rigid_self) return 0.0f;
  if (rigid_other) return 1.0f;
  return k_other / (k_self + k_other);
}

float effectiveStiffness(float k_self, float k_other) {  // springs in series
  const bool rigid_self = std::isinf(k_self);
  const bool rigid_other = std::isinf(k_other);
  if (rigid_self && rigid_other) return 1e9f;
  if (rigid_self) return k_other;
  if (rigid_other) return k_self;
  return k_self * k_other / (k_self + k_other);
}

struct Candidate {
  const PosedPrimitive* prim = nullptr;
  float omega =
      1.0f;  // partner field scale: its skin weight (see CandidateSlot::omega), 1 when rigid
  float iso = 0.5f;    // the pair's threshold
  float share = 0.5f;  // 1 - lambda: how much of the contact this vertex takes
  float rho = 1.0f;    // (1 - lambda) / lambda: weight of the penetration term (lambda > 0)
  bool hard = false;   // lambda = 0 (rigid partner, soft vertex): a constraint, see below
  float bulge = 0.0f;  // propagation amplitude (field units), 0 when off
  // A free vertex's omega F - iso at its rigid position (CandidateSlot::x_rigid).
  float x_rigid = -INFINITY;
  int collider = 0;
  int lane = -1;  // the vertex's own packed lane holding the same primitive, or -1 (the
                  // joint's opposite limb is both: its own field in DIFF and a collider)
};

// Everything the per-vertex function needs, gathered once per vertex.
struct VertexProblem {
  VertexClass cls = VertexClass::kLimb;
  const PosedPrimitive* own[4] = {nullptr, nullptr, nullptr, nullptr};  // p0, p1, p2, bone
  const FieldLanes* lanes = nullptr;  // own[0..3] packed (DeformState::own_lanes), or null
  float w = 1.0f;
  float slope = 0.0f;
  float iso = 0.5f;
  int diff_exponent = 4;
  glm::vec3 p0{0.0f};      // origin of the projection line (the rigid position)
  bool p0_rigid = false;   // a free vertex's p0, its rigid position (where the candidates'
                           // x_rigid hold)
  glm::vec3 n0{0.0f};      // rigid normal
  glm::vec3 anchor{0.0f};  // free vertices: their plane passes through this (rigid position)
  float width = 1.0f;
  int ncand = 0;
  bool overflow = false;  // more colliders than kMaxCandidates (the rest dropped)
  Candidate cand[kMaxCandidates];
  // Side results of the last evaluation (see ownExcess and evaluate).
  glm::vec3 smooth_gradient{0.0f};
  glm::vec3 last_point{NAN};  // where it was, and the gradient of g there
  glm::vec3 last_gradient{0.0f};
  float own_side = 0.0f;      // w_v (F_p0 + F_p1 + F_bone) at the last evaluation (see ownExcess)
  glm::vec3 hard_point{NAN};  // where deepestHard looked last, and what it found
  int hard_best = -1;
  float hard_x = 0.0f;
};

// ownExcess's sum for a limb or joint vertex, given field(k, grad) -> F of own[k] at p and
// its gradient.
template <typename Field>
inline float ownSum(VertexProblem& vp, glm::vec3& grad, Field&& field) {
  glm::vec3 g0;
  float d = field(0, g0);
  float own_side = d;
  glm::vec3 smooth = g0;
  if (vp.cls == VertexClass::kJoint) {
    glm::vec3 ga, gb, gd;
    const float fa = field(1, ga);
    const float fb = field(2, gb);
    d += diffField(fa, ga, fb, gb, vp.diff_exponent, &gd);
    g0 += gd;
    smooth += ga;
    own_side += fa;
  }
  if (vp.own[3] != nullptr) {
    glm::vec3 gbone;
    const float fbone = field(3, gbone);
    d += fbone;
    g0 += gbone;
    smooth += gbone;
    own_side += fbone;
  }
  grad = vp.w * g0;
  vp.smooth_gradient = vp.w * smooth;
  vp.own_side = vp.w * own_side;
  return vp.w * d - vp.iso;
}

// w_v D_v(P) - T (or the free vertex's planar excess) and its gradient; also the outward
// direction of the vertex's own side without the crease (DIFF's gradient is singular where
// the two limbs' fields are equal): vp.smooth_gradient = grad(F_p0 + F_p1 + F_bone) w_v, and
// vp.own_side = w_v (F_p0 + F_p1 + F_bone) (limb vertices: their own field; free vertices:
// the plane's gradient, no own_side). Not the larger of the two limbs: where the opposite limb's
// field is the larger it has come into the vertex's side, and its gradient points out of that limb,
// not out of the vertex's skin (a torso vertex under a lowered arm would follow the arm).
// `lanes` gets the own fields where they are packed (vp.lanes), and is left alone otherwise.
inline float ownExcess(VertexProblem& vp, const glm::vec3& p, glm::vec3& grad, FieldValues& lanes) {
  if (vp.cls == VertexClass::kFree) {
    grad = -vp.slope * vp.n0;
    vp.smooth_gradient = grad;
    return -vp.slope * glm::dot(p - vp.anchor, vp.n0);
  }
  // The own fields in one pass where they are packed (the same values), else one by one.
  if (vp.lanes != nullptr) {
    fieldLanes(*vp.lanes, p, lanes);
    return ownSum(vp, grad, [&lanes](int k, glm::vec3& g) {
      g = glm::vec3(lanes.gx[k], lanes.gy[k], lanes.gz[k]);
      return lanes.f[k];
    });
  }
  return ownSum(vp, grad,
                [&vp, &p](int k, glm::vec3& g) { return primitiveField(*vp.own[k], p, &g); });
}

// The soft part of Step 2's equation, g(P) = w_v D_v(P) - T + sum_i COLL_i with the
// penetration terms weighted by relative deformability:
//   g = (w_v D_v - T) + sum_i bulge_i h(s_i) - sum_{i soft} rho_i max(0, x_i),
// x_i = omega_i F_i(P) - iso_i, rho_i = (1 - lambda_i) / lambda_i, i.e. (for one partner)
// lambda (w_v D_v - T) = (1 - lambda) x: lambda = 1/2 is Gascuel's common surface. Rigid
// partners (lambda = 0) are not in g: they are hard constraints x_i <= 0 applied after.
inline float evaluateTerms(VertexProblem& vp, const glm::vec3& p, glm::vec3& grad) {
  FieldValues lanes;
  float g = ownExcess(vp, p, grad, lanes);
  for (int i = 0; i < vp.ncand; ++i) {
    const Candidate& c = vp.cand[i];
    // A hard partner without a bulge adds nothing to g (it is enforced after the solve).
    if ((c.hard && !(c.bulge > 0.0f)) || !inBounds(*c.prim, p)) continue;
    // A partner that is one of the vertex's own packed fields is already evaluated (the
    // same bits as primitiveField, see field_lanes.hpp).
    glm::vec3 gf;
    float f;
    if (c.lane >= 0) {
      const auto k = static_cast<std::size_t>(c.lane);
      f = lanes.f[k];
      gf = glm::vec3(lanes.gx[k], lanes.gy[k], lanes.gz[k]);
    } else {
      f = primitiveField(*c.prim, p, &gf);
    }
    const float x = c.omega * f - c.iso;
    if (x > 0.0f) {
      if (!c.hard) {
        g -= c.rho * x;
        grad -= (c.rho * c.omega) * gf;
      }
    } else if (c.bulge > 0.0f && x > -vp.width) {
      float dterm = 0.0f;
      g += collisionTerm(x, c.bulge, vp.width, &dterm);
      grad += (dterm * c.omega) * gf;
    }
  }
  return g;
}

// The same, remembering the point and the gradient (see gradientNear).
inline float evaluate(VertexProblem& vp, const glm::vec3& p, glm::vec3& grad) {
  const float g = evaluateTerms(vp, p, grad);
  vp.last_point = p;
  vp.last_gradient = grad;
  return g;
}

// The gradient of g near p for the relaxation's tangent plane: the last evaluation's when it
// was within `within` of p (a final Newton step, see RootOptions::final_step), else NaN.
inline glm::vec3 gradientNear(const VertexProblem& vp, const glm::vec3& p, float within) {
  const glm::vec3 d = vp.last_point - p;
  return glm::dot(d, d) <= within * within ? vp.last_gradient : glm::vec3(NAN);
}

// Deepest hard-constraint violation at p: the rigid partner with the largest x, or -1
// (remembered in vp, see deepestPartner).
inline int deepestHard(VertexProblem& vp, const glm::vec3& p, float& x_out) {
  int best = -1;
  x_out = -INFINITY;
  // At a free vertex's rigid position pass A has evaluated them (the same bits; -infinity
  // outside their boxes).
  const bool at_rigid = vp.p0_rigid && p == vp.p0;
  for (int i = 0; i < vp.ncand; ++i) {
    const Candidate& c = vp.cand[i];
    if (!c.hard) continue;
    float x = c.x_rigid;
    if (!at_rigid) {
      if (!inBounds(*c.prim, p)) continue;
      x = c.omega * primitiveField(*c.prim, p) - c.iso;
    }
    if (x > x_out) {
      x_out = x;
      best = i;
    }
  }
  vp.hard_point = p;
  vp.hard_best = best;
  vp.hard_x = x_out;
  return best;
}

float atomicMaxBits(std::uint32_t& target, float value) {
  // Non-negative floats order like their bit patterns.
  std::atomic_ref<std::uint32_t> ref(target);
  const std::uint32_t bits = std::bit_cast<std::uint32_t>(value);
  std::uint32_t cur = ref.load(std::memory_order_relaxed);
  while (cur < bits && !ref.compare_exchange_weak(cur, bits, std::memory_order_relaxed)) {
  }
  return value;
}

struct Frame {
  const ImplicitModel* model = nullptr;
  std::span<const BodyView> bodies;
  int self = 0;
  const DeformInput* in = nullptr;
  DeformState* st = nullptr;
  const DeformOptions* opt = nullptr;
  const PosedPrimitives* posed = nullptr;
  float dt = 0.0f;
  int nvert = 0;
  int chunk = 512;
};

float ownStiffness(const Frame& fr, int v) {
  const std::int16_t p0 = fr.model->calibration.prims[static_cast<std::size_t>(v)][0];
  return p0 >= 0 ? fr.model->primitives.items[static_cast<std::size_t>(p0)].stiffness
                 : kDefaultStiffness;
}

// Fills vp's own part for vertex v (no candidates).
void gatherOwn(const Frame& fr, int v, VertexProblem& vp) {
  const ImplicitModel& m = *fr.model;
  const Calibration& cal = m.calibration;
  const auto vi = static_cast<std::size_t>(v);
  const auto& pr = cal.prims[vi];
  vp.cls = cal.vertex_class[vi];
  for (std::size_t k = 0; k < 4; ++k) {
    vp.own[k] = pr[k] >= 0 ? &fr.posed->items[static_cast<std::size_t>(pr[k])] : nullptr;
  }
  const std::int16_t set = fr.st->lane_set[vi];
  vp.lanes = set >= 0 && fr.st->lane_set_packed[static_cast<std::size_t>(set)] != 0
                 ? &fr.st->own_lanes[static_cast<std::size_t>(set)]
                 : nullptr;
  vp.w = cal.w[vi];
  vp.slope = cal.slope[vi];
  vp.iso = m.primitives.iso;
  vp.diff_exponent = m.primitives.diff_exponent;
  vp.p0 = fr.in->rigid_positions[vi];
  vp.p0_rigid = vp.cls == VertexClass::kFree;
  vp.n0 = fr.in->rigid_normals[vi];
  vp.anchor = vp.p0;
  vp.width = m.primitives.propagation_width;
  vp.ncand = 0;
  vp.overflow = false;
  vp.last_point = glm::vec3(NAN);
  vp.hard_point = glm::vec3(NAN);
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
int listColliders(const Frame& fr, const std::array<std::int16_t, 4>& key,
                  std::span<const std::int16_t> always, const Bounds& box,
                  std::uint16_t (&out)[kMaxListed]) {
  const DeformState& st = *fr.st;
  int n = 0;
  const auto overlaps = [&box](const DeformState::Collider& col) {
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
    for (std::uint32_t j = st.prim_collider_offsets[ou]; j < st.prim_collider_offsets[ou + 1];
         ++j) {
      const int c = st.prim_colliders[j];
      const DeformState::Collider& col = st.colliders[static_cast<std::size_t>(c)];
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
    const std::int32_t c = st.always_collider[static_cast<std::size_t>(prim)];
    if (c < 0 || !overlaps(st.colliders[static_cast<std::size_t>(c)]) || listed(c)) continue;
    if (n == kMaxListed) return -1;
    out[n++] = static_cast<std::uint16_t>(c | kAlwaysEntry);
  }
  return n;
}

// The lowest x = omega F_i - iso at which collider col's term can be non-zero: -width where
// it may bulge (another body, propagation on), else the contact tolerance below 0.
float lowestTerm(const Frame& fr, const DeformState::Collider& col) {
  const bool bulges = fr.opt->propagation && (col.body != fr.self || fr.opt->self_propagation);
  return bulges ? -fr.model->primitives.propagation_width : -kContactTolerance;
}

// A collider list entry with what does not depend on the vertex (for vertices whose
// defining primitives are the key the list was made for).
// (No initialisers: a patch makes room for kMaxListed of them, and describeList fills each
// one it uses.)
struct Listed {
  DeformState::Collider* col;
  std::uint16_t c;    // collider index
  bool always_entry;  // from an always-pair (see kAlwaysEntry)
  bool same;          // the vertex's own body
  bool adjacent;      // own body, joined to a key primitive in the graph
  bool rigid;         // infinite stiffness
  float lowest;       // lowestTerm
};

// Describes `n` entries of a collider list for vertices with defining primitives key[0..2].
void describeList(const Frame& fr, const std::array<std::int16_t, 4>& key,
                  const std::uint16_t* entries, int n, Listed* out) {
  DeformState& st = *fr.st;
  const CombinationGraph& graph = fr.model->graph;
  for (int i = 0; i < n; ++i) {
    Listed& l = out[i];
    l.c = static_cast<std::uint16_t>(entries[i] & ~kAlwaysEntry);
    l.always_entry = (entries[i] & kAlwaysEntry) != 0;
    l.col = &st.colliders[l.c];
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
  const DeformState::Collider& col = *l.col;
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
void findCandidates(const Frame& fr, const PatchPoints& pts, std::span<const Listed> list) {
  const ImplicitModel& m = *fr.model;
  const Calibration& cal = m.calibration;
  DeformState& st = *fr.st;
  int count[kPatchSize] = {};
  bool overflow[kPatchSize] = {};
  float best_depth[kPatchSize] = {};
  float best_pressure[kPatchSize] = {};
  PatchOffsets off;
  for (const Listed& l : list) {
    const int c = l.c;
    DeformState::Collider& col = *l.col;
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
      DeformState::CandidateSlot& cs = st.candidates[slot];
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
        best_pressure[i] =
            effectiveStiffness(ownStiffness(fr, static_cast<int>(v)), k_other) * depth;
      }
    }
  }
  for (int i = 0; i < pts.count; ++i) {
    const std::uint32_t v = pts.vertex[i];
    st.cand_count[v] = static_cast<std::uint8_t>(count[i] | (overflow[i] ? 0x80 : 0));
    st.depth[v] = best_depth[i];
    st.pressure[v] = best_pressure[i];
  }
}

// Loads vertex v's cached candidates into vp with their material terms. with_bulge: use
// this frame's deepest penetrations (after pass A).
void loadCandidates(const Frame& fr, int v, bool with_bulge, VertexProblem& vp) {
  const DeformState& st = *fr.st;
  const auto vi = static_cast<std::size_t>(v);
  const int n = st.cand_count[vi] & 0x7F;
  vp.overflow = (st.cand_count[vi] & 0x80) != 0;
  vp.ncand = n;
  if (n == 0) return;
  const float k_self = ownStiffness(fr, v);
  const float amplitude = fr.opt->propagation ? fr.model->primitives.propagation_amplitude : 0.0f;
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    const std::size_t slot = vi * kMaxCandidates + static_cast<std::size_t>(i);
    const DeformState::CandidateSlot& cs = st.candidates[slot];
    const int c = cs.collider;
    const DeformState::Collider& col = st.colliders[static_cast<std::size_t>(c)];
    Candidate& cd = vp.cand[kept];
    cd.prim = col.posed;
    cd.collider = c;
    cd.lane = -1;
    for (int k = 0; k < 4 && vp.lanes != nullptr; ++k) {
      if (vp.own[k] == cd.prim) cd.lane = k;
    }
    const float k_other = col.posed->stiffness;
    cd.share = shareOf(k_self, k_other);
    // A free vertex has no field for the partner to meet: it takes the whole contact.
    cd.hard = cd.share == 1.0f || (vp.cls == VertexClass::kFree && cd.share > 0.0f);
    cd.rho = cd.hard ? 0.0f : cd.share / (1.0f - cd.share);
    cd.omega = cs.omega;
    cd.iso = cs.iso;
    cd.x_rigid = cs.x_rigid;
    const float pmax = std::bit_cast<float>(col.pmax_bits);
    const bool bulges = with_bulge && (col.body != fr.self || fr.opt->self_propagation);
    cd.bulge = bulges ? 2.0f * cd.share * vp.w * amplitude * pmax : 0.0f;
    // Without a bulge only penetration and contact count: a candidate that stays outside
    // the partner's surface near the vertex contributes nothing.
    if (cd.bulge > 0.0f || cs.reach >= -kContactTolerance) ++kept;
  }
  vp.ncand = kept;
}

// Own part and cached candidates of vertex v.
void gatherProblem(const Frame& fr, int v, bool with_bulge, VertexProblem& vp) {
  gatherOwn(fr, v, vp);
  loadCandidates(fr, v, with_bulge, vp);
}

// A relaxed vertex's problem as pass B gathered it, kept for the relaxation passes (which
// would gather the same again, twice): slot `slot` of DeformState::relax_problems, its
// candidates up to `ncand` (the side results after them are rewritten by every evaluation).
static_assert(std::is_trivially_copyable_v<VertexProblem>);
constexpr std::size_t kKeptProblemBytes = sizeof(VertexProblem);
void keepProblem(DeformState& st, std::size_t slot, const VertexProblem& vp, int ncand) {
  std::byte* const out = st.relax_problems.data() + slot * kKeptProblemBytes;
  const std::size_t bytes =
      offsetof(VertexProblem, cand) + static_cast<std::size_t>(ncand) * sizeof(Candidate);
  std::memcpy(out, &vp, bytes);
  std::memcpy(out + offsetof(VertexProblem, ncand), &ncand, sizeof ncand);
}
void keptProblem(const DeformState& st, std::size_t slot, VertexProblem& vp) {
  const std::byte* const in = st.relax_problems.data() + slot * kKeptProblemBytes;
  int ncand = 0;
  std::memcpy(&ncand, in + offsetof(VertexProblem, ncand), sizeof ncand);
  std::memcpy(&vp, in,
              offsetof(VertexProblem, cand) + static_cast<std::size_t>(ncand) * sizeof(Candidate));
  vp.last_point = glm::vec3(NAN);
  vp.hard_point = glm::vec3(NAN);
}

// Drops from a patch's collider list the colliders that cannot matter to any of its
// vertices: where x = omega F_i - iso stays at or below lowestTerm everywhere within the cull
// margin (grown by the patch's largest warm-start offset) of the patch's box, bounded with the
// largest omega a vertex of the patch can give the collider (w_max: the patch's largest
// calibration weight) and the set's iso (no pair's threshold is lower). Returns the new count.
int keepReachable(const Frame& fr, const Bounds& box, float offset_max, float w_max,
                  std::uint16_t (&list)[kMaxListed], int n) {
  const DeformState& st = *fr.st;
  const glm::vec3 centre = 0.5f * (box.min + box.max);
  const float radius = 0.5f * glm::length(box.max - box.min) + kCullMargin + offset_max;
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    const DeformState::Collider& col = st.colliders[list[i] & ~kAlwaysEntry];
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

// Pass A over patches [first, last): each patch's box, its collider list, then its
// vertices' candidates, rigid-pose penetrations and the colliders' deepest penetrations.
void passPenetration(Frame& fr, int first, int last) {
  DeformState& st = *fr.st;
  const Calibration& cal = fr.model->calibration;
  const auto pos = fr.in->rigid_positions;
  std::uint16_t list[kMaxListed];
  // Locals: through the vectors, each byte store would make the compiler load the addresses
  // again.
  std::uint8_t* const cand_count = st.cand_count.data();
  float* const depth = st.depth.data();
  float* const pressure = st.pressure.data();
  const auto clear = [=](std::size_t vi) {
    cand_count[vi] = 0;
    depth[vi] = 0.0f;
    pressure[vi] = 0.0f;
  };
  for (int q = first; q < last; ++q) {
    const std::uint32_t b = st.patch_offsets[static_cast<std::size_t>(q)];
    const std::uint32_t e = st.patch_offsets[static_cast<std::size_t>(q) + 1];
    const std::span<const std::int16_t> always(
        st.patch_always.data() + st.patch_always_offsets[static_cast<std::size_t>(q)],
        st.patch_always_offsets[static_cast<std::size_t>(q) + 1] -
            st.patch_always_offsets[static_cast<std::size_t>(q)]);
    const std::array<std::int16_t, 4> key = cal.prims[st.order[b]];
    bool any = false;  // any collider for the patch at all (before the box is needed)
    for (std::size_t k = 0; k < 3 && !any; ++k) {
      const auto o = static_cast<std::size_t>(key[k]);
      any = key[k] >= 0 && st.prim_collider_offsets[o + 1] > st.prim_collider_offsets[o];
    }
    for (std::size_t k = 0; k < always.size() && !any; ++k)
      any = st.always_collider[static_cast<std::size_t>(always[k])] >= 0;
    if (!any) {
      for (std::uint32_t i = b; i < e; ++i) clear(st.order[i]);
      continue;
    }
    const Bounds box = patchBox(pos.data(), st.order.data() + b, e - b);
    float offset_max = 0.0f;
    for (std::uint32_t i = b; i < e; ++i) {
      offset_max = std::max(offset_max, std::abs(st.offset[st.order[i]]));
    }
    int n = listColliders(fr, {key[0], key[1], key[2], kNoPrimitive}, always, box, list);
    if (n > 0) {
      n = keepReachable(fr, box, offset_max, st.patch_max_w[static_cast<std::size_t>(q)], list, n);
    }
    if (n == 0) {
      for (std::uint32_t i = b; i < e; ++i) clear(st.order[i]);
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
      for (std::uint32_t i = b; i < e; ++i) point(static_cast<int>(i - b), st.order[i]);
      findCandidates(fr, pts, {described, static_cast<std::size_t>(n)});
      continue;
    }
    for (std::uint32_t i = b; i < e; ++i) {
      const std::uint32_t v = st.order[i];
      // The patch's list overflowed: list the vertex's own.
      const auto& pr = cal.prims[v];
      std::int16_t own_always[kMaxListed];
      std::size_t na = 0;
      for (std::uint32_t k = cal.pair_offsets[v]; k < cal.pair_offsets[v + 1] && na < kMaxListed;
           ++k) {
        if ((cal.pairs[k].flags & kPairAlways) != 0) own_always[na++] = cal.pairs[k].prim;
      }
      int nv = listColliders(fr, {pr[0], pr[1], pr[2], pr[3]}, {own_always, na},
                             Bounds{pos[v], pos[v]}, list);
      if (nv < 0) nv = kMaxListed;  // more near one vertex than a list holds: the first ones
      describeList(fr, pr, list, nv, described);
      pts.count = 1;
      point(0, v);
      findCandidates(fr, pts, {described, static_cast<std::size_t>(nv)});
      if (nv == kMaxListed) st.cand_count[v] |= 0x80;
    }
  }
}

Elasticity vertexElasticity(const Frame& fr, int v) {
  const std::int16_t p0 = fr.model->calibration.prims[static_cast<std::size_t>(v)][0];
  return p0 >= 0 ? fr.model->primitives.items[static_cast<std::size_t>(p0)].elasticity
                 : Elasticity::kElastic;
}

float searchReach(float own_reach) { return std::max(own_reach, 0.02f); }
float searchReach(const VertexProblem& vp) {
  return searchReach(vp.own[0] != nullptr ? vp.own[0]->reach : 0.05f);
}

// Marks vertex v and its one-ring as needing new normals (other chunks may mark the same
// vertices: relaxed atomic stores of the same value, so the result does not depend on order).
inline void markReshaped(const Frame& fr, int v) {
  const Calibration& cal = fr.model->calibration;
  DeformState& st = *fr.st;
  const auto vi = static_cast<std::size_t>(v);
  std::uint8_t* const dirty = st.dirty.data();  // a local: see passSolve
  const std::uint32_t* const ring = cal.ring.data();
  const std::uint32_t end = cal.ring_offsets[vi + 1];
  std::atomic_ref<std::uint8_t>(dirty[vi]).store(1, std::memory_order_relaxed);
  for (std::uint32_t k = cal.ring_offsets[vi]; k < end; ++k) {
    std::atomic_ref<std::uint8_t>(dirty[ring[k]]).store(1, std::memory_order_relaxed);
  }
}

// Deepest partner term at p over all candidates (x and index, -1 when none).
inline int deepestPartner(const VertexProblem& vp, const glm::vec3& p, float& x_out) {
  // Where every candidate is hard (a free vertex's) and deepestHard last looked at p, its
  // answer stands for the contact test: the same largest x among the candidates in their
  // boxes (the others have -iso, below any contact).
  if (p == vp.hard_point &&
      std::all_of(vp.cand, vp.cand + vp.ncand, [](const Candidate& c) { return c.hard; })) {
    x_out = vp.hard_x;
    return vp.hard_best;
  }
  int best = -1;
  x_out = -INFINITY;
  for (int i = 0; i < vp.ncand; ++i) {
    const Candidate& c = vp.cand[i];
    const float x = inBounds(*c.prim, p) ? c.omega * primitiveField(*c.prim, p) - c.iso : -c.iso;
    if (x > x_out) {
      x_out = x;
      best = i;
    }
  }
  return best;
}

// Whether a joint vertex's root p is still on its own side: there w_v (F_p0 + F_p1 +
// F_bone), its own side without the opposite limb, keeps at least DeformOptions::
// joint_own_side of `from`, its value where the projection started (or of T, when that was
// more). Beyond its own side DIFF(F_p1, F_p2) is the opposite limb's field alone, so
// w_v D_v = T is the opposite limb's surface, and with the opposite-limb contact term the
// equation degenerates (g = w_v F_p0 + iso_pair - T, about 0, over the whole of the opposite
// limb's field): a root there is not the vertex's. Uses the last evaluation when it was
// within a final Newton step of p.
inline bool ownSideHolds(const VertexProblem& vp, float from, const glm::vec3& p,
                         const DeformOptions& opt) {
  if (vp.cls != VertexClass::kJoint || opt.joint_own_side <= 0.0f) return true;
  const glm::vec3 d = vp.last_point - p;
  float at_p = vp.own_side;
  if (!(glm::dot(d, d) <= opt.root.final_step * opt.root.final_step)) {
    at_p = primitiveField(*vp.own[0], p) + primitiveField(*vp.own[1], p);
    if (vp.own[3] != nullptr) at_p += primitiveField(*vp.own[3], p);
    at_p *= vp.w;
  }
  return at_p >= opt.joint_own_side * std::min(from, vp.iso);
}

// The skeleton distance at which hard partner c's term is zero (omega F = iso), where its
// profile inverts in closed form (see densityInverseSquared).
bool hardSurfaceDistance(const Candidate& c, float& rho) {
  const PosedPrimitive& prim = *c.prim;
  const float scale = c.omega * prim.weight;
  double u = 0.0;
  if (!(scale > 0.0f) || !densityInverseSquared(prim.density, c.iso / scale, u)) return false;
  rho = static_cast<float>(std::sqrt(u)) / prim.inv_r_out;
  return rho > 0.0f && std::isfinite(rho);
}

// A hard line search's result in closed form: going down from s_start, where the line
// p + s dir is inside the partner (skeleton distance below rho), it leaves the partner at the
// lower end of the interval lineInsideInterval gives; found when that lies within s_max, as
// findRoot's search is bounded. Returns false where that interval does not hold s_start
// (closed form and field disagree beyond rounding): the caller searches instead.
bool lineExit(const PosedPrimitive& prim, float rho, const glm::vec3& p, const glm::vec3& dir,
              float s_start, float s_max, RootResult& out) {
  constexpr float kSlack = 1e-5f;  // metres
  float t_in = 0.0f;
  float t_out = 0.0f;
  if (!lineInsideInterval(prim.shape, rho, p, dir, t_in, t_out) ||
      !(t_in <= s_start + kSlack && t_out >= s_start - kSlack)) {
    return false;
  }
  out = RootResult{};
  out.s = std::min(t_in, s_start);
  out.found = out.s >= -s_max;
  return true;
}

// Solves the soft equation along dir from s_start (first evaluation g, grad given), then
// enforces the hard constraints (rigid partners: the vertex ends on their surface). A hard
// partner's surface along a line is found in closed form where its shape and profile allow
// (hardSurfaceDistance, lineExit), else by a line search.
RootResult solveVertex(VertexProblem& vp, glm::vec3& dir, float s_start, float g,
                       const glm::vec3& grad, float reach, const RootOptions& ropt,
                       DeformCounters& cnt, bool& iterated) {
  const glm::vec3 p0 = vp.p0;
  RootResult res;
  res.s = s_start;
  const float dg0 = glm::dot(grad, dir);
  res.found = std::abs(g) < ropt.tolerance || std::abs(g) < ropt.step_tolerance * std::abs(dg0);
  if (!res.found) {
    auto eval = [&](float s, float* dg) {
      glm::vec3 gr;
      const float val = evaluate(vp, p0 + s * dir, gr);
      *dg = glm::dot(gr, dir);
      return val;
    };
    res = findRoot(eval, s_start, g, dg0, reach, ropt);
    cnt.evaluations += res.iterations;
    const int steps = res.iterations + (res.final_newton ? 1 : 0);
    cnt.iterations += steps;
    if (steps > 0) iterated = true;
  }
  // Rigid partners: a vertex inside one retreats onto its surface (x = 0).
  for (int round = 0; round < 2 && res.found; ++round) {
    float x = 0.0f;
    const int h = deepestHard(vp, p0 + res.s * dir, x);
    if (h < 0 || x <= ropt.tolerance) break;
    iterated = true;
    const Candidate& c = vp.cand[h];
    auto eval_hard = [&](float s, float* dg) {
      glm::vec3 gf;
      const float f = primitiveField(*c.prim, p0 + s * dir, &gf);
      *dg = -c.omega * glm::dot(gf, dir);
      return c.iso - c.omega * f;
    };
    // The partner's field at the soft root, once: the line search's start, and its gradient
    // for the way out below.
    const glm::vec3 p1 = p0 + res.s * dir;
    glm::vec3 inward;
    const float g1 = c.iso - c.omega * primitiveField(*c.prim, p1, &inward);
    // The partner's surface along the line in closed form where its shape and profile allow
    // (the result of the search below up to its tolerance), else by that search.
    float rho = 0.0f;
    const bool closed = hardSurfaceDistance(c, rho);
    RootResult rh;
    if (closed && lineExit(*c.prim, rho, p0, dir, res.s, reach, rh)) {
      cnt.evaluations += 2;
      cnt.iterations += 1;
    } else {
      rh = findRoot(eval_hard, res.s, g1, -c.omega * glm::dot(inward, dir), reach, ropt);
      cnt.evaluations += 1 + rh.iterations;
      cnt.iterations += 1 + rh.iterations;
    }
    // The shortest way out of the partner is along its gradient: about x / |grad(omega F)|.
    const float len = glm::length(inward);
    const float exit = len > 0.0f ? x / (c.omega * len) : INFINITY;
    if (rh.found && std::abs(rh.s - res.s) <= std::max(kGrazeMinOffset, kGrazeFactor * exit)) {
      res.s = rh.s;
      continue;
    }
    // Along the line the vertex leaves the partner only far away, or never (a fingertip
    // beside a face): it leaves along the partner's gradient from where the soft solve put
    // it instead (when that is nearer), and the line becomes the one from its rigid
    // position to there.
    bool escaped = false;
    if (len > 0.0f) {
      const glm::vec3 out = inward / len;
      auto eval_out = [&](float s, float* dg) {
        glm::vec3 gf;
        const float f = primitiveField(*c.prim, p1 + s * out, &gf);
        *dg = -c.omega * glm::dot(gf, out);
        return c.iso - c.omega * f;
      };
      // Within the partner's support: however deep the vertex, its way out is that short.
      // It starts where the line search did (g1 at p1).
      const float out_max = std::max(reach, c.prim->reach);
      RootResult ro;
      if (closed && lineExit(*c.prim, rho, p1, out, 0.0f, out_max, ro)) {
        cnt.evaluations += 1;
        cnt.iterations += 1;
      } else {
        ro = findRoot(eval_out, 0.0f, g1, -c.omega * glm::dot(inward, out), out_max, ropt);
        cnt.evaluations += ro.iterations;
        cnt.iterations += ro.iterations;
      }
      if (ro.found && (!rh.found || std::abs(ro.s) < std::abs(rh.s - res.s))) {
        const glm::vec3 moved = p1 + ro.s * out - p0;
        const float dist = glm::length(moved);
        res.s = dist;
        if (dist > 0.0f) dir = moved / dist;
        escaped = true;
      }
    }
    if (!escaped) {
      res.found = rh.found;
      if (!rh.found) break;
      res.s = rh.s;
    }
  }
  return res;
}

// Re-solves a contact vertex from its rigid position along the outward normal of the
// contact surface at the root `res` found along `dir`, and keeps the nearer of the two
// roots (replacing res and dir; returns whether it did). Along the rest normal carried by
// the skinning, a vertex whose own field is weak where it sits (far outside its
// primitive's fitted surface, w_v >> 1: the inner elbow of a real avatar, whose crease
// skin is weighted to the forearm) may meet the common surface w_v D_v = w_v F_i only at a
// grazing angle, or only deep inside, near both skeletons, centimetres from where it
// started; the contact normal leads to the nearby part of the same surface.
bool reprojectOnContact(VertexProblem& vp, float reach, const RootOptions& ropt,
                        DeformCounters& cnt, bool& iterated, glm::vec3& dir, RootResult& res) {
  glm::vec3 grad_root;
  evaluate(vp, vp.p0 + res.s * dir, grad_root);
  ++cnt.evaluations;
  const float len = glm::length(grad_root);
  if (!(len > 0.0f)) return false;
  glm::vec3 m = -grad_root / len;
  if (glm::dot(m, dir) >= kGrazeCos) return false;
  glm::vec3 grad0;
  const float g0 = evaluate(vp, vp.p0, grad0);
  ++cnt.evaluations;
  const RootResult rm = solveVertex(vp, m, 0.0f, g0, grad0, reach, ropt, cnt, iterated);
  if (!rm.found || !(std::abs(rm.s) < std::abs(res.s))) return false;
  res = rm;
  dir = m;
  return true;
}

// Writes vertex v's solution s_sol along dir from p0, placed at s_out (its elastic memory
// applied): the offset, the position (s_out snapped to 0 below kSnapOffset), the moved,
// reshaped and contact flags (marking the ring for new normals), the contact partner (a
// body, or -1 when not touching; a vertex held off its contact by memory is not touching)
// and max_offset. Returns the snapped s_out.
inline float writeSolved(const Frame& fr, int v, const glm::vec3& p0, const glm::vec3& dir,
                         float s_sol, float s_out, std::uint8_t flags, int partner,
                         DeformCounters& cnt) {
  DeformState& st = *fr.st;
  const auto vi = static_cast<std::size_t>(v);
  if (std::abs(s_out) < kSnapOffset) s_out = 0.0f;
  st.offset[vi] = s_sol;
  st.positions[vi] = p0 + s_out * dir;
  if (s_out != 0.0f) flags |= kVertexMoved;
  if (std::abs(s_out) > kReshapeOffset) {
    flags |= kVertexReshaped;
    markReshaped(fr, v);
  }
  if (partner >= 0 && s_out == s_sol) {
    flags |= kVertexContact;
    ++cnt.contact_vertices;
    st.contact_body[vi] = static_cast<std::int16_t>(partner);
  } else {
    st.contact_body[vi] = -1;
  }
  st.flags[vi] = flags;
  cnt.max_offset = std::max(cnt.max_offset, std::abs(s_out));
  return s_out;
}

// How far vertex v may end from its skinned position (DeformOptions::move_margin): its drift
// from where each of its own primitives' bones alone would carry its rest position (its
// own field, calibrated at rest, moves with those bones, so it can ask for no more), its
// rigid-pose penetration and the bulge this frame allows, plus the margin. Infinite when
// moves are not bounded.
float moveAllowance(const Frame& fr, std::size_t vi) {
  const DeformOptions& opt = *fr.opt;
  if (opt.move_margin < 0.0f || fr.in->rest_positions.empty()) return INFINITY;
  const glm::vec4 rest(fr.in->rest_positions[vi], 1.0f);
  const glm::vec3 p = fr.in->rigid_positions[vi];
  float drift = 0.0f;
  for (const std::int16_t prim : fr.model->calibration.prims[vi]) {
    if (prim < 0) continue;
    const glm::vec3 carried(fr.st->prim_to_world[static_cast<std::size_t>(prim)] * rest);
    drift = std::max(drift, glm::length(p - carried));
  }
  return drift + fr.st->depth[vi] + fr.st->bulge_allowance + opt.move_margin;
}

// Pass B's short way for the commonest solved vertex, the lone limb vertex: a limb vertex of
// one primitive (no bone), not fixed (DeformState::fixed_kind), that has no collider and no
// elastic memory this frame and is projected along its normal, as it was last frame (see
// solveLoneLimb). Its part that never changes (DeformState::lone_kind); passSolve tests the
// rest.
bool loneKind(const Calibration& cal, std::size_t vi, bool fixed) {
  const auto& pr = cal.prims[vi];
  return !fixed && cal.vertex_class[vi] == VertexClass::kLimb && pr[3] < 0 && pr[0] >= 0;
}

// A lone limb vertex's equation w_v F_p0(p) - T, and its gradient.
inline float loneEquation(const PosedPrimitive& prim, float w, float iso, const glm::vec3& p,
                          glm::vec3& grad) {
  glm::vec3 g0;
  const float d = primitiveField(prim, p, &g0);
  grad = w * g0;
  return w * d - iso;
}

// The equation at a lone limb vertex's warm start: the first evaluation of its solve.
struct LoneStart {
  float g;
  glm::vec3 grad;
};
LoneStart loneStart(const Frame& fr, std::size_t vi) {
  const Calibration& cal = fr.model->calibration;
  LoneStart start;
  start.g = loneEquation(fr.posed->items[static_cast<std::size_t>(cal.prims[vi][0])], cal.w[vi],
                         fr.model->primitives.iso,
                         fr.in->rigid_positions[vi] + fr.st->offset[vi] * fr.in->rigid_normals[vi],
                         start.grad);
  return start;
}

// Solves a lone limb vertex (see loneKind) from its first evaluation `start` (loneStart): its
// equation is w_v F_p0 - T alone, so it skips gathering a problem. Returns false, having
// changed nothing, where the full way is needed (the normal disagrees with the field's
// gradient, or finds no root); otherwise the result is the full way's, bit for bit.
bool solveLoneLimb(const Frame& fr, int v, const LoneStart& start, DeformCounters& cnt) {
  const DeformState& st = *fr.st;
  const Calibration& cal = fr.model->calibration;
  const DeformOptions& opt = *fr.opt;
  const auto vi = static_cast<std::size_t>(v);
  const auto& pr = cal.prims[vi];
  const PosedPrimitive& prim = fr.posed->items[static_cast<std::size_t>(pr[0])];
  const float w = cal.w[vi];
  const float iso = fr.model->primitives.iso;
  const glm::vec3 p0 = fr.in->rigid_positions[vi];
  const glm::vec3 dir = fr.in->rigid_normals[vi];
  const float s_start = st.offset[vi];
  const glm::vec3 grad = start.grad;
  const float g = start.g;
  const bool at_root = std::abs(g) < opt.root.tolerance;
  const float gn = at_root ? 0.0f : glm::length(grad);
  if (!at_root && gn > 0.0f && -glm::dot(dir, grad) / gn < opt.gradient_switch_cos) return false;
  const float dg0 = glm::dot(grad, dir);
  RootResult res;
  res.s = s_start;
  res.found = at_root || std::abs(g) < opt.root.step_tolerance * std::abs(dg0);
  if (!res.found) {
    const auto eval_line = [&](float s, float* dg) {
      glm::vec3 gr;
      const float val = loneEquation(prim, w, iso, p0 + s * dir, gr);
      *dg = glm::dot(gr, dir);
      return val;
    };
    res = findRoot(eval_line, s_start, g, dg0, searchReach(prim.reach), opt.root);
    if (!res.found && gn > 0.0f) return false;
  }
  const int steps = res.iterations + (res.final_newton ? 1 : 0);
  cnt.evaluations += 1 + res.iterations;
  cnt.iterations += steps;
  if (steps > 0) ++cnt.iterating_vertices;
  std::uint8_t flags = 0;
  float s_sol = 0.0f;
  if (res.found && std::abs(res.s) > moveAllowance(fr, vi)) {
    flags |= kVertexHeld;  // a root beyond what its own field can ask: see moveAllowance
    ++cnt.held_vertices;
  } else if (res.found) {
    s_sol = res.s;
  } else {
    flags |= kVertexUnsolved;
    ++cnt.unsolved_vertices;
  }
  // An inelastic body's free offset is its solution when nothing touches it (its memory
  // stays 0, see passSolve).
  if (vertexElasticity(fr, v) != Elasticity::kElastic) fr.st->free_offset[vi] = s_sol;
  writeSolved(fr, v, p0, dir, s_sol, s_sol, flags, -1, cnt);
  return true;
}

// Pass B: solve every vertex of [first, last).
void passSolve(Frame& fr, int first, int last, DeformCounters& cnt) {
  DeformState& st = *fr.st;
  const DeformOptions& opt = *fr.opt;
  VertexProblem vp;
  // The arrays the per-vertex test and the rigid vertices use, as locals: through the
  // vectors, every byte store (flags) would make the compiler load their addresses again.
  const float* const memory = st.memory.data();
  const std::uint8_t* const cand_count = st.cand_count.data();
  const glm::vec3* const rigid_positions = fr.in->rigid_positions.data();
  float* const offset = st.offset.data();
  float* const free_offset = st.free_offset.data();
  glm::vec3* const positions = st.positions.data();
  std::int16_t* const contact_body = st.contact_body.data();
  std::uint8_t* const vertex_flags = st.flags.data();
  const bool along_normal = opt.projection == ProjectionMode::kNormal;
  // Every vertex's rigid position in one copy; the vertices solved below overwrite theirs.
  std::copy(rigid_positions + first, rigid_positions + last, positions + first);
  // A rigid limb vertex with nothing near it is on its surface by construction; so is a
  // free vertex (its own field is a plane through its rigid position). Those without a
  // candidate ("resting") are written for the whole chunk at once, in loops without branches
  // (the compiler vectorises them); the others are listed for the loop below.
  std::uint8_t* const resting = st.resting.data();
  const std::uint8_t* const fixed_kind = st.fixed_kind.data();
  const auto is_fixed = [&](std::size_t vi) {
    return fixed_kind[vi] != 0 && memory[vi] == 0.0f && along_normal;
  };
  if (along_normal) {
    for (int v = first; v < last; ++v) {
      resting[v] = static_cast<std::uint8_t>(fixed_kind[v] & (memory[v] == 0.0f ? 1 : 0) &
                                             ((cand_count[v] & 0x7F) == 0 ? 1 : 0));
    }
  } else {
    std::fill(resting + first, resting + last, std::uint8_t{0});
  }
  for (int v = first; v < last; ++v) offset[v] = resting[v] != 0 ? 0.0f : offset[v];
  if (st.any_inelastic) {  // (an elastic vertex's free offset is never read)
    for (int v = first; v < last; ++v) free_offset[v] = resting[v] != 0 ? 0.0f : free_offset[v];
  }
  for (int v = first; v < last; ++v) {
    contact_body[v] = resting[v] != 0 ? std::int16_t{-1} : contact_body[v];
  }
  for (int v = first; v < last; ++v) {
    vertex_flags[v] = resting[v] != 0 ? std::uint8_t{0} : vertex_flags[v];
  }
  // The lists, eight resting vertices (a word of ones) at a time: the lone limb vertices
  // (loneKind and the rest, tested without a branch) in one, the others in the other, each in
  // vertex order.
  std::uint32_t* const work = st.solve_list.data() + first;
  std::uint32_t* const lone = st.lone_list.data() + first;
  const std::uint8_t* const lone_kind = st.lone_kind.data();
  const std::uint8_t lone_way = along_normal ? 1 : 0;
  int nwork = 0;
  int nlone = 0;
  int next = first;
  const auto list = [&](int end) {
    for (; next < end; ++next) {
      const std::uint8_t is_lone = lone_kind[next] & lone_way & (cand_count[next] == 0 ? 1 : 0) &
                                   (memory[next] == 0.0f ? 1 : 0) &
                                   ((vertex_flags[next] & kVertexGradient) == 0 ? 1 : 0);
      work[nwork] = static_cast<std::uint32_t>(next);
      nwork += (resting[next] | is_lone) ^ 1;
      lone[nlone] = static_cast<std::uint32_t>(next);
      nlone += is_lone;
    }
  };
  while (next + 8 <= last) {
    std::uint64_t word;
    std::memcpy(&word, resting + next, sizeof word);
    if (word == 0x0101010101010101ull) {
      next += 8;
    } else {
      list(next + 8);
    }
  }
  list(last);
  cnt.rigid_vertices += (last - first) - nwork - nlone;
  // The lone limb vertices first, a batch at a time: their first evaluations in a loop of
  // their own (each independent of the others: the processor overlaps them), then the rest of
  // each one's solve. Any the short way leaves join the others' list, after them (no lone one
  // touches a collider or is relaxed, so the contact and relaxation lists keep vertex order).
  constexpr int kLoneBatch = 32;
  LoneStart starts[kLoneBatch];
  for (int k0 = 0; k0 < nlone; k0 += kLoneBatch) {
    const int n = std::min(kLoneBatch, nlone - k0);
    for (int i = 0; i < n; ++i) starts[i] = loneStart(fr, lone[k0 + i]);
    for (int i = 0; i < n; ++i) {
      const std::uint32_t v = lone[k0 + i];
      if (!solveLoneLimb(fr, static_cast<int>(v), starts[i], cnt)) work[nwork++] = v;
    }
  }
  for (int k = 0; k < nwork; ++k) {
    const int v = static_cast<int>(work[k]);
    const auto vi = static_cast<std::size_t>(v);
    const bool fixed = is_fixed(vi);
    const bool listed = (cand_count[vi] & 0x7F) != 0;
    if (listed || !fixed) gatherProblem(fr, v, true, vp);
    const int gathered_ncand = vp.ncand;  // (the memory below drops the candidates)
    if (fixed && (!listed || vp.ncand == 0)) {
      offset[vi] = 0.0f;
      free_offset[vi] = 0.0f;
      contact_body[vi] = -1;
      vertex_flags[vi] = 0;
      ++cnt.rigid_vertices;
      continue;
    }
    if (vp.overflow) ++cnt.candidate_overflow;
    if (vp.ncand > 0) ++cnt.candidate_vertices;
    std::uint8_t flags = 0;
    const float reach = searchReach(vp);

    // First evaluation at the warm start along the normal.
    glm::vec3 dir = vp.n0;
    float s_start = st.offset[vi];
    if ((st.flags[vi] & kVertexGradient) != 0 || opt.projection == ProjectionMode::kGradient) {
      s_start = 0.0f;  // a gradient line is re-derived each frame from the rigid position
    }
    // A free vertex's own equation is the plane through its rigid position along its normal:
    // with no soft term (every candidate a hard constraint without a bulge) its root is the
    // rigid position itself, whatever its last solution was.
    if (vp.cls == VertexClass::kFree &&
        std::all_of(vp.cand, vp.cand + vp.ncand,
                    [](const Candidate& c) { return c.hard && !(c.bulge > 0.0f); })) {
      s_start = 0.0f;
    }
    glm::vec3 grad;
    float g = evaluate(vp, vp.p0 + s_start * dir, grad);
    ++cnt.evaluations;
    const float own_side_start = vp.own_side;
    // Project along -grad F when asked, or where the normal disagrees strongly with the
    // own side's (crease-free) gradient; also when the normal finds no root.
    const bool at_root = std::abs(g) < opt.root.tolerance;
    glm::vec3 smooth(0.0f);
    if (!at_root) smooth = vp.smooth_gradient;
    const float gn = glm::length(smooth);
    const auto use_gradient = [&]() {
      flags |= kVertexGradient;
      ++cnt.gradient_vertices;
      dir = -smooth / gn;
      s_start = 0.0f;
      g = evaluate(vp, vp.p0, grad);
      ++cnt.evaluations;
    };
    if (!at_root && gn > 0.0f &&
        (opt.projection == ProjectionMode::kGradient ||
         -glm::dot(dir, smooth) / gn < opt.gradient_switch_cos)) {
      use_gradient();
    }
    bool iterated = false;
    RootResult res = solveVertex(vp, dir, s_start, g, grad, reach, opt.root, cnt, iterated);
    if (!res.found && (flags & kVertexGradient) == 0 && gn > 0.0f) {
      use_gradient();
      res = solveVertex(vp, dir, s_start, g, grad, reach, opt.root, cnt, iterated);
    }
    // A contact root far beyond the rigid penetration: try the contact surface's normal.
    if (res.found && vp.ncand > 0 && st.depth[vi] > 0.0f &&
        std::abs(res.s) > std::max(kGrazeMinOffset, kGrazeFactor * st.depth[vi]) &&
        reprojectOnContact(vp, reach, opt.root, cnt, iterated, dir, res) &&
        (flags & kVertexGradient) == 0) {
      flags |= kVertexGradient;
      ++cnt.gradient_vertices;
    }
    if (iterated) ++cnt.iterating_vertices;
    // A joint vertex whose root left its own side stays where the skinning put it.
    const bool held = res.found && !ownSideHolds(vp, own_side_start, vp.p0 + res.s * dir, opt);
    if (held) {
      res.s = 0.0f;
      flags |= kVertexHeld;
      ++cnt.held_vertices;
    }
    // A root beyond what the vertex's own field and its contact can ask (see moveAllowance):
    // a vertex that resolves no penetration stays rigid; one that does goes that far.
    if (res.found && !held) {
      const float limit = moveAllowance(fr, vi);
      if (std::abs(res.s) > limit) {
        if (st.depth[vi] > 0.0f) {
          res.s = std::copysign(limit, res.s);
        } else {
          res.s = 0.0f;
          flags |= kVertexHeld;
          ++cnt.held_vertices;
        }
      }
    }

    float s_sol = res.found ? res.s : 0.0f;
    if (!res.found) {
      flags |= kVertexUnsolved;
      ++cnt.unsolved_vertices;
    }
    // Contact state at the solution: the partner body touched, or -1.
    int partner = -1;
    if (res.found && vp.ncand > 0 && st.depth[vi] > 0.0f) {
      float x = 0.0f;
      const int c = deepestPartner(vp, vp.p0 + s_sol * dir, x);
      if (c >= 0 && x >= -kContactTolerance) {
        partner = st.colliders[static_cast<std::size_t>(vp.cand[c].collider)].body;
      }
    }
    // Elastic memory: plastic and viscoelastic bodies keep the contact offset
    // c = s_sol - s_free (dents only; bulges stay elastic).
    float s_out = s_sol;
    const Elasticity mode = vertexElasticity(fr, v);
    if (mode != Elasticity::kElastic && !held) {  // a held vertex keeps its memory as it was
      float s_free = s_sol;
      if (vp.ncand > 0 && res.found) {
        vp.ncand = 0;
        vp.last_point = glm::vec3(NAN);  // a different function from here on
        auto eval_free = [&](float s, float* dg) {
          glm::vec3 gr;
          const float val = evaluate(vp, vp.p0 + s * dir, gr);
          *dg = glm::dot(gr, dir);
          return val;
        };
        const RootResult rf = findRoot(eval_free, st.free_offset[vi], reach, opt.root);
        cnt.evaluations += 1 + rf.iterations;
        s_free = rf.found ? rf.s : s_sol;
      }
      const float c = s_sol - s_free;
      const float target = std::min(c, 0.0f);
      float m = st.memory[vi];
      if (target < m) {
        m = target;  // pressing in follows the contact at once
      } else if (mode == Elasticity::kViscoelastic) {
        const float tau =
            fr.model->primitives.items[static_cast<std::size_t>(fr.model->calibration.prims[vi][0])]
                .time_constant;
        m = target + (m - target) * std::exp(-fr.dt / tau);
        if (m > -kSnapOffset) m = 0.0f;
      }
      st.memory[vi] = m;
      st.free_offset[vi] = s_free;
      if (m < 0.0f) s_out = s_free + std::min(m, c);
    }
    s_out = writeSolved(fr, v, vp.p0, dir, s_sol, s_out, flags, partner, cnt);
    if ((vertex_flags[vi] & kVertexContact) != 0) {  // for passContacts, in vertex order
      st.contact_list[static_cast<std::size_t>(first + cnt.contact_vertices - 1)] =
          static_cast<std::uint32_t>(v);
    }
    const bool relax = opt.relax_passes > 0 && (flags & (kVertexUnsolved | kVertexHeld)) == 0 &&
                       vp.cls == VertexClass::kJoint &&
                       (std::abs(s_out) > opt.relax_min_offset || (flags & kVertexGradient) != 0);
    if (relax) {
      st.flags[vi] |= kVertexRelaxed;
      st.relax_list[static_cast<std::size_t>(first + cnt.relaxed_vertices)] =
          static_cast<std::uint32_t>(v);
      keepProblem(st,
                  st.joint_prefix[static_cast<std::size_t>(first)] +
                      static_cast<std::size_t>(cnt.relaxed_vertices),
                  vp, gathered_ncand);
      ++cnt.relaxed_vertices;
      st.field_gradient[vi] = gradientNear(vp, st.positions[vi], opt.root.final_step);
    }
  }
}

// One tangential relaxation pass over the flagged vertices of a chunk (relax_list from
// `first`, `count` of them): move towards the rest barycentre of the one-ring within the
// tangent plane, then project back onto F = T along the outward field normal. Reads
// positions, writes relaxed.
void passRelax(Frame& fr, int first, int count, DeformCounters& cnt) {
  DeformState& st = *fr.st;
  const Calibration& cal = fr.model->calibration;
  const DeformOptions& opt = *fr.opt;
  VertexProblem vp;
  for (int k = 0; k < count; ++k) {
    const std::uint32_t v = st.relax_list[static_cast<std::size_t>(first + k)];
    const auto vi = static_cast<std::size_t>(v);
    st.relaxed[vi] = st.positions[vi];
    const std::uint32_t r0 = cal.ring_offsets[vi];
    const std::uint32_t r1 = cal.ring_offsets[vi + 1];
    if (r0 == r1) continue;
    keptProblem(st, st.joint_prefix[static_cast<std::size_t>(first)] + static_cast<std::size_t>(k),
                vp);
    // Outward field normal at the current position.
    const glm::vec3 p = st.positions[vi];
    glm::vec3 grad = st.field_gradient[vi];  // from the solve that put the vertex at p
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
      st.relaxed[vi] = q + res.s * nu;
      st.field_gradient[vi] = gradientNear(vp, st.relaxed[vi], opt.root.final_step);
    }
  }
}

// Whether a collision term may have shaped vertex v's solution this frame: it touches, it
// penetrated a collider in the rigid pose, or a collider may bulge it (another body's, or any
// with self-propagation). A vertex whose only colliders are its own body's, neither touched
// nor penetrated, solved its own equation alone (the joint's opposite limb, always paired
// with a joint vertex, acts only where the vertex enters it).
bool collisionShaped(const Frame& fr, std::uint32_t v) {
  const DeformState& st = *fr.st;
  const int n = st.cand_count[v] & 0x7F;
  if (n == 0) return false;
  if ((st.cand_count[v] & 0x80) != 0) return true;  // more colliders than were listed
  if ((st.flags[v] & kVertexContact) != 0 || st.depth[v] > 0.0f) return true;
  for (int i = 0; i < n; ++i) {
    const std::uint16_t c =
        st.candidates[static_cast<std::size_t>(v) * kMaxCandidates + static_cast<std::size_t>(i)]
            .collider;
    if (st.colliders[c].body != fr.self || fr.opt->self_propagation) return true;
  }
  return false;
}

// The last part of Step 2: smooths the corrections c = P' - P of the joint regions (see
// the header and DeformOptions::smooth_passes). The vertices smoothed are those of the pool
// (joint vertices and the free ones beside them) that no collision term shaped (see
// collisionShaped), so none in contact, that moved or have a neighbour that moved (beyond
// them nothing spreads); each pass moves their corrections smooth_rate of the way to the
// one-ring's mean (rest barycentric weights), reading the others' as they are. Serial and in
// vertex order (Jacobi), so the result does not depend on threads. Returns how many moved.
int smoothCorrections(Frame& fr) {
  DeformState& st = *fr.st;
  const DeformOptions& opt = *fr.opt;
  const Calibration& cal = fr.model->calibration;
  const auto rigid = fr.in->rigid_positions;
  const auto moved = [&](std::uint32_t u) {
    return (st.flags[u] & (kVertexMoved | kVertexRelaxed)) != 0;
  };
  st.smooth_list.clear();
  for (const std::uint32_t v : st.smooth_pool) {
    if (collisionShaped(fr, v)) continue;
    bool active = moved(v);
    for (std::uint32_t k = cal.ring_offsets[v]; k < cal.ring_offsets[v + 1] && !active; ++k) {
      active = moved(cal.ring[k]);
    }
    if (!active) continue;
    st.smooth_list.push_back(v);
    st.smooth_mark[v] = 1;
    st.correction[v] = st.positions[v] - rigid[v];
  }
  const float a = opt.smooth_rate;
  for (int pass = 0; pass < opt.smooth_passes; ++pass) {
    for (const std::uint32_t v : st.smooth_list) {
      glm::vec3 mean(0.0f);
      for (std::uint32_t k = cal.ring_offsets[v]; k < cal.ring_offsets[v + 1]; ++k) {
        const std::uint32_t u = cal.ring[k];
        mean += cal.ring_weights[k] *
                (st.smooth_mark[u] != 0 ? st.correction[u] : st.positions[u] - rigid[u]);
      }
      st.correction_next[v] = (1.0f - a) * st.correction[v] + a * mean;
    }
    for (const std::uint32_t v : st.smooth_list) st.correction[v] = st.correction_next[v];
  }
  int count = 0;
  for (const std::uint32_t v : st.smooth_list) {
    st.smooth_mark[v] = 0;
    const glm::vec3 c = st.correction[v];
    const glm::vec3 p = rigid[v] + c;
    if (p == st.positions[v]) continue;
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

// Step 3a: normals. Vertices untouched by deformation (and whose neighbours are too; a move
// below kReshapeOffset counts as untouched) keep their rigid normals; the others get
// area-weighted normals of the deformed faces. First the faces with a dirty vertex (each
// once), then the vertices.
void passFaceNormals(Frame& fr, int first, int last) {
  DeformState& st = *fr.st;
  const auto idx = fr.in->indices;
  for (int face = first; face < last; ++face) {
    const std::size_t f = 3u * static_cast<std::size_t>(face);
    const std::uint32_t a = idx[f], b = idx[f + 1], c = idx[f + 2];
    if ((st.dirty[a] | st.dirty[b] | st.dirty[c]) == 0) continue;
    const glm::vec3& pa = st.positions[a];
    st.face_cross[static_cast<std::size_t>(face)] =
        glm::cross(st.positions[b] - pa, st.positions[c] - pa);
  }
}

void passNormals(Frame& fr, int first, int last) {
  DeformState& st = *fr.st;
  // The rigid normals in one copy, then the dirty vertices' own.
  std::copy(fr.in->rigid_normals.begin() + first, fr.in->rigid_normals.begin() + last,
            st.normals.begin() + first);
  for (int v = first; v < last; ++v) {
    const auto vi = static_cast<std::size_t>(v);
    if (st.dirty[vi] == 0) continue;
    glm::vec3 n(0.0f);
    for (std::uint32_t k = st.vf_offsets[vi]; k < st.vf_offsets[vi + 1]; ++k)
      n += st.face_cross[st.vf_faces[k]];
    const float len = glm::length(n);
    st.normals[vi] = len > 0.0f ? n / len : fr.in->rigid_normals[vi];
  }
}

// Step 3b: contact areas and forces per partner (serial, fixed order: the chunks' contact
// lists one after the other, each in vertex order).
void passContacts(Frame& fr, int chunks) {
  DeformState& st = *fr.st;
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
    const int count = st.chunk_counters[static_cast<std::size_t>(chunk)].contact_vertices;
    for (int i = 0; i < count; ++i) {
      const std::uint32_t v = st.contact_list[static_cast<std::size_t>(first + i)];
      const int partner = st.contact_body[v];
      BodyContact& bc = entry(partner);
      ++bc.vertices;
      bc.max_depth = std::max(bc.max_depth, static_cast<double>(st.depth[v]));
      // Each contact face once: from its lowest vertex.
      for (std::uint32_t k = st.vf_offsets[v]; k < st.vf_offsets[v + 1]; ++k) {
        const std::size_t f = 3u * st.vf_faces[k];
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
        const double area = 0.5 * twice_area;
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

// Builds this frame's collider table: the partners Step 1 found for each own primitive,
// plus the same-body primitives named by always-pairs.
void buildColliders(Frame& fr, const InteractionList& list) {
  DeformState& st = *fr.st;
  const auto nprim = fr.model->primitives.items.size();
  st.colliders.clear();
  const auto find_or_add = [&](int body, int prim) -> int {
    for (std::size_t c = 0; c < st.colliders.size(); ++c) {
      if (st.colliders[c].body == body && st.colliders[c].prim == prim) return static_cast<int>(c);
    }
    DeformState::Collider col;
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
    st.colliders.push_back(col);
    return static_cast<int>(st.colliders.size() - 1);
  };
  std::fill(st.prim_collider_offsets.begin(), st.prim_collider_offsets.end(), 0u);
  st.prim_colliders.clear();
  const auto entries = fr.opt->collisions ? list.forBody(fr.self) : std::span<const Interaction>();
  // Entries are sorted by own primitive: count and fill in one pass.
  for (const Interaction& e : entries) {
    if (e.prim_a >= nprim) continue;
    ++st.prim_collider_offsets[e.prim_a + 1u];
    st.prim_colliders.push_back(static_cast<std::uint16_t>(find_or_add(e.body_b, e.prim_b)));
  }
  for (std::size_t p = 0; p < nprim; ++p)
    st.prim_collider_offsets[p + 1] += st.prim_collider_offsets[p];
  std::fill(st.always_collider.begin(), st.always_collider.end(), -1);
  if (fr.opt->collisions) {
    for (const std::int16_t p : st.always_prims) {
      st.always_collider[static_cast<std::size_t>(p)] = find_or_add(fr.self, p);
    }
  }
}

// Groups the vertices into patches: vertices with the same defining primitives p0..p2,
// grown breadth-first over the triangles into compact groups of at most kPatchSize (each
// next patch seeded at the previous one's frontier), with the union of their always-pair
// primitives. Deterministic; init time only.
void buildPatches(const Calibration& cal, DeformState& st) {
  const std::size_t nv = cal.prims.size();
  const auto idx = std::span<const std::uint32_t>(st.vf_faces);  // face ids per vertex
  std::vector<std::uint8_t> taken(nv, 0);
  std::vector<std::uint32_t> queue, seeds;
  st.order.clear();
  st.order.reserve(nv);
  st.patch_offsets.assign(1, 0);
  st.patch_max_w.clear();
  st.patch_always_offsets.assign(1, 0);
  st.patch_always.clear();
  const auto same_key = [&cal](std::uint32_t a, std::uint32_t b) {
    return cal.prims[a][0] == cal.prims[b][0] && cal.prims[a][1] == cal.prims[b][1] &&
           cal.prims[a][2] == cal.prims[b][2];
  };
  std::size_t next_index = 0;
  while (st.order.size() < nv) {
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
      st.order.push_back(v);
      for (std::uint32_t k = st.vf_offsets[v]; k < st.vf_offsets[v + 1]; ++k) {
        const std::uint32_t f = idx[k];
        for (std::uint32_t j = 0; j < 3; ++j) {
          const std::uint32_t u = st.face_vertices[3 * f + j];
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
    const std::size_t first_always = st.patch_always.size();
    for (std::size_t i = st.patch_offsets.back(); i < st.order.size(); ++i) {
      const std::uint32_t v = st.order[i];
      for (std::uint32_t q = cal.pair_offsets[v]; q < cal.pair_offsets[v + 1]; ++q) {
        if ((cal.pairs[q].flags & kPairAlways) == 0) continue;
        const std::int16_t prim = cal.pairs[q].prim;
        if (std::find(st.patch_always.begin() + static_cast<std::ptrdiff_t>(first_always),
                      st.patch_always.end(), prim) == st.patch_always.end()) {
          st.patch_always.push_back(prim);
        }
      }
    }
    st.patch_offsets.push_back(static_cast<std::uint32_t>(st.order.size()));
    float w_max = 0.0f;
    for (std::size_t i = st.patch_offsets[st.patch_offsets.size() - 2]; i < st.order.size(); ++i) {
      w_max = std::max(w_max, cal.w[st.order[i]]);
    }
    st.patch_max_w.push_back(w_max);
    st.patch_always_offsets.push_back(static_cast<std::uint32_t>(st.patch_always.size()));
  }
}

}  // namespace

// The sets of own primitives evaluated together (see DeformState::own_lanes): one per
// distinct (p0, p1, p2, bone) of the joint vertices and of the limb vertices with a bone.
void buildLaneSets(const Calibration& cal, DeformState& st) {
  const std::size_t nv = cal.vertex_class.size();
  st.lane_set.assign(nv, -1);
  st.lane_set_prims.clear();
  for (std::size_t v = 0; v < nv; ++v) {
    const auto& pr = cal.prims[v];
    const bool joint = cal.vertex_class[v] == VertexClass::kJoint;
    const bool limb_bone = cal.vertex_class[v] == VertexClass::kLimb && pr[3] >= 0;
    if ((!joint && !limb_bone) || pr[0] < 0) continue;
    const auto found = std::find(st.lane_set_prims.begin(), st.lane_set_prims.end(), pr);
    if (found == st.lane_set_prims.end() && st.lane_set_prims.size() >= 0x7FFF) continue;
    st.lane_set[v] = static_cast<std::int16_t>(found - st.lane_set_prims.begin());
    if (found == st.lane_set_prims.end()) st.lane_set_prims.push_back(pr);
  }
  st.own_lanes.assign(st.lane_set_prims.size(), FieldLanes{});
  st.lane_set_packed.assign(st.lane_set_prims.size(), 0);
}

// Packs every lane set from this frame's posed primitives (a set with a primitive the lanes
// do not cover stays unpacked: its vertices evaluate their fields one by one).
void packLaneSets(Frame& fr) {
  DeformState& st = *fr.st;
  for (std::size_t i = 0; i < st.lane_set_prims.size(); ++i) {
    bool packed = true;
    for (int k = 0; k < 4 && packed; ++k) {
      const std::int16_t prim = st.lane_set_prims[i][static_cast<std::size_t>(k)];
      packed = packFieldLane(prim >= 0 ? &fr.posed->items[static_cast<std::size_t>(prim)] : nullptr,
                             k, st.own_lanes[i]);
    }
    st.lane_set_packed[i] = packed ? 1 : 0;
  }
}

Status initDeformState(const ImplicitModel& model, std::span<const std::uint32_t> indices,
                       DeformState& st) {
  const int nvert = model.calibration.vertexCount();
  const auto nv = static_cast<std::size_t>(nvert);
  if (indices.size() % 3 != 0)
    return fail("deform state: index count {} not a multiple of 3", indices.size());
  for (std::size_t i = 0; i < indices.size(); ++i) {
    if (indices[i] >= nv) return fail("deform state: index {} = {} out of range", i, indices[i]);
  }
  const auto nprim = model.primitives.items.size();
  st.positions.assign(nv, glm::vec3(0.0f));
  st.normals.assign(nv, glm::vec3(0.0f));
  st.offset.assign(nv, 0.0f);
  st.free_offset.assign(nv, 0.0f);
  st.memory.assign(nv, 0.0f);
  st.contact_body.assign(nv, -1);
  st.pressure.assign(nv, 0.0f);
  st.depth.assign(nv, 0.0f);
  st.flags.assign(nv, 0);
  st.prim_to_world.assign(model.primitives.items.size(), glm::mat4(1.0f));
  st.relaxed.assign(nv, glm::vec3(0.0f));
  st.relax_list.assign(nv, 0);
  st.contact_list.assign(nv, 0);
  st.resting.assign(nv, 0);
  st.any_inelastic =
      std::any_of(model.primitives.items.begin(), model.primitives.items.end(),
                  [](const Primitive& p) { return p.elasticity != Elasticity::kElastic; });
  st.fixed_kind.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    st.fixed_kind[v] =
        (model.calibration.rigid[v] != 0 || model.calibration.vertex_class[v] == VertexClass::kFree)
            ? 1
            : 0;
  }
  st.lone_kind.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    st.lone_kind[v] = loneKind(model.calibration, v, st.fixed_kind[v] != 0) ? 1 : 0;
  }
  st.solve_list.assign(nv, 0);
  st.lone_list.assign(nv, 0);
  st.joint_prefix.assign(nv + 1, 0);
  for (std::size_t v = 0; v < nv; ++v) {
    st.joint_prefix[v + 1] =
        st.joint_prefix[v] + (model.calibration.vertex_class[v] == VertexClass::kJoint ? 1 : 0);
  }
  st.relax_problems.assign(st.joint_prefix[nv] * kKeptProblemBytes, std::byte{0});
  st.cand_count.assign(nv, 0);
  st.dirty.assign(nv, 0);
  st.candidates.assign(nv * kMaxCandidates, DeformState::CandidateSlot{});
  st.field_gradient.assign(nv, glm::vec3(NAN));
  // Joint vertices, and free vertices beside them (a vertex of a joint region demoted at
  // calibration): the vertices the smoothing of corrections may move.
  st.smooth_pool.clear();
  const Calibration& cal = model.calibration;
  for (std::size_t v = 0; v < nv; ++v) {
    bool pooled = cal.vertex_class[v] == VertexClass::kJoint;
    if (cal.vertex_class[v] == VertexClass::kFree) {
      for (std::uint32_t k = cal.ring_offsets[v]; k < cal.ring_offsets[v + 1] && !pooled; ++k) {
        pooled = cal.vertex_class[cal.ring[k]] == VertexClass::kJoint;
      }
    }
    if (pooled) st.smooth_pool.push_back(static_cast<std::uint32_t>(v));
  }
  st.smooth_list.clear();
  st.smooth_list.reserve(st.smooth_pool.size());
  st.correction.assign(nv, glm::vec3(0.0f));
  st.correction_next.assign(nv, glm::vec3(0.0f));
  st.smooth_mark.assign(nv, 0);
  st.contacts.clear();
  st.contacts.reserve(64);
  st.counters = {};
  st.time = 0.0;
  st.started = false;
  st.colliders.clear();
  st.colliders.reserve(512);
  st.prim_collider_offsets.assign(nprim + 1, 0);
  st.prim_colliders.clear();
  st.prim_colliders.reserve(4096);
  st.always_collider.assign(nprim, -1);
  // Primitives named by always-pairs.
  std::vector<std::uint8_t> named(nprim, 0);
  for (const VertexPair& p : model.calibration.pairs) {
    if ((p.flags & kPairAlways) != 0 && p.prim >= 0 && static_cast<std::size_t>(p.prim) < nprim) {
      named[static_cast<std::size_t>(p.prim)] = 1;
    }
  }
  st.always_prims.clear();
  for (std::size_t p = 0; p < nprim; ++p) {
    if (named[p] != 0) st.always_prims.push_back(static_cast<std::int16_t>(p));
  }
  st.face_vertices.assign(indices.begin(), indices.end());
  st.face_cross.assign(indices.size() / 3, glm::vec3(0.0f));
  // Vertex -> face adjacency.
  st.vf_offsets.assign(nv + 1, 0);
  for (const std::uint32_t i : indices) ++st.vf_offsets[i + 1];
  for (std::size_t v = 0; v < nv; ++v) st.vf_offsets[v + 1] += st.vf_offsets[v];
  st.vf_faces.assign(indices.size(), 0);
  std::vector<std::uint32_t> fill(st.vf_offsets.begin(), st.vf_offsets.end() - 1);
  for (std::size_t i = 0; i < indices.size(); ++i) {
    st.vf_faces[fill[indices[i]]++] = static_cast<std::uint32_t>(i / 3);
  }
  buildPatches(model.calibration, st);
  buildLaneSets(model.calibration, st);
  st.chunk_counters.assign(static_cast<std::size_t>((nvert + 511) / 512) + 1, DeformCounters{});
  return {};
}

void deformSkin(const ImplicitModel& model, std::span<const BodyView> bodies, int self,
                const InteractionList& interactions, const DeformInput& in, DeformState& st,
                const DeformOptions& opt, TaskPool* pool) {
  Frame fr;
  fr.model = &model;
  fr.bodies = bodies;
  fr.self = self;
  fr.in = &in;
  fr.st = &st;
  fr.opt = &opt;
  fr.posed = bodies[static_cast<std::size_t>(self)].posed;
  fr.nvert = model.calibration.vertexCount();
  fr.chunk = std::max(opt.chunk_size, 16);
  fr.dt = st.started ? static_cast<float>(std::max(in.time - st.time, 0.0)) : 0.0f;
  st.time = in.time;
  st.started = true;

  // Phase timing (DeformOptions::time_phases): lap(t) adds the time since the last lap to t.
  using Clock = std::chrono::steady_clock;
  DeformPhaseTimes times;
  Clock::time_point mark = opt.time_phases ? Clock::now() : Clock::time_point();
  const auto lap = [&](double& phase) {
    if (!opt.time_phases) return;
    const Clock::time_point now = Clock::now();
    phase += std::chrono::duration<double>(now - mark).count();
    mark = now;
  };

  // Setup: colliders of this body, per own primitive; the own fields' lanes.
  buildColliders(fr, interactions);
  packLaneSets(fr);
  const int chunks = (fr.nvert + fr.chunk - 1) / fr.chunk;
  if (st.chunk_counters.size() < static_cast<std::size_t>(chunks)) {
    st.chunk_counters.resize(static_cast<std::size_t>(chunks));
  }
  for (int c = 0; c < chunks; ++c)
    st.chunk_counters[static_cast<std::size_t>(c)] = DeformCounters{};
  const auto range = [&fr](int c) {
    return std::pair<int, int>(c * fr.chunk, std::min(fr.nvert, (c + 1) * fr.chunk));
  };

  // Pass A: rigid-pose penetrations (only vertices with candidates do any work).
  const int npatch = static_cast<int>(st.patch_offsets.size()) - 1;
  const int patch_tasks = (npatch + kPatchesPerTask - 1) / kPatchesPerTask;
  auto pass_a = [&](int t) {
    passPenetration(fr, t * kPatchesPerTask, std::min(npatch, (t + 1) * kPatchesPerTask));
  };
  if (!st.colliders.empty()) {
    parallelFor(pool, patch_tasks, pass_a);
  } else {
    std::fill(st.depth.begin(), st.depth.end(), 0.0f);
    std::fill(st.pressure.begin(), st.pressure.end(), 0.0f);
    std::fill(st.cand_count.begin(), st.cand_count.end(), std::uint8_t{0});
  }

  // The move bound's per-frame parts (see moveAllowance).
  if (opt.move_margin >= 0.0f && in.rest_positions.size() == static_cast<std::size_t>(fr.nvert)) {
    for (std::size_t i = 0; i < fr.posed->items.size(); ++i)
      st.prim_to_world[i] = glm::inverse(fr.posed->items[i].to_bind);
    const float deepest =
        st.colliders.empty() ? 0.0f : *std::max_element(st.depth.begin(), st.depth.end());
    st.bulge_allowance = 2.0f * model.primitives.propagation_amplitude * deepest;
  }

  lap(times.penetration);

  std::fill(st.dirty.begin(), st.dirty.end(), std::uint8_t{0});

  // Pass B: Step 2 proper.
  auto pass_b = [&](int c) {
    const auto [b, e] = range(c);
    passSolve(fr, b, e, st.chunk_counters[static_cast<std::size_t>(c)]);
  };
  parallelFor(pool, chunks, pass_b);
  lap(times.solve);

  // Relaxation passes (Jacobi: read positions, write relaxed, then copy back).
  for (int pass = 0; pass < opt.relax_passes; ++pass) {
    // Each chunk's relaxed vertices are listed from its first vertex on (see passSolve).
    auto relax = [&](int c) {
      DeformCounters& cnt = st.chunk_counters[static_cast<std::size_t>(c)];
      passRelax(fr, range(c).first, cnt.relaxed_vertices, cnt);
    };
    parallelFor(pool, chunks, relax);
    auto copy = [&](int c) {
      const int b = range(c).first;
      const int n = st.chunk_counters[static_cast<std::size_t>(c)].relaxed_vertices;
      for (int k = 0; k < n; ++k) {
        const std::uint32_t v = st.relax_list[static_cast<std::size_t>(b + k)];
        st.positions[v] = st.relaxed[v];
        // Its ring needs new normals: marked once a frame (a reshaped vertex is marked).
        if ((st.flags[v] & kVertexReshaped) == 0) {
          st.flags[v] |= kVertexReshaped;
          markReshaped(fr, static_cast<int>(v));
        }
      }
    };
    parallelFor(pool, chunks, copy);
  }

  lap(times.relax);

  // Smoothing the joint regions' corrections.
  const int smoothed = opt.smooth_passes > 0 ? smoothCorrections(fr) : 0;
  lap(times.smooth);

  // Step 3: normals, then contacts and forces.
  const int nface = static_cast<int>(st.face_cross.size());
  const int face_chunks = (nface + fr.chunk - 1) / fr.chunk;
  auto face_normals = [&](int c) {
    passFaceNormals(fr, c * fr.chunk, std::min(nface, (c + 1) * fr.chunk));
  };
  parallelFor(pool, face_chunks, face_normals);
  auto normals = [&](int c) {
    const auto [b, e] = range(c);
    passNormals(fr, b, e);
  };
  parallelFor(pool, chunks, normals);
  lap(times.normals);
  passContacts(fr, chunks);
  lap(times.contacts);

  // Counters, reduced in chunk order.
  DeformCounters total;
  for (int c = 0; c < chunks; ++c) {
    const DeformCounters& k = st.chunk_counters[static_cast<std::size_t>(c)];
    total.evaluations += k.evaluations;
    total.iterations += k.iterations;
    total.relax_iterations += k.relax_iterations;
    total.iterating_vertices += k.iterating_vertices;
    total.unsolved_vertices += k.unsolved_vertices;
    total.held_vertices += k.held_vertices;
    total.gradient_vertices += k.gradient_vertices;
    total.contact_vertices += k.contact_vertices;
    total.candidate_overflow += k.candidate_overflow;
    total.candidate_vertices += k.candidate_vertices;
    total.rigid_vertices += k.rigid_vertices;
    total.relaxed_vertices += k.relaxed_vertices;
    total.max_offset = std::max(total.max_offset, k.max_offset);
  }
  total.smoothed_vertices = smoothed;
  total.phase_seconds = times;
  st.counters = total;
}

float vertexFunction(const ImplicitModel& model, std::span<const BodyView> bodies, int self,
                     const DeformInput& input, const DeformState& state,
                     const DeformOptions& options, int v, const glm::vec3& p, glm::vec3* gradient) {
  Frame fr;
  fr.model = &model;
  fr.bodies = bodies;
  fr.self = self;
  fr.in = &input;
  fr.st = const_cast<DeformState*>(&state);  // gatherProblem only reads the state
  fr.opt = &options;
  fr.posed = bodies[static_cast<std::size_t>(self)].posed;
  fr.nvert = model.calibration.vertexCount();
  VertexProblem vp;
  gatherProblem(fr, v, true, vp);
  vp.lanes = nullptr;  // the own fields from `bodies` themselves (the same values)
  for (int i = 0; i < vp.ncand; ++i) vp.cand[i].lane = -1;
  glm::vec3 grad;
  const float g = evaluate(vp, p, grad);
  if (gradient != nullptr) *gradient = grad;
  return g;
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
