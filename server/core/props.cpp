#include "server/core/props.hpp"

#include <cmath>

namespace vistel::server {

Status validatePropSpec(const PropSpec& s) {
  const BallSpec& b = s.ball;
  if (!(b.radius >= 0.01f && b.radius <= 2.0f)) {
    return fail("ball radius {} m out of range [0.01, 2]", b.radius);
  }
  if (!(b.reach >= 1.05f && b.reach <= 4.0f)) {
    return fail("ball field reach {} out of range [1.05, 4] (support radius / radius)", b.reach);
  }
  if (!(b.stiffness > 0.0f)) return fail("ball stiffness {} must be positive", b.stiffness);
  if (!(b.time_constant > 0.0f) || !std::isfinite(b.time_constant)) {
    return fail("ball time constant {} s must be positive", b.time_constant);
  }
  if (static_cast<int>(b.elasticity) > 2) return fail("ball elasticity: unknown kind");
  if (!(s.mass >= 0.001f && s.mass <= 1000.0f)) {
    return fail("ball mass {} kg out of range [0.001, 1000]", s.mass);
  }
  if (!(s.restitution >= 0.0f && s.restitution <= 1.0f)) {
    return fail("ball restitution {} out of range [0, 1]", s.restitution);
  }
  return {};
}

BallState ballState(const PropSpec& spec, const glm::vec3& position, const glm::vec3& velocity) {
  BallState b;
  b.position = position;
  b.velocity = velocity;
  b.radius = spec.ball.radius;
  b.mass = spec.mass;
  b.restitution = spec.restitution;
  b.stiffness = spec.ball.stiffness;
  return b;
}

}  // namespace vistel::server
