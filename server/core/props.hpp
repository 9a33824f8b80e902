// Props of the shared room (DESIGN.md §6): rigid or soft bodies with their own primitives
// and dynamics, owned by the room. Version 1 has one kind, the ball: a sphere primitive
// (common/deform/prop.hpp makeBallPrimitives) stepped by stepBall from the posed
// primitives of everyone in the room.
//
// Units: metres, kilograms, seconds, pascals per metre; room space (+Y up, floor at y = 0
// unless configured).
#pragma once

#include <glm/glm.hpp>

#include "common/base/result.hpp"
#include "common/deform/prop.hpp"

namespace vistel::server {

// What every client needs to know of a ball once (sent in the Roster): its shape and
// material; the per-tick state travels in snapshots.
struct PropSpec {
  BallSpec ball;              // radius, stiffness, elasticity, time constant, field reach
  float mass = 0.43f;         // kg
  float restitution = 0.75f;  // rebound speed / impact speed, [0, 1]
};

// Checks every field (the message names it): radius 0.01..2 m, reach 1.05..4, stiffness
// > 0 (or rigid), time constant > 0, mass 0.001..1000 kg, restitution in [0, 1].
Status validatePropSpec(const PropSpec& spec);

// The dynamic state of a ball with this spec at a position and velocity.
BallState ballState(const PropSpec& spec, const glm::vec3& position, const glm::vec3& velocity);

}  // namespace vistel::server
