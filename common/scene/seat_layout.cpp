#include "common/scene/seat_layout.hpp"

#include <algorithm>
#include <bitset>
#include <cmath>
#include <cstdint>
#include <numbers>

#include <glm/gtc/matrix_transform.hpp>

namespace vistel {
namespace {

constexpr float kPi = std::numbers::pi_v<float>;
constexpr int kMaxSeatsPerRing = 8192;

// The van der Corput sequence in base 2: 0, 1/2, 1/4, 3/4, 1/8, ... (t's bits mirrored
// about the binary point), each new term halving the largest gap left.
double vanDerCorput(std::uint32_t t) {
  double value = 0.0;
  double weight = 0.5;
  for (; t != 0; t >>= 1, weight *= 0.5) {
    if ((t & 1u) != 0) value += weight;
  }
  return value;
}

// The slot (0..n-1 around the ring) that the m-th comer to a ring of n seats takes: the
// slots nearest the van der Corput points, first come first served.
int spreadSlot(int m, int n) {
  std::bitset<kMaxSeatsPerRing> taken;
  int found = 0;
  for (std::uint32_t t = 0;; ++t) {
    const int slot = static_cast<int>(std::lround(vanDerCorput(t) * n)) % n;
    if (taken[static_cast<std::size_t>(slot)]) continue;
    if (found == m) return slot;
    taken[static_cast<std::size_t>(slot)] = true;
    ++found;
  }
}

}  // namespace

Status validateSeatLayout(const SeatLayout& layout) {
  const auto positive = [](float v) { return std::isfinite(v) && v > 0.0f && v <= 1000.0f; };
  if (!positive(layout.first_radius_m)) {
    return fail("seat layout: first ring radius {} m must be in (0, 1000]", layout.first_radius_m);
  }
  if (!positive(layout.spacing_m)) {
    return fail("seat layout: seat spacing {} m must be in (0, 1000]", layout.spacing_m);
  }
  if (!positive(layout.ring_gap_m)) {
    return fail("seat layout: ring gap {} m must be in (0, 1000]", layout.ring_gap_m);
  }
  if (layout.spacing_m >= 2.0f * kPi * layout.first_radius_m) {
    return fail("seat layout: seat spacing {} m does not fit twice on the first ring ({} m round)",
                layout.spacing_m, 2.0f * kPi * layout.first_radius_m);
  }
  return {};
}

int seatsOnRing(int ring, const SeatLayout& layout) {
  const float radius = layout.first_radius_m + static_cast<float>(ring) * layout.ring_gap_m;
  // n seats on a circle of radius r are 2 r sin(pi / n) apart (the chord).
  int n = static_cast<int>(std::floor(2.0f * kPi * radius / layout.spacing_m));
  while (n > 1 && 2.0f * radius * std::sin(kPi / static_cast<float>(n)) < layout.spacing_m) --n;
  // An even count, so that the first two comers of a ring face each other across it.
  if (n > 2) n -= n % 2;
  return std::clamp(n, 1, kMaxSeatsPerRing);
}

SeatPlacement seatPlacement(int index, const SeatLayout& layout) {
  int ring = 0;
  int n = seatsOnRing(0, layout);
  while (index >= n) {
    index -= n;
    n = seatsOnRing(++ring, layout);
  }
  const float radius = layout.first_radius_m + static_cast<float>(ring) * layout.ring_gap_m;
  const float stagger = (ring % 2 == 1) ? 0.5f : 0.0f;
  const float theta =
      2.0f * kPi * (static_cast<float>(spreadSlot(index, n)) + stagger) / static_cast<float>(n);
  SeatPlacement s;
  s.x = radius * std::sin(theta);
  s.z = radius * std::cos(theta);
  s.yaw = theta + kPi;  // +Z turned to face the centre
  if (s.yaw > kPi) s.yaw -= 2.0f * kPi;
  return s;
}

glm::mat4 seatTransform(const SeatPlacement& seat) {
  return glm::rotate(glm::translate(glm::mat4(1.0f), glm::vec3(seat.x, 0.0f, seat.z)), seat.yaw,
                     glm::vec3(0.0f, 1.0f, 0.0f));
}

}  // namespace vistel
