// The jitter measure of drawn against sent motion (MotionJerk, RemoteJitter,
// PlaybackStats' "jerk"), issue 21's remote smoothness.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "client/net/motion_jerk.hpp"
#include "client/net/playback_stats.hpp"
#include "client/net/remote_jitter.hpp"

namespace vistel::net {
namespace {

TEST(MotionJerk, ExactOnACubicAtUnevenTimesAndZeroOnAStraightLine) {
  MotionJerk cubic, line;
  const double times[] = {0.0, 0.013, 0.031, 0.040, 0.062, 0.075, 0.101};
  for (const double t : times) {
    const glm::vec3 c(static_cast<float>(t * t * t), 0.0f, 0.0f);  // x''' = 6
    const glm::vec3 l(static_cast<float>(2.0 * t), static_cast<float>(-t), 1.0f);
    cubic.add(t, std::span(&c, 1));
    line.add(t, std::span(&l, 1));
  }
  ASSERT_EQ(cubic.count(), 4u);  // the first three fill the window
  EXPECT_NEAR(cubic.mean(), 6.0, 0.05);
  EXPECT_NEAR(line.mean(), 0.0, 1e-2);
  // A repeated time is skipped, a new point count starts again.
  const glm::vec3 p(0.0f);
  EXPECT_LT(line.add(0.101, std::span(&p, 1)), 0.0);
  const glm::vec3 two[2] = {p, p};
  EXPECT_LT(line.add(0.2, two), 0.0);
  EXPECT_EQ(line.count(), 4u);
}

// A member's head on a smooth sway, sent at 30 Hz; the viewer draws at 60 Hz behind it.
// Drawn by the jitter buffer's cubic interpolation the jerk stays near the sent motion's
// (a linear blend of the two postures around t measured 47 times it: its velocity jumps at
// every received posture); drawn with a hold every other frame (a stuttering playback) it
// is many times more.
TEST(RemoteJitter, InterpolationAddsLittleJitterAndStutterAddsMuch) {
  Skeleton s;
  s.names = {"root", "neck", "head"};
  s.parents = {kNoParent, 0, 1};
  s.rest_local.resize(3);
  s.rest_local[1].translation = glm::vec3(0.0f, 0.5f, 0.0f);
  s.rest_local[2].translation = glm::vec3(0.0f, 0.2f, 0.0f);
  s.inverse_bind.assign(3, glm::mat4(1.0f));
  const auto pose = [&](double t) {
    Posture p;
    p.time = t;
    p.root_translation = glm::vec3(0.1f * static_cast<float>(std::sin(2.0 * t)), 1.0f, 0.0f);
    p.rotations.assign(3, glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
    p.rotations[1] =
        glm::angleAxis(0.3f * static_cast<float>(std::sin(3.0 * t)), glm::vec3(0.0f, 0.0f, 1.0f));
    return p;
  };
  const auto play = [&](bool stutter) {
    RemoteMember m;
    m.id = 7;
    m.name = "alice";
    PlaybackStats stats;
    RemoteJitter jitter;
    std::uint16_t seq = 0;
    double sent_until = -1.0;
    Posture drawn, held;
    for (int frame = 0; frame < 300; ++frame) {
      const double now = frame / 60.0;
      for (; sent_until + 1.0 / 30.0 <= now; sent_until += 1.0 / 30.0) {
        m.buffer.push(seq++, pose(sent_until + 1.0 / 30.0));
      }
      jitter.collect(m);
      const double t = now - 0.1;
      if (!m.buffer.sample(t, drawn)) continue;
      if (stutter && frame % 2 == 1 && !held.rotations.empty()) drawn = held;
      held = drawn;
      jitter.measure(m.id, m.name, s, t, drawn, stats);
    }
    return stats;
  };
  const PlaybackStats smooth = play(false);
  const PlaybackStats stuttered = play(true);
  const ShownFigures& f = smooth.members().at("alice");
  ASSERT_GT(f.sent_jerk.count(), 100u);
  ASSERT_GT(f.drawn_jerk.count(), 200u);
  const double smooth_ratio = f.drawn_jerk.mean() / f.sent_jerk.mean();
  const double stutter_ratio =
      stuttered.total().drawn_jerk.mean() / stuttered.total().sent_jerk.mean();
  std::printf("drawn/sent jerk: interpolated %.2f, stuttering %.2f\n", smooth_ratio, stutter_ratio);
  EXPECT_LT(smooth_ratio, 2.0);
  EXPECT_GT(stutter_ratio, 10.0 * smooth_ratio);
  // The JSON carries it.
  const nlohmann::json doc = nlohmann::json::parse(playbackJson(smooth));
  EXPECT_NEAR(doc["members"]["alice"]["jerk"]["ratio"].get<double>(), smooth_ratio, 1e-9);
}

// A member not collected in a frame has left: endFrame forgets it, and measure then adds
// nothing for it.
TEST(RemoteJitter, ForgetsMembersThatLeft) {
  Skeleton s;
  s.names = {"root"};
  s.parents = {kNoParent};
  s.rest_local.resize(1);
  s.inverse_bind.assign(1, glm::mat4(1.0f));
  RemoteMember m;
  m.id = 3;
  m.name = "bob";
  Posture p;
  p.rotations.assign(1, glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
  PlaybackStats stats;
  RemoteJitter jitter;
  for (int f = 0; f < 6; ++f) {
    p.time = f * 0.01;
    p.root_translation.x = static_cast<float>(f * f) * 0.01f;
    jitter.collect(m);
    jitter.measure(m.id, m.name, s, p.time, p, stats);
    jitter.endFrame();
  }
  const std::uint64_t drawn = stats.members().at("bob").drawn_jerk.count();
  EXPECT_EQ(drawn, 3u);  // the first three fill the window
  jitter.endFrame();     // a frame without bob
  p.time = 0.06;
  jitter.measure(m.id, m.name, s, p.time, p, stats);
  EXPECT_EQ(stats.members().at("bob").drawn_jerk.count(), drawn);
}

}  // namespace
}  // namespace vistel::net
