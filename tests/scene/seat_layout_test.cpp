// The room's seat layout (common/scene/seat_layout.hpp): distinct seats at least the
// spacing apart, facing the centre, the first comers spread out, and no two rest bodies of
// the default avatar overlapping at any room size up to 128 members.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_set>
#include <vector>

#include <gtest/gtest.h>

#include "common/scene/seat_layout.hpp"
#include "offline/synth/default_avatar.hpp"

namespace vistel {
namespace {

glm::vec2 where(const SeatPlacement& s) { return {s.x, s.z}; }

TEST(SeatLayout, FirstSeatsFaceEachOtherAndEverySeatFacesTheCentre) {
  const SeatLayout layout;
  const SeatPlacement s0 = seatPlacement(0, layout);
  const SeatPlacement s1 = seatPlacement(1, layout);
  EXPECT_NEAR(s0.x, -s1.x, 1e-5f);
  EXPECT_NEAR(s0.z, -s1.z, 1e-5f);
  // The third and fourth face each other too, well away from the first two.
  const SeatPlacement s2 = seatPlacement(2, layout);
  const SeatPlacement s3 = seatPlacement(3, layout);
  EXPECT_NEAR(s2.x, -s3.x, 1e-5f);
  EXPECT_NEAR(s2.z, -s3.z, 1e-5f);
  const float cos_apart = glm::dot(glm::normalize(where(s0)), glm::normalize(where(s2)));
  EXPECT_LT(std::abs(cos_apart), 0.51f);  // at least 60 degrees from both
  for (int i = 0; i < 200; ++i) {
    const SeatPlacement s = seatPlacement(i, layout);
    const glm::vec3 facing(std::sin(s.yaw), 0.0f, std::cos(s.yaw));
    const glm::vec3 to_centre = glm::normalize(glm::vec3(-s.x, 0.0f, -s.z));
    EXPECT_GT(glm::dot(facing, to_centre), 0.9999f) << i;
  }
}

TEST(SeatLayout, SeatsAreDistinctAndAtLeastTheSpacingApart) {
  for (const SeatLayout layout : {SeatLayout{}, SeatLayout{0.3f, 0.3f, 1.0f},
                                  SeatLayout{2.0f, 0.7f, 0.8f}, SeatLayout{1.0f, 1.9f, 1.2f}}) {
    ASSERT_TRUE(validateSeatLayout(layout).ok());
    std::vector<glm::vec2> seats;
    for (int i = 0; i < 300; ++i) seats.push_back(where(seatPlacement(i, layout)));
    const float closest = std::min(layout.spacing_m, layout.ring_gap_m);
    for (std::size_t i = 0; i < seats.size(); ++i) {
      for (std::size_t j = i + 1; j < seats.size(); ++j) {
        ASSERT_GE(glm::distance(seats[i], seats[j]), closest * 0.999f)
            << "seats " << i << " and " << j << " of layout (" << layout.first_radius_m << ", "
            << layout.spacing_m << ", " << layout.ring_gap_m << ")";
      }
    }
  }
}

TEST(SeatLayout, RingsFillInOrderAndGrowWithTheirRadius) {
  const SeatLayout layout;
  int first = 0;
  for (int ring = 0; ring < 5; ++ring) {
    const int n = seatsOnRing(ring, layout);
    EXPECT_GE(n, ring == 0 ? 2 : seatsOnRing(ring - 1, layout)) << ring;
    const float radius = layout.first_radius_m + static_cast<float>(ring) * layout.ring_gap_m;
    for (int i = first; i < first + n; ++i) {
      EXPECT_NEAR(glm::length(where(seatPlacement(i, layout))), radius, 1e-4f) << i;
    }
    first += n;
  }
}

TEST(SeatLayout, ValidationNamesTheBadLength) {
  EXPECT_FALSE(validateSeatLayout(SeatLayout{0.0f, 1.0f, 1.0f}).ok());
  EXPECT_FALSE(validateSeatLayout(SeatLayout{1.0f, NAN, 1.0f}).ok());
  const Status too_wide = validateSeatLayout(SeatLayout{0.2f, 2.0f, 1.0f});
  ASSERT_FALSE(too_wide.ok());
  EXPECT_NE(too_wide.error().message.find("spacing"), std::string::npos);
}

// Cells of a 4 cm grid, packed into one key.
std::int64_t cellKey(const glm::vec3& p) {
  constexpr float kCell = 0.04f;
  const auto c = [](float v) { return static_cast<std::int64_t>(std::floor(v / kCell)) + 100000; };
  return (c(p.x) << 40) ^ (c(p.y) << 20) ^ c(p.z);
}

TEST(SeatLayout, DefaultAvatarsAtRestNeverOverlapUpToAFullRoom) {
  Result<AvatarModel> avatar = makeDefaultAvatar();
  ASSERT_TRUE(avatar) << avatar.error().message;
  const std::vector<glm::vec3>& rest = avatar->skin.positions;
  const SeatLayout layout;
  constexpr int kMembers = 128;
  // Every body's vertices in room space, and the grid cells each occupies.
  std::vector<std::unordered_set<std::int64_t>> cells(kMembers);
  std::vector<std::vector<glm::vec3>> bodies(kMembers);
  for (int i = 0; i < kMembers; ++i) {
    const glm::mat4 placement = seatTransform(seatPlacement(i, layout));
    for (const glm::vec3& p : rest) {
      const glm::vec3 q(placement * glm::vec4(p, 1.0f));
      bodies[static_cast<std::size_t>(i)].push_back(q);
      cells[static_cast<std::size_t>(i)].insert(cellKey(q));
    }
  }
  // How far the body reaches from its seat on the floor plane: farther seats cannot meet.
  float reach = 0.0f;
  for (const glm::vec3& p : rest) reach = std::max(reach, glm::length(glm::vec2(p.x, p.z)));
  // No vertex of one body falls in a cell another body occupies.
  int pairs_checked = 0;
  for (int a = 0; a < kMembers; ++a) {
    for (int b = 0; b < kMembers; ++b) {
      if (a == b || glm::distance(where(seatPlacement(a, layout)),
                                  where(seatPlacement(b, layout))) > 2.0f * reach + 0.1f) {
        continue;
      }
      ++pairs_checked;
      const auto& occupied = cells[static_cast<std::size_t>(a)];
      for (const glm::vec3& q : bodies[static_cast<std::size_t>(b)]) {
        ASSERT_EQ(occupied.count(cellKey(q)), 0u)
            << "the bodies at seats " << a << " and " << b << " overlap near (" << q.x << ", "
            << q.y << ", " << q.z << ")";
      }
    }
  }
  EXPECT_GT(pairs_checked, kMembers);  // neighbours were close enough to be compared
}

}  // namespace
}  // namespace vistel
