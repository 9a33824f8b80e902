// What a viewer shows of a remote member (JitterBuffer::sampleShown, PlaybackStats):
// interpolated while data is there, extrapolated for up to the limit past the newest
// posture, then held at the pose the limit reached; the counts and the shown age of a
// scripted stream with a half-second cut, frame by frame.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "client/net/jitter_buffer.hpp"
#include "client/net/playback_stats.hpp"
#include "common/math/transform.hpp"

namespace vistel::net {
namespace {

using Shown = JitterBuffer::Shown;

// Root moving along x at 1 m/s, joint 0 turning about y at 2 rad/s.
Posture moving(double t) {
  Posture p;
  p.time = t;
  p.root_translation = {static_cast<float>(t), 1.0f, 0.0f};
  p.rotations = {glm::angleAxis(static_cast<float>(2.0 * t), glm::vec3(0, 1, 0)),
                 glm::quat(1, 0, 0, 0)};
  return p;
}

TEST(SampleShown, InterpolatesExtrapolatesThenHoldsAtTheLimit) {
  JitterBuffer b(8);
  Posture p;
  double captured = -1.0;
  EXPECT_EQ(b.sampleShown(1.0, 0.1, p, &captured), Shown::kNone);
  b.push(1, moving(1.0));
  // One posture: nothing to extrapolate from.
  EXPECT_EQ(b.sampleShown(1.05, 0.1, p, &captured), Shown::kHeld);
  EXPECT_DOUBLE_EQ(captured, 1.0);
  b.push(2, moving(1.1));

  EXPECT_EQ(b.sampleShown(0.9, 0.1, p, &captured), Shown::kHeld);  // before the oldest
  EXPECT_DOUBLE_EQ(captured, 1.0);
  EXPECT_NEAR(p.root_translation.x, 1.0f, 1e-6f);

  EXPECT_EQ(b.sampleShown(1.04, 0.1, p, &captured), Shown::kInterpolated);
  EXPECT_DOUBLE_EQ(captured, 1.04);
  EXPECT_NEAR(p.root_translation.x, 1.04f, 1e-5f);

  EXPECT_EQ(b.sampleShown(1.15, 0.1, p, &captured), Shown::kExtrapolated);
  EXPECT_DOUBLE_EQ(captured, 1.1);  // no newer data than the newest
  EXPECT_NEAR(p.root_translation.x, 1.15f, 1e-5f);
  EXPECT_NEAR(angleBetween(p.rotations[0], glm::angleAxis(2.3f, glm::vec3(0, 1, 0))), 0.0f, 2e-3f);

  // Past the limit: the pose at newest + 0.1 s, held.
  EXPECT_EQ(b.sampleShown(1.5, 0.1, p, &captured), Shown::kHeld);
  EXPECT_DOUBLE_EQ(captured, 1.1);
  EXPECT_NEAR(p.root_translation.x, 1.2f, 1e-5f);
  EXPECT_NEAR(angleBetween(p.rotations[0], glm::angleAxis(2.4f, glm::vec3(0, 1, 0))), 0.0f, 2e-3f);

  // Without extrapolation: the newest, as sample() does.
  EXPECT_EQ(b.sampleShown(1.15, 0.0, p, &captured), Shown::kHeld);
  EXPECT_NEAR(p.root_translation.x, 1.1f, 1e-6f);
  ASSERT_TRUE(b.sample(1.15, p));
  EXPECT_NEAR(p.root_translation.x, 1.1f, 1e-6f);

  // classify() agrees without blending.
  EXPECT_EQ(b.classify(1.15, 0.1, &captured), Shown::kExtrapolated);
  EXPECT_EQ(b.classify(1.05, 0.1, &captured), Shown::kInterpolated);
  EXPECT_EQ(b.classify(1.25, 0.1, &captured), Shown::kHeld);
}

TEST(AgeHistogram, PercentilesWithinTwoPercent) {
  AgeHistogram h;
  for (int i = 1; i <= 1000; ++i) h.add(static_cast<double>(i));  // 1 .. 1000 ms
  EXPECT_EQ(h.count(), 1000u);
  EXPECT_NEAR(h.percentile(50.0), 500.0, 10.0);
  EXPECT_NEAR(h.percentile(99.0), 990.0, 20.0);
  EXPECT_DOUBLE_EQ(h.max(), 1000.0);
  EXPECT_NEAR(h.mean(), 500.5, 1e-9);
  h.add(-3.0);  // a slightly early clock: counted as 0
  h.add(1e9);   // beyond the last bin: counted there, max exact
  EXPECT_DOUBLE_EQ(h.max(), 1e9);
  EXPECT_LE(h.percentile(0.0), 1.0);
  AgeHistogram empty;
  EXPECT_EQ(empty.percentile(99.0), 0.0);
}

// A sender at 30 Hz whose postures arrive 50 ms after capture, except that those captured
// in [2.0, 2.5) s are lost; a viewer at 60 Hz playing 100 ms behind, extrapolating up to
// 100 ms. Every frame is classified the way the timeline says.
TEST(PlaybackStats, CountsAStreamWithACut) {
  constexpr double kDelay = 0.1;
  constexpr double kLimit = 0.1;
  constexpr double kTransit = 0.05;
  JitterBuffer buffer(32);
  PlaybackStats stats;
  Posture shown;
  int next = 0;  // next posture to arrive
  int expected_interpolated = 0;
  int expected_extrapolated = 0;
  int expected_held = 0;
  double previous_x = 0.0;
  double largest_step = 0.0;
  for (int frame = 0; frame < 240; ++frame) {  // 4 s
    const double now = 0.3 + frame / 60.0;
    // Arrivals up to now.
    for (; next / 30.0 + kTransit <= now; ++next) {
      const double capture = next / 30.0;
      if (capture >= 2.0 - 1e-9 && capture < 2.5 - 1e-9) continue;
      buffer.push(static_cast<std::uint16_t>(next), moving(capture));
    }
    const double play = now - kDelay;
    double captured = 0.0;
    const Shown kind = buffer.sampleShown(play, kLimit, shown, &captured);
    stats.add("ada", kind, now - captured);

    // The timeline: the newest posture before the cut is 59/30 s; data after it arrives
    // from 2.55 s on.
    const double newest = std::floor((now - kTransit) * 30.0 + 1e-9) / 30.0;
    const double newest_before_cut = 59.0 / 30.0;
    const bool in_cut = now >= 2.0 + kTransit && now < 2.5 + kTransit;
    const double buffered_newest = in_cut ? std::min(newest, newest_before_cut) : newest;
    if (play <= buffered_newest + 1e-9) {
      ++expected_interpolated;
    } else if (play - buffered_newest <= kLimit + 1e-9) {
      ++expected_extrapolated;
    } else {
      ++expected_held;
    }
    // What is drawn moves at most at the motion's speed, but for the jump back to real
    // data after the hold.
    if (frame > 0)
      largest_step = std::max(largest_step, std::abs(shown.root_translation.x - previous_x));
    previous_x = shown.root_translation.x;
  }
  const ShownFigures& f = stats.total();
  EXPECT_EQ(f.frames(), 240u);
  EXPECT_NEAR(static_cast<double>(f.extrapolated), expected_extrapolated, 1.0);
  EXPECT_NEAR(static_cast<double>(f.held), expected_held, 1.0);
  EXPECT_NEAR(static_cast<double>(f.interpolated), expected_interpolated, 2.0);
  EXPECT_NEAR(static_cast<double>(f.extrapolated), 6.0, 1.0);  // 100 ms at 60 Hz
  EXPECT_NEAR(static_cast<double>(f.held), 23.0, 2.0);         // the rest of the cut
  // Interpolated frames are 100 ms old; the oldest shown is the newest posture before the
  // cut, just before data comes back (2.55 s - 59/30 s).
  EXPECT_NEAR(f.age_ms.percentile(50.0), 100.0, 2.5);
  EXPECT_NEAR(f.age_ms.max(), (2.55 - 59.0 / 30.0) * 1e3, 17.0);
  EXPECT_GT(f.age_ms.percentile(99.0), 400.0);
  // The jump back when data returns: the motion since the held pose (2.55 - 0.1 - 2.067 s).
  EXPECT_NEAR(largest_step, 2.45 - (59.0 / 30.0 + kLimit), 0.03);

  // The member's figures are the total's; the JSON says the same.
  ASSERT_EQ(stats.members().count("ada"), 1u);
  EXPECT_EQ(stats.members().at("ada").held, f.held);
  const auto doc = nlohmann::json::parse(playbackJson(stats));
  EXPECT_EQ(doc["frames"], 240);
  EXPECT_EQ(doc["held"], f.held);
  EXPECT_EQ(doc["extrapolated"], f.extrapolated);
  EXPECT_EQ(doc["members"]["ada"]["interpolated"], f.interpolated);
  EXPECT_NEAR(doc["age_ms"]["p99"].get<double>(), f.age_ms.percentile(99.0), 1e-9);
  EXPECT_NE(playbackSummary(f).find("240 frames"), std::string::npos) << playbackSummary(f);

  PlaybackStats merged;
  merged.merge(stats);
  merged.merge(stats);
  EXPECT_EQ(merged.total().frames(), 480u);
  EXPECT_EQ(merged.members().at("ada").frames(), 480u);
}

}  // namespace
}  // namespace vistel::net
