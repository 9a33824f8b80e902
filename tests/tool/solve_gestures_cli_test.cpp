// vistel-avatar solve (the posture pipeline on a clip) and gestures (the bundled clips).
#include <filesystem>

#include <gtest/gtest.h>

#include "common/motion/bvh.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tool/tool_runner.hpp"

namespace vistel {
namespace {

TEST(VistelAvatarCli, GesturesWritesParsableLoopingClips) {
  const std::string dir = test::scratchDir();
  const test::ToolRun run = test::runTool("gestures --out-dir " + dir + "/g", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  for (const char* name : {"wave", "point", "clap", "idle"}) {
    Result<MotionClip> clip = loadBvh(dir + "/g/" + name + ".bvh");
    ASSERT_TRUE(clip.ok()) << clip.error().message;
    EXPECT_GT(clip->frame_count, 30) << name;
    EXPECT_NEAR(clip->frame_time, 1.0 / 30.0, 1e-6) << name;
  }
}

TEST(VistelAvatarCli, SolveWritesTheClipsHierarchyAndFrameRate) {
  VISTEL_REQUIRE_SHARED(clip_path, "mocap/gestures/dataset-2_wave-right-hand_normal_001.bvh");
  const std::string dir = test::scratchDir();
  const test::ToolRun run =
      test::runTool("solve --bvh " + clip_path + " --out " + dir + "/solved.bvh --seed 3", dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  Result<MotionClip> source = loadBvh(clip_path);
  Result<MotionClip> solved = loadBvh(dir + "/solved.bvh");
  ASSERT_TRUE(source.ok() && solved.ok());
  ASSERT_EQ(solved->joints.size(), source->joints.size());
  for (std::size_t j = 0; j < source->joints.size(); ++j) {
    EXPECT_EQ(solved->joints[j].name, source->joints[j].name);
  }
  EXPECT_EQ(solved->frame_count, source->frame_count);
  EXPECT_NEAR(solved->frame_time, source->frame_time, 1e-6);

  // The solved right hand follows the clip's: compare world positions frame by frame.
  const Skeleton s_src = clipSkeleton(*source), s_out = clipSkeleton(*solved);
  const int hand = s_src.find("Hand_R");
  ASSERT_GE(hand, 0);
  std::vector<glm::mat4> m_src(s_src.names.size()), m_out(s_out.names.size());
  Posture p;
  double sum = 0.0;
  for (int k = 0; k < source->frame_count; ++k) {
    samplePosture(*source, k, p);
    poseSkeleton(s_src, p, m_src);
    samplePosture(*solved, k, p);
    poseSkeleton(s_out, p, m_out);
    sum += glm::length(glm::vec3(m_src[hand][3]) - glm::vec3(m_out[hand][3]));
  }
  EXPECT_LT(sum / source->frame_count, 0.02) << "mean right-hand error in metres";
}

TEST(VistelAvatarCli, SolveRejectsBadArguments) {
  const std::string dir = test::scratchDir();
  const test::ToolRun missing =
      test::runTool("solve --bvh " + dir + "/absent.bvh --out " + dir + "/x.bvh", dir);
  EXPECT_GT(missing.exit_code, 0);
  EXPECT_LT(missing.exit_code, 128);
  EXPECT_NE(missing.err.find("absent.bvh"), std::string::npos) << missing.err;
  const test::ToolRun noise = test::runTool("solve --bvh x.bvh --out y.bvh --noise loud", dir);
  EXPECT_GT(noise.exit_code, 0);
  EXPECT_LT(noise.exit_code, 128);
}

}  // namespace
}  // namespace vistel
