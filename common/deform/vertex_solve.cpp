// Step 2's vertex solve (see vertex_solve.hpp): Gascuel 1993, "An implicit formulation for
// precise contact modeling between flexible solids" (penetration and propagation zones, the
// partner's field scaled by the vertex weight), with relative deformability and elastic
// memory (collision_terms.hpp).
#include "common/deform/vertex_solve.hpp"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>

namespace vistel {
namespace {

// A contact root along the projection line farther than this many times the vertex's
// rigid-pose penetration depth (and than kGrazeMinOffset) is re-solved along the contact
// surface's normal (see reprojectOnContact), unless the line already meets the surface
// within acos(kGrazeCos) of that normal.
constexpr float kGrazeFactor = 2.0f;
constexpr float kGrazeMinOffset = 1e-3f;
constexpr float kGrazeCos = 0.95f;

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

// Fills vp's own part for vertex v (no candidates).
void gatherOwn(const DeformFrame& fr, int v, VertexProblem& vp) {
  const ImplicitModel& m = *fr.model;
  const Calibration& cal = m.calibration;
  const auto vi = static_cast<std::size_t>(v);
  const auto& pr = cal.prims[vi];
  vp.cls = cal.vertex_class[vi];
  for (std::size_t k = 0; k < 4; ++k) {
    vp.own[k] = pr[k] >= 0 ? &fr.posed->items[static_cast<std::size_t>(pr[k])] : nullptr;
  }
  const std::int16_t set = fr.sc->lane_set[vi];
  vp.lanes =
      set >= 0 && fr.sc->lane_set_packed[static_cast<std::size_t>(set)] != 0 && !fr.opt->reference
          ? &fr.sc->own_lanes[static_cast<std::size_t>(set)]
          : nullptr;
  vp.w = cal.w[vi];
  vp.slope = cal.slope[vi];
  vp.iso = m.primitives.iso;
  vp.diff_exponent = m.primitives.diff_exponent;
  vp.p0 = fr.in->rigid_positions[vi];
  vp.p0_rigid = vp.cls == VertexClass::kFree;
  vp.yields_own = pr[0] >= 0 && fr.sc->adopted[static_cast<std::size_t>(pr[0])] != 0;
  vp.n0 = fr.in->rigid_normals[vi];
  vp.anchor = vp.p0;
  vp.width = m.primitives.propagation_width;
  vp.ncand = 0;
  vp.overflow = false;
  vp.last_point = glm::vec3(NAN);
  vp.hard_point = glm::vec3(NAN);
  // The faded own surface: w_v D_v solved for T shifted by the share of the skinned
  // position's own excess (0 there for a fully faded vertex: its skinned position).
  vp.target = vp.iso;
  vp.faded = 0.0f;
  if (vp.cls != VertexClass::kFree) {
    const float keep = skinnedShare(fr, vi);
    vp.faded = keep;
    if (keep > 0.0f) {
      glm::vec3 grad;
      FieldValues lanes;
      vp.target += keep * ownExcess(vp, vp.p0, grad, lanes);
    }
  }
}

// Loads vertex v's cached candidates into vp with their material terms. with_bulge: use
// this frame's deepest penetrations (after pass A).
[[gnu::always_inline]] inline void loadCandidates(const DeformFrame& fr, int v, bool with_bulge,
                                                  VertexProblem& vp) {
  const DeformScratch& sc = *fr.sc;
  const auto vi = static_cast<std::size_t>(v);
  const int n = sc.cand_count[vi] & 0x7F;
  vp.overflow = (sc.cand_count[vi] & 0x80) != 0;
  vp.ncand = n;
  if (n == 0) return;
  const float k_self = ownStiffness(fr, v);
  const float amplitude = fr.opt->propagation ? fr.model->primitives.propagation_amplitude : 0.0f;
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    const std::size_t slot = vi * kMaxCandidates + static_cast<std::size_t>(i);
    const DeformScratch::CandidateSlot& cs = sc.candidates[slot];
    const int c = cs.collider;
    const DeformScratch::Collider& col = sc.colliders[static_cast<std::size_t>(c)];
    Candidate& cd = vp.cand[kept];
    cd.prim = col.posed;
    cd.collider = c;
    cd.lane = -1;
    for (int k = 0; k < 4 && vp.lanes != nullptr; ++k) {
      if (vp.own[k] == cd.prim) cd.lane = k;
    }
    // Relative deformability (a free vertex takes the whole contact of a partner it yields to;
    // so does an adopted one against its own body, see DeformScratch::adopted).
    const PartnerShare ps =
        partnerShare(k_self, col.posed->stiffness,
                     vp.cls == VertexClass::kFree || (vp.yields_own && col.body == fr.self));
    cd.share = ps.share;
    cd.hard = ps.hard;
    cd.rho = ps.rho;
    cd.omega = cs.omega;
    cd.iso = cs.iso;
    cd.x_rigid = cs.x_rigid;
    // A faded joint vertex's opposite limb is part of the own field it fades (DIFF's other
    // side): its crease starts from the skinned position's value, not from the rest one.
    if (vp.faded > 0.0f && vp.cls == VertexClass::kJoint && cd.prim == vp.own[2]) {
      const float excess = cd.omega * primitiveField(*cd.prim, vp.p0) - cd.iso;
      if (excess > 0.0f) cd.iso += vp.faded * excess;
    }
    const float pmax = std::bit_cast<float>(col.pmax_bits);
    // An adopted vertex does not bulge (see DeformScratch::adopted).
    const bool bulges =
        with_bulge && !vp.yields_own && (col.body != fr.self || fr.opt->self_propagation);
    cd.bulge = bulges ? propagationBulge(cd.share, vp.w, amplitude, pmax) : 0.0f;
    // Without a bulge only penetration and contact count: a candidate that stays outside
    // the partner's surface near the vertex contributes nothing.
    if (cd.bulge > 0.0f || cs.reach >= -kContactTolerance) ++kept;
  }
  vp.ncand = kept;
}

// The limit of relative deformability where the vertex's own field cannot answer a partner:
// every soft partner the vertex yields to (share > 0) becomes a hard constraint, as for a
// free vertex (partnerShare), so the vertex ends on that partner's skin. Returns whether any
// changed (and then forgets the cached evaluation points).
bool yieldWhole(VertexProblem& vp) {
  bool changed = false;
  for (int i = 0; i < vp.ncand; ++i) {
    Candidate& c = vp.cand[i];
    if (c.hard || !(c.share > 0.0f)) continue;
    c.hard = true;
    c.rho = 0.0f;
    changed = true;
  }
  if (changed) {
    vp.last_point = glm::vec3(NAN);
    vp.hard_point = glm::vec3(NAN);
  }
  return changed;
}

// Own part and cached candidates of vertex v.
void gatherProblem(const DeformFrame& fr, int v, bool with_bulge, VertexProblem& vp) {
  gatherOwn(fr, v, vp);
  loadCandidates(fr, v, with_bulge, vp);
}

}  // namespace

