#include "common/deform/posed_primitives.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include <glm/gtc/matrix_inverse.hpp>

namespace vistel {

PosedPrimitive posePrimitive(const Primitive& p, const glm::mat4& xform) {
  PosedPrimitive out;
  out.shape = transformShape(p.shape, xform);
  out.inv_r_out = 1.0f / p.r_out;
  out.surface = p.r_in;
  out.weight = p.weight;
  out.density = p.density;
  out.stiffness = p.stiffness;
  out.bounds = shapeBounds(out.shape, p.r_out);
  out.reach = metricReach(out.shape, p.r_out);
  out.role = p.role;
  out.collides = p.collides;
  if (p.skin_weight.n >= 2) {
    out.skin_weight = &p.skin_weight;
    out.max_skin_weight = p.skin_weight.max_value;
    out.to_bind = glm::affineInverse(xform);
  }
  return out;
}

float skinSurfaceDistance(const PosedPrimitive& p, float w) {
  if (w == 1.0f) return p.surface;
  // T / (w W) = f(r_in / r_out) / w: the profile's value at the skin on this ray.
  const float r_out = 1.0f / p.inv_r_out;
  const float target = densityValue(p.density, p.surface * p.inv_r_out) / w;
  if (!(target < 1.0f)) return 0.0f;
  if (!(target > 0.0f)) return r_out;
  double u = 0.0;
  if (densityInverseSquared(p.density, target, u)) {
    return r_out * static_cast<float>(std::sqrt(std::clamp(u, 0.0, 1.0)));
  }
  // Any other profile: bisection on the decreasing f(r).
  float lo = 0.0f, hi = 1.0f;
  for (int i = 0; i < 40; ++i) {
    const float mid = 0.5f * (lo + hi);
    if (densityValue(p.density, mid) > target) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return r_out * 0.5f * (lo + hi);
}

void posePrimitives(const PrimitiveSet& set, std::span<const glm::mat4> skin_xforms,
                    PosedPrimitives& out) {
  if (out.items.size() != set.items.size()) out.items.resize(set.items.size());
  for (std::size_t i = 0; i < set.items.size(); ++i) {
    const Primitive& p = set.items[i];
    assert(static_cast<std::size_t>(p.bone) < skin_xforms.size());
    out.items[i] = posePrimitive(p, skin_xforms[static_cast<std::size_t>(p.bone)]);
    const Bounds& b = out.items[i].bounds;
    out.bounds.min = i == 0 ? b.min : glm::min(out.bounds.min, b.min);
    out.bounds.max = i == 0 ? b.max : glm::max(out.bounds.max, b.max);
  }
}

}  // namespace vistel
