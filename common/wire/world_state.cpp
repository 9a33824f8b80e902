#include "common/wire/world_state.hpp"

#include <algorithm>
#include <cmath>

namespace vistel::wire {
namespace {

std::int16_t quantize(float value, float unit) {
  if (!std::isfinite(value)) return 0;
  const float units = std::round(value / unit);
  return static_cast<std::int16_t>(std::clamp(units, -32767.0f, 32767.0f));
}

}  // namespace

PropStateRecord encodePropState(std::uint32_t prop_id, const glm::vec3& position,
                                const glm::vec3& velocity) {
  PropStateRecord p;
  p.prop_id = prop_id;
  for (int k = 0; k < 3; ++k) {
    p.position_mm[static_cast<std::size_t>(k)] = quantize(position[k], kPropPositionUnit);
    p.velocity_mm_s[static_cast<std::size_t>(k)] = quantize(velocity[k], kPropVelocityUnit);
  }
  return p;
}

glm::vec3 propPosition(const PropStateRecord& p) {
  return glm::vec3(p.position_mm[0], p.position_mm[1], p.position_mm[2]) * kPropPositionUnit;
}

glm::vec3 propVelocity(const PropStateRecord& p) {
  return glm::vec3(p.velocity_mm_s[0], p.velocity_mm_s[1], p.velocity_mm_s[2]) * kPropVelocityUnit;
}

}  // namespace vistel::wire
