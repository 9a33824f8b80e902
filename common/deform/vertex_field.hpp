// The per-vertex function D_v (DESIGN.md §3 "Per-vertex function"), shared by Step 2,
// calibration and tests:
//   limb vertex:  D_v(P) = F_p0(P)                       (+ F_bone(P))
//   joint vertex: D_v(P) = F_p0(P) + DIFF(F_p1, F_p2)(P)  (+ F_bone(P)), p0 the joint
//   DIFF(a, b) = |a^n - b^n|^(1/n): near zero where the two limbs' fields are equal, which
//   pulls the surface in and forms the crease.
// Free vertices have no D_v (their own field is planar, see VertexClass::kFree).
#pragma once

#include <cmath>

#include <glm/glm.hpp>

#include "common/deform/implicit_model.hpp"
#include "common/deform/posed_primitives.hpp"

namespace vistel {

// a^n for small positive integer n (multiplied left to right; n = 3, DIFF's usual a^(n-1),
// without the loop).
inline float powInt(float a, int n) {
  if (n == 3) return a * a * a;
  float r = 1.0f;
  for (int i = 0; i < n; ++i) r *= a;
  return r;
}

// DIFF(a, b) with gradient from the two fields' gradients.
inline float diffField(float a, const glm::vec3& ga, float b, const glm::vec3& gb, int n,
                       glm::vec3* gradient) {
  const float an1 = powInt(a, n - 1);
  const float bn1 = powInt(b, n - 1);
  const float x = an1 * a - bn1 * b;
  const float ax = std::abs(x);
  float d;
  if (n == 1) {
    d = ax;
  } else if (n == 2) {
    d = std::sqrt(ax);
  } else if (n == 4) {
    d = std::sqrt(std::sqrt(ax));
  } else {
    d = std::pow(ax, 1.0f / static_cast<float>(n));
  }
  if (gradient != nullptr) {
    // d/da = a^(n-1) d / x (sign included); singular where x = 0 (there d = 0).
    *gradient = x != 0.0f ? (d / x) * (an1 * ga - bn1 * gb) : glm::vec3(0.0f);
  }
  return d;
}

// The side results of assembleDensity for Step 2 (vertex_solve.hpp): the vertex's own side
// without the crease, F_p0 + F_p1 + F_bone (a limb vertex: F_p0 + F_bone), and its gradient.
// DIFF's gradient is singular where the two limbs' fields are equal; the opposite limb's field
// points out of that limb, not out of the vertex's skin.
struct OwnSide {
  float value = 0.0f;
  glm::vec3 gradient{0.0f};
};

// D_v(P) of a limb or joint vertex (no w_v), the one place it is assembled: field(k, g) returns
// F of the vertex's own primitive k at P (0: p0, the limb or the joint; 1, 2: a joint's two
// limbs; 3: the bone) and, where g is not null, writes its gradient there. The gradient of D_v
// goes to `gradient` and the own side to `own` where they are not null. The sums run in a
// fixed order (p0, DIFF, bone), so every caller gets the same bits.
template <typename Field>
inline float assembleDensity(VertexClass cls, bool has_bone, int diff_exponent, Field&& field,
                             glm::vec3* gradient, OwnSide* own = nullptr) {
  const bool want = gradient != nullptr || own != nullptr;
  glm::vec3 g0(0.0f);
  float d = field(0, want ? &g0 : nullptr);
  float side = d;
  glm::vec3 smooth = g0;
  if (cls == VertexClass::kJoint) {
    glm::vec3 ga(0.0f), gb(0.0f), gd(0.0f);
    const float fa = field(1, want ? &ga : nullptr);
    const float fb = field(2, want ? &gb : nullptr);
    d += diffField(fa, ga, fb, gb, diff_exponent, want ? &gd : nullptr);
    g0 += gd;
    smooth += ga;
    side += fa;
  }
  if (has_bone) {
    glm::vec3 gbone(0.0f);
    const float fbone = field(3, want ? &gbone : nullptr);
    d += fbone;
    g0 += gbone;
    smooth += gbone;
    side += fbone;
  }
  if (gradient != nullptr) *gradient = g0;
  if (own != nullptr) {
    own->value = side;
    own->gradient = smooth;
  }
  return d;
}

// D_v(P) of a limb or joint vertex from its primitives' posed copies (no w_v).
inline float vertexDensity(VertexClass cls, const PosedPrimitive* p0, const PosedPrimitive* p1,
                           const PosedPrimitive* p2, const PosedPrimitive* bone, int diff_exponent,
                           const glm::vec3& p, glm::vec3* gradient) {
  const PosedPrimitive* const own[4] = {p0, p1, p2, bone};
  return assembleDensity(
      cls, bone != nullptr, diff_exponent,
      [&own, &p](int k, glm::vec3* g) { return primitiveField(*own[k], p, g); }, gradient);
}

// Convenience for calibration and tests: D_v of vertex v of a model, primitives posed.
// Returns 0 for free vertices.
inline float vertexDensity(const ImplicitModel& model, const PosedPrimitives& posed, int v,
                           const glm::vec3& p, glm::vec3* gradient = nullptr) {
  const Calibration& c = model.calibration;
  const auto& pr = c.prims[static_cast<std::size_t>(v)];
  const VertexClass cls = c.vertex_class[static_cast<std::size_t>(v)];
  if (cls == VertexClass::kFree) {
    if (gradient != nullptr) *gradient = glm::vec3(0.0f);
    return 0.0f;
  }
  const auto at = [&](std::int16_t i) {
    return i >= 0 ? &posed.items[static_cast<std::size_t>(i)] : nullptr;
  };
  return vertexDensity(cls, at(pr[0]), at(pr[1]), at(pr[2]), at(pr[3]),
                       model.primitives.diff_exponent, p, gradient);
}

}  // namespace vistel
