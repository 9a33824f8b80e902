#include "server/core/seat.hpp"

#include <cmath>
#include <numbers>

#include <glm/gtc/matrix_transform.hpp>

namespace vistel::server {
namespace {

constexpr int kSeatsPerRing = 16;

// Bit-reversal of a 4-bit seat number: 0, 8, 4, 12, 2, ... spreads the first comers.
int spreadOrder(int i) {
  int r = 0;
  for (int b = 0; b < 4; ++b) r |= ((i >> b) & 1) << (3 - b);
  return r;
}

}  // namespace

SeatPlacement seatPlacement(int index, float radius) {
  const int ring = index / kSeatsPerRing;
  const float r = radius * (1.0f + 0.6f * static_cast<float>(ring));
  const float theta = 2.0f * std::numbers::pi_v<float> *
                      static_cast<float>(spreadOrder(index % kSeatsPerRing)) /
                      static_cast<float>(kSeatsPerRing);
  SeatPlacement s;
  s.x = r * std::sin(theta);
  s.z = r * std::cos(theta);
  s.yaw = theta + std::numbers::pi_v<float>;  // +Z turned to face the centre
  if (s.yaw > std::numbers::pi_v<float>) s.yaw -= 2.0f * std::numbers::pi_v<float>;
  return s;
}

glm::mat4 seatTransform(const SeatPlacement& seat) {
  return glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(seat.x, 0.0f, seat.z)), seat.yaw,
                     glm::vec3(0.0f, 1.0f, 0.0f));
}

}  // namespace vistel::server
