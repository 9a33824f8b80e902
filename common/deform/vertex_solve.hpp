// Internal to common/deform (not a public header). Step 2's vertex solve (DESIGN.md §3
// "Root-finding"): a vertex's problem (its own function w_v D_v - T and its collision
// candidates with their terms, collision_terms.hpp), the function g evaluated at a point,
// and the solve along a line from the rigid position with the hard constraints of rigid
// partners (Gascuel 1993; the relaxation's projections reuse it, Vaillant et al. 2013).
// The per-vertex pass B (passSolve), the lone limb vertices' short way and the move bound
// (moveAllowance) are in vertex_solve.cpp.
//
// Space: world, metres; g in field units (a positive multiple of F(P) - T near the
// solution). Cost: an evaluation is O(own primitives + candidates) <= 4 + kMaxCandidates
// field evaluations; a solve 2-3 evaluations on average (DeformCounters); no allocation.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <type_traits>

#include <glm/glm.hpp>

#include "common/deform/collision_terms.hpp"
#include "common/deform/deform_scratch.hpp"
#include "common/deform/field_lanes.hpp"
#include "common/deform/root_finding.hpp"
#include "common/deform/vertex_field.hpp"

namespace vistel {

// One collision candidate of a vertex, with its terms (collision_terms.hpp) for this vertex.
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
  const FieldLanes* lanes = nullptr;  // own[0..3] packed (DeformScratch::own_lanes), or null
  float w = 1.0f;
  float slope = 0.0f;
  float iso = 0.5f;
  float target = 0.5f;  // what w_v D_v is solved for: iso, shifted towards the skinned
                        // position's own value where the own field is faded (ownFade)
  float faded = 0.0f;   // the faded share (skinnedShare) of a limb or joint vertex
  int diff_exponent = 4;
  glm::vec3 p0{0.0f};       // origin of the projection line (the rigid position)
  bool p0_rigid = false;    // a free vertex's p0, its rigid position (where the candidates'
                            // x_rigid hold)
  bool yields_own = false;  // an adopted vertex: takes an own-body partner's whole contact
                            // (DeformScratch::adopted)
  glm::vec3 n0{0.0f};       // rigid normal
  glm::vec3 anchor{0.0f};   // free vertices: their plane passes through this (rigid position)
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
// its gradient (assembleDensity, vertex_field.hpp).
template <typename Field>
inline float ownSum(VertexProblem& vp, glm::vec3& grad, Field&& field) {
  glm::vec3 g0;
  OwnSide own;
  const float d = assembleDensity(vp.cls, vp.own[3] != nullptr, vp.diff_exponent, field, &g0, &own);
  grad = vp.w * g0;
  vp.smooth_gradient = vp.w * own.gradient;
  vp.own_side = vp.w * own.value;
  return vp.w * d - vp.target;
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
    return ownSum(vp, grad, [&lanes](int k, glm::vec3* g) {
      *g = glm::vec3(lanes.gx[k], lanes.gy[k], lanes.gz[k]);
      return lanes.f[k];
    });
  }
  return ownSum(vp, grad,
                [&vp, &p](int k, glm::vec3* g) { return primitiveField(*vp.own[k], p, g); });
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

inline float searchReach(float own_reach) { return std::max(own_reach, 0.02f); }
inline float searchReach(const VertexProblem& vp) {
  return searchReach(vp.own[0] != nullptr ? vp.own[0]->reach : 0.05f);
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

// A relaxed vertex's problem as pass B gathered it, kept for the relaxation passes (which
// would gather the same again, twice): slot `slot` of DeformScratch::relax_problems, its
// candidates up to `ncand` (the side results after them are rewritten by every evaluation).
static_assert(std::is_trivially_copyable_v<VertexProblem>);
inline constexpr std::size_t kKeptProblemBytes = sizeof(VertexProblem);
inline void keepProblem(DeformScratch& sc, std::size_t slot, const VertexProblem& vp, int ncand) {
  std::byte* const out = sc.relax_problems.data() + slot * kKeptProblemBytes;
  const std::size_t bytes =
      offsetof(VertexProblem, cand) + static_cast<std::size_t>(ncand) * sizeof(Candidate);
  std::memcpy(out, &vp, bytes);
  std::memcpy(out + offsetof(VertexProblem, ncand), &ncand, sizeof ncand);
}
inline void keptProblem(const DeformScratch& sc, std::size_t slot, VertexProblem& vp) {
  const std::byte* const in = sc.relax_problems.data() + slot * kKeptProblemBytes;
  int ncand = 0;
  std::memcpy(&ncand, in + offsetof(VertexProblem, ncand), sizeof ncand);
  std::memcpy(&vp, in,
              offsetof(VertexProblem, cand) + static_cast<std::size_t>(ncand) * sizeof(Candidate));
  vp.last_point = glm::vec3(NAN);
  vp.hard_point = glm::vec3(NAN);
}

// Gathers vertex v's problem: its own part (class, own primitives, weight, packed lanes, rigid
// position and normal) and its cached candidates (DeformScratch::candidates) with their terms.
// with_bulge: use this frame's deepest penetrations (after pass A).
void gatherVertexProblem(const DeformFrame& fr, int v, bool with_bulge, VertexProblem& vp);

// Solves the soft equation along dir from s_start (first evaluation g, grad given), then
// enforces the hard constraints (rigid partners: the vertex ends on their surface; dir may
// turn to the partner's way out). Counts evaluations and iterations in cnt; sets iterated
// when it took a step.
RootResult solveVertex(VertexProblem& vp, glm::vec3& dir, float s_start, float g,
                       const glm::vec3& grad, float reach, const RootOptions& ropt,
                       DeformCounters& cnt, bool& iterated);

// Pass B: Step 2 for every vertex of [first, last) (a chunk): solves, writes positions,
// offsets, flags, contact partners and elastic memory, and lists the chunk's contact and
// relaxed vertices (from `first` on) with the relaxed ones' problems.
void passSolve(DeformFrame& fr, int first, int last, DeformCounters& cnt);

// The move bound (DeformOptions::move_margin): how far vertex vi may end from its skinned
// position (infinite when moves are not bounded); `bulging`: a partner near it bulges it.
float moveAllowance(const DeformFrame& fr, std::size_t vi, bool bulging);

// The move bound applied once more after relaxation and smoothing (which move vertices the
// solve bounded). O(nvert) flag tests.
void boundRelaxedMoves(DeformFrame& fr);

// The share of vertex vi's own-field surface that is faded into its skinned position
// (DeformOptions::own_fade_low): 0 where the bones its own field models carry enough of its
// skin weight (and for models without Calibration::own_weight), 1 where they carry too
// little, linear between.
float skinnedShare(const DeformFrame& fr, std::size_t vi);

// Whether vertex vi is a lone limb vertex: a limb vertex of one primitive (no bone), not fixed
// (the part of the short way's test that never changes; init time).
bool loneKind(const Calibration& cal, std::size_t vi, bool fixed);

}  // namespace vistel
