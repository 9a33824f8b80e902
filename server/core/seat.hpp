// Where members stand in a room (proto/SESSION.md §2 "Seats"): seat i on a circle facing
// its centre; the placement takes an avatar's model space to room space.
#pragma once

#include <glm/glm.hpp>

namespace vistel::server {

struct SeatPlacement {
  float x = 0.0f;
  float z = 0.0f;
  float yaw = 0.0f;  // radians about +Y; the avatar faces +Z at 0
};

// Where seat `index` of a room stands: on a circle of `radius` metres (a second, wider
// ring past 16 seats), facing the centre. Seats fill in an order that spreads people
// out: two members face each other, four form a square.
SeatPlacement seatPlacement(int index, float radius);

// Model space -> room space: T(x, 0, z) * R_y(yaw), as every client places the avatar.
glm::mat4 seatTransform(const SeatPlacement& seat);

}  // namespace vistel::server
