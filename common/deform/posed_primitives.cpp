#include "common/deform/posed_primitives.hpp"

#include <cassert>

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
