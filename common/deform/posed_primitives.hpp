// Posing primitives (per frame): each primitive carried by its bone's skinning transform
// into world space, with what its field needs and its bounding volume (DESIGN.md §3).
//
// Field of a posed primitive i: F_i(P) = W * f(d), d = skeletonDistance(P) / r_out,
// zero for d >= 1 (outside the bound), falling off outward (F > iso means inside).
#pragma once

#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "common/deform/implicit_model.hpp"

namespace vistel {

struct PosedPrimitive {
  Shape shape;             // world space, prepared
  float inv_r_out = 1.0f;  // 1 / r_out (skeleton-distance units)
  float surface = 0.5f;    // r_in: the skeleton distance of its own surface F_i = T
  float weight = 1.0f;     // W
  Density density;
  float stiffness = 3.0e4f;  // Pa per metre; infinity = rigid
  Bounds bounds;             // world box of the field's support
  float reach = 0.0f;        // metres from the skeleton to the support's edge
  PrimitiveRole role = PrimitiveRole::kLimb;
  bool collides = true;
  const SkinWeightGrid* skin_weight = nullptr;  // its Primitive's (null: none); the set must
                                                // outlive the posed copy
  float max_skin_weight = 1.0f;                 // the grid's largest value
  glm::mat4 to_bind{1.0f};                      // world -> bind-pose model space
};

// One body's posed primitives (sized once from its PrimitiveSet; reused every frame).
struct PosedPrimitives {
  std::vector<PosedPrimitive> items;  // (nprim) world space
  Bounds bounds;                      // union of the items' boxes
};

// Poses every primitive with skin_xforms[bone]: the skinning matrices (bind-pose model
// space -> posed model space, see skinningMatrices()) premultiplied by the body's
// placement in the world, so the result is in world space. skin_xforms.size() must exceed
// every bone index (checked by validatePrimitiveSet). Resizes `out` on first use only.
// Cost: O(nprim).
void posePrimitives(const PrimitiveSet& set, std::span<const glm::mat4> skin_xforms,
                    PosedPrimitives& out);

// One primitive carried by one transform (rest posture: the identity).
PosedPrimitive posePrimitive(const Primitive& primitive, const glm::mat4& xform);

// F_i at the point whose skeleton offset is d, with its scale (skeletonOffset), and optionally
// its gradient (zero outside the support and on the skeleton). From the squared skeleton
// distance: no square root for the Wyvill profile.
inline float fieldAtOffset(const PosedPrimitive& prim, const glm::vec3& d, float scale,
                           glm::vec3* gradient = nullptr) {
  const float s = scale * prim.inv_r_out;
  const float s2 = s * s;
  const float u = glm::dot(d, d) * s2;  // (distance / r_out)^2
  if (u >= 1.0f) {
    if (gradient != nullptr) *gradient = glm::vec3(0.0f);
    return 0.0f;
  }
  float fu = 0.0f;
  const float f = densityValueSquared(prim.density, u, gradient != nullptr ? &fu : nullptr);
  if (gradient != nullptr) *gradient = (2.0f * prim.weight * fu * s2) * d;
  return prim.weight * f;
}

// F_i(p) and, optionally, its gradient (fieldAtOffset).
inline float primitiveField(const PosedPrimitive& prim, const glm::vec3& p,
                            glm::vec3* gradient = nullptr) {
  float scale;
  const glm::vec3 d = skeletonOffset(prim.shape, p, scale);
  return fieldAtOffset(prim, d, scale, gradient);
}

// Where p's ray from the skeleton (from its closest skeleton point through p) crosses the
// shell at skeleton distance r_out / 2: the point at which the primitive's skin weight is
// looked up for p, so that the weight is constant along every ray (a partner point deep
// inside meets the weight of the skin above it). p itself on the skeleton. d and scale:
// p's skeleton offset and its scale (skeletonOffset).
inline glm::vec3 skinWeightKey(const PosedPrimitive& prim, const glm::vec3& p, const glm::vec3& d,
                               float scale) {
  const float r = std::sqrt(glm::dot(d, d)) * scale * prim.inv_r_out;  // distance / r_out
  if (!(r > 0.0f)) return p;
  return p + (0.5f / r - 1.0f) * d;
}

// w_i(p): the calibration weight of the primitive's own skin on p's ray from the skeleton
// (1 without a grid). A partner vertex meets that skin where w_i F_i = T. The overload
// takes p's skeleton offset and scale when the caller has them.
inline float skinWeight(const PosedPrimitive& prim, const glm::vec3& p, const glm::vec3& d,
                        float scale) {
  if (prim.skin_weight == nullptr) return 1.0f;
  const glm::vec3 key = skinWeightKey(prim, p, d, scale);
  return skinWeightAt(*prim.skin_weight, glm::vec3(prim.to_bind * glm::vec4(key, 1.0f)));
}
inline float skinWeight(const PosedPrimitive& prim, const glm::vec3& p) {
  if (prim.skin_weight == nullptr) return 1.0f;
  float scale;
  const glm::vec3 d = skeletonOffset(prim.shape, p, scale);
  return skinWeight(prim, p, d, scale);
}

// The skeleton distance (skeleton-distance units, as `surface`) of the primitive's skin on a
// ray whose skin weight is w (skinWeight): where w W f(s / r_out) = T. Without a grid (w = 1)
// that is `surface`, the raw iso-surface at r_in; a calibrated primitive's skin lies farther
// out where w > 1 and nearer where w < 1. 0 when w W <= T (no skin on the ray: the field
// never reaches T). Cost: a few multiplications and one short Newton solve (the Wyvill
// profile; others bisect).
float skinSurfaceDistance(const PosedPrimitive& prim, float w);

// Whether p lies in the primitive's world box (a cheap reject before primitiveField).
inline bool inBounds(const PosedPrimitive& prim, const glm::vec3& p) {
  return p.x >= prim.bounds.min.x && p.x <= prim.bounds.max.x && p.y >= prim.bounds.min.y &&
         p.y <= prim.bounds.max.y && p.z >= prim.bounds.min.z && p.z <= prim.bounds.max.z;
}

}  // namespace vistel
