// Smoothness of the solved motion on every shared clip (issue 21): through the simulated rig
// with the default tracker noise and the default (Kalman) station filter, no joint's largest
// frame-to-frame jump exceeds 1.5 times the clip's own largest (no pops from the shared update
// rate, IK branch flips or swivel flips), and on the conversation clips the upper body does not
// trail the clip by more than one sensor frame. Skips when ../shared is absent.
#include <cctype>
#include <string>

#include <gtest/gtest.h>

#include "common/sensors/clip_solve.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

class SharedClipSmoothness : public ::testing::TestWithParam<const char*> {};

TEST_P(SharedClipSmoothness, NoPopsAndLittleLag) {
  VISTEL_REQUIRE_SHARED(path, std::string("mocap/") + GetParam());
  auto body = loadClipBody(path);
  ASSERT_TRUE(body.ok()) << body.error().message;
  const ClipSolveOptions options;  // default noise, default filter
  auto solved = solveClip(*body, options);
  ASSERT_TRUE(solved.ok()) << solved.error().message;
  const std::vector<Posture> truth = clipPostures(body->clip);
  const PostureMetrics m =
      measurePostures(body->skeleton, body->roles, truth, solved->postures, body->clip.frame_time);
  EXPECT_GT(m.max_jump_truth_m, 0.0);
  EXPECT_LE(m.jumpRatio(), 1.5) << "largest jump " << m.max_jump_solved_m * 100.0
                                << " cm against the clip's " << m.max_jump_truth_m * 100.0 << " cm";
  // Lag: at most one 120 Hz sensor frame on the conversation clips; the walking and jumping
  // (CMU) clips trail by more (bench_posture reports the figures; issue 21 keeps it open).
  if (std::string(GetParam()).rfind("gestures/", 0) == 0) {
    EXPECT_LT(m.lag_s, 1.0 / 120.0) << "lag " << m.lag_s * 1e3 << " ms";
  }
}

INSTANTIATE_TEST_SUITE_P(Clips, SharedClipSmoothness,
                         ::testing::Values("gestures/dataset-1_bow_normal_001.bvh",
                                           "gestures/dataset-1_call_normal_001.bvh",
                                           "gestures/dataset-2_wave-right-hand_normal_001.bvh",
                                           "cmu/01_01.bvh", "cmu/131_01.bvh", "cmu/131_02.bvh",
                                           "cmu/scaled_131_03.bvh"),
                         [](const ::testing::TestParamInfo<const char*>& param) {
                           std::string name = param.param;
                           name = name.substr(name.find('/') + 1);
                           name = name.substr(0, name.find('.'));
                           for (char& c : name)
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           return name;
                         });

}  // namespace
}  // namespace vistel
