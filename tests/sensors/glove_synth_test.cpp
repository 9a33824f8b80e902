// Synthetic glove streams: the shapes they claim, smooth over time.
#include <gtest/gtest.h>

#include "common/sensors/glove_synth.hpp"

namespace vistel {
namespace {

using Angles = std::array<float, kGloveSensorCount>;

TEST(GloveSynth, ShapesAndTransitions) {
  Angles a{};
  syntheticGlove(GlovePattern::kNeutral, 1.0, 2.0, a);
  for (float v : a) EXPECT_EQ(v, 0.0f);
  syntheticGlove(GlovePattern::kGrasp, 0.0, 2.0, a);
  EXPECT_NEAR(a[kIndexPij], 0.0f, 1e-6f);  // open at the start of the cycle
  syntheticGlove(GlovePattern::kGrasp, 1.0, 2.0, a);
  EXPECT_GT(a[kIndexPij], glm::radians(80.0f));  // closed half way
  EXPECT_GT(a[kPinkyMpj], glm::radians(60.0f));
  syntheticGlove(GlovePattern::kPoint, 0.3, 2.0, a);
  EXPECT_EQ(a[kIndexMpj], 0.0f);
  EXPECT_GT(a[kMiddleMpj], glm::radians(60.0f));
  syntheticGlove(GlovePattern::kSpread, 0.3, 2.0, a);
  EXPECT_GT(a[kMiddleIndexAbduction], 0.1f);
  EXPECT_GT(a[kPinkyRingAbduction], 0.1f);
  EXPECT_EQ(a[kIndexPij], 0.0f);
  // The cycle never jumps: at 120 Hz no angle moves more than a few degrees per sample.
  Angles prev{};
  syntheticGlove(GlovePattern::kCycle, 0.0, 2.0, prev);
  for (int k = 1; k < 120 * 8; ++k) {
    syntheticGlove(GlovePattern::kCycle, k / 120.0, 2.0, a);
    for (int i = 0; i < kGloveSensorCount; ++i)
      EXPECT_LT(std::abs(a[i] - prev[i]), glm::radians(6.0f)) << k;
    prev = a;
  }
  EXPECT_EQ(parseGlovePattern("spread"), GlovePattern::kSpread);
  EXPECT_FALSE(parseGlovePattern("wave").has_value());
}

}  // namespace
}  // namespace vistel