void gatherVertexProblem(const DeformFrame& fr, int v, bool with_bulge, VertexProblem& vp) {
  gatherProblem(fr, v, with_bulge, vp);
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

namespace {

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
inline float writeSolved(const DeformFrame& fr, int v, const glm::vec3& p0, const glm::vec3& dir,
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

}  // namespace

// (See vertex_solve.hpp.)
float skinnedShare(const DeformFrame& fr, std::size_t vi) {
  const std::vector<float>& own = fr.model->calibration.own_weight;
  const float lo = fr.opt->own_fade_low, hi = fr.opt->own_fade_high;
  if (own.empty() || !(hi > 0.0f) || own[vi] >= hi) return 0.0f;
  if (own[vi] <= lo || !(hi > lo)) return 1.0f;
  return (hi - own[vi]) / (hi - lo);
}

// Pass B's short way for the commonest solved vertex, the lone limb vertex: a limb vertex of
// one primitive (no bone), not fixed (DeformScratch::fixed_kind), that has no collider and no
// elastic memory this frame and is projected along its normal, as it was last frame (see
// solveLoneLimb). Its part that never changes (DeformScratch::lone_kind); passSolve tests the
// rest.
bool loneKind(const Calibration& cal, std::size_t vi, bool fixed) {
  const auto& pr = cal.prims[vi];
  return !fixed && cal.vertex_class[vi] == VertexClass::kLimb && pr[3] < 0 && pr[0] >= 0;
}

namespace {

// A lone limb vertex's equation w_v F_p0(p) - T, and its gradient.
[[gnu::flatten]] inline float loneEquation(const PosedPrimitive& prim, float w, float iso,
                                           const glm::vec3& p, glm::vec3& grad) {
  glm::vec3 g0;
  const float d = primitiveField(prim, p, &g0);
  grad = w * g0;
  return w * d - iso;
}

// The equation at a lone limb vertex's warm start: the first evaluation of its solve.
struct LoneStart {
  float g;
  glm::vec3 grad;
  float target;  // what w_v F_p0 is solved for (VertexProblem::target)
};
LoneStart loneStart(const DeformFrame& fr, std::size_t vi) {
  const Calibration& cal = fr.model->calibration;
  const PosedPrimitive& prim = fr.posed->items[static_cast<std::size_t>(cal.prims[vi][0])];
  LoneStart start;
  start.target = fr.model->primitives.iso;
  const float keep = skinnedShare(fr, vi);
  if (keep > 0.0f) {
    start.target += keep * (cal.w[vi] * primitiveField(prim, fr.in->rigid_positions[vi]) -
                            fr.model->primitives.iso);
  }
  start.g = loneEquation(prim, cal.w[vi], start.target,
                         fr.in->rigid_positions[vi] + fr.st->offset[vi] * fr.in->rigid_normals[vi],
                         start.grad);
  return start;
}

// Solves a lone limb vertex (see loneKind) from its first evaluation `start` (loneStart): its
// equation is w_v F_p0 - T alone, so it skips gathering a problem. Returns false, having
// changed nothing, where the full way is needed (the normal disagrees with the field's
// gradient, or finds no root); otherwise the result is the full way's, bit for bit.
bool solveLoneLimb(const DeformFrame& fr, int v, const LoneStart& start, DeformCounters& cnt) {
  const DeformState& st = *fr.st;
  const Calibration& cal = fr.model->calibration;
  const DeformOptions& opt = *fr.opt;
  const auto vi = static_cast<std::size_t>(v);
  const auto& pr = cal.prims[vi];
  const PosedPrimitive& prim = fr.posed->items[static_cast<std::size_t>(pr[0])];
  const float w = cal.w[vi];
  const float iso = start.target;
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
  if (res.found && std::abs(res.s) > moveAllowance(fr, vi, false)) {
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

}  // namespace

// Pass B: solve every vertex of [first, last).
void passSolve(DeformFrame& fr, int first, int last, DeformCounters& cnt) {
  DeformState& st = *fr.st;
  DeformScratch& sc = *fr.sc;
  const DeformOptions& opt = *fr.opt;
  VertexProblem vp;
  // The arrays the per-vertex test and the rigid vertices use, as locals: through the
  // vectors, every byte store (flags) would make the compiler load their addresses again.
  const float* const memory = st.memory.data();
  const std::uint8_t* const cand_count = sc.cand_count.data();
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
  std::uint8_t* const resting = sc.resting.data();
  const std::uint8_t* const fixed_kind = sc.fixed_kind.data();
  const auto is_fixed = [&](std::size_t vi) {
    return fixed_kind[vi] != 0 && memory[vi] == 0.0f && along_normal;
  };
  if (along_normal && !opt.reference) {
    for (int v = first; v < last; ++v) {
      resting[v] = static_cast<std::uint8_t>(fixed_kind[v] & (memory[v] == 0.0f ? 1 : 0) &
                                             ((cand_count[v] & 0x7F) == 0 ? 1 : 0));
    }
  } else {
    std::fill(resting + first, resting + last, std::uint8_t{0});
  }
  for (int v = first; v < last; ++v) offset[v] = resting[v] != 0 ? 0.0f : offset[v];
  if (sc.any_inelastic) {  // (an elastic vertex's free offset is never read)
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
  std::uint32_t* const work = sc.solve_list.data() + first;
  std::uint32_t* const lone = sc.lone_list.data() + first;
  const std::uint8_t* const lone_kind = sc.lone_kind.data();
  const std::uint8_t lone_way = along_normal && !opt.reference ? 1 : 0;
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
    // rigid position itself, whatever its last solution was. So is, nearly, an adopted
    // vertex's (its own field alone, calibrated through its skinned position), whose last
    // solution may lie beyond its small primitive's reach.
    if ((vp.cls == VertexClass::kFree || vp.yields_own) &&
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
    // No common surface within reach: the partner is deeper than the vertex's own field can
    // answer (a finger sunk whole into the hips). The vertex takes the whole contact, as a
    // free vertex does (yieldWhole), and ends on the partner's skin.
    if (!res.found && yieldWhole(vp)) {
      s_start = 0.0f;
      g = evaluate(vp, vp.p0, grad);
      ++cnt.evaluations;
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
      const bool bulging = std::any_of(vp.cand, vp.cand + vp.ncand,
                                       [](const Candidate& c) { return c.bulge > 0.0f; });
      const float limit = moveAllowance(fr, vi, bulging);
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
        partner = sc.colliders[static_cast<std::size_t>(vp.cand[c].collider)].body;
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
      const float tau =
          fr.model->primitives.items[static_cast<std::size_t>(fr.model->calibration.prims[vi][0])]
              .time_constant;
      const float m = updateElasticMemory(mode, st.memory[vi], c, fr.dt, tau);
      st.memory[vi] = m;
      st.free_offset[vi] = s_free;
      s_out = rememberedOffset(s_sol, s_free, m, c);
    }
    s_out = writeSolved(fr, v, vp.p0, dir, s_sol, s_out, flags, partner, cnt);
    if ((vertex_flags[vi] & kVertexContact) != 0) {  // for passContacts, in vertex order
      sc.contact_list[static_cast<std::size_t>(first + cnt.contact_vertices - 1)] =
          static_cast<std::uint32_t>(v);
    }
    const bool relax = opt.relax_passes > 0 && (flags & (kVertexUnsolved | kVertexHeld)) == 0 &&
                       vp.cls == VertexClass::kJoint &&
                       (std::abs(s_out) > opt.relax_min_offset || (flags & kVertexGradient) != 0);
    if (relax) {
      st.flags[vi] |= kVertexRelaxed;
      sc.relax_list[static_cast<std::size_t>(first + cnt.relaxed_vertices)] =
          static_cast<std::uint32_t>(v);
      if (!opt.reference) {  // (the reference way gathers it again)
        keepProblem(sc,
                    sc.joint_prefix[static_cast<std::size_t>(first)] +
                        static_cast<std::size_t>(cnt.relaxed_vertices),
                    vp, gathered_ncand);
      }
      ++cnt.relaxed_vertices;
      sc.field_gradient[vi] = gradientNear(vp, st.positions[vi], opt.root.final_step);
    }
  }
}

// How far vertex v may end from its skinned position (DeformOptions::move_margin): its drift
// from where each of its own primitives' bones alone would carry its rest position (its
// own field, calibrated at rest, moves with those bones, so it can ask for no more), its
// rigid-pose penetration, plus the margin; and the bulge this frame allows where a partner
// near it bulges it (`bulging`) or it penetrates one (the common surface, split in field
// units, may lie beyond the first-order depth). Infinite when moves are not bounded.
float moveAllowance(const DeformFrame& fr, std::size_t vi, bool bulging) {
  const DeformOptions& opt = *fr.opt;
  if (opt.move_margin < 0.0f || fr.in->rest_positions.empty()) return INFINITY;
  const glm::vec4 rest(fr.in->rest_positions[vi], 1.0f);
  const glm::vec3 p = fr.in->rigid_positions[vi];
  float drift = 0.0f;
  for (const std::int16_t prim : fr.model->calibration.prims[vi]) {
    if (prim < 0) continue;
    const glm::vec3 carried(fr.sc->prim_to_world[static_cast<std::size_t>(prim)] * rest);
    drift = std::max(drift, glm::length(p - carried));
  }
  const float depth = fr.st->depth[vi];
  const bool slack = bulging || depth > 0.0f;
  return drift + depth + (slack ? fr.sc->bulge_allowance : 0.0f) + opt.move_margin;
}

// The move bound once more after relaxation and smoothing, which move vertices the solve
// bounded: a vertex they carried beyond its allowance is pulled back along its correction.
void boundRelaxedMoves(DeformFrame& fr) {
  DeformState& st = *fr.st;
  if (fr.opt->move_margin < 0.0f || fr.in->rest_positions.empty()) return;
  const bool bulging =
      fr.opt->self_propagation || std::any_of(fr.sc->colliders.begin(), fr.sc->colliders.end(),
                                              [&](const auto& c) { return c.body != fr.self; });
  for (std::size_t v = 0; v < static_cast<std::size_t>(fr.nvert); ++v) {
    if ((st.flags[v] & (kVertexRelaxed | kVertexSmoothed)) == 0) continue;
    const glm::vec3 c = st.positions[v] - fr.in->rigid_positions[v];
    const float len = glm::length(c);
    const float limit = moveAllowance(fr, v, bulging);
    if (len > limit) st.positions[v] = fr.in->rigid_positions[v] + c * (limit / len);
  }
}

}  // namespace vistel
