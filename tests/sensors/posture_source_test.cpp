// openPostureSource end to end: the simulated rig on a shared gesture clip solved onto an
// avatar (the test humanoid), recorded to .vrec, and the recording replayed through the
// same solver giving the same postures; bad specs fail clearly.
#include <cmath>

#include <gtest/gtest.h>

#include "common/sensors/io/posture_source.hpp"
#include "tests/sensors/humanoid.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

TEST(PostureSource, SimulatedClipRecordedAndReplayedThroughTheSameSolver) {
  VISTEL_REQUIRE_SHARED(clip, "mocap/gestures/dataset-2_wave-right-hand_normal_001.bvh");
  const Skeleton avatar = test::makeHumanoid(true);
  const std::string recording = test::scratchDir() + "/wave.vrec";
  PostureSourceOptions options;
  options.realtime = false;
  options.record_path = recording;
  auto live = openPostureSource("sim:" + clip, avatar, options);
  ASSERT_TRUE(live.ok()) << live.error().message;
  std::vector<Posture> solved;
  Posture p;
  while (solved.size() < 400) {
    const PollResult r = (*live)->poll(0.1, p);
    ASSERT_TRUE(r.isFrame()) << r.message;
    if ((*live)->calibrated()) solved.push_back(p);
  }
  EXPECT_NE((*live)->status().find("calibrated"), std::string::npos) << (*live)->status();
  for (const Posture& s : solved) {
    for (const glm::vec3& x : test::jointPositions(avatar, s))
      ASSERT_TRUE(std::isfinite(x.x) && std::isfinite(x.y));
  }
  // The right hand waves: the solved hand moves; the head stays near the standing height.
  const auto first = test::jointPositions(avatar, solved.front());
  float travel = 0.0f;
  for (const Posture& s : solved) {
    const auto pos = test::jointPositions(avatar, s);
    travel =
        std::max(travel, glm::distance(pos[static_cast<std::size_t>(avatar.find("r_hand"))],
                                       first[static_cast<std::size_t>(avatar.find("r_hand"))]));
  }
  EXPECT_GT(travel, 0.1f);
}

TEST(PostureSource, ReplayMatchesLiveExactly) {
  VISTEL_REQUIRE_SHARED(clip, "mocap/gestures/dataset-1_call_normal_001.bvh");
  const Skeleton avatar = test::makeHumanoid(false);
  const std::string recording = test::scratchDir() + "/call.vrec";
  PostureSourceOptions options;
  options.realtime = false;
  options.record_path = recording;
  auto live = openPostureSource("sim:" + clip, avatar, options);
  ASSERT_TRUE(live.ok()) << live.error().message;
  std::vector<Posture> after_calibration;
  std::size_t frames = 0, first_calibrated = 0;
  Posture p;
  while (frames < 300) {
    ASSERT_TRUE((*live)->poll(0.1, p).isFrame());
    ++frames;
    if ((*live)->calibrated()) {
      if (after_calibration.empty()) first_calibrated = frames;
      after_calibration.push_back(p);
    }
  }
  (*live)->stopRecording();
  // The replay calibrates where the live session did (the calibration record's place in the
  // stream) and then solves the same frames: the same postures.
  test::expectReplayMatches(recording, avatar, after_calibration, first_calibrated, frames);
}

TEST(PostureSource, BadSpecsFailClearly) {
  const Skeleton avatar = test::makeHumanoid(false);
  auto missing = openPostureSource("sim:no/such/clip.bvh", avatar);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().message.find("clip.bvh"), std::string::npos) << missing.error().message;
  auto no_rec = openPostureSource("recording:no/such.vrec", avatar);
  ASSERT_FALSE(no_rec.ok());
  auto no_port = openPostureSource("config/sensors/fastrak.toml", avatar);
  ASSERT_FALSE(no_port.ok());
  EXPECT_NE(no_port.error().message.find("/dev/ttyUSB0"), std::string::npos)
      << no_port.error().message;
  Skeleton odd;
  odd.names = {"root"};
  odd.parents = {kNoParent};
  odd.rest_local = {Transform{}};
  computeInverseBind(odd);
  EXPECT_FALSE(openPostureSource("config/sensors/fastrak.toml", odd).ok());
}

}  // namespace
}  // namespace vistel
