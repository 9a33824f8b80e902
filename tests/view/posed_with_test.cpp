// DeformScene::posedWith: true exactly for the posture the last prepare() posed (the rest
// posture for one that did not fit), so a renderer may take the scene's matrices.
#include <gtest/gtest.h>

#include "common/scene/deform_scene.hpp"
#include "tests/scene/scene_fixtures.hpp"

namespace vistel {
namespace {

TEST(DeformScenePosedWith, OnlyThePosturePreparedLast) {
  const std::shared_ptr<const AvatarModel> tube = test::tubeAvatar();
  Result<DeformScene> made = DeformScene::create({SceneBody{"tube", tube, glm::mat4(1.0f), true}});
  ASSERT_TRUE(made.ok()) << made.error().message;
  DeformScene& scene = *made;
  Posture bent = restPosture(tube->skeleton);
  test::bendTube(bent, 0.8f);
  scene.setPosture(0, bent);
  ASSERT_TRUE(scene.prepare(0.0).ok());
  EXPECT_TRUE(scene.posedWith(0, bent));
  Posture other = bent;
  test::bendTube(other, 0.8001f);
  EXPECT_FALSE(scene.posedWith(0, other));
  other = bent;
  other.root_translation.y += 1e-3f;
  EXPECT_FALSE(scene.posedWith(0, other));
  other = bent;
  other.translations.assign(bent.rotations.size(), glm::vec3(0.0f));
  EXPECT_FALSE(scene.posedWith(0, other));
  EXPECT_FALSE(scene.posedWith(0, Posture{}));

  // A posture that does not fit is posed at rest: the rest posture matches.
  Posture broken = bent;
  broken.rotations.pop_back();
  scene.setPosture(0, broken);
  ASSERT_TRUE(scene.prepare(0.1).ok());
  EXPECT_EQ(scene.posturesAtRest(), 1);
  EXPECT_FALSE(scene.posedWith(0, broken));
  EXPECT_TRUE(scene.posedWith(0, restPosture(tube->skeleton)));
}

}  // namespace
}  // namespace vistel
