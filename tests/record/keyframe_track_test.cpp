// KeyframeTrack: every sample is reproduced within the tolerance by interpolating the keys
// (lerp / slerp, as glTF LINEAR plays them), with far fewer keys than samples on smooth
// motion; constant runs keep two keys; cut() keeps a gap's ends; rotations stay in one
// hemisphere.
#include "common/record/keyframe_track.hpp"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

namespace vistel::record {
namespace {

// The track's value at t by linear interpolation of its keys (held outside them).
template <typename V, typename F>
V evaluate(const KeyframeTrack<V>& track, double t, F interpolate) {
  const auto& ts = track.times();
  const auto& vs = track.values();
  if (t <= ts.front()) return vs.front();
  if (t >= ts.back()) return vs.back();
  std::size_t i = 1;
  while (ts[i] < t) ++i;
  const auto u = static_cast<float>((t - ts[i - 1]) / (ts[i] - ts[i - 1]));
  return interpolate(vs[i - 1], vs[i], u);
}

glm::vec3 lerp3(const glm::vec3& a, const glm::vec3& b, float u) { return glm::mix(a, b, u); }
glm::quat slerpq(const glm::quat& a, const glm::quat& b, float u) { return glm::slerp(a, b, u); }

TEST(KeyframeTrack, SmoothTranslationWithinToleranceAndFewKeys) {
  const float tol = 0.0005f;
  Vec3Track track(tol);
  std::vector<std::pair<double, glm::vec3>> samples;
  for (int i = 0; i < 600; ++i) {  // 10 s at 60 Hz
    const double t = i / 60.0;
    const glm::vec3 v(0.3f * static_cast<float>(std::sin(t)), 1.0f,
                      0.1f * static_cast<float>(std::cos(2.0 * t)));
    samples.emplace_back(t, v);
    track.add(t, v);
  }
  track.finish();
  EXPECT_EQ(track.samples(), 600u);
  EXPECT_LT(track.times().size(), 600u / 4) << "keys: " << track.times().size();
  EXPECT_DOUBLE_EQ(track.times().front(), 0.0);
  EXPECT_DOUBLE_EQ(track.times().back(), samples.back().first);
  for (const auto& [t, v] : samples) {
    EXPECT_LE(glm::length(evaluate(track, t, lerp3) - v), tol * 1.001f) << "t = " << t;
  }
}

TEST(KeyframeTrack, RotationWithinAngleToleranceInOneHemisphere) {
  const float tol = 0.25f * 3.14159265f / 180.0f;
  QuatTrack track(tol);
  std::vector<std::pair<double, glm::quat>> samples;
  const glm::vec3 axis = glm::normalize(glm::vec3(1.0f, 0.3f, -0.2f));
  for (int i = 0; i < 300; ++i) {
    const double t = i / 60.0;
    glm::quat q = glm::angleAxis(2.5f * static_cast<float>(std::sin(1.5 * t)), axis);
    if (i % 2 == 1) q = -q;  // the same rotation from the other hemisphere
    samples.emplace_back(t, q);
    track.add(t, q);
  }
  track.finish();
  EXPECT_LT(track.times().size(), 100u);
  for (std::size_t k = 1; k < track.values().size(); ++k) {
    EXPECT_GE(glm::dot(track.values()[k - 1], track.values()[k]), 0.0f) << "key " << k;
  }
  for (const auto& [t, q] : samples) {
    EXPECT_LE(rotationAngle(evaluate(track, t, slerpq), q), tol * 1.01f) << "t = " << t;
  }
}

TEST(KeyframeTrack, ConstantRunKeepsItsEnds) {
  QuatTrack track(0.001f);
  const glm::quat q = glm::angleAxis(0.7f, glm::vec3(0.0f, 1.0f, 0.0f));
  for (int i = 0; i < 1000; ++i) track.add(i / 60.0, q);
  track.finish();
  ASSERT_EQ(track.times().size(), 2u);
  EXPECT_TRUE(track.constant());
  EXPECT_DOUBLE_EQ(track.times().back(), 999 / 60.0);
}

TEST(KeyframeTrack, CutKeepsTheGapsEndsAndIgnoresTimeGoingBack) {
  Vec3Track track(0.001f);
  for (int i = 0; i <= 60; ++i) track.add(i / 60.0, glm::vec3(i / 60.0f, 0.0f, 0.0f));
  track.add(0.5, glm::vec3(9.0f));  // not after the previous sample: ignored
  track.cut();
  for (int i = 120; i <= 180; ++i) track.add(i / 60.0, glm::vec3(5.0f, 0.0f, 0.0f));
  track.finish();
  // A straight line (two keys), then a constant run (two keys).
  ASSERT_EQ(track.times().size(), 4u);
  EXPECT_DOUBLE_EQ(track.times()[1], 1.0);
  EXPECT_DOUBLE_EQ(track.times()[2], 2.0);
  EXPECT_EQ(track.values()[1], glm::vec3(1.0f, 0.0f, 0.0f));
  EXPECT_EQ(track.values()[2], glm::vec3(5.0f, 0.0f, 0.0f));
  EXPECT_FALSE(track.constant());
  EXPECT_EQ(track.samples(), 122u);
}

TEST(KeyframeTrack, WindowIsBoundedOnSlowDrift) {
  // A line is reproduced exactly, but a key is forced every kMaxPending samples.
  Vec3Track track(0.01f);
  const int n = 1000;
  for (int i = 0; i < n; ++i) track.add(i, glm::vec3(static_cast<float>(i), 0.0f, 0.0f));
  track.finish();
  EXPECT_LE(track.times().size(), n / Vec3Track::kMaxPending + 3);
  EXPECT_GE(track.times().size(), n / (Vec3Track::kMaxPending + 1));
}

TEST(KeyframeTrack, RotationAngleIsAccurateForSmallAngles) {
  const glm::quat a = glm::angleAxis(0.3f, glm::vec3(0.0f, 0.0f, 1.0f));
  const glm::quat b = glm::angleAxis(0.3f + 1e-3f, glm::vec3(0.0f, 0.0f, 1.0f));
  EXPECT_NEAR(rotationAngle(a, b), 1e-3f, 2e-5f);
  EXPECT_NEAR(rotationAngle(a, -b), 1e-3f, 2e-5f);
  EXPECT_FLOAT_EQ(rotationAngle(a, a), 0.0f);
}

}  // namespace
}  // namespace vistel::record
