// Where the members of a room stand (proto/SESSION.md §2 "Seats"): concentric rings about
// the room's centre, every seat facing it. Ring k has radius first_radius_m + k *
// ring_gap_m and as many seats as fit at spacing_m apart along it (at least one); odd
// rings are turned by half a seat so that a back row looks between the people in front.
// Within a ring the seats fill in an order that spreads the first comers (the first two
// face each other, and so do the next two), ring after ring. Room space: metres, +Y up, floor
// at y = 0; an avatar's model space faces +Z and is placed by seatTransform.
//
// The layout is shared by the server (which assigns seats) and by clients and benches
// that lay out a room the same way. Pure arithmetic: O(seats on the seat's ring) per
// call, no allocation.
#pragma once

#include <glm/glm.hpp>

#include "common/base/result.hpp"

namespace vistel {

struct SeatLayout {
  float first_radius_m = 1.5f;  // the innermost ring
  float spacing_m = 1.5f;       // at least this far apart along a ring (centre to centre)
  float ring_gap_m = 1.0f;      // between one ring and the next
};

// A layout a room can use: every length finite and positive, spacing below the
// circumference of the first ring; the error names the key.
Status validateSeatLayout(const SeatLayout& layout);

struct SeatPlacement {
  float x = 0.0f;
  float z = 0.0f;
  float yaw = 0.0f;  // radians about +Y, in (-pi, pi]; the avatar faces +Z at 0
};

// Seats on ring `ring` (0 = innermost).
int seatsOnRing(int ring, const SeatLayout& layout);

// Where seat `index` (0, 1, ...: the order in which seats are handed out) stands. Any
// index >= 0 has a seat; two different indices never share a place, and neighbours on a
// ring are at least spacing_m apart, rings ring_gap_m apart.
SeatPlacement seatPlacement(int index, const SeatLayout& layout);

// Model space -> room space: T(x, 0, z) * R_y(yaw), as every client places the avatar.
glm::mat4 seatTransform(const SeatPlacement& seat);

}  // namespace vistel
