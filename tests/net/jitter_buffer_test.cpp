// The jitter buffer: order, duplicates, staleness, interpolation.
#include <cmath>

#include <gtest/gtest.h>

#include "client/net/jitter_buffer.hpp"
#include "common/math/transform.hpp"

namespace vistel::net {
namespace {

Posture postureAt(double t, float x, float angle = 0.0f) {
  Posture p;
  p.time = t;
  p.root_translation = {x, 1.0f, 0.0f};
  p.rotations = {glm::angleAxis(angle, glm::vec3(0, 1, 0)), glm::quat(1, 0, 0, 0)};
  return p;
}

TEST(JitterBuffer, KeepsCaptureOrderAndRefusesDuplicates) {
  JitterBuffer b(4);
  EXPECT_EQ(b.push(1, postureAt(0.10, 1)), JitterBuffer::Push::kAccepted);
  EXPECT_EQ(b.push(3, postureAt(0.30, 3)), JitterBuffer::Push::kAccepted);
  EXPECT_EQ(b.push(2, postureAt(0.20, 2)), JitterBuffer::Push::kAccepted);  // late, fills the gap
  EXPECT_EQ(b.push(3, postureAt(0.30, 3)), JitterBuffer::Push::kDuplicate);
  EXPECT_EQ(b.size(), 3);
  EXPECT_DOUBLE_EQ(b.oldestTime(), 0.10);
  EXPECT_DOUBLE_EQ(b.newestTime(), 0.30);
  Posture p;
  ASSERT_TRUE(b.sample(0.25, p));
  EXPECT_NEAR(p.root_translation.x, 2.5f, 1e-5f);
}

TEST(JitterBuffer, FullBufferDropsTheOldestAndRefusesOlder) {
  JitterBuffer b(3);
  for (int i = 0; i < 3; ++i)
    ASSERT_EQ(b.push(static_cast<std::uint16_t>(i), postureAt(i, i)),
              JitterBuffer::Push::kAccepted);
  EXPECT_EQ(b.push(10, postureAt(-1.0, 0)), JitterBuffer::Push::kStale);
  EXPECT_EQ(b.push(3, postureAt(3.0, 3)), JitterBuffer::Push::kAccepted);
  EXPECT_EQ(b.size(), 3);
  EXPECT_DOUBLE_EQ(b.oldestTime(), 1.0);
  EXPECT_DOUBLE_EQ(b.newestTime(), 3.0);
}

TEST(JitterBuffer, InterpolatesAndHoldsAtTheEnds) {
  JitterBuffer b(8);
  b.push(1, postureAt(1.0, 0.0f, 0.0f));
  b.push(2, postureAt(2.0, 2.0f, 1.0f));
  Posture p;
  EXPECT_TRUE(b.sample(1.5, p));
  EXPECT_NEAR(p.root_translation.x, 1.0f, 1e-5f);
  EXPECT_NEAR(angleBetween(p.rotations[0], glm::angleAxis(0.5f, glm::vec3(0, 1, 0))), 0.0f, 2e-3f);
  EXPECT_TRUE(b.sample(0.0, p));  // before: the oldest
  EXPECT_NEAR(p.root_translation.x, 0.0f, 1e-6f);
  EXPECT_TRUE(b.sample(9.0, p));  // after: the newest, held
  EXPECT_NEAR(p.root_translation.x, 2.0f, 1e-6f);
  JitterBuffer empty(2);
  EXPECT_FALSE(empty.sample(1.0, p));
}

// The cubic through the neighbours: velocity continuous across a key (a blend of the two
// around t would jump from 1 to 3 m/s at t = 1), the keys themselves exact, and a sender
// whose clock stood still (equal capture times) gives finite postures.
TEST(JitterBuffer, InterpolatesAlongACubicThroughTheNeighbours) {
  JitterBuffer b(8);
  b.push(1, postureAt(0.0, 0.0f));
  b.push(2, postureAt(1.0, 1.0f));
  b.push(3, postureAt(2.0, 4.0f));
  b.push(4, postureAt(3.0, 9.0f));
  Posture p, q;
  const double h = 1e-3;
  ASSERT_TRUE(b.sample(1.0 - h, p));
  ASSERT_TRUE(b.sample(1.0 + h, q));
  const float left = (1.0f - p.root_translation.x) / static_cast<float>(h);
  const float right = (q.root_translation.x - 1.0f) / static_cast<float>(h);
  EXPECT_NEAR(left, right, 0.05f) << "velocity just before and after the key";
  EXPECT_NEAR(left, 2.0f, 0.05f);  // the Catmull-Rom tangent (4 - 0) / 2
  ASSERT_TRUE(b.sample(2.0, p));
  EXPECT_NEAR(p.root_translation.x, 4.0f, 1e-5f);

  JitterBuffer still(8);
  still.push(1, postureAt(1.0, 0.0f, 0.0f));
  still.push(2, postureAt(1.0, 1.0f, 0.5f));
  still.push(3, postureAt(1.0, 2.0f, 1.0f));
  still.push(4, postureAt(2.0, 3.0f, 1.5f));
  for (const double t : {0.5, 1.0, 1.5, 2.0}) {
    ASSERT_TRUE(still.sample(t, p));
    EXPECT_TRUE(std::isfinite(p.root_translation.x)) << t;
    EXPECT_TRUE(std::isfinite(p.rotations[0].w)) << t;
  }
}

}  // namespace
}  // namespace vistel::net
