// Solving a shared gesture clip through the simulated rig (what `vistel-avatar solve` does):
// noiseless, the upper body follows the clip within millimetres; the written BVH, read back,
// has the clip's hierarchy and frame rate and the same joint positions.
#include <gtest/gtest.h>

#include "common/base/file.hpp"
#include "common/sensors/clip_solve.hpp"
#include "tests/sensors/humanoid.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

TEST(ClipSolve, GestureClipSolvedWrittenAndReadBack) {
  VISTEL_REQUIRE_SHARED(path, "mocap/gestures/dataset-1_call_normal_001.bvh");
  auto body = loadClipBody(path);
  ASSERT_TRUE(body.ok()) << body.error().message;
  EXPECT_EQ(body->map_name, "bandai_gestures");
  ClipSolveOptions options;
  options.sim.position_noise_m = 0.0f;
  options.sim.orientation_noise_deg = 0.0f;
  auto solved = solveClip(*body, options);
  ASSERT_TRUE(solved.ok()) << solved.error().message;
  ASSERT_EQ(solved->postures.size(), static_cast<std::size_t>(body->clip.frame_count));
  const std::vector<Posture> truth = clipPostures(body->clip);
  const PostureMetrics m =
      measurePostures(body->skeleton, body->roles, truth, solved->postures, body->clip.frame_time);
  EXPECT_LT(m.mpjpe_upper_m, 0.01);
  EXPECT_GT(m.frames, 100);

  // Written with the clip's hierarchy and frame rate; read back it has the same joints.
  const MotionClip out = clipFromPostures(body->skeleton, solved->postures, body->clip.frame_time,
                                          body->clip.unit_scale, "solved.bvh");
  const std::string file = test::scratchDir() + "/solved.bvh";
  ASSERT_TRUE(writeFileText(file, writeBvh(out)).ok());
  auto back = loadBvh(file);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back->frame_count, body->clip.frame_count);
  EXPECT_DOUBLE_EQ(back->frame_time, body->clip.frame_time);
  ASSERT_EQ(back->joints.size(), body->clip.joints.size());
  for (std::size_t j = 0; j < back->joints.size(); ++j)
    EXPECT_EQ(back->joints[j].name, body->clip.joints[j].name);
  const Skeleton back_skeleton = clipSkeleton(*back);
  float worst = 0.0f;
  Posture p;
  for (int k = 0; k < back->frame_count; k += 7) {
    samplePosture(*back, k, p);
    const auto a = test::jointPositions(back_skeleton, p);
    const auto b =
        test::jointPositions(body->skeleton, solved->postures[static_cast<std::size_t>(k)]);
    for (std::size_t j = 0; j < a.size(); ++j) worst = std::max(worst, glm::distance(a[j], b[j]));
  }
  EXPECT_LT(worst, 1e-3f);
}

TEST(ClipSolve, SimulatorIsDeterministicPerSeed) {
  VISTEL_REQUIRE_SHARED(path, "mocap/gestures/dataset-1_bow_normal_001.bvh");
  auto body = loadClipBody(path);
  ASSERT_TRUE(body.ok());
  ClipSolveOptions options;
  auto a = simulateClip(*body, options);
  auto b = simulateClip(*body, options);
  options.sim.seed = 2;
  auto c = simulateClip(*body, options);
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  ASSERT_EQ(a->frames.size(), b->frames.size());
  bool differs = false;
  for (std::size_t i = 0; i < a->frames.size(); ++i) {
    for (int s = 0; s < kBodySiteCount; ++s) {
      ASSERT_EQ(a->frames[i].stations[static_cast<std::size_t>(s)].position,
                b->frames[i].stations[static_cast<std::size_t>(s)].position);
      differs = differs || a->frames[i].stations[static_cast<std::size_t>(s)].position !=
                               c->frames[i].stations[static_cast<std::size_t>(s)].position;
    }
  }
  EXPECT_TRUE(differs);
  // Shared rate: each tick one station is new (120 Hz shared by 4 = 30 Hz each).
  int updated = 0;
  for (int s = 0; s < kBodySiteCount; ++s) {
    updated += a->frames[10].stations[static_cast<std::size_t>(s)].time !=
               a->frames[9].stations[static_cast<std::size_t>(s)].time;
  }
  EXPECT_EQ(updated, 1);
  // Noise as specified: the RMS of the 3-D position error over many readings ~0.8 mm.
  SimOptions noisy;
  noisy.shared_rate = false;
  noisy.latency_s = 0.0;
  auto still = RigSimulator::create(
      body->skeleton, body->roles, [&](double, Posture& out) { samplePosture(body->clip, 0, out); },
      20.0, noisy);
  auto exact_options = noiselessSimOptions();
  exact_options.shared_rate = false;
  auto exact = RigSimulator::create(
      body->skeleton, body->roles, [&](double, Posture& out) { samplePosture(body->clip, 0, out); },
      20.0, exact_options);
  ASSERT_TRUE(still.ok() && exact.ok());
  SensorFrame fn, fe;
  double sum_p = 0.0, sum_r = 0.0;
  int n = 0;
  while ((*still)->poll(0, fn).isFrame() && (*exact)->poll(0, fe).isFrame()) {
    for (int s = 0; s < kUpperBodySiteCount; ++s) {  // the feet are not worn
      {
        const float d = glm::distance(fn.stations[static_cast<std::size_t>(s)].position,
                                      fe.stations[static_cast<std::size_t>(s)].position);
        sum_p += d * d;
      }
      const float a_deg = test::angleDegrees(fn.stations[static_cast<std::size_t>(s)].orientation,
                                             fe.stations[static_cast<std::size_t>(s)].orientation);
      sum_r += a_deg * a_deg;
      ++n;
    }
  }
  EXPECT_NEAR(std::sqrt(sum_p / n) * 1000.0, 0.8, 0.05);
  EXPECT_NEAR(std::sqrt(sum_r / n), 0.15, 0.01);
}

}  // namespace
}  // namespace vistel
