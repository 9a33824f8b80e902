// The collision terms of Step 2 (DESIGN.md §3 "Collision terms"), after Gascuel 1993, "An
// implicit formulation for precise contact modeling between flexible solids": each a function
// named after the paper's concept, so that the vertex solve (vertex_solve.hpp) and pass A
// (penetration_pass.cpp) read as the paper.
//   penetration and propagation zones: collisionTerm
//   the bulge's amplitude from p_max:   propagationBulge, bulgeAllowance
//   relative deformability lambda:      shareOf, partnerShare
//   reaction pressure:                  effectiveStiffness, contactPressure
//   elastic memory:                     updateElasticMemory, rememberedOffset
// Field units (the implicit functions' values, dimensionless) unless stated; stiffness in Pa
// per metre (infinity: rigid); metres and seconds. Every function is a few operations, pure,
// allocation-free; the order of the floating-point operations is part of the contract (the
// fast and reference paths of deformSkin must agree bit for bit where they share a term).
#pragma once

#include <algorithm>
#include <cmath>

#include "common/deform/implicit_model.hpp"

namespace vistel {

// A solved offset (metres) below this is zero: the vertex stays exactly rigid, and an elastic
// memory this small is forgotten.
inline constexpr float kSnapOffset = 1e-7f;

// One collision term COLL_i,v of DESIGN.md §3 in field units, as a function of
// x = omega * F_i(P) - iso_pair (omega = w_i, the partner's skin weight near the vertex,
// for a deformable partner, so x = 0 on the partner's skin; 1 for a rigid one):
//   penetration zone (x > 0):          COLL = -x (so F = T where w_v D_v = omega F_i)
//   propagation zone (-width < x <= 0): COLL = bulge * h(-x / width), h(s) = 27/4 s (1-s)^2
//   elsewhere:                          0.
// Continuous at both borders (x = 0 and x = -width). Step 2 weighs the penetration part
// by relative deformability, lambda = k_v / (k_v + k_i) (k: the primitives' stiffness):
// for lambda > 0 it solves
//   (w_v D_v - T + bulges) - rho * max(0, x) = 0,  rho = (1 - lambda) / lambda
// (one partner: lambda (w_v D_v - T) = (1 - lambda) x; lambda = 1/2 is the paper's common
// surface, lambda = 1 leaves the vertex undeformed); a rigid partner (lambda = 0) is a
// hard constraint x <= 0 solved after, which puts the vertex exactly on its surface.
// A free vertex (no field of its own for the partner to meet) treats every soft partner
// as rigid: it ends on the partner's skin.
// bulge = propagationBulge(...) (see there).
inline float collisionTerm(float x, float bulge, float width, float* derivative = nullptr) {
  if (x > 0.0f) {
    if (derivative != nullptr) *derivative = -1.0f;
    return -x;
  }
  if (x > -width && bulge > 0.0f) {
    const float s = -x / width;
    if (derivative != nullptr)
      *derivative = -bulge * 6.75f * (1.0f - s) * (1.0f - 3.0f * s) / width;
    return bulge * 6.75f * s * (1.0f - s) * (1.0f - s);
  }
  if (derivative != nullptr) *derivative = 0.0f;
  return 0.0f;
}

// The propagation zone's amplitude for a vertex (field units): the bulge grows with how deep
// the bodies interpenetrate, p_max the deepest x of this partner over the body's rigid vertices
// this frame (pass A), a the set's propagation amplitude; the vertex's share (1 - lambda) of
// the contact and its weight w_v scale it, and 2 makes the paper's equal split (share 1/2)
// the identity: bulge = 2 (1 - lambda) w_v a p_max.
inline float propagationBulge(float share, float w, float amplitude, float p_max) {
  return 2.0f * share * w * amplitude * p_max;
}

// The farthest any vertex may bulge this frame (metres): the largest bulge a vertex of unit
// weight taking the whole contact could get from the deepest rigid-pose penetration (metres),
// the same form as propagationBulge.
inline float bulgeAllowance(float amplitude, float deepest) { return 2.0f * amplitude * deepest; }

// Relative deformability: 1 - lambda, lambda = k_self / (k_self + k_other), the share of a
// contact that the vertex (stiffness k_self) takes against a partner of stiffness k_other.
// Two rigid bodies split it equally; a rigid vertex takes none of it; against a rigid partner
// it takes it all.
inline float shareOf(float k_self, float k_other) {
  const bool rigid_self = std::isinf(k_self);
  const bool rigid_other = std::isinf(k_other);
  if (rigid_self && rigid_other) return 0.5f;
  if (rigid_self) return 0.0f;
  if (rigid_other) return 1.0f;
  return k_other / (k_self + k_other);
}

// How a vertex meets one partner in Step 2's equation (see collisionTerm).
struct PartnerShare {
  float share = 0.5f;  // 1 - lambda (shareOf)
  bool hard = false;   // lambda = 0, or a free vertex against any partner it yields to: a
                       // constraint x <= 0 enforced after the soft solve
  float rho = 1.0f;    // (1 - lambda) / lambda: the penetration term's weight (0 when hard)
};
inline PartnerShare partnerShare(float k_self, float k_other, bool free_vertex) {
  PartnerShare s;
  s.share = shareOf(k_self, k_other);
  // A free vertex has no field for the partner to meet: it takes the whole contact.
  s.hard = s.share == 1.0f || (free_vertex && s.share > 0.0f);
  s.rho = s.hard ? 0.0f : s.share / (1.0f - s.share);
  return s;
}

// The stiffness of a contact between two bodies (springs in series), Pa per metre; two rigid
// bodies get 1e9.
inline float effectiveStiffness(float k_self, float k_other) {
  const bool rigid_self = std::isinf(k_self);
  const bool rigid_other = std::isinf(k_other);
  if (rigid_self && rigid_other) return 1e9f;
  if (rigid_self) return k_other;
  if (rigid_other) return k_self;
  return k_self * k_other / (k_self + k_other);
}

// Reaction pressure of a vertex penetrating `depth` metres in the rigid pose (Pa): the
// contact's stiffness times the depth. Step 3 sums it over faces into forces.
inline float contactPressure(float k_self, float k_other, float depth) {
  return effectiveStiffness(k_self, k_other) * depth;
}

// Elastic memory, per vertex of a plastic or viscoelastic body: the contact offset it keeps
// (metres, <= 0: dents only, bulges stay elastic). Given the last frame's `memory` and this
// frame's contact offset c = s_sol - s_free (the solution's offset from the free solution,
// without collision terms), returns the new memory: pressing in follows the contact at once;
// a plastic dent then stays; a viscoelastic one decays towards the contact's as
// exp(-dt / tau) and is forgotten below kSnapOffset. `tau` is read only for viscoelastic.
inline float updateElasticMemory(Elasticity mode, float memory, float c, float dt, float tau) {
  const float target = std::min(c, 0.0f);
  float m = memory;
  if (target < m) {
    m = target;  // pressing in follows the contact at once
  } else if (mode == Elasticity::kViscoelastic) {
    m = target + (m - target) * std::exp(-dt / tau);
    if (m > -kSnapOffset) m = 0.0f;
  }
  return m;
}

// Where a vertex with elastic memory `memory` ends along its projection line: its free
// solution s_free offset by the deeper of the memory and this frame's contact offset c; a
// vertex without memory (0) ends at its solution s_sol.
inline float rememberedOffset(float s_sol, float s_free, float memory, float c) {
  return memory < 0.0f ? s_free + std::min(memory, c) : s_sol;
}

}  // namespace vistel
