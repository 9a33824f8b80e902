// A clip played on an avatar (ClipPlayer): retargeted against the clip's natural pose, not
// its zero pose, so a clip whose zero pose is no standing pose (the gesture clips') still
// stands on the avatar.
#include <gtest/gtest.h>

#include "client/net/clip_player.hpp"
#include "common/math/transform.hpp"
#include "common/motion/bvh.hpp"
#include "common/motion/joint_map.hpp"
#include "offline/synth/default_avatar.hpp"
#include "tests/support/test_support.hpp"

namespace vistel {
namespace {

TEST(ClipPlayer, AGestureClipStandsOnTheAvatar) {
  VISTEL_REQUIRE_SHARED(path, "mocap/gestures/dataset-1_bow_normal_001.bvh");
  Result<MotionClip> clip = loadBvh(path);
  ASSERT_TRUE(clip.ok()) << clip.error().message;
  Result<AvatarModel> avatar = makeDefaultAvatar();
  ASSERT_TRUE(avatar.ok()) << avatar.error().message;
  const Skeleton& as = avatar->skeleton;

  auto player = net::ClipPlayer::create(*clip, as);
  ASSERT_TRUE(player.ok()) << player.error().message;
  ASSERT_TRUE((*player)->retargeted());
  Posture played;
  (*player)->sample(0.0, false, played);

  // What the retargeter made for the clip gives, joint for joint.
  Result<std::vector<JointMap>> maps = loadJointMaps("config");
  ASSERT_TRUE(maps.ok()) << maps.error().message;
  Result<const JointMap*> clip_map = selectJointMap(*maps, clipSkeleton(*clip));
  Result<const JointMap*> avatar_map = selectJointMap(*maps, as);
  ASSERT_TRUE(clip_map.ok() && avatar_map.ok());
  Result<Retargeter> rt = Retargeter::forClip(*clip, **clip_map, as, **avatar_map);
  ASSERT_TRUE(rt.ok()) << rt.error().message;
  Posture src, expected;
  samplePosture(*clip, 0, src);
  rt->apply(src, expected);
  ASSERT_EQ(played.rotations.size(), expected.rotations.size());
  for (std::size_t j = 0; j < played.rotations.size(); ++j) {
    EXPECT_LT(angleBetween(played.rotations[j], expected.rotations[j]), 1e-3f) << as.names[j];
  }

  // Standing: the thighs near their rest rotation (the zero pose's reference twisted the
  // right one 165 degrees).
  for (const char* name : {"l_thigh", "r_thigh"}) {
    const int j = as.find(name);
    ASSERT_GE(j, 0) << name;
    const auto ju = static_cast<std::size_t>(j);
    const float from_rest = angleBetween(played.rotations[ju], as.rest_local[ju].rotation);
    EXPECT_LT(from_rest, glm::radians(45.0f)) << name << " " << glm::degrees(from_rest) << " deg";
  }
}

}  // namespace
}  // namespace vistel
