// Smoothness of the solved motion on every shared clip (issue 21): through the simulated rig
// with the default tracker noise and the default (Kalman) station filter, no joint's largest
// frame-to-frame jump exceeds 1.5 times the clip's own largest (no pops from the shared update
// rate, IK branch flips or swivel flips), the jitter (mean |jerk| of the joints, solved / clip)
// stays at or below what the solver reached (bench_posture; issue 21's target of 1.5 is met on
// none of the gesture clips, see the README), and on the conversation clips the upper body
// does not trail the clip by more than one sensor frame and is within 1 cm. The same with six
// sensors (a tracker on each foot): no pops, the legs near the truth. Skips when ../shared is
// absent.
#include <cctype>
#include <optional>
#include <string>

#include <gtest/gtest.h>

#include "common/sensors/clip_solve.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

struct ClipCase {
  const char* path;   // under mocap/
  double max_jitter;  // solved / clip, default noise: about 1.1 x what was measured
};

// The clip at `path` solved with `options` and scored against the clip itself (a failure and
// nothing when it cannot be); no pops (largest jump at most 1.5x the clip's) and the jitter
// at most max_jitter.
std::optional<PostureMetrics> solveWithoutPops(const std::string& path,
                                               const ClipSolveOptions& options, double max_jitter) {
  auto body = loadClipBody(path);
  if (!body) {
    ADD_FAILURE() << body.error().message;
    return std::nullopt;
  }
  auto solved = solveClip(*body, options);
  if (!solved) {
    ADD_FAILURE() << solved.error().message;
    return std::nullopt;
  }
  const std::vector<Posture> truth = clipPostures(body->clip);
  const PostureMetrics m =
      measurePostures(body->skeleton, body->roles, truth, solved->postures, body->clip.frame_time);
  EXPECT_GT(m.max_jump_truth_m, 0.0);
  EXPECT_LE(m.jumpRatio(), 1.5) << "largest jump " << m.max_jump_solved_m * 100.0
                                << " cm against the clip's " << m.max_jump_truth_m * 100.0 << " cm";
  EXPECT_LE(m.jitterRatio(), max_jitter);
  return m;
}

class SharedClipSmoothness : public ::testing::TestWithParam<ClipCase> {};

TEST_P(SharedClipSmoothness, NoPopsAndLittleLag) {
  const ClipCase& clip = GetParam();
  VISTEL_REQUIRE_SHARED(path, std::string("mocap/") + clip.path);
  const ClipSolveOptions options;  // default noise, default filter
  const std::optional<PostureMetrics> solved = solveWithoutPops(path, options, clip.max_jitter);
  ASSERT_TRUE(solved.has_value());
  const PostureMetrics& m = *solved;
  // Lag: at most one 120 Hz sensor frame on the conversation clips; the walking and jumping
  // (CMU) clips trail by more (bench_posture reports the figures; issue 21 keeps it open).
  if (std::string(clip.path).rfind("gestures/", 0) == 0) {
    EXPECT_LT(m.lag_s, 1.0 / 120.0) << "lag " << m.lag_s * 1e3 << " ms";
    EXPECT_LT(m.mpjpe_upper_m, 0.01);
  }
}

std::string clipName(const ::testing::TestParamInfo<ClipCase>& param) {
  std::string name = param.param.path;
  name = name.substr(name.find('/') + 1);
  name = name.substr(0, name.find('.'));
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return name;
}

// Measured with the default noise (bench_posture): bow 5.79, call 4.24, wave 2.18; CMU
// 01_01 0.59, 131_01 2.46, 131_02 3.38, scaled_131_03 3.51.
INSTANTIATE_TEST_SUITE_P(
    Clips, SharedClipSmoothness,
    ::testing::Values(ClipCase{"gestures/dataset-1_bow_normal_001.bvh", 6.4},
                      ClipCase{"gestures/dataset-1_call_normal_001.bvh", 4.7},
                      ClipCase{"gestures/dataset-2_wave-right-hand_normal_001.bvh", 2.4},
                      ClipCase{"cmu/01_01.bvh", 0.7}, ClipCase{"cmu/131_01.bvh", 2.7},
                      ClipCase{"cmu/131_02.bvh", 3.7}, ClipCase{"cmu/scaled_131_03.bvh", 3.9}),
    clipName);

// Six sensors (a tracker on each foot, six stations sharing 240 Hz: 40 Hz each, as
// bench_posture's /sensors:6 runs), default noise: no pops either. The CMU 131 kicks and dance
// steps popped the knees and toes by 20-40 cm (largest jump 1.6-2.4x the clip's) before the
// knee's swivel came from the foot's left-right axis and the feet were no longer extrapolated
// past their newest reading. The legs stay near the truth (measured: legs MPJPE 0.3-4.1 cm).
class SharedClipFootTrackers : public ::testing::TestWithParam<ClipCase> {};

TEST_P(SharedClipFootTrackers, NoPops) {
  const ClipCase& clip = GetParam();
  VISTEL_REQUIRE_SHARED(path, std::string("mocap/") + clip.path);
  ClipSolveOptions options;  // default noise, default filter
  options.sim.foot_trackers = true;
  options.sim.rate_hz = 240.0;
  const std::optional<PostureMetrics> solved = solveWithoutPops(path, options, clip.max_jitter);
  ASSERT_TRUE(solved.has_value());
  EXPECT_LT(solved->mpjpe_legs_m, 0.05);
}

// Jitter measured with six sensors and the default noise (bench_posture /sensors:6): bow 6.61,
// call 4.65, wave 2.42; CMU 01_01 0.52, 131_01 2.58, 131_02 2.83, scaled_131_03 3.08.
INSTANTIATE_TEST_SUITE_P(
    Clips, SharedClipFootTrackers,
    ::testing::Values(ClipCase{"gestures/dataset-1_bow_normal_001.bvh", 7.3},
                      ClipCase{"gestures/dataset-1_call_normal_001.bvh", 5.1},
                      ClipCase{"gestures/dataset-2_wave-right-hand_normal_001.bvh", 2.7},
                      ClipCase{"cmu/01_01.bvh", 0.6}, ClipCase{"cmu/131_01.bvh", 2.9},
                      ClipCase{"cmu/131_02.bvh", 3.1}, ClipCase{"cmu/scaled_131_03.bvh", 3.4}),
    clipName);

}  // namespace
}  // namespace vistel
